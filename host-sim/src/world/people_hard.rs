//! Seeded families of people who are hard for a LiDAR tracker to see (the
//! `[generator]` kinds `group_crossing`, `headon_offset`, `occluded_person`;
//! drawn by [`crate::world::families::generate`] with the same generator,
//! redraws and validity check as every family).
//!
//! People are as in [`crate::world::people`] but wider: regular octagons of
//! radius 0.2-0.3 m walking at a constant velocity through everything, the people
//! first in the obstacle list, walls after them, at rest. Crossings are timed
//! against [`NOMINAL_SPEED`] as there. World frame W, metres, seconds.
//!
//! | family | what is drawn |
//! |---|---|
//! | `group_crossing` | goal 8-12 m ahead on the start's line; a group of 2-3 people crossing that line at right angles at 0.3-1.0 m/s, at 2 m to 2 m before the goal, at the robot's nominal arrival time plus -1.5 to 1.5 s: side by side (their centres 0.55-0.7 m apart along the robot's line) or in file (0.55-0.7 m apart along their walk), half the seeds each; the group seen as one DBSCAN cluster when their gaps are narrow |
//! | `headon_offset` | goal 8-12 m ahead; one person starting between 0.6 of the way to the goal and 3 m past it, 0-0.3 m off the line (either side), walking toward the start along it at 0.3-1.0 m/s |
//! | `occluded_person` | goal 8-12 m ahead; half the seeds a wall block (1-3 m along the line, 1-3 m deep and at least 0.5 m past the person's start) 0.7-1.5 m to one side of the line, ending at `x_c` 3 m to 3 m before the goal, and a person walking out from behind its corner (0.3-0.9 m past it) across the line at 0.3-0.8 m/s, crossing at the robot's nominal arrival time plus -2 to 1 s; the other half two people walking across the line in opposite directions at 0.3-0.8 m/s, the far one 0.8-1.5 m further along the line, both 0.5-1.5 m to one side of it at the same time (the robot's nominal arrival plus -2 to 1 s): seen from the robot the far one passes behind the near one |

use ldcbf_controller::nalgebra::Vector2;

use crate::world::Polygon;
use crate::world::families::{Draw, Layout, rect};
use crate::world::people::{NOMINAL_SPEED, body};

/// The largest radius of a person here, m (the crowd-navigation
/// benchmark's people are 0.3 m).
const R_MAX: f64 = 0.3;

/// A person of radius 0.2 m to [`R_MAX`] at `c`.
fn person(d: &mut Draw, c: Vector2<f64>) -> Polygon {
    body(d, c, R_MAX)
}

/// The straight layout every family here starts from: the start at the
/// origin facing +x, the goal 8-12 m ahead on the x axis.
fn line(d: &mut Draw) -> (Vector2<f64>, Vec<Polygon>, Vec<Vector2<f64>>) {
    (Vector2::new(d.unif(8.0, 12.0), 0.0), Vec::new(), Vec::new())
}

/// The time (s) at which a robot walking at [`NOMINAL_SPEED`] from the
/// origin reaches `x` (m), plus `jitter` s, never negative.
fn arrival(x: f64, jitter: f64) -> f64 {
    (x / NOMINAL_SPEED + jitter).max(0.0)
}

pub(super) fn group_crossing(d: &mut Draw) -> Layout {
    let (goal, mut obstacles, mut velocities) = line(d);
    let n = d.int(2, 3);
    let x = d.unif(2.0, goal.x - 2.0);
    let speed = d.unif(0.3, 1.0);
    let dir = if d.coin() { 1.0 } else { -1.0 };
    let t_cross = arrival(x, d.unif(-1.5, 1.5));
    let abreast = d.coin();
    let mut off = 0.0;
    for k in 0..n {
        if k > 0 {
            off += d.unif(0.55, 0.7);
        }
        // Side by side: apart along x (the robot's line); in file: apart
        // along the walk, each following the one before.
        let c = if abreast {
            Vector2::new(x + off, -dir * speed * t_cross)
        } else {
            Vector2::new(x, -dir * (speed * t_cross + off))
        };
        obstacles.push(person(d, c));
        velocities.push(Vector2::new(0.0, dir * speed));
    }
    Layout {
        start: Vector2::zeros(),
        heading: 0.0,
        goal,
        obstacles,
        velocities,
    }
}

pub(super) fn headon_offset(d: &mut Draw) -> Layout {
    let (goal, _, _) = line(d);
    let side = if d.coin() { 1.0 } else { -1.0 };
    let c = Vector2::new(d.unif(0.6 * goal.x, goal.x + 3.0), side * d.unif(0.0, 0.3));
    let speed = d.unif(0.3, 1.0);
    Layout {
        start: Vector2::zeros(),
        heading: 0.0,
        goal,
        obstacles: vec![person(d, c)],
        velocities: vec![Vector2::new(-speed, 0.0)],
    }
}

