//! The closed loop of [`super::run`], one tick at a time (the order of the
//! steps is in the module docs of [`super`]): [`Loop::new`] sets it up (the
//! plant, the controller with its QP backend, the world, the global plan),
//! [`Loop::tick`] runs one plant tick (world time, push, step end, control,
//! record, end conditions, integration), and [`Loop::finish`] hands over what
//! it recorded. A control cycle is [`Loop::control`]: measure, advance the
//! subgoal, perceive ([`Loop::perceive`]), call the controller (timed,
//! [`timed_control`]) and log ([`Loop::log_cycle`]).

use std::time::Instant;

use ldcbf_controller::nalgebra::Vector2;
use ldcbf_controller::{
    CycleInput, CycleOutput, CycleStatus, NO_SPEED_CAP, QpBackend, RobotController,
};

use super::contacts::{self, ContactMonitor};
use super::mapping::{self, ReplanReason};
use super::people::People;
use super::{
    ActiveHalfPlane, CycleRecord, Footstep, HORIZON, MpcRate, NC, NV, Navigation, Outcome,
    PLANT_DT, Sample, ScanRecord, SimError, SimOptions, SimResult,
};
use crate::plan::{Planner, remaining_length};
use crate::plant::disturbance::Disturber;
use crate::plant::{Plant, PlantParams};
use crate::scenario::Scenario;
use crate::sense::Perception;
use crate::world::crowd::RobotBody;
use crate::world::moving::MovingMap;
use crate::world::obstacle_index::{Candidates, ObstacleIndex};
use crate::world::{MAX_VERTICES, Polygon};

/// The state of one closed loop between two ticks.
pub(super) struct Loop<'s, B: QpBackend<NV, NC>> {
    scenario: &'s Scenario,
    options: SimOptions,
    controller: RobotController<B>,
    disturber: Disturber,
    plant: Plant,
    /// Plant ticks between two control cycles (`None`: once per step).
    period: Option<u64>,
    /// The true map at the plant's time (moving obstacles,
    /// crate::world::moving), with the index of its obstacles at rest.
    world: MovingMap,
    /// The people who react (`None` without), stepped every tick.
    people: Option<People>,
    /// The index of the controller's candidates with a known static map (with
    /// LiDAR its few obstacles per scan are passed whole, and so is a map with
    /// moving obstacles).
    control_index: Option<ObstacleIndex>,
    candidates: Candidates,
    /// The LiDAR, its occupancy map and the planner on it (`perception =
    /// "lidar"`).
    mapper: Option<mapping::Mapper>,
    /// The global plan is made (and remade) on the LiDAR map.
    on_map: bool,
    contacts: ContactMonitor,
    /// A foot landed at this tick.
    landed_now: bool,
    navigation: Navigation,
    /// The subgoals being followed (the goal last) and the current one.
    subgoals: Vec<Vector2<f64>>,
    current: usize,
    /// The inferred obstacles of the current cycle (LiDAR) and, with people
    /// tracking, their velocities (the map's pieces at rest, then the people).
    seen: Vec<Polygon>,
    seen_velocities: Vec<Vector2<f64>>,
    /// The velocity uncertainty radius of each of `seen`, m/s (0 for the
    /// map's pieces; the tracker's for the people,
    /// [`crate::sense::movers::MoverScan::velocity_radii`]).
    seen_radii: Vec<f64>,
    /// With known velocities and `disturbance.velocity_error`: each
    /// obstacle's velocity error (m/s, zero at rest), the velocities handed
    /// to the controller (true plus error) and their radii (m/s).
    velocity_errors: Vec<Vector2<f64>>,
    estimates: Vec<Vector2<f64>>,
    estimate_radii: Vec<f64>,
    /// With LiDAR, the cycle's capture-step speed cap, m/s
    /// ([`super::capture`]; [`NO_SPEED_CAP`] when off).
    speed_cap: f64,
    progress: Progress,
    cycles: Vec<CycleRecord>,
    /// [`SimResult::obstacle_centres`].
    obstacle_centres: Vec<Vec<Vector2<f64>>>,
    footsteps: Vec<Footstep>,
    samples: Vec<Sample>,
    scans: Vec<ScanRecord>,
    qps: Vec<(usize, ldcbf_reference::DenseProblem)>,
}

