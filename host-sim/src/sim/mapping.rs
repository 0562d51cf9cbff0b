//! The unknown-map part of the closed loop (`perception = "lidar"`): each
//! control cycle, a LiDAR scan updates the occupancy map
//! ([`crate::sense::OccupancyMap`]), the controller's obstacles are the map's
//! pieces near the robot, and, with `planner = "rrt_star"`, the path is planned
//! on the map seen so far ([`crate::plan::on_map`]) and replanned when needed.
//!
//! **Pieces handed to the controller** ([`Mapper::obstacles`]): the map's
//! pieces within `r_active` of the cycle's `p_0`
//! ([`ldcbf_controller::Controller::obstacle_query`]), nearest first, without
//! the pieces that lie wholly beyond the LDCBF half-plane of a nearer piece
//! kept (the half-plane the controller itself takes at that piece's point
//! nearest `p_0`): such a piece adds no row the nearer one does not already
//! enforce, and a wall seen as a staircase of cell rectangles would otherwise
//! fill the controller's few obstacle slots with one side of a corridor.
//!
//! **The robot's own body** ([`inside_the_body`]): a hit closer to the CoM
//! than the body radius (a person who walked into the robot) marks no cell,
//! so the map never puts a wall where the robot stands.
//!
//! **Replanning** ([`Mapper::plan`]): a path is planned at the first cycle;
//! then, every `replan_period` s, the rest of the path (from the robot through
//! the remaining subgoals) is checked against the map's occupied cells inflated
//! by the plan's inflation and replanned when it crosses one ("blocked"), and
//! it is replanned when the robot has made no progress for half the stuck
//! window ("stalled", at most once per half window). Each plan keeps at least
//! [`crate::plan::RrtParams::map_floor`] beyond the body radius
//! ([`crate::plan::on_map`]). A failed plan keeps the goal as the only
//! subgoal and counts as a failure.
//!
//! **Speed cap** ([`Mapper::capture_cap`]): with
//! `lidar.map.capture_speed_limit`, each cycle's
//! [`ldcbf_controller::CycleInput::speed_cap`] lets the robot stop inside the
//! space the map has seen free along its way ([`super::capture`]).

use std::time::Instant;

use ldcbf_controller::nalgebra::Vector2;
use ldcbf_controller::{Config, CycleInput, ObstacleQuery, closest_point_point_polygon};

use super::capture;

use crate::plan::on_map::{CellMap, plan_on_map};
use crate::scenario::Scenario;
use crate::sense::movers::{MoverScan, Movers};
use crate::sense::track::TrackParams;
use crate::sense::{Lidar, OccupancyMap, faces};
use crate::world::Polygon;
use crate::world::grid::InflatedCells;

/// Why a path was (re)planned.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ReplanReason {
    /// The first plan of the run.
    Initial,
    /// The path crossed a cell newly seen occupied (inflated).
    Blocked,
    /// No progress for half the stuck window.
    Stalled,
}

/// One plan on the perceived map.
#[derive(Clone, Debug)]
pub struct ReplanRecord {
    /// Simulated time, s.
    pub time: f64,
    /// Why.
    pub reason: ReplanReason,
    /// Wall-clock planning time, ns.
    pub ns: u64,
    /// The subgoals it gave (empty when it failed), m.
    pub subgoals: Vec<Vector2<f64>>,
}

/// What the mapping did in a run.
#[derive(Clone, Debug)]
pub struct MappingLog {
    /// The map at the end of the run.
    pub map: OccupancyMap,
    /// Wall-clock time of each scan's map update, ns.
    pub update_ns: Vec<u64>,
    /// Every plan on the perceived map, in order.
    pub plans: Vec<ReplanRecord>,
}

impl MappingLog {
    /// Plans after the first.
    pub fn replans(&self) -> usize {
        self.plans.len().saturating_sub(1)
    }

    /// Plans that found no path.
    pub fn failures(&self) -> usize {
        self.plans.iter().filter(|p| p.subgoals.is_empty()).count()
    }
}

