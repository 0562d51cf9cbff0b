//! The tracking patterns of people who are hard to see, one test each: a
//! LiDAR (the default: 360 rays, 3 m, 1 cm noise) on a robot walking along
//! +x scans people (octagons) and walls at 20 Hz; [`Movers::observe`] hands
//! over hulls with velocities and velocity uncertainty radii, and the tests
//! check them against the truth. World frame W, metres, seconds.

use ldcbf_controller::nalgebra::Vector2;

use super::movers::{MoverScan, Movers};
use super::track::TrackParams;
use super::{Lidar, LidarParams};
use crate::world::Polygon;
use crate::world::moving::{translated, vertex_centre};
use crate::world::random::regular_polygon;

/// A person: an octagon of radius `r` at `c` (t = 0) walking at `v`, or
/// following `path(t)` (a displacement from `c`) when given.
/// A walk that is not at constant velocity: the displacement and the
/// velocity at `t`.
type Path = fn(f64) -> (Vector2<f64>, Vector2<f64>);

struct Person {
    body: Polygon,
    v: Vector2<f64>,
    /// Displacement at `t` when the walk is not at constant velocity.
    path: Option<Path>,
}

impl Person {
    fn walking(c: [f64; 2], r: f64, v: [f64; 2]) -> Self {
        Person {
            body: Polygon::new(&regular_polygon(c, r, 8, 0.2)).unwrap(),
            v: Vector2::new(v[0], v[1]),
            path: None,
        }
    }
    /// Its body and velocity at `t`.
    fn at(&self, t: f64) -> (Polygon, Vector2<f64>) {
        match self.path {
            Some(f) => {
                let (d, v) = f(t);
                (translated(&self.body, d), v)
            }
            None => (translated(&self.body, self.v * t), self.v),
        }
    }
}

/// One scan of a recorded walk: the time, what the movers handed over, and
/// the people's true centres and velocities.
struct Frame {
    t: f64,
    scan: MoverScan,
    ids: Vec<u64>,
    truth: Vec<(Vector2<f64>, Vector2<f64>)>,
}

/// Scans at 20 Hz for `secs` s from a robot at `robot_x0` walking along +x
/// at `robot_speed` (m/s), among `people` and `walls`.
fn record(
    people: &[Person],
    walls: &[Polygon],
    robot_x0: f64,
    robot_speed: f64,
    secs: f64,
) -> Vec<Frame> {
    let params = LidarParams::default();
    let mut lidar = Lidar::new(params.clone(), 11).unwrap();
    let mut movers = Movers::new(&params, TrackParams::default());
    let n = (secs / 0.05).round() as u32;
    (0..n)
        .map(|k| {
            let t = 0.05 * f64::from(k);
            let now: Vec<(Polygon, Vector2<f64>)> = people.iter().map(|p| p.at(t)).collect();
            let mut world: Vec<Polygon> = now.iter().map(|(b, _)| *b).collect();
            world.extend_from_slice(walls);
            let origin = Vector2::new(robot_x0 + robot_speed * t, 0.0);
            let rays = lidar.scan_rays(origin, 0.0, &world);
            let scan = movers.observe(t, origin, &rays);
            let ids = movers.tracker().matched().to_vec();
            let truth = now.iter().map(|(b, v)| (vertex_centre(b), *v)).collect();
            Frame {
                t,
                scan,
                ids,
                truth,
            }
        })
        .collect()
}

/// The obstacle of `scan` whose hull centre is nearest `c` within `reach`
/// (m): its index.
fn nearest(scan: &MoverScan, c: Vector2<f64>, reach: f64) -> Option<usize> {
    scan.obstacles
        .iter()
        .enumerate()
        .map(|(i, h)| (i, (vertex_centre(h) - c).norm()))
        .filter(|&(_, d)| d <= reach)
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(i, _)| i)
}

