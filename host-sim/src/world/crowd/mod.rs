//! People who react: each walks from a start to a goal at a preferred speed
//! and avoids the other people and the walls, by ORCA ([`orca`], the crate
//! `dodgy_2d`, a port of RVO2) or by the social force model
//! ([`social_force`], Helbing & Molnar 1995), or walks straight through
//! everything at a constant velocity (`constant_velocity`, the people of
//! [`crate::world::moving`] given a goal). A person either sees the robot
//! (a visible robot: an ORCA agent, a repulsive body, with its current
//! velocity) or does not (an invisible robot, as in the crowd-navigation
//! benchmark). World frame W, metres, seconds.
//!
//! **Stepping.** [`Crowd::step`] is called once per plant tick (1 kHz)
//! inside the closed loop: every [`DECISION_PERIOD`] (the controller's 20 Hz)
//! each person chooses a new velocity from the state at that instant (all
//! people at once, as in CrowdNav and RVO2's `doStep`), and every tick moves
//! each person by its velocity times the tick.
//!
//! **Preferred velocity** (the velocity a person wants before avoiding
//! anyone): toward its goal at its speed, `(goal - p)` clipped to `speed`
//! (as CrowdNav's humans: they slow down within `speed x 1 s` of the goal
//! and stop on it); zero during a stop (`stops`: intervals `[t0, t1)` of
//! simulated time in which the person stands; an ORCA or social-force
//! person still steps aside for others while standing). People of one
//! `group` walk together: each member's preferred speed is scaled by
//! `1 + clamp(mean progress - own progress, -0.5, 0.5)` (progress: the
//! distance covered along its own start-goal line, m), so members given
//! side-by-side starts and goals stay abreast and wait for one another.
//!
//! A person is a regular [`PERSON_SIDES`]-gon of its radius (the vertices on
//! the circle: the polygon lies at most `r (1 - cos(pi / 12))`, 1 cm at
//! `r = 0.3`, inside the disk the policies avoid with).

use ldcbf_controller::nalgebra::Vector2;
use serde::{Deserialize, Serialize};

use crate::world::Polygon;
use crate::world::random::regular_polygon;
use crate::world::setting::SettingError;

pub mod families;
pub mod orca;
pub mod social_force;

/// Sides of a person's polygon.
pub const PERSON_SIDES: u32 = 12;

/// Time between two velocity choices of the people, s (the controller's
/// 20 Hz cycle); positions are integrated every plant tick.
pub const DECISION_PERIOD: f64 = 0.05;

/// Largest accepted preferred speed, m/s (as [`crate::world::moving::MAX_SPEED`]).
pub const MAX_PERSON_SPEED: f64 = crate::world::moving::MAX_SPEED;

/// Largest number of people in one scenario.
pub const MAX_PEOPLE: usize = 200;

/// How a person chooses its velocity.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Policy {
    /// ORCA (Optimal Reciprocal Collision Avoidance, van den Berg et al.
    /// 2011) through `dodgy_2d`, with CrowdNav's settings ([`orca`]).
    #[default]
    Orca,
    /// The social force model of Helbing & Molnar (1995) ([`social_force`]).
    SocialForce,
    /// Toward the goal at the preferred velocity, through everything.
    ConstantVelocity,
}

impl Policy {
    /// The name used in scenario files.
    pub fn name(self) -> &'static str {
        match self {
            Policy::Orca => "orca",
            Policy::SocialForce => "social_force",
            Policy::ConstantVelocity => "constant_velocity",
        }
    }
}

/// One person who walks to a goal (a `[[people]]` entry of a scenario).
#[derive(Clone, Debug, PartialEq)]
pub struct Person {
    /// Start (centre of the body), m, world frame.
    pub start: Vector2<f64>,
    /// Goal, m, world frame.
    pub goal: Vector2<f64>,
    /// Preferred speed, m/s.
    pub speed: f64,
    /// Body radius, m.
    pub radius: f64,
    /// How the person chooses its velocity.
    pub policy: Policy,
    /// The person sees the robot (avoids it as a body with its current
    /// velocity); `false`: the robot is invisible to the person.
    pub sees_robot: bool,
    /// People with the same group number walk together (see the module docs).
    pub group: Option<u32>,
    /// Intervals `[t0, t1)` of simulated time (s) in which the person stands.
    pub stops: Vec<[f64; 2]>,
}