/// The mapping state of a run.
pub(super) struct Mapper {
    lidar: Lidar,
    pub(super) log: MappingLog,
    planning: bool,
    /// The next time the path is checked, s.
    next_check: f64,
    last_stall_replan: f64,
    last_update: Option<f64>,
    /// With `lidar.track_moving`: the people kept out of the map
    /// ([`crate::sense::movers`]) and what the last scan showed of them.
    movers: Option<(Movers, MoverScan)>,
    /// The controller's pendulum, for the capture-step speed cap
    /// ([`Mapper::capture_cap`]; built once from the scenario's config).
    pendulum: ldcbf_controller::Lip,
    /// The robot's body radius, m: hits closer than this to the scan's origin
    /// (the CoM) are of something inside the body and mark no cell
    /// ([`inside_the_body`]).
    body_radius: f64,
}

impl Mapper {
    /// A mapper for `scenario` (its `[lidar]` and `[lidar.map]` tables), with
    /// planning when `planning`.
    pub(super) fn new(scenario: &Scenario, planning: bool) -> Result<Self, String> {
        let lidar = Lidar::new(scenario.lidar.clone(), scenario.seed)?;
        let map = OccupancyMap::new(scenario.lidar.map.clone(), scenario.start, scenario.goal)
            .map_err(|e| format!("lidar.{e}"))?;
        Ok(Mapper {
            lidar,
            log: MappingLog {
                map,
                update_ns: Vec::new(),
                plans: Vec::new(),
            },
            planning,
            next_check: 0.0,
            last_stall_replan: f64::NEG_INFINITY,
            last_update: None,
            movers: scenario.lidar.track_moving.then(|| {
                (
                    Movers::new(&scenario.lidar, TrackParams::default()),
                    MoverScan::default(),
                )
            }),
            pendulum: capture::pendulum(&scenario.config),
            body_radius: scenario.robot.body_radius,
        })
    }

    /// Scans from `origin` (m) along `heading` (rad) at time `time` (s)
    /// against the true `obstacles` and updates the map; returns the hit
    /// points (m).
    pub(super) fn sense(
        &mut self,
        origin: Vector2<f64>,
        heading: f64,
        time: f64,
        obstacles: &[Polygon],
    ) -> Vec<Vector2<f64>> {
        let rays = self.lidar.scan_rays(origin, heading, obstacles);
        let p = self.lidar.params();
        let (marks, free) = faces::fit_scan(&rays, origin, heading, p);
        let dt = self.last_update.map_or(0.0, |t| time - t);
        self.last_update = Some(time);
        let people: &[bool] = match self.movers.as_mut() {
            Some((movers, scan)) => {
                *scan = movers.observe(time, origin, &rays);
                &scan.kept_out
            }
            None => &[],
        };
        let kept_out = inside_the_body(&rays, origin, self.body_radius, people);
        let t0 = Instant::now();
        self.log
            .map
            .update_scan(origin, heading, &marks, &free, dt, &kept_out);
        if let Some((_, scan)) = &self.movers {
            let r = self.log.map.resolution;
            for hull in &scan.obstacles {
                self.log.map.clear_polygon(hull, r);
            }
        }
        self.log
            .update_ns
            .push(u64::try_from(t0.elapsed().as_nanos()).unwrap_or(u64::MAX));
        rays.into_iter().flatten().collect()
    }

    /// The capture-step speed cap of a cycle (m/s, [`super::capture`]):
    /// `input` is the cycle's measured state, `subgoals` the rest of the
    /// planned path. [`ldcbf_controller::NO_SPEED_CAP`] without planning.
    pub(super) fn capture_cap(
        &self,
        config: &Config,
        input: &CycleInput<'_, { crate::world::MAX_VERTICES }>,
        subgoals: &[Vector2<f64>],
    ) -> f64 {
        if !self.planning {
            return ldcbf_controller::NO_SPEED_CAP;
        }
        let tau = config.step_duration - input.time_in_step;
        let lip = &self.pendulum;
        let (p0, v0) = capture::end_of_step(
            lip,
            input.com_position,
            input.com_velocity,
            input.stance_foot,
            tau,
        );
        let map = &self.log.map;
        let s0 = (p0 - input.com_position).norm();
        let max = capture::march_length(config, lip, s0, v0.norm(), map.resolution);
        let free = capture::free_distance(
            map,
            &capture::travel_path(input.com_position, subgoals),
            input.heading,
            config.body_radius,
            max,
        );
        capture::capture_cap(config, lip, input.com_position, (p0, v0), free)
    }

