//! The capture-step speed limit of the unknown-map loop (`perception =
//! "lidar"`, `[lidar.map] capture_speed_limit`): the robot never commits to a
//! step it could not stop from inside the space it has seen to be free.
//!
//! **Free distance** ([`free_distance`]): the body disk (radius
//! `body_radius`) is swept along the planned path (the CoM, then the
//! planner's subgoals still ahead: the direction of travel; the path ends at
//! the goal, where the robot stops anyway); the free distance is the path
//! length swept before the disk first covers the centre of a cell of the
//! occupancy map that is occupied or unknown (cells beside or behind the disk
//! where a leg starts do not stop it: the barrier keeps those clear). The
//! planner inflates the occupied cells by the same radius, so a path on the
//! map seen so far is swept free up to where it enters unknown space or
//! crosses a cell newly seen occupied. Without a planner there is no
//! planned direction and no cap.
//!
//! **Stopping distance** ([`stop_distance`]): the capture point of the linear
//! inverted pendulum (Pratt et al. 2006, "Capture Point: a step toward
//! humanoid push recovery"), `xi = x + v / beta`, is where the CoM comes to
//! rest over a foot placed on it. With the foot's reach `l_max` from the CoM
//! at a step end, a robot whose capture point is farther stops in several
//! steps (N-step capturability, Koolen et al. 2012): each step puts the foot
//! `l_max` ahead of the CoM, the pendulum runs for `T`, until the capture
//! point is within reach. The stopping distance is where the CoM comes to
//! rest, from the step end where the stop begins.
//!
//! **The cap** ([`capture_cap`]): the controller's first planned step starts
//! at `p_0` (the end of the current step, already committed, with velocity
//! `v_0`) and ends at `p_1` with speed at most the cap `c`; over that step
//! the LIP moves `k (v_0 + c)` along the way, `k = tanh(beta T / 2) / beta`
//! (the closed-form flow with both end velocities). The cap is the largest
//! `c` in `[0, vx_max]` with `|p_0 - p| + k (v_0 + c) + stop(c) <= D`, the
//! free distance: every later cycle can still stop inside it. It reaches the
//! controller as [`ldcbf_controller::CycleInput::speed_cap`] (its
//! longitudinal velocity rows). When even `c = 0` does not fit (a cell seen
//! late), the cap is 0 and the controller's gait relaxation brakes as hard as
//! the steps allow.

use ldcbf_controller::nalgebra::Vector2;
use ldcbf_controller::{Config, Lip};

use crate::sense::{CellState, OccupancyMap};

/// Most steps a stop may take before the state counts as not capturable.
const MAX_STOP_STEPS: usize = 20;

/// The distance (m) the CoM of the pendulum `lip` travels to rest from a
/// step end where it moves at `speed` (m/s, `>= 0`) along a line, stepping
/// at most `l_max` (m) ahead of the CoM every step (module docs).
/// `f64::INFINITY` when it does not stop within `MAX_STOP_STEPS` steps.
pub fn stop_distance(lip: &Lip, l_max: f64, speed: f64) -> f64 {
    let (mut x, mut v) = (0.0, speed.max(0.0));
    for _ in 0..MAX_STOP_STEPS {
        let xi = x + v / lip.beta;
        if xi - x <= l_max {
            return xi;
        }
        (x, v) = lip.propagate_axis(x, v, x + l_max, lip.step_duration);
    }
    f64::INFINITY
}

/// `k` (s): the distance the first planned step adds per m/s of the speeds
/// at its two ends, `tanh(beta T / 2) / beta` (module docs).
fn step_travel(lip: &Lip) -> f64 {
    (0.5 * lip.beta * lip.step_duration).tanh() / lip.beta
}

/// The controller's pendulum for `config` (the one [`end_of_step`],
/// [`capture_cap`] and [`march_length`] take).
pub fn pendulum(config: &Config) -> Lip {
    Lip::new(config.gravity, config.com_height, config.step_duration)
}

