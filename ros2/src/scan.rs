//! `/scan` (`sensor_msgs/LaserScan`) through the project's perception: the
//! scan's ranges become hit points in the world frame, and the obstacles are
//! the ones `ldcbf-sim` infers from its own LiDAR
//! ([`ldcbf_sim::sense::infer_obstacles`], the map scenario's `[lidar]`
//! settings).
//!
//! The perception expects a full turn of evenly spaced rays: ray `i` of `n`
//! at the sensor's zero angle plus `2 pi i / n`. A scan is taken at the CoM
//! (the frame of the odometry's pose, turned by its yaw); its `angle_min` is
//! the sensor's zero angle relative to the heading, `angle_increment` must be
//! `2 pi / n` (to 1e-4 rad over the turn). A range that is not finite or
//! outside `[range_min, range_max]` is no hit (ROS's `+inf`).

//!
//! A scan the perception cannot read is refused ([`check`]): more rays than
//! [`MAX_RAYS`] (the cap that bounds the perception's time, docs/ros2.md),
//! fewer than 3, or metadata that is not finite or out of range.

use anyhow::{Result, bail, ensure};
use ldcbf_controller::nalgebra::Vector2;
use ldcbf_sim::sense::movers::Movers;
use ldcbf_sim::sense::{LidarParams, infer_obstacles, ray_direction};
use ldcbf_sim::world::Polygon;

use crate::msgs::{Header, LaserScan, Time};

/// Most rays of a `/scan` (a 360-degree scan at 0.088 degrees): the cap
/// that bounds the perception's work per cycle (its DBSCAN is O(n k) for n
/// rays with k neighbours each; docs/ros2.md gives the measured cycle
/// times at the cap). A scan with more rays is refused, not decimated:
/// dropping rays could drop a thin obstacle.
pub const MAX_RAYS: usize = 4096;

/// Largest `|angle_min|`, rad (two turns: any sensor's zero angle).
pub const MAX_ANGLE: f32 = 2.0 * core::f32::consts::TAU;

/// Whether a stamp is a time (`nanosec < 1e9`).
pub fn valid_stamp(t: &Time) -> bool {
    t.nanosec < 1_000_000_000
}

/// Fails on a scan the perception cannot read, with the field and why: an
/// invalid stamp, fewer than 3 or more than [`MAX_RAYS`] rays, intensities
/// neither absent nor one per ray, `angle_min`, `angle_max`,
/// `time_increment` or `scan_time` not finite, `|angle_min|` over
/// [`MAX_ANGLE`], `angle_increment` not positive or not a full turn of the
/// rays, `range_min` not finite and `>= 0`, `range_max` not finite and `>
/// range_min`.
pub fn check(scan: &LaserScan) -> Result<()> {
    let n = scan.ranges.len();
    ensure!(
        valid_stamp(&scan.header.stamp),
        "/scan: header.stamp.nanosec = {} (at most 999999999)",
        scan.header.stamp.nanosec
    );
    ensure!(
        (3..=MAX_RAYS).contains(&n),
        "/scan: ranges: {n} rays (3 to {MAX_RAYS})"
    );
    let m = scan.intensities.len();
    ensure!(
        m == 0 || m == n,
        "/scan: intensities: {m} values for {n} rays (none or one per ray)"
    );
    for (name, v) in [
        ("angle_min", scan.angle_min),
        ("angle_max", scan.angle_max),
        ("time_increment", scan.time_increment),
        ("scan_time", scan.scan_time),
    ] {
        ensure!(v.is_finite(), "/scan: {name} = {v} (not finite)");
    }
    ensure!(
        scan.angle_min.abs() <= MAX_ANGLE,
        "/scan: angle_min = {} rad (|angle_min| at most {MAX_ANGLE})",
        scan.angle_min
    );
    let inc = scan.angle_increment;
    if !(inc.is_finite() && inc > 0.0) {
        bail!("/scan: angle_increment = {inc} (finite and > 0: counterclockwise rays)");
    }
    let turn = f64::from(inc) * n as f64;
    ensure!(
        (turn - core::f64::consts::TAU).abs() <= 1e-4,
        "/scan: angle_increment x {n} rays = {turn} rad, not a full turn (2 pi)"
    );
    let (lo, hi) = (scan.range_min, scan.range_max);
    ensure!(
        lo.is_finite() && lo >= 0.0,
        "/scan: range_min = {lo} (finite and >= 0)"
    );
    ensure!(
        hi.is_finite() && hi > lo,
        "/scan: range_max = {hi} (finite and > range_min = {lo})"
    );
    Ok(())
}