impl Person {
    /// A person with CrowdNav's body (radius 0.3 m) who sees the robot and
    /// never stops, walking by ORCA.
    pub fn new(start: Vector2<f64>, goal: Vector2<f64>, speed: f64) -> Self {
        Person {
            start,
            goal,
            speed,
            radius: 0.3,
            policy: Policy::Orca,
            sees_robot: true,
            group: None,
            stops: Vec::new(),
        }
    }

    /// Checks the fields; the error names the bad one.
    pub fn validate(&self) -> Result<(), SettingError> {
        let fin = |v: &Vector2<f64>| v.x.is_finite() && v.y.is_finite();
        if !fin(&self.start) {
            return Err(SettingError::new("start", "must be finite [x, y], m"));
        }
        if !fin(&self.goal) {
            return Err(SettingError::new("goal", "must be finite [x, y], m"));
        }
        if !(self.speed.is_finite() && self.speed > 0.0 && self.speed <= MAX_PERSON_SPEED) {
            return Err(SettingError::new(
                "speed",
                format!("must be in (0, {MAX_PERSON_SPEED}] m/s"),
            ));
        }
        if !(self.radius.is_finite() && (0.05..=1.0).contains(&self.radius)) {
            return Err(SettingError::new("radius", "must be in [0.05, 1] m"));
        }
        for s in &self.stops {
            if !(s[0].is_finite() && s[1].is_finite() && s[0] >= 0.0 && s[1] > s[0]) {
                return Err(SettingError::new(
                    "stops",
                    "each stop must be [t0, t1] with 0 <= t0 < t1, s",
                ));
            }
        }
        Ok(())
    }

    /// The person's polygon centred at `c` (m).
    pub fn polygon_at(&self, c: Vector2<f64>) -> Polygon {
        Polygon::new(&regular_polygon([c.x, c.y], self.radius, PERSON_SIDES, 0.0))
            .expect("a regular polygon is convex")
    }

    /// The velocity toward the goal at the preferred speed, m/s (zero when
    /// the start is the goal): what a constant-velocity obstacle standing in
    /// for the person would have.
    pub fn initial_velocity(&self) -> Vector2<f64> {
        self.direction() * self.speed
    }

    /// Whether the person stands at time `t` (s).
    pub fn stopped_at(&self, t: f64) -> bool {
        self.stops.iter().any(|s| s[0] <= t && t < s[1])
    }

    /// The unit vector from the start to the goal (zero when they coincide).
    fn direction(&self) -> Vector2<f64> {
        let d = self.goal - self.start;
        let n = d.norm();
        if n > 1e-9 { d / n } else { Vector2::zeros() }
    }
}

/// The robot as the people see it: a disk with its current velocity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RobotBody {
    /// Centre (the CoM), m.
    pub position: Vector2<f64>,
    /// Velocity, m/s.
    pub velocity: Vector2<f64>,
    /// Radius, m.
    pub radius: f64,
}

/// What a policy sees of one other body: centre, velocity, radius.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Body {
    /// Centre, m.
    pub position: Vector2<f64>,
    /// Velocity, m/s.
    pub velocity: Vector2<f64>,
    /// Radius, m.
    pub radius: f64,
}

/// The people of a scenario and their state.
#[derive(Clone, Debug)]
pub struct Crowd {
    people: Vec<Person>,
    /// The walls (the map's obstacles at rest), world frame.
    walls: Vec<Polygon>,
    orca_walls: Vec<dodgy_2d::Obstacle>,
    positions: Vec<Vector2<f64>>,
    velocities: Vec<Vector2<f64>>,
    time: f64,
    /// Time of the next velocity choice, s.
    next_decision: f64,
}

impl Crowd {
    /// The people at their starts, at rest, at `t = 0`, among `walls` (the
    /// obstacles at rest, m).
    pub fn new(people: Vec<Person>, walls: &[Polygon]) -> Self {
        Crowd {
            positions: people.iter().map(|p| p.start).collect(),
            velocities: vec![Vector2::zeros(); people.len()],
            people,
            walls: walls.to_vec(),
            orca_walls: walls.iter().map(orca::obstacle).collect(),
            time: 0.0,
            next_decision: 0.0,
        }
    }