/// Every hull handed over with a velocity: its scan's time and its centre.
fn moving_hulls(frames: &[Frame]) -> Vec<(f64, Vector2<f64>)> {
    frames
        .iter()
        .flat_map(|f| {
            f.scan
                .velocities
                .iter()
                .zip(&f.scan.obstacles)
                .filter(|(v, _)| v.norm() > 0.0)
                .map(move |(_, h)| (f.t, vertex_centre(h)))
        })
        .collect()
}

/// Counts, over the frames from `from` s on, the scans in which person `k`
/// was handed over as an obstacle of its own (its nearest hull is nearest no
/// other person), and of those, the scans whose velocity was within `tol`
/// (m/s) of the truth.
fn own_and_right(frames: &[Frame], k: usize, from: f64, tol: f64) -> (usize, usize, usize) {
    let (mut scans, mut own, mut right) = (0, 0, 0);
    for f in frames.iter().filter(|f| f.t >= from) {
        scans += 1;
        let Some(i) = nearest(&f.scan, f.truth[k].0, 0.35) else {
            continue;
        };
        let shared = f
            .truth
            .iter()
            .enumerate()
            .any(|(q, (c, _))| q != k && nearest(&f.scan, *c, 0.35) == Some(i));
        if shared {
            continue;
        }
        own += 1;
        right += usize::from((f.scan.velocities[i] - f.truth[k].1).norm() <= tol);
    }
    (scans, own, right)
}

#[test]
fn two_people_in_file_across_the_view_are_two_tracks() {
    // Walking together along +y, 0.55 m apart along their walk: seen side by
    // side from the robot, 0.11 m of gap between them (one DBSCAN cluster).
    let people = [
        Person::walking([2.4, -1.6], 0.22, [0.0, 0.5]),
        Person::walking([2.4, -2.15], 0.22, [0.0, 0.5]),
    ];
    let frames = record(&people, &[], 0.0, 0.0, 8.0);
    for k in 0..2 {
        let (scans, own, right) = own_and_right(&frames, k, 2.0, 0.2);
        assert!(
            own * 10 >= scans * 9,
            "person {k}: own hull in {own} of {scans}"
        );
        assert!(
            right * 10 >= own * 9,
            "person {k}: right velocity in {right} of {own}"
        );
    }
}

#[test]
fn two_people_side_by_side_across_the_path_are_two_tracks() {
    // Walking together along +y, 0.6 m apart along the robot's line: the far
    // one seen beside the near one, at a different depth.
    let people = [
        Person::walking([2.0, -1.8], 0.22, [0.0, 0.5]),
        Person::walking([2.6, -1.8], 0.22, [0.0, 0.5]),
    ];
    let frames = record(&people, &[], 0.0, 0.0, 8.0);
    // Each person has their own hull with the right velocity whenever both
    // are in view and the far one is not hidden.
    for k in 0..2 {
        let (scans, own, right) = own_and_right(&frames, k, 2.0, 0.2);
        assert!(
            own * 10 >= scans * 7,
            "person {k}: own hull in {own} of {scans}"
        );
        assert!(
            right * 10 >= own * 9,
            "person {k}: right velocity in {right} of {own}"
        );
    }
}