/// The end conditions' clock: the best remaining path length so far and its
/// tick, and the limits in ticks.
struct Progress {
    best_distance: f64,
    best_tick: u64,
    stuck_ticks: u64,
    max_ticks: u64,
}

impl<'s, B: QpBackend<NV, NC> + Clone> Loop<'s, B> {
    /// The loop before its first tick: the controller with `backend`, the
    /// plant at the scenario's start, the world, the LiDAR and the global
    /// plan. Fails on an invalid controller configuration, plant, map or
    /// LiDAR.
    pub(super) fn new(
        scenario: &'s Scenario,
        options: SimOptions,
        backend: B,
    ) -> Result<Self, SimError> {
        let cfg = scenario.config;
        let controller =
            RobotController::with_backend(cfg, backend).map_err(SimError::Controller)?;
        let disturber = Disturber::new(
            &scenario.disturbance,
            scenario.seed,
            PLANT_DT,
            cfg.com_height,
        );
        let plant = Plant::new(
            PlantParams {
                gravity: cfg.gravity,
                com_height: disturber.plant_com_height(),
                step_duration: cfg.step_duration,
                dt: PLANT_DT,
            },
            scenario.start,
            scenario.start_heading,
            scenario.stance,
        )
        .map_err(SimError::Plant)?;
        let period = match options.mpc_rate {
            MpcRate::Hz(h) => Some(((1.0 / f64::from(h)) / PLANT_DT).round().max(1.0) as u64),
            MpcRate::PerStep => None,
        };
        let world = MovingMap::with_driven(
            &scenario.obstacles,
            &scenario.velocities,
            scenario.people_from(),
        )
        .map_err(SimError::Map)?;
        let people = People::new(&scenario.people, &world, scenario.people_from());
        let control_index = (scenario.perception == Perception::Known && world.is_static())
            .then(|| world.rest_index().clone());
        let on_map = crate::scenario::plans_on_map(scenario.planner, scenario.perception);
        let navigation = global_plan(scenario, &world, on_map);
        let mapper = match scenario.perception {
            Perception::Lidar => {
                Some(mapping::Mapper::new(scenario, on_map).map_err(SimError::Mapping)?)
            }
            Perception::Known => None,
        };
        let max_ticks = (scenario.time_limit / PLANT_DT).round() as u64;
        let footsteps = vec![Footstep {
            index: 0,
            position: plant.stance_foot,
            side: plant.stance_side,
            time: 0.0,
            heading: plant.heading,
            clearance: world.foot_clearance(&scenario.robot, plant.stance_foot, plant.heading),
        }];
        let velocity_errors = disturber.velocity_errors(scenario.seed, scenario.obstacles.len());
        Ok(Loop {
            scenario,
            options,
            controller,
            disturber,
            plant,
            period,
            world,
            people,
            control_index,
            candidates: Candidates::default(),
            mapper,
            on_map,
            contacts: ContactMonitor::default(),
            landed_now: true,
            subgoals: navigation.subgoals.clone(),
            navigation,
            current: 0,
            seen: Vec::new(),
            seen_velocities: Vec::new(),
            seen_radii: Vec::new(),
            velocity_errors,
            estimates: Vec::new(),
            estimate_radii: Vec::new(),
            speed_cap: NO_SPEED_CAP,
            progress: Progress {
                best_distance: f64::INFINITY,
                best_tick: 0,
                stuck_ticks: (scenario.stuck_window / PLANT_DT).round() as u64,
                max_ticks,
            },
            cycles: Vec::new(),
            obstacle_centres: Vec::new(),
            footsteps,
            samples: Vec::with_capacity(max_ticks.min(1 << 20) as usize + 1),
            scans: Vec::new(),
            qps: Vec::new(),
        })
    }