    /// With `lidar.track_moving`, the last scan's people kept out of the
    /// map ([`MoverScan`]: hulls, world frame; velocities, m/s; velocity
    /// uncertainty radii, m/s); `None` otherwise.
    pub(super) fn people(&self) -> Option<&MoverScan> {
        self.movers.as_ref().map(|(_, scan)| scan)
    }

    /// The controller's obstacles for a cycle whose selection disk is `q`
    /// (module docs), world frame.
    pub(super) fn obstacles(&self, q: &ObstacleQuery) -> Vec<Polygon> {
        let mut pieces: Vec<(f64, Polygon)> = self
            .log
            .map
            .pieces(q.center, q.padded_radius())
            .into_iter()
            .map(|p| {
                (
                    closest_point_point_polygon(&q.center, &p).signed_distance,
                    p,
                )
            })
            .collect();
        pieces.sort_by(|a, b| a.0.total_cmp(&b.0));
        // Kept half-planes: point c and unit outward normal eta (from p_0).
        let mut planes: Vec<(Vector2<f64>, Vector2<f64>)> = Vec::new();
        let mut out = Vec::with_capacity(pieces.len());
        for (d, p) in pieces {
            let beyond = planes
                .iter()
                .any(|(c, eta)| p.vertices().iter().all(|v| eta.dot(&(v - c)) >= -1e-12));
            if beyond {
                continue;
            }
            if d > 1e-9 {
                let cp = closest_point_point_polygon(&q.center, &p);
                planes.push((cp.point, (cp.point - q.center) / d));
            }
            out.push(p);
        }
        out
    }

    /// With planning: the new subgoals when the path is (re)planned this
    /// cycle (module docs), else `None`. `position` is the robot's (m),
    /// `subgoals[current..]` the rest of the path, `stalled` whether the
    /// robot has made no progress for half the stuck window.
    pub(super) fn plan(
        &mut self,
        scenario: &Scenario,
        time: f64,
        position: Vector2<f64>,
        subgoals: &[Vector2<f64>],
        stalled: bool,
    ) -> Option<(ReplanReason, Vec<Vector2<f64>>)> {
        if !self.planning {
            return None;
        }
        let half_window = 0.5 * scenario.stuck_window;
        let floor = scenario.rrt.map_floor(scenario.config.delta);
        let reason = if self.log.plans.is_empty() {
            ReplanReason::Initial
        } else if stalled && time - self.last_stall_replan >= half_window {
            self.last_stall_replan = time;
            ReplanReason::Stalled
        } else if time + 1e-9 >= self.next_check {
            self.next_check = time + scenario.rrt.replan_period;
            let m = &self.log.map;
            let occupied = m.occupied();
            let mut grid = InflatedCells::new(
                m.origin,
                m.resolution,
                m.width,
                m.height,
                &occupied,
                scenario.robot.body_radius,
            );
            if !path_blocked(&mut grid, position, subgoals) {
                return None;
            }
            ReplanReason::Blocked
        } else {
            return None;
        };
        self.next_check = time + scenario.rrt.replan_period;
        let (occupied, unknown) = self.log.map.flags();
        let map = &self.log.map;
        let cells = CellMap {
            origin: map.origin,
            resolution: map.resolution,
            width: map.width,
            height: map.height,
            occupied: &occupied,
            unknown: &unknown,
        };
        let t0 = Instant::now();
        let res = plan_on_map(
            &cells,
            position,
            scenario.goal,
            &scenario.rrt,
            scenario.robot.body_radius,
            floor,
        );
        let ns = u64::try_from(t0.elapsed().as_nanos()).unwrap_or(u64::MAX);
        let subgoals = match res {
            Ok(p) => p.subgoals,
            Err(_) => Vec::new(),
        };
        self.log.plans.push(ReplanRecord {
            time,
            reason,
            ns,
            subgoals: subgoals.clone(),
        });
        Some((
            reason,
            if subgoals.is_empty() {
                vec![scenario.goal]
            } else {
                subgoals
            },
        ))
    }
}

