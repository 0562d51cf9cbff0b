//! The node's logic without DDS: messages in, the controller's cycle, messages
//! out. [`NavNode`] keeps the newest goal and odometry; each [`GaitState`]
//! triggers one control cycle once an odometry at least as recent as its
//! stamp has arrived (the gait state waits otherwise), so the cycle sees the
//! state of the same instant whatever order DDS delivers the two topics in.
//!
//! Conversions (world frame = the frame of the odometry's pose, m, rad):
//! CoM position = the odometry's position (x, y); heading = the yaw of its
//! orientation; CoM velocity = its `twist.linear` (the body frame,
//! `child_frame_id`) turned by that yaw into the world frame; the goal is the
//! position of the newest `/goal_pose`; stance side, stance foot, time in step
//! and turning rate come from the gait state. The obstacles are the known map,
//! or with LiDAR perception ([`NavNode::with_lidar`]) the ones inferred from
//! the newest `/scan` taken at the odometry's pose ([`crate::scan`]); the gait
//! state then also waits for a scan at least as recent.

use ldcbf_controller::nalgebra::Vector2;
use ldcbf_controller::{
    CommandSource, CycleInput, CycleOutput, CycleStatus, RobotController, Side,
};
use ldcbf_sim::sense::LidarParams;
use ldcbf_sim::world::Polygon;

use crate::msgs::{
    ColorRgba, DiagnosticArray, DiagnosticStatus, FootstepCommand, GaitState, Header, KeyValue,
    LaserScan, Marker, MarkerArray, Odometry, Path, Point, Pose, PoseStamped, Quaternion, Time,
};

/// The controller's horizon.
pub const HORIZON: usize = ldcbf_sim::sim::HORIZON;

/// What one cycle publishes.
#[derive(Clone, Debug, PartialEq)]
pub struct CycleMessages {
    /// The footstep command (`ldcbf_msgs/FootstepCommand`).
    pub command: FootstepCommand,
    /// The planned feet as `nav_msgs/Path` (`/footsteps`).
    pub footsteps: Path,
    /// Obstacles, active half-planes and planned feet (`/markers`).
    pub markers: MarkerArray,
    /// Cycle time and relaxations (`/diagnostics`).
    pub diagnostics: DiagnosticArray,
}

/// The node's state between messages.
pub struct NavNode {
    controller: RobotController,
    /// The known map, or the obstacles perceived in the last cycle's scan.
    obstacles: Vec<Polygon>,
    /// With LiDAR perception: its settings and the newest scan.
    lidar: Option<(LidarParams, Option<LaserScan>)>,
    frame_id: String,
    goal: Option<Vector2<f64>>,
    odom: Option<Odometry>,
    pending: Option<GaitState>,
    last: Option<Time>,
}

/// Yaw of a quaternion, rad.
pub fn yaw(q: &Quaternion) -> f64 {
    (2.0 * (q.w * q.z + q.x * q.y)).atan2(1.0 - 2.0 * (q.y * q.y + q.z * q.z))
}

/// The quaternion of a yaw `psi` (rad) about z.
pub fn quaternion(psi: f64) -> Quaternion {
    let (s, c) = (0.5 * psi).sin_cos();
    Quaternion {
        x: 0.0,
        y: 0.0,
        z: s,
        w: c,
    }
}

fn point(p: Vector2<f64>) -> Point {
    Point {
        x: p.x,
        y: p.y,
        z: 0.0,
    }
}

fn side_code(s: Side) -> u8 {
    match s {
        Side::Left => GaitState::LEFT,
        Side::Right => GaitState::RIGHT,
    }
}

/// The `result` code of a cycle (`FootstepCommand.msg`).
pub fn result_code(o: &CycleOutput<HORIZON>) -> u8 {
    match (o.info.source, o.status) {
        (_, CycleStatus::InvalidInput(_)) | (CommandSource::Hold, _) => {
            FootstepCommand::INVALID_INPUT
        }
        (CommandSource::Optimal, _) => FootstepCommand::SOLVED,
        (CommandSource::RelaxedGait | CommandSource::RelaxedSafety, _) => FootstepCommand::RELAXED,
        (_, CycleStatus::Infeasible) => FootstepCommand::INFEASIBLE,
        _ => FootstepCommand::FALLBACK,
    }
}

/// The `source` code of a cycle (`FootstepCommand.msg`, `SOURCE_*`).
pub fn source_code(s: CommandSource) -> u8 {
    match s {
        CommandSource::Optimal => 0,
        CommandSource::RelaxedGait => 1,
        CommandSource::RelaxedSafety => 2,
        CommandSource::PreviousPlan => 3,
        CommandSource::CaptureStep => 4,
        CommandSource::Hold => 5,
    }
}