#[test]
fn a_person_walking_at_the_robot_gets_a_velocity_in_time() {
    // Head-on, 2 cm off the line, 0.8 m/s, the robot walking at 0.4 m/s: the
    // person enters the 3 m range 3 m ahead; the closing speed is 1.2 m/s.
    let people = [Person::walking([4.0, 0.02], 0.22, [-0.8, 0.0])];
    let frames = record(&people, &[], 0.0, 0.4, 2.5);
    let seen = frames
        .iter()
        .find(|f| nearest(&f.scan, f.truth[0].0, 0.35).is_some())
        .map(|f| f.t)
        .expect("the person is seen");
    let found = frames
        .iter()
        .find(|f| {
            nearest(&f.scan, f.truth[0].0, 0.35)
                .is_some_and(|i| (f.scan.velocities[i] - f.truth[0].1).norm() <= 0.25)
        })
        .map(|f| f.t)
        .expect("the velocity is found");
    // Within 0.6 s of first sight: the gap is still more than 1.5 m.
    assert!(
        found - seen <= 0.6,
        "seen at {seen} s, velocity at {found} s"
    );
    // From then on every scan hands the velocity over within 0.3 m/s, and
    // the truth within the uncertainty radius.
    for f in frames.iter().filter(|f| f.t > found) {
        let i = nearest(&f.scan, f.truth[0].0, 0.35).expect("the person stays in view");
        let e = (f.scan.velocities[i] - f.truth[0].1).norm();
        assert!(e <= 0.3, "t = {}: {e} m/s off", f.t);
    }
}

/// The passing pair: the near person walks +y across 1.5 m ahead, the far
/// one (1 m behind, 0.5 m/s) walks -y: seen from the robot the far one passes
/// behind the near one.
fn passing_pair() -> [Person; 2] {
    [
        Person::walking([1.5, -1.0], 0.22, [0.0, 0.5]),
        Person::walking([2.5, 1.4], 0.22, [0.0, -0.5]),
    ]
}

#[test]
fn a_person_hidden_behind_another_coasts_and_is_found_again() {
    let people = passing_pair();
    let frames = record(&people, &[], 0.0, 0.0, 5.0);
    // The far person's hull, while hidden, is handed over where the track
    // predicts (coasting), and the track seen before is the track after.
    let mut hidden = 0;
    let mut ids_before = Vec::new();
    let mut ids_after = Vec::new();
    for f in &frames {
        let c = f.truth[1].0;
        // The bearing of the far person within the near one's shadow.
        let b_far = c.y.atan2(c.x);
        let n = f.truth[0].0;
        let shadow = (b_far - n.y.atan2(n.x)).abs() < 0.22 / n.norm();
        if shadow {
            hidden += 1;
            let i = nearest(&f.scan, c, 0.4).unwrap_or_else(|| {
                panic!("t = {}: the hidden person at {c} is not handed over", f.t)
            });
            // The truth is within the coasting track's uncertainty radius.
            let e = (f.scan.velocities[i] - f.truth[1].1).norm();
            assert!(e <= f.scan.velocity_radii[i], "t = {}: {e} m/s off", f.t);
        } else if let Some(i) = nearest(&f.scan, c, 0.3)
            && i < f.ids.len()
            && f.t > 1.0
        {
            if hidden == 0 {
                ids_before.push(f.ids[i]);
            } else {
                ids_after.push(f.ids[i]);
            }
        }
    }
    assert!(hidden >= 5, "the far person was hidden in {hidden} scans");
    let (before, after) = (ids_before.last(), ids_after.first());
    assert!(
        before.is_some() && before == after,
        "track {before:?} then {after:?}"
    );
}

#[test]
fn a_person_emerging_from_behind_a_corner_gets_a_velocity_in_time() {
    // A wall block to the left, its corner at x = 2.5; a person walks out
    // from behind it (0.5 m past the corner) toward the line at 0.6 m/s.
    let wall = Polygon::new(&[[0.5, 0.8], [2.5, 0.8], [2.5, 3.5], [0.5, 3.5]]).unwrap();
    let people = [Person::walking([3.0, 2.5], 0.22, [0.0, -0.6])];
    let frames = record(&people, &[wall], 0.0, 0.3, 5.0);
    let seen = frames
        .iter()
        .find(|f| nearest(&f.scan, f.truth[0].0, 0.35).is_some())
        .map(|f| f.t)
        .expect("seen");
    let found = frames
        .iter()
        .find(|f| {
            nearest(&f.scan, f.truth[0].0, 0.35)
                .is_some_and(|i| (f.scan.velocities[i] - f.truth[0].1).norm() <= 0.25)
        })
        .map(|f| f.t)
        .expect("velocity found");
    assert!(
        found - seen <= 0.8,
        "seen at {seen} s, velocity at {found} s"
    );
    // The wall is never handed over as moving.
    for f in &frames {
        for (h, v) in f.scan.obstacles.iter().zip(&f.scan.velocities) {
            let c = vertex_centre(h);
            if c.x < 2.4 && c.y > 0.8 {
                assert_eq!(*v, Vector2::zeros(), "t = {}: the wall at {c} moves", f.t);
            }
        }
    }
}

