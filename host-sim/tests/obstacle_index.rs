//! The known map's spatial index (`ldcbf_sim::world::obstacle_index`, issue 14
//! part 2): its query returns exactly what a linear scan of the bounding boxes
//! returns, the candidates it gives hold every obstacle the controller can
//! select, and `Controller::step` on them is `Controller::step` on the
//! whole map, bit for bit (random maps with exact duplicates, so that distance
//! ties are broken by the map's order); a closed loop on a 10,000-polygon map
//! reaches its goal and its every cycle replays on the whole map.

use ldcbf_controller::nalgebra::Vector2;
use ldcbf_controller::{
    Assembly, CycleInput, ObstacleQuery, RobotController, Side, closest_point_point_polygon,
};
use ldcbf_sim::scenario::{LoadOptions, load};
use ldcbf_sim::sim::{Outcome, SimOptions, run};
use ldcbf_sim::studies::replay::Recording;
use ldcbf_sim::world::Polygon;
use ldcbf_sim::world::obstacle_index::{Candidates, ObstacleIndex, scan_within};
use ldcbf_sim::world::robot::RobotParams;
use proptest::prelude::*;

/// A polygon: centre, circumradius, point angles (the hull of the points).
#[derive(Clone, Debug)]
struct Shape {
    center: [f64; 2],
    radius: f64,
    angles: Vec<f64>,
}

fn shape() -> impl Strategy<Value = Shape> {
    (
        prop::array::uniform2(-15.0..15.0f64),
        prop_oneof![3 => 0.05..0.5f64, 1 => 0.5..4.0f64],
        prop::collection::vec(0.0..std::f64::consts::TAU, 3..8),
    )
        .prop_map(|(center, radius, angles)| Shape {
            center,
            radius,
            angles,
        })
}

/// A map of up to 120 polygons, some of them exact copies of earlier ones
/// (`dups`: indices of the polygons to repeat, appended at the end).
fn map() -> impl Strategy<Value = Vec<Polygon>> {
    (
        prop::collection::vec(shape(), 0..120),
        prop::collection::vec(any::<prop::sample::Index>(), 0..10),
    )
        .prop_map(|(shapes, dups)| {
            let mut map: Vec<Polygon> = shapes
                .iter()
                .filter_map(|s| {
                    let pts: Vec<[f64; 2]> = s
                        .angles
                        .iter()
                        .map(|a| {
                            [
                                s.center[0] + s.radius * a.cos(),
                                s.center[1] + s.radius * a.sin(),
                            ]
                        })
                        .collect();
                    Polygon::hull(&pts).ok()
                })
                .collect();
            if !map.is_empty() {
                let n = map.len();
                for d in dups {
                    map.push(map[d.index(n)]);
                }
            }
            map
        })
}

/// One cycle's measured state (the obstacles and goal added by the test).
#[derive(Clone, Debug)]
struct State {
    com: [f64; 2],
    vel: [f64; 2],
    heading: f64,
    turning_rate: f64,
    foot: [f64; 2],
    left: bool,
    time_in_step: f64,
    goal: [f64; 2],
}

impl State {
    /// At rest at the origin, heading 0, left stance foot under the CoM, at
    /// the start of a step, walking to `goal` (m).
    fn at_rest(goal: [f64; 2]) -> State {
        State {
            com: [0.0, 0.0],
            vel: [0.0, 0.0],
            heading: 0.0,
            turning_rate: 0.0,
            foot: [0.0, 0.0],
            left: true,
            time_in_step: 0.0,
            goal,
        }
    }
}

fn state() -> impl Strategy<Value = State> {
    (
        prop::array::uniform2(-16.0..16.0f64),
        prop::array::uniform2(-0.6..0.6f64),
        -3.2..3.2f64,
        -0.5..0.5f64,
        prop::array::uniform2(-0.3..0.3f64),
        any::<bool>(),
        0.0..0.4f64,
        prop::array::uniform2(-16.0..16.0f64),
    )
        .prop_map(
            |(com, vel, heading, turning_rate, foot, left, time_in_step, goal)| State {
                com,
                vel,
                heading,
                turning_rate,
                foot: [com[0] + foot[0], com[1] + foot[1]],
                left,
                time_in_step,
                goal,
            },
        )
}

fn input<'a>(s: &State, obstacles: &'a [Polygon]) -> CycleInput<'a, 32> {
    let v = |a: [f64; 2]| Vector2::new(a[0], a[1]);
    CycleInput {
        com_position: v(s.com),
        com_velocity: v(s.vel),
        heading: s.heading,
        turning_rate: s.turning_rate,
        stance_foot: v(s.foot),
        stance_side: if s.left { Side::Left } else { Side::Right },
        time_in_step: s.time_in_step,
        goal: v(s.goal),
        obstacles,
        obstacle_velocities: &[],
        obstacle_velocity_radii: &[],
        speed_cap: ldcbf_controller::NO_SPEED_CAP,
    }
}

