//! Seeded families with people who react ([`super::Person`]; the
//! `[generator]` kinds below), drawn with the generator, the redraws and the
//! validity check of [`crate::world::families`] (the people count as moving
//! obstacles at their starts: the start and the goal at least `r + 0.05` m
//! from them, the passage checked on the walls alone).
//!
//! Speeds are scaled to the robot's walking speed
//! [`NOMINAL_SPEED`] (0.6 m/s), and
//! crossings are timed against it as in [`crate::world::people`]. Unless the
//! table says otherwise the people walk by ORCA and see the robot, radius
//! 0.25-0.3 m.
//!
//! | family | what is drawn |
//! |---|---|
//! | `circle_crossing` | CrowdNav's circle crossing (Chen et al. 2019, `crowd_sim.py`): 5 humans of radius 0.3 m on the circle of radius 4 m, each at a uniform angle plus uniform noise of +-0.5 m per axis, going to the opposite point, redrawn while within `0.3 + r_other + 0.2` m of another agent's start or goal; the robot from (0, -4) to (0, 4); humans at `NOMINAL_SPEED`, robot invisible |
//! | `square_crossing` | CrowdNav's square crossing: 5 humans, start uniform in one half of the 10 m square (x of a random sign), goal uniform in the other half, redrawn as above; the robot as in `circle_crossing` |
//! | `orca_crowd_low`, `orca_crowd`, `orca_crowd_dense` | goal 10 m ahead; 2, 5 or 10 people (0.05, 0.125, 0.25 people per m^2: `orca_crowd_dense` is 5 people per 20 m^2) with starts and goals uniform in the 8 m x 5 m box between the start and the goal, 0.3-0.7 m/s, starts at least 0.8 m apart and 1 m from the robot's start and goal |
//! | `overtaking` | goal 10 m ahead; one person on the robot's line (+-0.3 m) walking its way: from 1.5-3 m behind the start at 0.8-1.0 m/s (overtakes the robot) or from 1.5-3 m ahead at 0.2-0.4 m/s (is overtaken), to 3 m past the goal |
//! | `door_emerge` | goal 10 m ahead; a wall along the path 1.0-1.4 m to its left (x from 1 to 9 m, 0.2 m thick) with a door 0.9-1.2 m wide at x = 3-7 m; one person 2.5 m behind the wall walks through the door and across the path to 3 m on the other side, timed to reach the path at the robot's nominal arrival -1.5 to 1.5 s |
//! | `corner_emerge` | goal 10 m ahead; a block beside the path (x from 2 m to a corner at 4-7 m, 0.9-1.3 m to the left, 3 m deep); one person starts 0.4-0.8 m past the corner, 3 m to the left, and walks across the path, hidden by the block until it steps out, timed as `door_emerge` |
//! | `stop_and_go` | as `crossing` of [`crate::world::people`] (2-3 people crossing at right angles, 0.3-0.6 m/s), each standing for 1-3 s from 0-2 s before it would reach the robot's line |
//! | `group_reacting` | goal 10 m ahead; a group of 2-3 people side by side (0.55-0.7 m between centres, radius 0.25 m) crossing the path at right angles at 0.4-0.6 m/s, timed as `crossing` |

use ldcbf_controller::nalgebra::Vector2;

use super::Person;
use crate::world::families::{Draw, Layout, is_valid, rect};
use crate::world::people::NOMINAL_SPEED;

/// The family names.
pub const FAMILIES: &[&str] = &[
    "circle_crossing",
    "square_crossing",
    "orca_crowd_low",
    "orca_crowd",
    "orca_crowd_dense",
    "overtaking",
    "door_emerge",
    "corner_emerge",
    "stop_and_go",
    "group_reacting",
];

/// CrowdNav's circle radius, m.
pub const CIRCLE_RADIUS: f64 = 4.0;
/// CrowdNav's square width, m.
pub const SQUARE_WIDTH: f64 = 10.0;
/// CrowdNav's human radius, m.
pub const HUMAN_RADIUS: f64 = 0.3;
/// CrowdNav's discomfort distance, m.
pub const DISCOMFORT_DIST: f64 = 0.2;