pub(super) fn occluded_person(d: &mut Draw) -> Layout {
    let (goal, mut obstacles, mut velocities) = line(d);
    let side = if d.coin() { 1.0 } else { -1.0 };
    let speed = d.unif(0.3, 0.8);
    let mut walls = Vec::new();
    if d.coin() {
        // A wall corner: the block ends at x_c; the person walks out from
        // behind it, 0.3-0.9 m past the corner, toward the line.
        let x_c = d.unif(3.0, goal.x - 3.0);
        let (len, depth, w) = (d.unif(1.0, 3.0), d.unif(1.0, 3.0), d.unif(0.7, 1.5));
        let x = x_c + d.unif(0.3, 0.9);
        let t_cross = arrival(x, d.unif(-2.0, 1.0));
        let y0 = speed * t_cross;
        // The block reaches 0.5 m past the person's start (a building's side).
        let depth = depth.max(y0 - w + 0.5);
        walls.push(rect(x_c - len, side * w, x_c, side * (w + depth)));
        obstacles.push(person(d, Vector2::new(x, side * y0)));
        velocities.push(Vector2::new(0.0, -side * speed));
    } else {
        // Two people crossing in opposite directions, the far one behind the
        // near one (as seen from the line) when they pass each other.
        let x = d.unif(3.0, goal.x - 3.0);
        let behind = d.unif(0.8, 1.5);
        let t_meet = arrival(x, d.unif(-2.0, 1.0));
        // They pass each other at y_meet, on the near side of the line.
        let y_meet = side * d.unif(0.5, 1.5);
        let far_speed = d.unif(0.3, 0.8);
        obstacles.push(person(d, Vector2::new(x, y_meet + side * speed * t_meet)));
        velocities.push(Vector2::new(0.0, -side * speed));
        obstacles.push(person(
            d,
            Vector2::new(x + behind, y_meet - side * far_speed * t_meet),
        ));
        velocities.push(Vector2::new(0.0, side * far_speed));
    }
    obstacles.extend(walls);
    Layout {
        start: Vector2::zeros(),
        heading: 0.0,
        goal,
        obstacles,
        velocities,
    }
}

#[cfg(test)]
mod tests {
    use ldcbf_controller::closest_point_point_polygon;

    use crate::world::families::generate;
    use crate::world::moving::vertex_centre;

    #[test]
    fn groups_walk_close_together() {
        for seed in 0..30 {
            let g = generate("group_crossing", seed, 0.25).unwrap();
            assert!((2..=3).contains(&g.velocities.len()));
            assert_eq!(g.obstacles.len(), g.velocities.len(), "open ground");
            for v in &g.velocities {
                assert!(v.x == 0.0 && (0.3..=1.0).contains(&v.y.abs()), "{v}");
                assert_eq!(*v, g.velocities[0], "a group walks together");
            }
            for w in g.obstacles.windows(2) {
                let d = (vertex_centre(&w[0]) - vertex_centre(&w[1])).norm();
                assert!((0.55..=0.7).contains(&d), "seed {seed}: {d} m apart");
            }
        }
    }

    #[test]
    fn headon_people_walk_along_the_line() {
        for seed in 0..30 {
            let h = generate("headon_offset", seed, 0.25).unwrap();
            assert_eq!(h.velocities.len(), 1);
            let v = h.velocities[0];
            assert!(v.y == 0.0 && (-1.0..=-0.3).contains(&v.x), "{v}");
            assert!(vertex_centre(&h.obstacles[0]).y.abs() <= 0.3);
        }
    }

    #[test]
    fn occluded_people_start_out_of_sight() {
        let (mut corners, mut pairs, mut hidden) = (0, 0, 0);
        for seed in 0..40 {
            let o = generate("occluded_person", seed, 0.25).unwrap();
            let start = o.start;
            match o.velocities.len() {
                1 => {
                    corners += 1;
                    assert_eq!(o.obstacles.len(), 2, "a person and a wall");
                    // The wall reaches past the person's start; mostly it
                    // hides the person from the start at t = 0.
                    let p = vertex_centre(&o.obstacles[0]);
                    let wall = &o.obstacles[1];
                    let far = wall
                        .vertices()
                        .iter()
                        .map(|v| v.y.abs())
                        .fold(0.0, f64::max);
                    assert!(far >= p.y.abs() + 0.5 - 1e-9, "seed {seed}");
                    hidden += usize::from((1..100).any(|k| {
                        let q = start + (p - start) * (f64::from(k) / 100.0);
                        closest_point_point_polygon(&q, wall).signed_distance < 0.0
                    }));
                }
                2 => {
                    pairs += 1;
                    let (v0, v1) = (o.velocities[0], o.velocities[1]);
                    assert!(v0.y * v1.y < 0.0, "opposite directions");
                }
                n => panic!("seed {seed}: {n} people"),
            }
        }
        assert!(corners > 5 && pairs > 5, "{corners} corners, {pairs} pairs");
        assert!(
            2 * hidden >= corners,
            "hidden from the start in {hidden} of {corners}"
        );
    }
}