/// Walks +y from (2.5, -2) at 0.6 m/s for 3 s, stands 2 s, walks on.
fn stop_and_go(t: f64) -> (Vector2<f64>, Vector2<f64>) {
    let v = Vector2::new(0.0, 0.6);
    if t < 3.0 {
        (v * t, v)
    } else if t < 5.0 {
        (v * 3.0, Vector2::zeros())
    } else {
        (v * (t - 2.0), v)
    }
}

#[test]
fn a_person_who_stops_and_walks_on_is_followed() {
    let people = [Person {
        body: Polygon::new(&regular_polygon([2.5, -2.0], 0.22, 8, 0.2)).unwrap(),
        v: Vector2::zeros(),
        path: Some(stop_and_go),
    }];
    let frames = record(&people, &[], 0.0, 0.0, 7.5);
    let (mut scans, mut inside) = (0, 0);
    for f in frames.iter().filter(|f| f.t > 1.0) {
        let Some(i) = nearest(&f.scan, f.truth[0].0, 0.35) else {
            continue;
        };
        let e = (f.scan.velocities[i] - f.truth[0].1).norm();
        // Within 0.8 s of a change of pace the estimate follows it.
        let settled = [3.0, 5.0].iter().all(|c| !(*c..c + 0.8).contains(&f.t));
        if settled {
            assert!(e <= 0.25, "t = {}: {e} m/s off", f.t);
        }
        scans += 1;
        inside += usize::from(e <= f.scan.velocity_radii[i]);
    }
    // The truth is within the uncertainty radius (also through the stop).
    assert!(inside * 100 >= scans * 95, "inside in {inside} of {scans}");
}

/// Regression (room_crossing seed 200, unseen seeds 200..299): walls seen at
/// a slant or cut by the edge of the range came out of the detector in
/// person-sized pieces that slid along the wall as the robot walked; the
/// tracker gave them velocities up to 1.6 m/s, they were kept out of the map
/// and the velocity margin closed the door, so the robot stood 60 s in front
/// of it. A robot walking along a room's walls (one beside the path, one
/// near the edge of the range, one across the way ahead with a door) is
/// handed no obstacle that moves: the walls stay the map's
/// ([`super::walls`]).
#[test]
fn walls_seen_at_a_slant_or_at_the_edge_of_the_range_are_no_people() {
    let wall = |x0: f64, y0: f64, x1: f64, y1: f64| {
        Polygon::new(&[[x0, y0], [x1, y0], [x1, y1], [x0, y1]]).unwrap()
    };
    let walls = [
        // Beside the path, 1 m to the left.
        wall(-2.0, 1.0, 9.0, 1.2),
        // At the edge of the range to the right (2.9-3.0 m away).
        wall(-2.0, -3.1, 9.0, -2.9),
        // Across the way at x = 5, with a door 0.9 m wide at y in (-0.2, 0.7).
        wall(5.0, -2.9, 5.2, -0.2),
        wall(5.0, 0.7, 5.2, 1.0),
    ];
    let frames = record(&[], &walls, 0.0, 0.5, 8.0);
    let moving = moving_hulls(&frames);
    assert!(
        moving.is_empty(),
        "{} moving hulls handed over, the first (t, centre) {:?}",
        moving.len(),
        &moving[..moving.len().min(5)]
    );
    // What is handed over at all (while tentative, with the walking speed as
    // its radius) is at most the door's two jambs, seen end on.
    let most = frames.iter().map(|f| f.scan.obstacles.len()).max().unwrap();
    assert!(most <= 2, "{most} hulls handed over in one scan");
}