/// A layout with people who react: the walls (and any constant-velocity
/// obstacles) in `layout`, the people apart.
#[derive(Clone, Debug)]
pub struct CrowdLayout {
    /// Start, heading, goal and the obstacles that are not people.
    pub layout: Layout,
    /// The people who react.
    pub people: Vec<Person>,
}

/// The two CrowdNav layouts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CrowdNavLayout {
    /// Humans on a circle cross to the opposite point.
    Circle,
    /// Humans cross a square from one half to the other.
    Square,
}

/// The layout of family `kind` for `seed` and a body of radius
/// `body_radius` (m); `None` when `kind` is not one of [`FAMILIES`].
pub fn generate(kind: &str, seed: u64, body_radius: f64) -> Option<Result<CrowdLayout, String>> {
    if !FAMILIES.contains(&kind) {
        return None;
    }
    let mut d = Draw::seeded(seed);
    for _ in 0..crate::world::families::MAX_DRAWS {
        let c = match kind {
            "circle_crossing" => crowdnav(&mut d, CrowdNavLayout::Circle, 5, body_radius),
            "square_crossing" => crowdnav(&mut d, CrowdNavLayout::Square, 5, body_radius),
            "orca_crowd_low" => orca_crowd(&mut d, 2),
            "orca_crowd" => orca_crowd(&mut d, 5),
            "orca_crowd_dense" => orca_crowd(&mut d, 10),
            "overtaking" => overtaking(&mut d),
            "door_emerge" => door_emerge(&mut d),
            "corner_emerge" => corner_emerge(&mut d),
            "stop_and_go" => stop_and_go(&mut d),
            _ => group_reacting(&mut d),
        };
        if valid(&c, body_radius) {
            return Some(Ok(c));
        }
    }
    Some(Err(format!(
        "no valid {kind} layout for a body of radius {body_radius} m in {} draws",
        crate::world::families::MAX_DRAWS
    )))
}

/// One CrowdNav case: `humans` ORCA humans of `layout`, drawn for `seed`,
/// who do not see the robot (the caller sets `sees_robot` for a visible
/// robot).
pub fn crowdnav_case(
    layout: CrowdNavLayout,
    humans: usize,
    seed: u64,
    body_radius: f64,
) -> CrowdLayout {
    let mut d = Draw::seeded(seed);
    crowdnav(&mut d, layout, humans, body_radius)
}

/// Whether `c` is valid for a body of radius `r` (module docs).
pub fn valid(c: &CrowdLayout, r: f64) -> bool {
    let mut check = c.layout.clone();
    let mut velocities: Vec<Vector2<f64>> = c
        .people
        .iter()
        // Any non-zero velocity: the people are not walls.
        .map(|_| Vector2::new(1.0, 0.0))
        .collect();
    velocities.extend(check.velocities_padded());
    let mut obstacles: Vec<_> = c.people.iter().map(|p| p.polygon_at(p.start)).collect();
    obstacles.extend(check.obstacles);
    check.obstacles = obstacles;
    check.velocities = velocities;
    is_valid(&check, r)
}

fn open(start: Vector2<f64>, heading: f64, goal: Vector2<f64>) -> Layout {
    Layout {
        start,
        heading,
        goal,
        obstacles: Vec::new(),
        velocities: Vec::new(),
    }
}