/// The rays of `scan` as hit points (world frame, m) from `origin` with the
/// sensor's zero angle at `heading + angle_min` (rad). Fails as [`check`].
pub fn rays(
    scan: &LaserScan,
    origin: Vector2<f64>,
    heading: f64,
) -> Result<Vec<Option<Vector2<f64>>>> {
    check(scan)?;
    let n = scan.ranges.len();
    let zero = heading + f64::from(scan.angle_min);
    let (lo, hi) = (f64::from(scan.range_min), f64::from(scan.range_max));
    Ok(scan
        .ranges
        .iter()
        .enumerate()
        .map(|(i, &r)| {
            let r = f64::from(r);
            (r.is_finite() && r >= lo && r <= hi).then(|| origin + ray_direction(zero, i, n) * r)
        })
        .collect())
}

/// What the perception makes of one scan: the controller's obstacles (world
/// frame) and their velocities (m/s; empty: all at rest).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Perceived {
    /// The obstacles: the pieces at rest, then the people.
    pub obstacles: Vec<Polygon>,
    /// One velocity per obstacle, or none (all at rest).
    pub velocities: Vec<Vector2<f64>>,
    /// One velocity uncertainty radius per obstacle (m/s; 0 at rest), or
    /// none (all exact).
    pub radii: Vec<f64>,
}

/// The obstacles inferred from `scan` (see the module docs). With `movers`
/// (`lidar.track_moving`: the simulator's people tracker,
/// [`ldcbf_sim::sense::movers`], and the scan's time, s), the people are
/// tracked as the simulator tracks them: the rays of a person kept out of
/// the map are left out of the pieces at rest, and the person's hull is
/// handed over with its velocity and its uncertainty radius (at rest, with
/// the walking speed as radius, while tentative). Fails as
/// [`check`].
pub fn perceive(
    scan: &LaserScan,
    origin: Vector2<f64>,
    heading: f64,
    params: &LidarParams,
    movers: Option<(&mut Movers, f64)>,
) -> Result<Perceived> {
    let mut r = rays(scan, origin, heading)?;
    let zero = heading + f64::from(scan.angle_min);
    let Some((movers, t)) = movers else {
        return Ok(Perceived {
            obstacles: infer_obstacles(&r, origin, zero, params),
            ..Perceived::default()
        });
    };
    let people = movers.observe(t, origin, &r);
    for (ray, out) in r.iter_mut().zip(&people.kept_out) {
        if *out {
            *ray = None;
        }
    }
    let mut obstacles = infer_obstacles(&r, origin, zero, params);
    let mut velocities = vec![Vector2::zeros(); obstacles.len()];
    let mut radii = vec![0.0; obstacles.len()];
    obstacles.extend(people.obstacles);
    velocities.extend(people.velocities);
    radii.extend(people.velocity_radii);
    Ok(Perceived {
        obstacles,
        velocities,
        radii,
    })
}

/// A full turn of `ranges` (ray `i` at `2 pi i / n` from the zero angle,
/// m; `+inf`: no return) stamped `stamp` in the body frame `base_link`,
/// ranges `[0, range_max]`.
pub fn full_turn(stamp: Time, ranges: Vec<f32>, range_max: f32) -> LaserScan {
    let n = ranges.len().max(1);
    LaserScan {
        header: Header {
            stamp,
            frame_id: "base_link".into(),
        },
        angle_min: 0.0,
        angle_max: (core::f64::consts::TAU * (n - 1) as f64 / n as f64) as f32,
        angle_increment: (core::f64::consts::TAU / n as f64) as f32,
        time_increment: 0.0,
        scan_time: 0.0,
        range_min: 0.0,
        range_max,
        ranges,
        intensities: Vec::new(),
    }
}

/// A full-turn scan (zero angle along the heading) of the hit points `hits`
/// (ray order, `None` = no return, `+inf`) from `origin`, stamped `stamp` in
/// the body frame `base_link`.
pub fn laser_scan(
    stamp: Time,
    origin: Vector2<f64>,
    hits: &[Option<Vector2<f64>>],
    range: f64,
) -> LaserScan {
    let ranges = hits
        .iter()
        .map(|h| h.map_or(f32::INFINITY, |p| (p - origin).norm() as f32))
        .collect();
    full_turn(stamp, ranges, range as f32)
}