    /// One plant tick; `Some` with the outcome when the run ends at it (the
    /// plant is then not integrated).
    pub(super) fn tick(&mut self) -> Option<Outcome> {
        if !self.world.is_static() {
            self.world.set_time(self.plant.time());
        }
        if let Some(people) = self.people.as_mut() {
            let robot = RobotBody {
                position: self.plant.position,
                velocity: self.plant.velocity,
                radius: self.scenario.robot.body_radius,
            };
            people.advance(self.plant.time(), PLANT_DT, &robot, &mut self.world);
        }
        // 0. Push.
        if let Some(dv) = self.disturber.push_at(self.plant.tick, self.plant.heading) {
            self.plant.push(dv);
        }
        // 1. Step end.
        if self.plant.step_over() {
            self.land();
        }
        // 2. Control.
        let due = match self.period {
            Some(p) => self.plant.tick.is_multiple_of(p),
            None => self.plant.tick_in_step == 0,
        };
        if due {
            self.control();
        }
        let diverged = due
            && self
                .cycles
                .last()
                .is_some_and(|c| matches!(c.output.status, CycleStatus::InvalidInput(_)));
        // 3. Record and check the end conditions.
        self.record();
        if let Some(outcome) = self.end_condition(diverged) {
            return Some(outcome);
        }
        // 4. Integrate.
        self.plant.tick();
        None
    }

    /// Step end: the swing foot lands at the latest cycle's target (off it by
    /// the foot placement error) and that cycle's turning rate takes effect.
    fn land(&mut self) {
        let last = self
            .cycles
            .last_mut()
            .expect("a cycle runs at t = 0, before the first step ends");
        last.landed = true;
        let (target, omega) = (last.output.foot_target, last.output.turning_rate);
        let foot = self.disturber.land(target);
        let plant = &mut self.plant;
        plant.land(foot, omega);
        self.footsteps.push(Footstep {
            index: plant.steps,
            position: foot,
            side: plant.stance_side,
            time: plant.time(),
            heading: plant.heading,
            clearance: self
                .world
                .foot_clearance(&self.scenario.robot, foot, plant.heading),
        });
        self.landed_now = true;
    }