/// The simulator's controller configuration (the default robot: foot rows on).
fn controller() -> RobotController {
    let sc = load("paper", &LoadOptions::default()).expect("paper loads");
    RobotController::new(sc.config).expect("valid configuration")
}

/// The parts of two assemblies that depend on the obstacles, compared bit for
/// bit (through `Debug`, so that NaN equals NaN).
fn same_assembly<const N: usize, const NV: usize, const NC: usize, const NOBS: usize>(
    a: &Assembly<N, NV, NC, NOBS>,
    b: &Assembly<N, NV, NC, NOBS>,
) -> bool {
    format!(
        "{:?}",
        (a.active_obstacles(), a.obstacles_truncated, &a.rows, &a.qp)
    ) == format!(
        "{:?}",
        (b.active_obstacles(), b.obstacles_truncated, &b.rows, &b.qp)
    )
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    /// The R-tree query returns exactly the linear scan's obstacles, in
    /// increasing order; with a cycle's padded radius it holds every polygon
    /// within the radius (the controller's signed distance). The clearances
    /// through the index are the linear scans' values, bit for bit.
    #[test]
    fn the_index_query_is_the_linear_scan(
        map in map(),
        center in prop::array::uniform2(-20.0..20.0f64),
        radius in prop_oneof![0.0..0.5f64, 0.0..10.0f64],
        heading in -3.2..3.2f64,
    ) {
        let index = ObstacleIndex::new(&map).unwrap();
        prop_assert_eq!(index.len(), map.len());
        let c = Vector2::new(center[0], center[1]);
        let mut out = vec![u32::MAX];
        index.within_into(&c, radius, &mut out);
        prop_assert_eq!(&out, &scan_within(&map, &c, radius));
        prop_assert!(out.windows(2).all(|w| w[0] < w[1]));
        let q = ObstacleQuery { center: c, radius };
        index.candidates_into(&q, &mut out);
        for (j, p) in map.iter().enumerate() {
            if closest_point_point_polygon(&c, p).signed_distance <= radius {
                prop_assert!(out.binary_search(&(j as u32)).is_ok(), "obstacle {} missing", j);
            }
        }
        prop_assert_eq!(
            index.clearance(&c, &map).to_bits(),
            ldcbf_sim::world::clearance(&c, &map).to_bits()
        );
        let robot = RobotParams::default();
        prop_assert_eq!(
            index.foot_clearance(&robot, c, heading, &map).to_bits(),
            robot.foot_clearance(c, heading, &map).to_bits()
        );
    }

    /// A sequence of cycles (the warm start carried from one to the next) on
    /// the candidates of the index, queried every cycle or reused while they
    /// cover it (`Candidates`; each state is followed by one moved by up to
    /// 0.3 m, which the last list may cover), gives the outputs and
    /// assemblies of the same cycles on the whole map, and the query's centre
    /// is the cycle's `p_0`.
    #[test]
    fn step_on_the_candidates_is_step_on_the_whole_map(
        map in map(),
        states in prop::collection::vec((state(), prop::array::uniform2(-0.3..0.3f64)), 1..6),
    ) {
        let index = ObstacleIndex::new(&map).unwrap();
        let mut whole = controller();
        let mut among = whole.clone();
        let mut reused = whole.clone();
        let mut candidates = Vec::new();
        let mut cache = Candidates::default();
        for (s, d) in &states {
            let mut moved = s.clone();
            moved.com = [s.com[0] + d[0], s.com[1] + d[1]];
            for s in [s, &moved] {
                let inp = input(s, &map);
                let q = among.obstacle_query(&inp).expect("a valid input");
                index.candidates_into(&q, &mut candidates);
                let a = whole.step(&inp, None);
                let b = among.step(&inp, Some(&candidates));
                let c = reused.step(&inp, Some(cache.update(&index, &q)));
                prop_assert_eq!(format!("{a:?}"), format!("{b:?}"));
                prop_assert_eq!(format!("{a:?}"), format!("{c:?}"));
                prop_assert!(same_assembly(whole.last_assembly(), among.last_assembly()));
                prop_assert!(same_assembly(whole.last_assembly(), reused.last_assembly()));
                prop_assert_eq!(q.center, whole.last_assembly().prediction.p0);
                // The reused list holds this cycle's candidates, in order.
                let list = cache.list();
                prop_assert!(list.windows(2).all(|w| w[0] < w[1]));
                prop_assert!(candidates.iter().all(|j| list.binary_search(j).is_ok()));
            }
        }
    }
}