/// The speed cap (m/s) for a cycle whose current step ends at `p0` with
/// velocity `v0` (m/s, world frame) while the CoM is at `position`, with the
/// free distance `free` (m) along the way, for the controller `config` and
/// its pendulum `lip` ([`pendulum`]; module docs). In `[0, config.vx_max]`.
pub fn capture_cap(
    config: &Config,
    lip: &Lip,
    position: Vector2<f64>,
    (p0, v0): (Vector2<f64>, Vector2<f64>),
    free: f64,
) -> f64 {
    let k = step_travel(lip);
    let need =
        |c: f64| (p0 - position).norm() + k * (v0.norm() + c) + stop_distance(lip, config.l_max, c);
    if need(config.vx_max) <= free {
        return config.vx_max;
    }
    if need(0.0) > free {
        return 0.0;
    }
    let (mut lo, mut hi) = (0.0, config.vx_max);
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if need(mid) <= free {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// The path length (m) at which the disk of radius `radius` (m), swept from
/// `path[0]` through `path[1..]` and then on along the last leg's direction
/// (or `heading`, rad, when every leg is shorter than a micrometre), first
/// touches a cell of `map` that is occupied or unknown; `max` (m) when it
/// does not within `max` (module docs).
pub fn free_distance(
    map: &OccupancyMap,
    path: &[Vector2<f64>],
    heading: f64,
    radius: f64,
    max: f64,
) -> f64 {
    let Some(&start) = path.first() else {
        return 0.0;
    };
    let mut travelled = 0.0;
    let mut from = start;
    let mut dir = Vector2::new(heading.cos(), heading.sin());
    for &to in &path[1..] {
        let d = to - from;
        let len = d.norm();
        if len < 1e-6 {
            continue;
        }
        dir = d / len;
        let len = len.min(max - travelled);
        if let Some(s) = first_contact(map, from, dir, len, radius) {
            return travelled + s;
        }
        travelled += len;
        from = to;
        if travelled >= max {
            return max;
        }
    }
    let rest = max - travelled;
    match first_contact(map, from, dir, rest, radius) {
        Some(s) => travelled + s,
        None => max,
    }
}

/// The distance `s` in `[0, len]` (m) at which the disk of radius `radius`
/// centred on `from + s dir` first touches an occupied or unknown cell that
/// lies ahead of `from` (`dir` a unit vector), if it does.
fn first_contact(
    map: &OccupancyMap,
    from: Vector2<f64>,
    dir: Vector2<f64>,
    len: f64,
    radius: f64,
) -> Option<f64> {
    let rr = radius;
    let to = from + dir * len;
    let lo = from.inf(&to) - Vector2::repeat(rr);
    let hi = from.sup(&to) + Vector2::repeat(rr);
    let ((i0, i1), (j0, j1)) = map.cell_range(lo, hi);
    let normal = Vector2::new(-dir.y, dir.x);
    let mut best: Option<f64> = None;
    // Beyond the map's box every cell is unknown.
    let outside = |p: Vector2<f64>| map.cell_of(p).is_none();
    if outside(to + dir * radius) {
        let edge = (0..=64)
            .map(|n| len * f64::from(n) / 64.0)
            .find(|&s| outside(from + dir * (s + radius)));
        best = edge;
    }
    for j in j0..=j1 {
        for i in i0..=i1 {
            if map.state(i, j) == CellState::Free {
                continue;
            }
            let rel = map.centre(i, j) - from;
            let (along, across) = (dir.dot(&rel), normal.dot(&rel).abs());
            if along <= 0.0 || across >= rr {
                continue;
            }
            let s = (along - (rr * rr - across * across).sqrt()).max(0.0);
            if s <= len && best.is_none_or(|b| s < b) {
                best = Some(s);
            }
        }
    }
    best
}

/// The polyline the robot is about to walk (m, world frame): its CoM
/// `position`, then the planner's `subgoals` still ahead.
pub fn travel_path(position: Vector2<f64>, subgoals: &[Vector2<f64>]) -> Vec<Vector2<f64>> {
    let mut path = vec![position];
    path.extend_from_slice(subgoals);
    path
}

/// `(p_0, v_0)`: the CoM at the end of the current step (m, m/s, world
/// frame) from the CoM `position`, `velocity`, the `stance` foot and the
/// time left in the step `tau` (s), by the controller's pendulum `lip`.
pub fn end_of_step(
    lip: &Lip,
    position: Vector2<f64>,
    velocity: Vector2<f64>,
    stance: Vector2<f64>,
    tau: f64,
) -> (Vector2<f64>, Vector2<f64>) {
    lip.propagate(&position, &velocity, &stance, tau.max(0.0))
}

/// The longest free distance worth measuring (m): the need of
/// [`capture_cap`] at `vx_max`, plus a cell.
pub fn march_length(config: &Config, lip: &Lip, p0_distance: f64, v0: f64, resolution: f64) -> f64 {
    p0_distance
        + step_travel(lip) * (v0 + config.vx_max)
        + stop_distance(lip, config.l_max, config.vx_max).min(10.0)
        + resolution
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sense::MapParams;

    #[test]
    fn a_capture_point_within_reach_is_a_one_step_stop() {
        let lip = Lip::new(9.81, 1.0, 0.4);
        let beta = lip.beta;
        let d = stop_distance(&lip, 0.2, 0.3);
        assert!((d - 0.3 / beta).abs() < 1e-12);
        // Farther than the reach: more steps, and farther than the capture point.
        let d = stop_distance(&lip, 0.17, 0.8);
        assert!(d.is_finite() && d > 0.8 / beta, "{d}");
        assert!(stop_distance(&lip, 0.17, 0.5) < d);
        // A reach too short to catch the pendulum: no stop.
        assert_eq!(stop_distance(&lip, 0.01, 3.0), f64::INFINITY);
    }

    #[test]
    fn the_cap_is_the_largest_speed_that_stops_within_the_free_distance() {
        let c = Config::default();
        let p = Vector2::zeros();
        let lip = pendulum(&c);
        let rest = (p, Vector2::zeros());
        assert_eq!(capture_cap(&c, &lip, p, rest, 100.0), c.vx_max);
        assert_eq!(capture_cap(&c, &lip, p, rest, 0.0), 0.0);
        let beta = (c.gravity / c.com_height).sqrt();
        let k = (0.5 * beta * c.step_duration).tanh() / beta;
        for free in [0.1, 0.2, 0.4] {
            let cap = capture_cap(&c, &lip, p, rest, free);
            assert!(cap > 0.0 && cap < c.vx_max, "{free}: {cap}");
            let need = |v: f64| k * v + stop_distance(&lip, c.l_max, v);
            assert!(need(cap) <= free + 1e-12 && need(cap + 1e-6) > free);
        }
    }

    /// A map seen free within 3 m of (-0.5, 0) but for the cell holding
    /// (2, 0), seen occupied (one scan of 3,600 rays).
    fn map_with_one_cell() -> OccupancyMap {
        let mut m = OccupancyMap::new(
            MapParams::default(),
            Vector2::new(-1.0, -1.0),
            Vector2::new(3.0, 1.0),
        )
        .unwrap();
        let rays: Vec<Option<Vector2<f64>>> = (0..3600)
            .map(|k| (k == 0).then_some(Vector2::new(2.0, 0.001)))
            .collect();
        m.update(Vector2::new(-0.5, 0.001), 0.0, &rays, 3.0, 0.0, 0.0);
        assert_eq!(m.state_at(Vector2::new(2.01, 0.01)), CellState::Occupied);
        assert_eq!(m.state_at(Vector2::new(1.0, 0.5)), CellState::Free);
        m
    }

    #[test]
    fn the_swept_disk_stops_at_the_first_cell_it_touches() {
        let m = map_with_one_cell();
        let r = 0.3;
        let s = free_distance(&m, &[Vector2::new(0.0, 0.0)], 0.0, r, 3.0);
        // The cell [2, 2.025] x [0, 0.025]: touched when the front of the
        // disk reaches its centre.
        let expect = 2.0125 - r;
        assert!((s - expect).abs() < 0.02, "{s} vs {expect}");
        // Passing 0.4 m beside it: past it, up to the unknown beyond the range.
        let s = free_distance(&m, &[Vector2::new(0.0, 0.4)], 0.0, r, 3.0);
        assert!(s > 2.1, "{s}");
        // A path turning away before the cell: free as far as it was seen.
        let path = [
            Vector2::new(0.0, 0.0),
            Vector2::new(1.0, 0.0),
            Vector2::new(1.0, 0.5),
        ];
        let s = free_distance(&m, &path, 0.0, 0.1, 1.4);
        assert_eq!(s, 1.4);
    }
}