/// Whether the rest of the path (from `position`, m, through `subgoals`)
/// crosses an occupied cell of `grid`: a subgoal before the last in an
/// occupied cell, or a leg between two free cells that leaves the free cells.
/// A leg from or to a point inside the inflation (the robot near a wall, a
/// goal near a wall) is the plan's way out or in and is not checked.
fn path_blocked(
    grid: &mut InflatedCells<'_>,
    position: Vector2<f64>,
    subgoals: &[Vector2<f64>],
) -> bool {
    let mut prev = [position.x, position.y];
    for (k, s) in subgoals.iter().enumerate() {
        let q = [s.x, s.y];
        let (a, b) = (grid.is_free(prev), grid.is_free(q));
        if (k + 1 < subgoals.len() && !b) || (a && b && !grid.segment_free(prev, q)) {
            return true;
        }
        prev = q;
    }
    false
}

/// The rays whose hits the map leaves out: those flagged in `kept_out` (a
/// tracked person, [`crate::sense::movers`]; missing flags are `false`) and
/// those whose hit is closer than `body_radius` (m) to the scan's `origin`
/// (the CoM, m): a return from inside the robot's own body (a person who
/// walked into it) is not a wall where the robot stands, as with Nav2's
/// `footprint_clearing_enabled`. Such a ray still clears the cells in front of
/// its hit, and the people tracker still sees it.
pub(super) fn inside_the_body(
    rays: &[Option<Vector2<f64>>],
    origin: Vector2<f64>,
    body_radius: f64,
    kept_out: &[bool],
) -> Vec<bool> {
    rays.iter()
        .enumerate()
        .map(|(k, p)| {
            kept_out.get(k).copied().unwrap_or(false)
                || p.is_some_and(|p| (p - origin).norm() < body_radius)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::{LoadOptions, load};
    use crate::sense::CellState;
    use crate::world::random::regular_polygon;

    /// The occupied cells of `simple`'s LiDAR map (with the default humanoid's
    /// body, radius 0.25 m) after one scan from the
    /// origin with a person (radius 0.25 m) centred at (`x`, 0) and nothing
    /// else, and whether any of them has its centre within the body radius.
    fn scan_with_a_person_at(x: f64) -> (usize, bool) {
        let sc = load(
            "simple",
            &LoadOptions::with_sets(&[("perception", "\"lidar\""), ("robot.body_radius", "0.25")]),
        )
        .unwrap();
        let mut m = Mapper::new(&sc, false).unwrap();
        let person = Polygon::new(&regular_polygon([x, 0.0], 0.25, 8, 0.0)).unwrap();
        let origin = Vector2::zeros();
        let hits = m.sense(origin, 0.0, 0.0, &[person]);
        assert!(!hits.is_empty());
        assert_eq!(sc.robot.body_radius, 0.25);
        let map = &m.log.map;
        let states = map.states();
        let mut occupied = 0;
        let mut in_body = false;
        for (k, s) in states.iter().enumerate() {
            if *s == CellState::Occupied {
                occupied += 1;
                let c = map.centre(k % map.width, k / map.width);
                in_body |= c.norm() < sc.robot.body_radius;
            }
        }
        (occupied, in_body)
    }

    #[test]
    fn returns_from_inside_the_body_mark_no_cell() {
        // The person overlaps the body (its near side 5 cm from the CoM):
        // every hit is inside the body, none becomes a wall.
        assert_eq!(scan_with_a_person_at(0.3), (0, false));
        // A person clear of the body is mapped as before.
        let (occupied, in_body) = scan_with_a_person_at(1.0);
        assert!(occupied > 0 && !in_body, "{occupied} {in_body}");
    }

    #[test]
    fn inside_the_body_keeps_the_flags_and_adds_the_near_hits() {
        let o = Vector2::new(1.0, 1.0);
        let rays = [
            Some(Vector2::new(1.1, 1.0)),
            Some(Vector2::new(2.0, 1.0)),
            None,
            Some(Vector2::new(3.0, 1.0)),
        ];
        assert_eq!(
            inside_the_body(&rays, o, 0.25, &[false, false, false, true]),
            [true, false, false, true]
        );
        assert_eq!(
            inside_the_body(&rays, o, 0.25, &[]),
            [true, false, false, false]
        );
    }
}