/// A door in a wall beside the path (`door-emerge` seed 700): walking past
/// it, the robot sees the wall's end (a jamb) from changing angles, and the
/// centre of its visible part slides by up to its length. The tracker gave
/// the jamb a small, "significant" speed; moving was sticky, so the jamb
/// stayed a person for good, and its reachable set (with that of a person
/// standing beyond the door) held the robot for 60 s. No hull near a jamb
/// may move ([`TrackParams::still_time`]). (The visible part of a wall cut
/// by the edge of the range slides with the robot and can still be handed
/// over as moving, also where that edge passes a jamb, as it does when the
/// robot walks on 2.8 m past it, so the robot stops 1 m past the door here:
/// docs/results.md, "People hard to track".)
#[test]
fn the_jambs_of_a_door_beside_the_path_are_no_people() {
    let wall = |x0: f64, y0: f64, x1: f64, y1: f64| {
        Polygon::new(&[[x0, y0], [x1, y0], [x1, y1], [x0, y1]]).unwrap()
    };
    // As door-emerge draws them: 1.3 m to the left, a door 1.2 m wide.
    let walls = [wall(1.0, 1.2, 4.8, 1.4), wall(6.0, 1.2, 9.0, 1.4)];
    let jambs = [Vector2::new(4.8, 1.3), Vector2::new(6.0, 1.3)];
    for (x0, speed) in [(2.0, 0.4), (1.0, 0.3), (3.0, 0.25), (3.0, 0.5)] {
        // Up to 1 m past the door, at most 10 s.
        let frames = record(&[], &walls, x0, speed, ((7.0 - x0) / speed).min(10.0));
        let moving: Vec<(f64, Vector2<f64>)> = moving_hulls(&frames)
            .into_iter()
            .filter(|(_, c)| jambs.iter().any(|j| (c - j).norm() <= 0.4))
            .collect();
        assert!(
            moving.is_empty(),
            "walking from x = {x0} at {speed} m/s: {} moving hulls at a jamb, the first (t, centre) {:?}",
            moving.len(),
            &moving[..moving.len().min(3)]
        );
    }
}

/// A person walking slowly at the robot (`crowd` seed 614: 0.3 m/s): in the
/// filter's steady state two standard deviations of the velocity estimate
/// are about 0.31 m/s, so the speed was never significant and the person
/// stood in the map as a wall for 2.8 s while the robot walked into them.
/// Walking 0.3 m is evidence too ([`TrackParams::still_radius`]): the
/// person has a velocity within 2 s of first sight, and from then on.
#[test]
fn a_person_walking_slowly_at_the_robot_gets_a_velocity() {
    for speed in [0.2, 0.3] {
        let people = [Person::walking([2.6, 0.4], 0.25, [-speed, -0.15 * speed])];
        let frames = record(&people, &[], 0.0, 0.0, 6.0);
        let first = frames
            .iter()
            .find(|f| nearest(&f.scan, f.truth[0].0, 0.35).is_some())
            .map(|f| f.t)
            .expect("the person is seen");
        let late: Vec<f64> = frames
            .iter()
            .filter(|f| f.t >= first + 2.0)
            .filter(|f| {
                nearest(&f.scan, f.truth[0].0, 0.35)
                    .is_none_or(|i| f.scan.velocities[i] == Vector2::zeros())
            })
            .map(|f| f.t)
            .collect();
        assert!(
            late.is_empty(),
            "{speed} m/s, seen at {first} s: no velocity at {} scans from 2 s after, the first {:?}",
            late.len(),
            late.first()
        );
    }
}