    /// The people.
    pub fn people(&self) -> &[Person] {
        &self.people
    }

    /// Their current centres, m.
    pub fn positions(&self) -> &[Vector2<f64>] {
        &self.positions
    }

    /// Their current velocities, m/s.
    pub fn velocities(&self) -> &[Vector2<f64>] {
        &self.velocities
    }

    /// The crowd's clock, s.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Advances the crowd by `dt` (s): the people choose new velocities
    /// when a decision is due (seeing `robot` if they see the robot), then
    /// move.
    pub fn step(&mut self, dt: f64, robot: Option<&RobotBody>) {
        if self.time + 1e-9 >= self.next_decision {
            self.decide(robot);
            self.next_decision += DECISION_PERIOD;
        }
        for (p, v) in self.positions.iter_mut().zip(&self.velocities) {
            *p += v * dt;
        }
        self.time += dt;
    }

    /// Every person's new velocity, from the state now.
    fn decide(&mut self, robot: Option<&RobotBody>) {
        let preferred: Vec<Vector2<f64>> =
            (0..self.people.len()).map(|i| self.preferred(i)).collect();
        let new: Vec<Vector2<f64>> = (0..self.people.len())
            .map(|i| {
                let p = &self.people[i];
                let others = self.others(i, robot);
                match p.policy {
                    Policy::ConstantVelocity => preferred[i],
                    Policy::Orca => orca::velocity(
                        &Body {
                            position: self.positions[i],
                            velocity: self.velocities[i],
                            radius: p.radius,
                        },
                        orca::perturbed(preferred[i]),
                        p.speed,
                        &others,
                        &self.orca_walls,
                        DECISION_PERIOD,
                    ),
                    Policy::SocialForce => social_force::velocity(
                        &Body {
                            position: self.positions[i],
                            velocity: self.velocities[i],
                            radius: p.radius,
                        },
                        preferred[i],
                        p.speed,
                        &others,
                        &self.walls,
                        DECISION_PERIOD,
                    ),
                }
            })
            .collect();
        self.velocities = new;
    }

    /// What person `i` avoids: the other people, and the robot when `i`
    /// sees it.
    fn others(&self, i: usize, robot: Option<&RobotBody>) -> Vec<Body> {
        let mut out: Vec<Body> = (0..self.people.len())
            .filter(|&j| j != i)
            .map(|j| Body {
                position: self.positions[j],
                velocity: self.velocities[j],
                radius: self.people[j].radius,
            })
            .collect();
        if let Some(r) = robot.filter(|_| self.people[i].sees_robot) {
            out.push(Body {
                position: r.position,
                velocity: r.velocity,
                radius: r.radius,
            });
        }
        out
    }

    /// Person `i`'s preferred velocity now (see the module docs), m/s.
    fn preferred(&self, i: usize) -> Vector2<f64> {
        let p = &self.people[i];
        if p.stopped_at(self.time) {
            return Vector2::zeros();
        }
        let speed = p.speed * self.group_pace(i);
        let to_goal = p.goal - self.positions[i];
        let n = to_goal.norm();
        if n > speed {
            to_goal * (speed / n)
        } else {
            to_goal
        }
    }

    /// The speed factor that keeps person `i` level with its group (1
    /// without a group).
    fn group_pace(&self, i: usize) -> f64 {
        let Some(g) = self.people[i].group else {
            return 1.0;
        };
        let progress =
            |j: usize| (self.positions[j] - self.people[j].start).dot(&self.people[j].direction());
        let members: Vec<usize> = (0..self.people.len())
            .filter(|&j| self.people[j].group == Some(g))
            .collect();
        let mean = members.iter().map(|&j| progress(j)).sum::<f64>() / members.len() as f64;
        1.0 + (mean - progress(i)).clamp(-0.5, 0.5)
    }
}

/// `v` clipped to length `max`.
pub(crate) fn clip(v: Vector2<f64>, max: f64) -> Vector2<f64> {
    let n = v.norm();
    if n > max && n > 0.0 { v * (max / n) } else { v }
}

#[cfg(test)]
mod tests;