    /// One control cycle: the measured state, the subgoal, the obstacles,
    /// the controller call (timed) and its log.
    fn control(&mut self) {
        let (position, velocity, heading) =
            self.disturber
                .measure(self.plant.position, self.plant.velocity, self.plant.heading);
        let state = Measured {
            position,
            velocity,
            heading,
        };
        while self.current + 1 < self.subgoals.len()
            && (position - self.subgoals[self.current]).norm() <= self.scenario.rrt.switch_radius
        {
            self.navigation.reached_at.push(self.plant.time());
            self.current += 1;
        }
        if self.mapper.is_some() {
            self.perceive(&state);
        }
        // Known velocities (the oracle) are exact: no radii (every one 0).
        type Seen<'a> = (&'a [Polygon], &'a [Vector2<f64>], &'a [f64]);
        let (obstacles, velocities, radii): Seen<'_> = if self.mapper.is_some() {
            if self.scenario.lidar.track_moving {
                (&self.seen, &self.seen_velocities, &self.seen_radii)
            } else {
                (&self.seen, &[], &[])
            }
        } else if self.world.is_static() {
            // Every obstacle at rest: the static controller, bit for bit.
            (self.world.obstacles(), &[], &[])
        } else if self.scenario.disturbance.velocity_error > 0.0 {
            // Wrong estimates of the people's velocities, by the radius given.
            let truth = self.world.velocities();
            let u = self.scenario.disturbance.velocity_error;
            let moving = |v: &Vector2<f64>| *v != Vector2::zeros();
            self.estimates.clear();
            self.estimates.extend(
                truth.iter().zip(&self.velocity_errors).map(
                    |(v, e)| {
                        if moving(v) { v + e } else { *v }
                    },
                ),
            );
            self.estimate_radii.clear();
            self.estimate_radii
                .extend(truth.iter().map(|v| if moving(v) { u } else { 0.0 }));
            (
                self.world.obstacles(),
                &self.estimates,
                &self.estimate_radii,
            )
        } else {
            (self.world.obstacles(), self.world.velocities(), &[])
        };
        let speed_cap = if self.mapper.is_some() {
            self.speed_cap
        } else {
            NO_SPEED_CAP
        };
        let input = CycleInput {
            obstacles,
            obstacle_velocities: velocities,
            obstacle_velocity_radii: radii,
            speed_cap,
            ..state.input(&self.plant, self.subgoals[self.current])
        };
        let (output, compute_ns) = timed_control(
            &mut self.controller,
            &input,
            self.control_index.as_ref(),
            &mut self.candidates,
            self.options.timing_repeats,
        );
        let obstacles_seen = obstacles.len();
        self.log_cycle(output, compute_ns, obstacles_seen);
    }

    /// With LiDAR: a scan from the true pose updates the occupancy map, the
    /// subgoals are replanned on it when due, and this cycle's obstacles are
    /// the map's pieces around the controller's [`ObstacleQuery`] (then, with
    /// people tracking, the people kept out of the map, with their
    /// velocities and velocity uncertainty radii), in `seen`,
    /// `seen_velocities` and `seen_radii`.
    ///
    /// [`ObstacleQuery`]: ldcbf_controller::ObstacleQuery
    fn perceive(&mut self, state: &Measured) {
        let Some(m) = self.mapper.as_mut() else {
            return;
        };
        let plant = &self.plant;
        let points = m.sense(
            plant.position,
            plant.heading,
            plant.time(),
            self.world.obstacles(),
        );
        let progress = &mut self.progress;
        let stalled = 2 * (plant.tick - progress.best_tick) >= progress.stuck_ticks
            && progress.stuck_ticks > 0;
        if let Some((reason, new)) = m.plan(
            self.scenario,
            plant.time(),
            state.position,
            &self.subgoals[self.current..],
            stalled,
        ) {
            self.subgoals = new;
            self.current = 0;
            self.navigation.plan_time_ns += m.log.plans.last().map_or(0, |p| p.ns);
            // The progress measure follows the new path; a stall replan does
            // not restart the stuck clock.
            progress.best_distance = remaining_length(plant.position, &self.subgoals, 0);
            if reason != ReplanReason::Stalled {
                progress.best_tick = plant.tick;
            }
        }
        let input: CycleInput<'_, MAX_VERTICES> = state.input(plant, self.subgoals[self.current]);
        let q = self.controller.obstacle_query(&input);
        if self.scenario.lidar.map.capture_speed_limit {
            self.speed_cap = m.capture_cap(
                &self.scenario.config,
                &input,
                &self.subgoals[self.current..],
            );
        }
        self.seen = match q {
            Ok(q) => m.obstacles(&q),
            Err(_) => Vec::new(),
        };
        if self.scenario.lidar.track_moving {
            self.seen_velocities = vec![Vector2::zeros(); self.seen.len()];
            self.seen_radii = vec![0.0; self.seen.len()];
            if let Some(people) = m.people() {
                self.seen.extend_from_slice(&people.obstacles);
                self.seen_velocities.extend_from_slice(&people.velocities);
                self.seen_radii.extend_from_slice(&people.velocity_radii);
            }
        }
        if self.options.record_scans {
            self.scans.push(ScanRecord {
                cycle: self.cycles.len(),
                origin: plant.position,
                points,
                obstacles: self.seen.clone(),
                speed_cap: self.speed_cap,
            });
        }
    }

    /// Logs a cycle: its output and time, the LDCBF half-planes it used (and
    /// its QP with [`SimOptions::record_qps`]; none for an invalid input).
    fn log_cycle(&mut self, output: CycleOutput<HORIZON>, compute_ns: u64, obstacles_seen: usize) {
        let valid = output.status.name() != "invalid_input";
        if self.options.record_qps && valid {
            self.qps.push((
                self.cycles.len(),
                ldcbf_reference::DenseProblem::from_assembly(
                    self.controller.solver(),
                    self.controller.last_assembly(),
                ),
            ));
        }
        let half_planes = if valid {
            let asm = self.controller.last_assembly();
            asm.obstacles[..asm.n_obstacles]
                .iter()
                .map(|o| ActiveHalfPlane {
                    obstacle: o.index as usize,
                    half_plane: o.half_plane,
                })
                .collect()
        } else {
            Vec::new()
        };
        if !self.world.is_static() {
            self.obstacle_centres.push(
                self.world
                    .obstacles()
                    .iter()
                    .map(crate::world::moving::vertex_centre)
                    .collect(),
            );
        }
        let plant = &self.plant;
        self.cycles.push(CycleRecord {
            index: self.cycles.len(),
            time: plant.time(),
            time_in_step: plant.time_in_step(),
            step: plant.steps,
            stance_side: plant.stance_side,
            goal: self.subgoals[self.current],
            output,
            compute_ns,
            landed: false,
            half_planes,
            subgoal: self.current,
            obstacles_seen,
        });
    }

    /// Records the tick's 1 kHz sample (with its clearance to the true
    /// obstacles) and the contacts.
    fn record(&mut self) {
        let plant = &self.plant;
        let record_clearance = self.options.record_clearance;
        self.samples.push(Sample {
            time: plant.time(),
            position: plant.position,
            velocity: plant.velocity,
            heading: plant.heading,
            turning_rate: plant.turning_rate,
            stance_side: plant.stance_side,
            clearance: if record_clearance {
                self.world.clearance(&plant.position)
            } else {
                f64::NAN
            },
        });
        if record_clearance {
            let stance = self.footsteps.last().expect("the initial stance foot");
            self.contacts.observe(
                &self.world,
                &self.scenario.robot,
                plant.time(),
                plant.position,
                contacts::mean_velocity(&self.samples, plant.ticks_per_step() as usize),
                stance.position,
                stance.heading,
                self.landed_now,
            );
        }
        self.landed_now = false;
    }

    /// The end conditions, in order: goal reached, diverged (`diverged`: this
    /// tick's cycle rejected its input), stuck, time limit.
    fn end_condition(&mut self, diverged: bool) -> Option<Outcome> {
        let plant = &self.plant;
        let scenario = self.scenario;
        if (plant.position - scenario.goal).norm() <= scenario.success_radius {
            self.navigation.reached_at.push(plant.time());
            return Some(Outcome::GoalReached);
        }
        if diverged {
            return Some(Outcome::Diverged);
        }
        let p = &mut self.progress;
        let remaining = remaining_length(plant.position, &self.subgoals, self.current);
        if remaining < p.best_distance - 0.05 {
            p.best_distance = remaining;
            p.best_tick = plant.tick;
        }
        if p.stuck_ticks > 0 && plant.tick - p.best_tick >= p.stuck_ticks {
            return Some(Outcome::Stuck);
        }
        if plant.tick >= p.max_ticks {
            return Some(Outcome::TimeLimit);
        }
        None
    }

    /// What the run recorded, ended by `outcome`.
    pub(super) fn finish(self, outcome: Outcome) -> SimResult {
        let mut navigation = self.navigation;
        if self.on_map {
            navigation.subgoals = self.subgoals;
        }
        SimResult {
            scenario: self.scenario.clone(),
            options: self.options,
            outcome,
            cycles: self.cycles,
            footsteps: self.footsteps,
            samples: self.samples,
            navigation,
            scans: self.scans,
            qps: self.qps,
            disturbance: self.disturber.log,
            contacts: self.contacts.contacts,
            mapping: self.mapper.map(|m| m.log),
            obstacle_centres: self.obstacle_centres,
        }
    }
}

