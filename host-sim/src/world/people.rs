//! Seeded families with people who walk (the `[generator]` kinds `crossing`,
//! `headon`, `crowd`, `room_crossing`; drawn by
//! [`crate::world::families::generate`] with the same generator, the same
//! redraws and the same validity check as the static families).
//!
//! A person is a regular octagon of radius 0.2-0.25 m (a body seen from above)
//! walking at a constant velocity ([`crate::world::moving`]): people do not
//! stop, turn, or avoid anything; they pass through walls, each other and the
//! robot. Layouts are valid at t = 0 ([`crate::world::families::is_valid`]: the
//! start and the goal at least `r + 0.05` m from every obstacle, people
//! included, and the goal reachable on the map at t = 0). The people come
//! first in the obstacle list, with their velocities; walls follow, at rest.
//! World frame W, metres, seconds.
//!
//! Crossings are timed against [`NOMINAL_SPEED`]: a person crosses the
//! robot's straight line at `x` around the time a robot walking at that speed
//! from the start would get there, give or take the drawn offset, so most
//! seeds put the person in the robot's way.
//!
//! | family | what is drawn |
//! |---|---|
//! | `crossing` | goal 8-12 m ahead on the start's line; 2-4 people at 0.3-0.6 m/s crossing that line at right angles (from either side) at 2 m to 2 m before the goal, at the robot's nominal arrival time plus -2 to 2 s |
//! | `headon` | goal 8-12 m ahead; one person starting 1-3 m behind the goal, 0-0.15 m off the line, walking toward the start along it at 0.3-0.6 m/s |
//! | `crowd` | goal 8-12 m ahead over open ground; 10-20 people at 0.2-0.8 m/s in uniformly random directions, placed uniformly in the box 1 m around the start and the goal (4 m to either side of the line), none within 1 m of the start or the goal |
//! | `room_crossing` | a `doorway` layout (a closed room split by a wall with one door) and one person crossing the room at right angles to the x axis, at 0.3-0.6 m/s, at an `x` between 1 m past the start and 1 m before the goal, timed as in `crossing` |

use ldcbf_controller::nalgebra::Vector2;

use crate::world::Polygon;
use crate::world::families::{Draw, Layout, doorway};
use crate::world::random::regular_polygon;

/// The robot's walking speed the crossings are timed against, m/s.
pub const NOMINAL_SPEED: f64 = 0.6;

/// A person: a regular octagon of radius 0.2-0.25 m centred at `c`.
fn person(d: &mut Draw, c: Vector2<f64>) -> Polygon {
    body(d, c, 0.25)
}

/// A person: a regular octagon of radius 0.2 m to `r_max` centred at `c`.
pub(super) fn body(d: &mut Draw, c: Vector2<f64>, r_max: f64) -> Polygon {
    let r = d.unif(0.2, r_max);
    let rot = d.unif(0.0, core::f64::consts::FRAC_PI_4);
    Polygon::new(&regular_polygon([c.x, c.y], r, 8, rot)).expect("an octagon is convex")
}

/// A person crossing the line `y = y_line` at `x`, at right angles, from a
/// random side, at 0.3-0.6 m/s, at the robot's nominal arrival time at `x`
/// (from `x = 0`) plus -2 to 2 s: the person and their velocity.
fn crosser(d: &mut Draw, x: f64, y_line: f64) -> (Polygon, Vector2<f64>) {
    let speed = d.unif(0.3, 0.6);
    let dir = if d.coin() { 1.0 } else { -1.0 };
    let t_cross = (x / NOMINAL_SPEED + d.unif(-2.0, 2.0)).max(0.0);
    let c = Vector2::new(x, y_line - dir * speed * t_cross);
    (person(d, c), Vector2::new(0.0, dir * speed))
}

pub(super) fn crossing(d: &mut Draw) -> Layout {
    let goal = Vector2::new(d.unif(8.0, 12.0), 0.0);
    let n = d.int(2, 4);
    let (mut obstacles, mut velocities) = (Vec::new(), Vec::new());
    for _ in 0..n {
        let x = d.unif(2.0, goal.x - 2.0);
        let (p, v) = crosser(d, x, 0.0);
        obstacles.push(p);
        velocities.push(v);
    }
    Layout {
        start: Vector2::zeros(),
        heading: 0.0,
        goal,
        obstacles,
        velocities,
    }
}

pub(super) fn headon(d: &mut Draw) -> Layout {
    let goal = Vector2::new(d.unif(8.0, 12.0), 0.0);
    let c = Vector2::new(goal.x + d.unif(1.0, 3.0), d.unif(-0.15, 0.15));
    let speed = d.unif(0.3, 0.6);
    Layout {
        start: Vector2::zeros(),
        heading: 0.0,
        goal,
        obstacles: vec![person(d, c)],
        velocities: vec![Vector2::new(-speed, 0.0)],
    }
}

pub(super) fn crowd(d: &mut Draw, r: f64) -> Layout {
    let goal = Vector2::new(d.unif(8.0, 12.0), 0.0);
    let n = d.int(10, 20);
    let (mut obstacles, mut velocities) = (Vec::new(), Vec::new());
    let keep = r + 0.05 + 0.25 + 1.0;
    while obstacles.len() < n {
        let c = Vector2::new(d.unif(-1.0, goal.x + 1.0), d.unif(-4.0, 4.0));
        let a = d.unif(0.0, core::f64::consts::TAU);
        let speed = d.unif(0.2, 0.8);
        if c.norm() < keep || (c - goal).norm() < keep {
            continue;
        }
        obstacles.push(person(d, c));
        velocities.push(Vector2::new(a.cos(), a.sin()) * speed);
    }
    Layout {
        start: Vector2::zeros(),
        heading: 0.0,
        goal,
        obstacles,
        velocities,
    }
}

pub(super) fn room_crossing(d: &mut Draw) -> Layout {
    let room = doorway(d);
    let x = d.unif(1.0, room.goal.x - 1.0);
    // The robot's line from the start to the goal, at x.
    let y_line = room.goal.y * x / room.goal.x;
    let (p, v) = crosser(d, x, y_line);
    let mut obstacles = vec![p];
    obstacles.extend(room.obstacles);
    Layout {
        obstacles,
        velocities: vec![v],
        ..room
    }
}

#[cfg(test)]
mod tests {
    use crate::world::families::generate;

    #[test]
    fn people_walk_within_the_drawn_ranges() {
        for seed in 0..30 {
            let c = generate("crossing", seed, 0.25).unwrap();
            assert!((2..=4).contains(&c.velocities.len()));
            for v in &c.velocities {
                assert!(v.x == 0.0 && (0.3..=0.6).contains(&v.y.abs()), "{v}");
            }
            let h = generate("headon", seed, 0.25).unwrap();
            assert_eq!(h.velocities.len(), 1);
            assert!(h.velocities[0].x < 0.0, "toward the start");
            let crowd = generate("crowd", seed, 0.25).unwrap();
            assert!((10..=20).contains(&crowd.velocities.len()));
            assert_eq!(crowd.velocities.len(), crowd.obstacles.len(), "open ground");
            for v in &crowd.velocities {
                assert!((0.2 - 1e-12..=0.8 + 1e-12).contains(&v.norm()));
            }
            let room = generate("room_crossing", seed, 0.25).unwrap();
            assert_eq!(room.velocities.len(), 1);
            assert_eq!(
                room.obstacles.len(),
                7,
                "a person and the doorway's six walls"
            );
            for p in c.obstacles.iter().chain(&crowd.obstacles) {
                assert_eq!(p.len(), 8, "people are octagons");
            }
        }
    }
}