/// The random maps of the property above do put obstacles within reach: over
/// 64 fixed draws, most cycles select some, and some are truncated at the
/// capacity (so the order of the candidates matters).
#[test]
fn selection_is_not_vacuous() {
    use proptest::strategy::ValueTree;
    use proptest::test_runner::TestRunner;
    let mut runner = TestRunner::deterministic();
    let (mut with, mut truncated, mut total) = (0, 0, 0);
    for _ in 0..64 {
        let map = map().new_tree(&mut runner).unwrap().current();
        let s = state().new_tree(&mut runner).unwrap().current();
        let ctl = controller();
        let mut asm = Assembly::default();
        if ctl.assemble(&input(&s, &map), None, &mut asm).is_ok() {
            total += 1;
            with += usize::from(asm.n_obstacles > 0);
            truncated += usize::from(asm.obstacles_truncated);
        }
    }
    assert!(
        total == 64 && with > 32 && truncated > 0,
        "{with} {truncated} of {total}"
    );
}

/// Out-of-range candidates are skipped, not a panic; the order of the
/// candidates breaks distance ties (two copies of one polygon).
#[test]
fn candidates_out_of_range_are_skipped_and_order_breaks_ties() {
    let sq = Polygon::new(&[[1.0, -0.2], [1.4, -0.2], [1.4, 0.2], [1.0, 0.2]]).unwrap();
    let map = vec![sq, sq];
    let s = State::at_rest([5.0, 0.0]);
    let ctl = controller();
    let inp = input(&s, &map);
    let mut asm = Assembly::default();
    ctl.assemble(&inp, Some(&[1, 0, 7, u32::MAX]), &mut asm)
        .unwrap();
    let idx: Vec<u32> = asm.active_obstacles().iter().map(|o| o.index).collect();
    assert_eq!(idx, [1, 0]);
    ctl.assemble(&inp, None, &mut asm).unwrap();
    let idx: Vec<u32> = asm.active_obstacles().iter().map(|o| o.index).collect();
    assert_eq!(idx, [0, 1]);
}

/// Past 65,536 obstacles (the old `u16` index), the controller still sees the
/// last one, on the whole map and among the index's candidates alike.
#[test]
fn a_map_past_u16_indices_is_selected_whole() {
    let far = Polygon::new(&[[500.0, 500.0], [500.1, 500.0], [500.0, 500.1]]).unwrap();
    let near = Polygon::new(&[[1.0, -0.2], [1.4, -0.2], [1.4, 0.2], [1.0, 0.2]]).unwrap();
    let mut map = vec![far; 70_000];
    map.push(near);
    let s = State::at_rest([5.0, 0.0]);
    let ctl = controller();
    let inp = input(&s, &map);
    let index = ObstacleIndex::new(&map).unwrap();
    let mut candidates = Vec::new();
    index.candidates_into(&ctl.obstacle_query(&inp).unwrap(), &mut candidates);
    assert_eq!(candidates, [70_000]);
    let (mut a, mut b) = (Assembly::default(), Assembly::default());
    ctl.assemble(&inp, None, &mut a).unwrap();
    ctl.assemble(&inp, Some(&candidates), &mut b).unwrap();
    assert_eq!(a.active_obstacles().len(), 1);
    assert_eq!(a.active_obstacles()[0].index, 70_000);
    assert!(!a.obstacles_truncated);
    assert!(same_assembly(&a, &b));
}

/// `scenarios/large-map.toml` (10,000 polygons over 110 m x 110 m): the closed
/// loop, which passes the controller only the index's candidates, reaches the
/// goal without touching a polygon, among polygons (most cycles have some
/// within `r_active`), and its cycles replayed on the whole map give the
/// logged outputs bit for bit (every cycle in a release build; in a debug
/// build, where a full scan of the map is slow, the first 100, warm start
/// carried).
#[test]
fn a_large_map_closed_loop_reaches_the_goal_and_replays_on_the_whole_map() {
    let sc = load("large-map", &LoadOptions::default()).expect("large-map loads");
    assert_eq!(sc.obstacles.len(), 10_000);
    let res = run(
        &sc,
        SimOptions {
            record_scans: false,
            ..SimOptions::default()
        },
    )
    .unwrap();
    let summary = ldcbf_sim::summarize(&res);
    assert_eq!(res.outcome, Outcome::GoalReached);
    assert!(summary.success && !summary.collision, "{summary:?}");
    let busy = res
        .cycles
        .iter()
        .filter(|c| c.output.info.active_obstacles > 0)
        .count();
    assert!(
        busy * 2 > res.cycles.len(),
        "{busy} of {}",
        res.cycles.len()
    );
    let mut rec = Recording::from_run("large-map", &res).unwrap();
    if cfg!(debug_assertions) {
        rec.inputs.truncate(100);
        rec.outputs.truncate(100);
    }
    rec.verify().unwrap_or_else(|e| panic!("{e:#}"));
}