/// A cycle's measured CoM position (m), velocity (m/s) and heading (rad),
/// world frame W: the plant's true ones plus the estimation noise.
struct Measured {
    position: Vector2<f64>,
    velocity: Vector2<f64>,
    heading: f64,
}

impl Measured {
    /// The cycle's input toward `goal` without obstacles: the measured state
    /// and the plant's turning rate, stance foot and side and time in step.
    fn input<const V: usize>(&self, plant: &Plant, goal: Vector2<f64>) -> CycleInput<'static, V> {
        CycleInput {
            com_position: self.position,
            com_velocity: self.velocity,
            heading: self.heading,
            turning_rate: plant.turning_rate,
            stance_foot: plant.stance_foot,
            stance_side: plant.stance_side,
            time_in_step: plant.time_in_step(),
            goal,
            obstacles: &[],
            obstacle_velocities: &[],
            obstacle_velocity_radii: &[],
            speed_cap: NO_SPEED_CAP,
        }
    }
}

/// The global plan made before the first tick: with `planner = "rrt_star"`
/// and the known map (not `on_map`), the RRT* subgoals (the goal last);
/// otherwise, or when planning fails (the error kept), the goal alone.
fn global_plan(scenario: &Scenario, world: &MovingMap, on_map: bool) -> Navigation {
    let mut navigation = Navigation::default();
    if scenario.planner == Planner::RrtStar && !on_map {
        let t0 = Instant::now();
        let res = crate::plan::plan(
            (scenario.start, scenario.goal),
            world.rest_obstacles(),
            &scenario.rrt,
            scenario.robot.body_radius,
            scenario.seed,
            &|| super::cancel::check().is_err(),
        );
        navigation.plan_time_ns = u64::try_from(t0.elapsed().as_nanos()).unwrap_or(u64::MAX);
        match res {
            Ok(p) => {
                navigation.subgoals = p.subgoals.clone();
                navigation.plan = Some(p);
            }
            Err(e) => navigation.error = Some(e.to_string()),
        }
    }
    if navigation.subgoals.is_empty() {
        navigation.subgoals.push(scenario.goal);
    }
    navigation
}

