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

use anyhow::{Result, ensure};
use ldcbf_controller::nalgebra::Vector2;
use ldcbf_sim::sense::{LidarParams, infer_obstacles, ray_direction};
use ldcbf_sim::world::Polygon;

use crate::msgs::{Header, LaserScan, Time};

/// Fails on a scan the perception cannot read: fewer than 3 rays, or not a
/// full turn of evenly spaced rays.
pub fn check(scan: &LaserScan) -> Result<()> {
    let n = scan.ranges.len();
    ensure!(n >= 3, "/scan: {n} rays (at least 3)");
    let turn = f64::from(scan.angle_increment) * n as f64;
    ensure!(
        (turn - core::f64::consts::TAU).abs() <= 1e-4,
        "/scan: angle_increment x {n} rays = {turn} rad, not a full turn (2 pi)"
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

/// The obstacles inferred from `scan` (see the module docs).
pub fn obstacles(
    scan: &LaserScan,
    origin: Vector2<f64>,
    heading: f64,
    params: &LidarParams,
) -> Result<Vec<Polygon>> {
    let r = rays(scan, origin, heading)?;
    Ok(infer_obstacles(
        &r,
        origin,
        heading + f64::from(scan.angle_min),
        params,
    ))
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
    let n = hits.len().max(1);
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
        range_max: range as f32,
        ranges: hits
            .iter()
            .map(|h| h.map_or(f32::INFINITY, |p| (p - origin).norm() as f32))
            .collect(),
        intensities: Vec::new(),
    }
}