/// The controller's input fields from an odometry and a gait state (the
/// obstacles and the goal are the caller's).
pub fn input_of<'a>(
    odom: &Odometry,
    gait: &GaitState,
    goal: Vector2<f64>,
    obstacles: &'a [Polygon],
) -> CycleInput<'a, { ldcbf_sim::world::MAX_VERTICES }> {
    let p = &odom.pose.pose;
    let psi = yaw(&p.orientation);
    let (s, c) = psi.sin_cos();
    let v = &odom.twist.twist.linear;
    CycleInput {
        com_position: Vector2::new(p.position.x, p.position.y),
        com_velocity: Vector2::new(c * v.x - s * v.y, s * v.x + c * v.y),
        heading: psi,
        turning_rate: gait.turning_rate,
        stance_foot: Vector2::new(gait.stance_foot.x, gait.stance_foot.y),
        // Any code but RIGHT is the left foot.
        stance_side: if gait.stance_side == GaitState::RIGHT {
            Side::Right
        } else {
            Side::Left
        },
        time_in_step: gait.time_in_step,
        goal,
        obstacles,
        // The known map is at rest.
        obstacle_velocities: &[],
        obstacle_velocity_radii: &[],
        speed_cap: ldcbf_controller::NO_SPEED_CAP,
    }
}

fn color(r: f32, g: f32, b: f32) -> ColorRgba {
    ColorRgba { r, g, b, a: 1.0 }
}

impl NavNode {
    /// A node planning with `controller` among the known map `obstacles`
    /// (world frame `frame_id`).
    pub fn new(controller: RobotController, obstacles: Vec<Polygon>, frame_id: &str) -> Self {
        NavNode {
            controller,
            obstacles,
            lidar: None,
            frame_id: frame_id.into(),
            goal: None,
            odom: None,
            pending: None,
            last: None,
        }
    }

    /// The same node planning among the obstacles perceived in `/scan`
    /// ([`crate::scan`]) instead of a known map: a gait state then also waits
    /// for a scan at least as recent.
    pub fn with_lidar(mut self, params: LidarParams) -> Self {
        self.obstacles.clear();
        self.lidar = Some((params, None));
        self
    }

    /// A new scan (`/scan`; ignored without LiDAR perception). A scan the
    /// perception cannot read (not a full turn) is refused, with the reason.
    pub fn on_scan(&mut self, scan: LaserScan) -> anyhow::Result<Option<CycleMessages>> {
        let Some((_, newest)) = &mut self.lidar else {
            return Ok(None);
        };
        crate::scan::check(&scan)?;
        *newest = Some(scan);
        Ok(self.try_cycle())
    }

    /// A new goal (`/goal_pose`): its position; runs a gait state's cycle
    /// that waited for a goal.
    pub fn on_goal(&mut self, goal: &PoseStamped) -> Option<CycleMessages> {
        self.goal = Some(Vector2::new(goal.pose.position.x, goal.pose.position.y));
        self.try_cycle()
    }

    /// A new odometry (`/odom`); runs the waiting gait state's cycle if this
    /// odometry is recent enough for it.
    pub fn on_odom(&mut self, odom: Odometry) -> Option<CycleMessages> {
        self.odom = Some(odom);
        self.try_cycle()
    }

    /// A new gait state: one control cycle, now or when its odometry (and a
    /// goal) arrives; a newer gait state replaces a waiting one. A gait state
    /// not newer than the last one planned on is ignored (a repeated sample),
    /// so a cycle runs once per gait state.
    pub fn on_gait(&mut self, gait: GaitState) -> Option<CycleMessages> {
        if self.last.is_some_and(|t| gait.header.stamp <= t) {
            return None;
        }
        self.pending = Some(gait);
        self.try_cycle()
    }

    fn try_cycle(&mut self) -> Option<CycleMessages> {
        let (odom, gait, goal) = (self.odom.as_ref()?, self.pending.as_ref()?, self.goal?);
        if odom.header.stamp < gait.header.stamp {
            return None;
        }
        let start = std::time::Instant::now();
        if let Some((params, scan)) = &self.lidar {
            let scan = scan
                .as_ref()
                .filter(|s| s.header.stamp >= gait.header.stamp)?;
            let p = &odom.pose.pose;
            let origin = Vector2::new(p.position.x, p.position.y);
            // Checked on arrival: a full turn.
            self.obstacles = crate::scan::obstacles(scan, origin, yaw(&p.orientation), params)
                .unwrap_or_default();
        }
        let gait = self.pending.take()?;
        let odom = self.odom.clone()?;
        self.last = Some(gait.header.stamp);
        let out = self
            .controller
            .step(&input_of(&odom, &gait, goal, &self.obstacles), None);
        let compute_ns = start.elapsed().as_nanos() as u64;
        Some(self.messages(&out, gait.header.stamp, compute_ns))
    }