/// CrowdNav's humans for `layout` (module docs).
fn crowdnav(d: &mut Draw, layout: CrowdNavLayout, n: usize, body_radius: f64) -> CrowdLayout {
    let start = Vector2::new(0.0, -CIRCLE_RADIUS);
    let goal = Vector2::new(0.0, CIRCLE_RADIUS);
    // (position, goal, radius) of every agent placed so far, the robot first.
    let mut agents = vec![(start, goal, body_radius)];
    let mut people = Vec::with_capacity(n);
    let near = |agents: &[(Vector2<f64>, Vector2<f64>, f64)], p: Vector2<f64>, goals: bool| {
        agents.iter().any(|(s, g, r)| {
            let min = HUMAN_RADIUS + r + DISCOMFORT_DIST;
            (p - s).norm() < min || (goals && (p - g).norm() < min)
        })
    };
    for _ in 0..n {
        let (p, g) = match layout {
            CrowdNavLayout::Circle => loop {
                let a = d.unif(0.0, core::f64::consts::TAU);
                // CrowdNav's noise, (U - 0.5) v_pref with v_pref = 1 m/s: the
                // geometry is CrowdNav's, only speeds and times are scaled.
                let noise = Vector2::new(d.unif(-0.5, 0.5), d.unif(-0.5, 0.5));
                let p = Vector2::new(a.cos(), a.sin()) * CIRCLE_RADIUS + noise;
                if !near(&agents, p, true) {
                    break (p, -p);
                }
            },
            CrowdNavLayout::Square => {
                let sign = if d.coin() { -1.0 } else { 1.0 };
                let half = 0.5 * SQUARE_WIDTH;
                let p = loop {
                    let p = Vector2::new(d.unif(0.0, half) * sign, d.unif(-half, half));
                    if !near(&agents, p, false) {
                        break p;
                    }
                };
                let g = loop {
                    let g = Vector2::new(d.unif(0.0, half) * -sign, d.unif(-half, half));
                    let clash = agents
                        .iter()
                        .any(|(_, og, r)| (g - og).norm() < HUMAN_RADIUS + r + DISCOMFORT_DIST);
                    if !clash {
                        break g;
                    }
                };
                (p, g)
            }
        };
        agents.push((p, g, HUMAN_RADIUS));
        people.push(Person {
            sees_robot: false,
            ..Person::new(p, g, NOMINAL_SPEED)
        });
    }
    CrowdLayout {
        layout: open(start, core::f64::consts::FRAC_PI_2, goal),
        people,
    }
}

fn orca_crowd(d: &mut Draw, n: usize) -> CrowdLayout {
    let (start, goal) = (Vector2::zeros(), Vector2::new(10.0, 0.0));
    let mut people: Vec<Person> = Vec::with_capacity(n);
    let mut tries = 0;
    while people.len() < n && tries < 10_000 {
        tries += 1;
        let p = Vector2::new(d.unif(1.0, 9.0), d.unif(-2.5, 2.5));
        let g = Vector2::new(d.unif(1.0, 9.0), d.unif(-2.5, 2.5));
        let speed = d.unif(0.3, 0.7);
        let r = d.unif(0.25, 0.3);
        let apart = people.iter().all(|q| (q.start - p).norm() >= 0.8);
        if apart && (p - start).norm() >= 1.0 && (p - goal).norm() >= 1.0 && (g - p).norm() > 1.0 {
            people.push(Person {
                radius: r,
                ..Person::new(p, g, speed)
            });
        }
    }
    CrowdLayout {
        layout: open(start, 0.0, goal),
        people,
    }
}

fn overtaking(d: &mut Draw) -> CrowdLayout {
    let goal = Vector2::new(10.0, 0.0);
    let y = d.unif(-0.3, 0.3);
    let (x, speed) = if d.coin() {
        (-d.unif(1.5, 3.0), d.unif(0.8, 1.0))
    } else {
        (d.unif(1.5, 3.0), d.unif(0.2, 0.4))
    };
    let p = Person {
        radius: d.unif(0.25, 0.3),
        ..Person::new(Vector2::new(x, y), Vector2::new(goal.x + 3.0, y), speed)
    };
    CrowdLayout {
        layout: open(Vector2::zeros(), 0.0, goal),
        people: vec![p],
    }
}

/// A person who crosses the robot's line `y = 0` at `x` going toward `-y`
/// from `from_y`, at `speed`, arriving at the robot's nominal arrival time
/// plus `dt`: its start (held back along its path so that it arrives then).
fn timed_start(x: f64, from_y: f64, speed: f64, dt: f64) -> (Vector2<f64>, Vec<[f64; 2]>) {
    let t_cross = (x / NOMINAL_SPEED + dt).max(0.0);
    let walk = from_y / speed;
    // If the walk takes longer than the wait, start walking at once from
    // farther away is not possible behind a wall: wait at the start instead.
    let wait = (t_cross - walk).max(0.0);
    let stops = if wait > 0.0 {
        vec![[0.0, wait]]
    } else {
        Vec::new()
    };
    (Vector2::new(x, from_y), stops)
}