/// [`control`] and its wall-clock time, ns: with `repeats > 1`, the minimum
/// over that call and `repeats - 1` calls on clones made just before it
/// ([`time_on_clones`]); the output is the controller's own call's.
fn timed_control<const V: usize, B: QpBackend<NV, NC> + Clone>(
    controller: &mut RobotController<B>,
    input: &CycleInput<'_, V>,
    index: Option<&ObstacleIndex>,
    candidates: &mut Candidates,
    repeats: u32,
) -> (CycleOutput<HORIZON>, u64) {
    let on_clones = time_on_clones(controller, input, index, candidates, repeats);
    let t0 = Instant::now();
    let output = control(controller, input, index, candidates);
    let ns = u64::try_from(t0.elapsed().as_nanos())
        .unwrap_or(u64::MAX)
        .min(on_clones);
    (output, ns)
}

/// One controller call: `step` on the whole obstacle list, or, with an
/// index of that list, on the candidates around `obstacle_query`
/// (`candidates`: the index queried again only when the last list does not
/// cover this cycle; bit for bit the same output, see
/// [`crate::world::obstacle_index`]).
fn control<const V: usize, B: QpBackend<NV, NC>>(
    controller: &mut RobotController<B>,
    input: &CycleInput<'_, V>,
    index: Option<&ObstacleIndex>,
    candidates: &mut Candidates,
) -> CycleOutput<HORIZON> {
    let Some(index) = index else {
        return controller.step(input, None);
    };
    match controller.obstacle_query(input) {
        Ok(q) => controller.step(input, Some(candidates.update(index, &q))),
        // The controller rejects the input before reading any obstacle.
        Err(_) => controller.step(input, Some(&[])),
    }
}

/// Times [`control`] `repeats - 1` times on clones (of the controller with
/// its QP backend, and of the candidates, so the originals are untouched), ns
/// each; the minimum, or `u64::MAX` when `repeats <= 1`.
fn time_on_clones<const V: usize, B: QpBackend<NV, NC> + Clone>(
    controller: &RobotController<B>,
    input: &CycleInput<'_, V>,
    index: Option<&ObstacleIndex>,
    candidates: &Candidates,
    repeats: u32,
) -> u64 {
    let mut best = u64::MAX;
    for _ in 1..repeats {
        let mut c = controller.clone();
        let mut candidates = candidates.clone();
        let t0 = Instant::now();
        let out = control(&mut c, input, index, &mut candidates);
        let ns = u64::try_from(t0.elapsed().as_nanos()).unwrap_or(u64::MAX);
        // Keep the computation (the clone and its output are dropped unused).
        std::hint::black_box((&out, &c));
        best = best.min(ns);
    }
    best
}