    /// The messages of one cycle's output, stamped `stamp`.
    pub fn messages(
        &self,
        o: &CycleOutput<HORIZON>,
        stamp: Time,
        compute_ns: u64,
    ) -> CycleMessages {
        let header = Header {
            stamp,
            frame_id: self.frame_id.clone(),
        };
        let feet: Vec<Point> = o.plan.feet.iter().map(|f| point(*f)).collect();
        let mut com = vec![point(o.plan.x0.position)];
        com.extend(o.plan.states.iter().map(|s| point(s.position)));
        let command = FootstepCommand {
            header: header.clone(),
            result: result_code(o),
            source: source_code(o.info.source),
            status: o.status.name().into(),
            foot_target: point(o.foot_target),
            turning_rate: o.turning_rate,
            planned_feet: feet.clone(),
            first_side: side_code(o.plan.first_side),
            predicted_com: com.clone(),
            iterations: o.info.iterations,
            active_obstacles: o.info.active_obstacles,
            relax_gait: o.info.relax_gait,
            relax_safety: o.info.relax_safety,
        };
        let footsteps = Path {
            header: header.clone(),
            poses: o
                .plan
                .feet
                .iter()
                .zip(o.plan.states.iter())
                .map(|(f, s)| PoseStamped {
                    header: header.clone(),
                    pose: Pose {
                        position: point(*f),
                        orientation: quaternion(s.heading),
                    },
                })
                .collect(),
        };
        CycleMessages {
            command,
            footsteps,
            markers: self.markers(&header, o, &feet, &com),
            diagnostics: diagnostics(&header, o, compute_ns),
        }
    }

    fn markers(
        &self,
        header: &Header,
        o: &CycleOutput<HORIZON>,
        feet: &[Point],
        com: &[Point],
    ) -> MarkerArray {
        let marker =
            |ns: &str, id: i32, kind: i32, width: f64, c: ColorRgba, points: Vec<Point>| Marker {
                header: header.clone(),
                ns: ns.into(),
                id,
                kind,
                action: Marker::ADD,
                scale: Point {
                    x: width,
                    y: width,
                    z: width,
                },
                color: c,
                points,
                ..Marker::default()
            };
        let mut markers = vec![Marker {
            header: header.clone(),
            action: Marker::DELETEALL,
            ..Marker::default()
        }];
        for (j, poly) in self.obstacles.iter().enumerate() {
            let mut pts: Vec<Point> = poly.vertices().iter().map(|v| point(*v)).collect();
            pts.extend(pts.first().copied());
            let grey = color(0.4, 0.4, 0.4);
            markers.push(marker(
                "obstacles",
                j as i32,
                Marker::LINE_STRIP,
                0.03,
                grey,
                pts,
            ));
        }
        // The active half-planes: the boundary through the obstacle's closest
        // point c and a tick towards the safe side, from the controller's
        // last assembly.
        let mut planes = Vec::new();
        // (none on a hold: an invalid input builds no assembly).
        if result_code(o) != FootstepCommand::INVALID_INPUT {
            for ob in self.controller.last_assembly().active_obstacles() {
                let (c, n) = (ob.half_plane.c, ob.half_plane.eta);
                let along = Vector2::new(-n.y, n.x) * 0.8;
                planes.extend([c - along, c + along, c, c + n * 0.2].map(point));
            }
        }
        let magenta = color(0.9, 0.1, 0.6);
        markers.push(marker(
            "half_planes",
            0,
            Marker::LINE_LIST,
            0.02,
            magenta,
            planes,
        ));
        let blue = color(0.15, 0.45, 0.95);
        markers.push(marker(
            "planned_feet",
            0,
            Marker::SPHERE_LIST,
            0.08,
            blue,
            feet.to_vec(),
        ));
        let green = color(0.1, 0.7, 0.2);
        markers.push(marker(
            "predicted_com",
            0,
            Marker::LINE_STRIP,
            0.02,
            green,
            com.to_vec(),
        ));
        MarkerArray { markers }
    }
}

fn diagnostics(header: &Header, o: &CycleOutput<HORIZON>, compute_ns: u64) -> DiagnosticArray {
    let level = match result_code(o) {
        FootstepCommand::SOLVED => 0,
        FootstepCommand::RELAXED | FootstepCommand::FALLBACK => 1,
        _ => 2,
    };
    let kv = |k: &str, v: String| KeyValue {
        key: k.into(),
        value: v,
    };
    DiagnosticArray {
        header: header.clone(),
        status: vec![DiagnosticStatus {
            level,
            name: "ldcbf_nav: footstep planner".into(),
            message: format!("{} ({})", o.status.name(), o.info.source.name()),
            hardware_id: String::new(),
            values: vec![
                kv("cycle_time_us", format!("{:.1}", compute_ns as f64 * 1e-3)),
                kv("iterations", o.info.iterations.to_string()),
                kv("active_obstacles", o.info.active_obstacles.to_string()),
                kv("relax_gait", o.info.relax_gait.to_string()),
                kv("relax_safety", o.info.relax_safety.to_string()),
                kv("relax_capture", o.info.relax_capture.to_string()),
                kv("min_h0", o.info.min_h0.to_string()),
            ],
        }],
    }
}
