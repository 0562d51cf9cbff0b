//! The node's cycle time on scans at the ray cap (`ldcbf_ros2::scan::MAX_RAYS`),
//! for the layouts that cost the perception most (docs/ros2.md, "Limits"):
//!
//! ```text
//! cargo run --release -p ldcbf-ros2 --example scan_cycle_time
//! ```
//!
//! Each layout is one `/scan` of `MAX_RAYS` rays handed to the LiDAR node of
//! `crowded` (with and without people tracking), then a gait state; the time
//! is the node's whole cycle (checks, perception, controller), wall clock,
//! the largest of `REPEATS` cycles.

use std::time::Instant;

use ldcbf_controller::RobotController;
use ldcbf_controller::nalgebra::Vector2;
use ldcbf_ros2::msgs::{GaitState, Header, Point, Time};
use ldcbf_ros2::node::NavNode;
use ldcbf_ros2::record::odometry;
use ldcbf_ros2::scan::{MAX_RAYS, full_turn};
use ldcbf_sim::scenario::{LoadOptions, load};

const REPEATS: usize = 20;

fn main() {
    let sc = load("crowded", &LoadOptions::default()).expect("crowded");
    let n = MAX_RAYS;
    // A fixed pseudo-random sequence (xorshift), for the noise layout.
    let mut s = 0x2545_f491_4f6c_dd1du64;
    let mut rnd = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 40) as f32 / (1u64 << 24) as f32
    };
    let noise: Vec<f32> = (0..n).map(|_| 0.3 + 2.6 * rnd()).collect();
    let mut lidar = ldcbf_sim::sense::Lidar::new(
        ldcbf_sim::sense::LidarParams {
            rays: n as u32,
            ..sc.lidar.clone()
        },
        1,
    )
    .expect("lidar");
    let world: Vec<f32> = lidar
        .scan_rays(sc.start, 0.0, &sc.obstacles)
        .iter()
        .map(|h| h.map_or(f32::INFINITY, |p| (p - sc.start).norm() as f32))
        .collect();
    let layouts: Vec<(&str, Vec<f32>)> = vec![
        ("ring at 0.6 m", vec![0.6; n]),
        ("every ray at 0.05 m", vec![0.05; n]),
        (
            "hit, miss, hit, miss at 1 m",
            (0..n)
                .map(|i| if i % 2 == 0 { 1.0 } else { f32::INFINITY })
                .collect(),
        ),
        (
            "zigzag 0.5 / 2.9 m",
            (0..n).map(|i| if i % 2 == 0 { 0.5 } else { 2.9 }).collect(),
        ),
        (
            "sawtooth 0.3 .. 2.9 m",
            (0..n).map(|i| 0.3 + 2.6 * (i % 64) as f32 / 63.0).collect(),
        ),
        ("uniform noise 0.3 .. 2.9 m", noise),
        ("crowded's map", world),
    ];
    println!("| layout ({n} rays) | people tracking | largest cycle of {REPEATS}, ms |");
    println!("|---|---|---|");
    for track in [false, true] {
        for (name, ranges) in &layouts {
            let ctl = RobotController::new(sc.config).expect("controller");
            let params = ldcbf_sim::sense::LidarParams {
                track_moving: track,
                ..sc.lidar.clone()
            };
            let mut nav = NavNode::new(ctl, Vec::new(), "map").with_lidar(params);
            let robot = ldcbf_ros2::robot::Robot::new(&sc, "map").expect("stand-in");
            let _ = nav.on_goal(&robot.goal());
            let mut worst = 0f64;
            for k in 0..REPEATS {
                let t = Time::from_secs(0.05 * k as f64);
                let _ = nav.on_odom(odometry(t, "map", sc.start, Vector2::zeros(), 0.0, 0.0));
                let _ = nav.on_scan(full_turn(t, ranges.clone(), 3.0));
                let g = GaitState {
                    header: Header {
                        stamp: t,
                        frame_id: "map".into(),
                    },
                    stance_side: GaitState::LEFT,
                    stance_foot: Point {
                        x: sc.start.x,
                        y: sc.start.y + 0.1,
                        z: 0.0,
                    },
                    time_in_step: 0.1,
                    turning_rate: 0.0,
                };
                let t0 = Instant::now();
                let m = nav.on_gait(g).expect("answered");
                worst = worst.max(t0.elapsed().as_secs_f64() * 1e3);
                assert_ne!(
                    m.command.result,
                    ldcbf_ros2::msgs::FootstepCommand::INVALID_INPUT
                );
            }
            println!(
                "| {name} | {} | {worst:.1} |",
                if track { "on" } else { "off" }
            );
        }
    }
}