fn door_emerge(d: &mut Draw) -> CrowdLayout {
    let goal = Vector2::new(10.0, 0.0);
    let wall_y = d.unif(1.0, 1.4);
    let door_w = d.unif(0.9, 1.2);
    let door_x = d.unif(3.0, 7.0);
    let t = 0.2;
    let obstacles = vec![
        rect(1.0, wall_y, door_x - 0.5 * door_w, wall_y + t),
        rect(door_x + 0.5 * door_w, wall_y, 9.0, wall_y + t),
    ];
    let speed = d.unif(0.3, 0.6);
    let from_y = wall_y + 2.5;
    let (start, stops) = timed_start(door_x, from_y, speed, d.unif(-1.5, 1.5));
    let p = Person {
        radius: d.unif(0.25, 0.3),
        stops,
        ..Person::new(start, Vector2::new(door_x, -3.0), speed)
    };
    CrowdLayout {
        layout: Layout {
            obstacles,
            ..open(Vector2::zeros(), 0.0, goal)
        },
        people: vec![p],
    }
}

fn corner_emerge(d: &mut Draw) -> CrowdLayout {
    let goal = Vector2::new(10.0, 0.0);
    let corner = d.unif(4.0, 7.0);
    let near_y = d.unif(0.9, 1.3);
    let obstacles = vec![rect(2.0, near_y, corner, near_y + 3.0)];
    let speed = d.unif(0.3, 0.6);
    let x = corner + d.unif(0.4, 0.8);
    let (start, stops) = timed_start(x, 3.0, speed, d.unif(-1.5, 1.5));
    let p = Person {
        radius: d.unif(0.25, 0.3),
        stops,
        ..Person::new(start, Vector2::new(x, -3.0), speed)
    };
    CrowdLayout {
        layout: Layout {
            obstacles,
            ..open(Vector2::zeros(), 0.0, goal)
        },
        people: vec![p],
    }
}

fn stop_and_go(d: &mut Draw) -> CrowdLayout {
    let goal = Vector2::new(d.unif(8.0, 12.0), 0.0);
    let n = d.int(2, 3);
    let mut people = Vec::with_capacity(n);
    for _ in 0..n {
        let x = d.unif(2.0, goal.x - 2.0);
        let speed = d.unif(0.3, 0.6);
        let dir = if d.coin() { 1.0 } else { -1.0 };
        let t_cross = (x / NOMINAL_SPEED + d.unif(-2.0, 2.0)).max(0.0);
        let start = Vector2::new(x, -dir * speed * t_cross);
        let t0 = (t_cross - d.unif(0.0, 2.0)).max(0.0);
        let stop = [t0, t0 + d.unif(1.0, 3.0)];
        people.push(Person {
            radius: d.unif(0.25, 0.3),
            stops: vec![stop],
            ..Person::new(start, Vector2::new(x, dir * 4.0), speed)
        });
    }
    CrowdLayout {
        layout: open(Vector2::zeros(), 0.0, goal),
        people,
    }
}

fn group_reacting(d: &mut Draw) -> CrowdLayout {
    let goal = Vector2::new(10.0, 0.0);
    let n = d.int(2, 3);
    let gap = d.unif(0.55, 0.7);
    let speed = d.unif(0.4, 0.6);
    let x = d.unif(3.0, 7.0);
    let dir = if d.coin() { 1.0 } else { -1.0 };
    let t_cross = (x / NOMINAL_SPEED + d.unif(-2.0, 2.0)).max(0.0);
    let y0 = -dir * (speed * t_cross).max(1.5);
    let people = (0..n)
        .map(|k| {
            let dx = (k as f64 - 0.5 * (n as f64 - 1.0)) * gap;
            Person {
                radius: 0.25,
                group: Some(0),
                ..Person::new(
                    Vector2::new(x + dx, y0),
                    Vector2::new(x + dx, dir * 4.0),
                    speed,
                )
            }
        })
        .collect();
    CrowdLayout {
        layout: open(Vector2::zeros(), 0.0, goal),
        people,
    }
}
