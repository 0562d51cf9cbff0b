//! The robot stand-in without DDS: the simulator's 1 kHz plant
//! ([`ldcbf_sim::Plant`], the 3D-LIP of `ldcbf-sim`), stepped as the
//! simulator's loop steps it, that publishes the odometry and the gait state
//! of each control cycle (20 Hz) and applies the footstep commands it gets
//! back: at a step end the swing foot lands at the newest command's
//! `foot_target` and its `turning_rate` takes effect. `ldcbf-ros2 robot`
//! runs it against the node over DDS (two processes, the closed loop).
//! No disturbances. In a LiDAR scenario (`perception = "lidar"`) it also
//! publishes a scan of the true map per cycle (the simulator's LiDAR, from the
//! CoM, zero angle along the heading; people where they are at that time)
//! for a node with `perception: lidar`.

use anyhow::Result;
use ldcbf_controller::Side;
use ldcbf_controller::nalgebra::Vector2;
use ldcbf_sim::scenario::Scenario;
use ldcbf_sim::sense::{Lidar, Perception};
use ldcbf_sim::sim::PLANT_DT;
use ldcbf_sim::world::moving::MovingMap;
use ldcbf_sim::{Plant, PlantParams};

use crate::msgs::{FootstepCommand, GaitState, Header, LaserScan, Point, Pose, PoseStamped, Time};
use crate::record::odometry;

/// Plant ticks between two control cycles (20 Hz).
pub const TICKS_PER_CYCLE: u64 = 50;

/// The simulated robot between two control cycles.
pub struct Robot {
    plant: Plant,
    frame_id: String,
    goal: Vector2<f64>,
    success_radius: f64,
    time_limit: f64,
    command: Option<(Vector2<f64>, f64)>,
    /// The LiDAR and the true map (its people move as in the simulator).
    lidar: Option<(Lidar, MovingMap)>,
}

/// How a walk of the stand-in ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum End {
    /// Within the scenario's `success_radius` of the goal.
    GoalReached,
    /// The scenario's time limit.
    TimeLimit,
}

impl Robot {
    /// At the scenario's start, at rest, walking towards its goal.
    pub fn new(sc: &Scenario, frame_id: &str) -> Result<Robot> {
        let params = PlantParams {
            gravity: sc.config.gravity,
            com_height: sc.config.com_height,
            step_duration: sc.config.step_duration,
            dt: PLANT_DT,
        };
        let plant = Plant::new(params, sc.start, sc.start_heading, sc.stance)
            .map_err(|e| anyhow::anyhow!("{}: plant: {e}", sc.name))?;
        let lidar = match sc.perception {
            Perception::Lidar => Some((
                Lidar::new(sc.lidar.clone(), sc.seed)
                    .map_err(|e| anyhow::anyhow!("{}: {e}", sc.name))?,
                MovingMap::new(&sc.obstacles, &sc.velocities)
                    .map_err(|e| anyhow::anyhow!("{}: {e}", sc.name))?,
            )),
            _ => None,
        };
        Ok(Robot {
            plant,
            frame_id: frame_id.into(),
            goal: sc.goal,
            success_radius: sc.success_radius,
            time_limit: sc.time_limit,
            command: None,
            lidar,
        })
    }

    /// Simulated time, s.
    pub fn time(&self) -> f64 {
        self.plant.time()
    }

    /// CoM position, m.
    pub fn position(&self) -> Vector2<f64> {
        self.plant.position
    }

    /// Footsteps landed.
    pub fn steps(&self) -> u32 {
        self.plant.steps
    }

    /// The goal to publish on `/goal_pose`.
    pub fn goal(&self) -> PoseStamped {
        PoseStamped {
            header: self.header(),
            pose: Pose {
                position: Point {
                    x: self.goal.x,
                    y: self.goal.y,
                    z: 0.0,
                },
                ..Pose::default()
            },
        }
    }

    fn header(&self) -> Header {
        Header {
            stamp: Time::from_secs(self.plant.time()),
            frame_id: self.frame_id.clone(),
        }
    }

    /// The odometry, gait state and (LiDAR scenarios) scan of this instant
    /// (the inputs of a cycle).
    pub fn sense(&mut self) -> (crate::msgs::Odometry, GaitState, Option<LaserScan>) {
        let p = &self.plant;
        let odom = odometry(
            Time::from_secs(p.time()),
            &self.frame_id,
            p.position,
            p.velocity,
            p.heading,
            p.turning_rate,
        );
        let gait = GaitState {
            header: self.header(),
            stance_side: match p.stance_side {
                Side::Left => GaitState::LEFT,
                Side::Right => GaitState::RIGHT,
            },
            stance_foot: Point {
                x: p.stance_foot.x,
                y: p.stance_foot.y,
                z: 0.0,
            },
            time_in_step: p.time_in_step(),
            turning_rate: p.turning_rate,
        };
        let scan = self.lidar.as_mut().map(|(l, map)| {
            map.set_time(p.time());
            let hits = l.scan_rays(p.position, p.heading, map.obstacles());
            crate::scan::laser_scan(gait.header.stamp, p.position, &hits, l.params().range)
        });
        (odom, gait, scan)
    }

    /// Takes this cycle's command (an invalid-input answer holds the last).
    pub fn apply(&mut self, c: &FootstepCommand) {
        if c.result != FootstepCommand::INVALID_INPUT {
            let f = Vector2::new(c.foot_target.x, c.foot_target.y);
            self.command = Some((f, c.turning_rate));
        }
    }

    /// Integrates to the next control cycle (landing the swing foot at each
    /// step end on the newest command); `Some` when the walk ended.
    pub fn advance(&mut self) -> Option<End> {
        for _ in 0..TICKS_PER_CYCLE {
            self.plant.tick();
            if self.plant.step_over() {
                // Without any command yet, the foot lands where it stands.
                let (f, w) = self.command.unwrap_or((self.plant.stance_foot, 0.0));
                self.plant.land(f, w);
            }
            if (self.plant.position - self.goal).norm() <= self.success_radius {
                return Some(End::GoalReached);
            }
            if self.plant.time() >= self.time_limit {
                return Some(End::TimeLimit);
            }
        }
        None
    }
}
