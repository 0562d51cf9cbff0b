//! The hits of a scan that lie on a straight face longer than any person
//! (a wall), so that the people detector ([`super::movers`]) never sees them.
//! World frame W, metres.
//!
//! A wall seen at a slant, or cut by the edge of the LiDAR's range, comes out
//! of the detector's fine DBSCAN ([`super::track::TrackParams::cluster_eps`])
//! in short pieces: the hits along a slanted face are farther apart than the
//! clustering radius, and the part of a wall inside the range circle is a
//! chord. Each piece is person-sized, and as the robot walks its hits slide
//! along the wall with it: the tracker sees people walking along every wall
//! at up to the robot's speed, keeps them out of the map and hands them to
//! the controller with a velocity margin that closes every door (before this
//! room: a `room_crossing` run stood 60 s in front of its door, 0 of 100
//! unseen seeds reached the goal with the margin on).
//!
//! The classic first step of a laser people detector is to take the lines out
//! first: consecutive rays whose hits are linked by the adaptive breakpoint
//! detector (G. A. Borges and M.-J. Aldon, "Line extraction in 2D range
//! images for mobile robotics", J. Intelligent and Robotic Systems 40, 2004;
//! the chains of [`super::infer_obstacles`], `breakpoint_chains`, with every
//! hit in one group)
//! form chains; split and merge ([`super::split_and_merge`], tolerance the
//! LiDAR's `line_tolerance`) cuts each chain into straight segments; the hits
//! of a segment at least `min_length` long, with at least `min_points` hits,
//! are a wall's. A person's outline is round (a person of radius 0.2-0.3 m
//! bulges 0.08 m or more over a chord of 0.4 m, more than the 0.05 m
//! tolerance), so no segment of a person is that long; a person standing in
//! front of a wall breaks the wall's chain or bulges out of its line.

use ldcbf_controller::nalgebra::Vector2;

use super::infer::breakpoint_chains;
use super::{LidarParams, split_and_merge};

/// One flag per ray of `rays` (`rays[k]` ray `k`'s hit point, m, or `None`,
/// from `origin`, m, the rays evenly spread over 360 degrees): its hit lies
/// on a straight face at least `min_length` (m) long with at least
/// `min_points` hits (module docs). Deterministic.
pub fn wall_hits(
    rays: &[Option<Vector2<f64>>],
    origin: Vector2<f64>,
    params: &LidarParams,
    min_length: f64,
    min_points: usize,
) -> Vec<bool> {
    let n = rays.len();
    let mut wall = vec![false; n];
    // One group: the chains break at missed rays and at the detector's jumps.
    for chain in breakpoint_chains(rays, origin, params, |k| rays[k].map(|_| 0)) {
        let p: Vec<Vector2<f64>> = chain.iter().filter_map(|&u| rays[u % n]).collect();
        for (a, b) in split_and_merge(&p, params.line_tolerance) {
            if b + 1 - a >= min_points && (p[b] - p[a]).norm() >= min_length {
                for &u in &chain[a..=b] {
                    wall[u % n] = true;
                }
            }
        }
    }
    wall
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sense::Lidar;
    use crate::world::Polygon;
    use crate::world::random::regular_polygon;

    fn scan(world: &[Polygon], origin: Vector2<f64>) -> Vec<Option<Vector2<f64>>> {
        let mut lidar = Lidar::new(LidarParams::default(), 3).unwrap();
        lidar.scan_rays(origin, 0.0, world)
    }

    fn wall_of(rays: &[Option<Vector2<f64>>], origin: Vector2<f64>) -> Vec<bool> {
        let length = crate::sense::track::TrackParams::default().wall_length;
        wall_hits(rays, origin, &LidarParams::default(), length, 3)
    }

    #[test]
    fn a_slanted_wall_and_the_chord_inside_the_range_are_walls() {
        // A wall 2.9 m to the side, seen along 1.5 m of chord within the 3 m
        // range, at slants up to 60 degrees; the DBSCAN of 0.15 m would cut
        // its far ends into pieces.
        let wall = Polygon::new(&[[-6.0, 2.9], [6.0, 2.9], [6.0, 3.1], [-6.0, 3.1]]).unwrap();
        let origin = Vector2::zeros();
        let rays = scan(&[wall], origin);
        let flags = wall_of(&rays, origin);
        let hits = rays.iter().flatten().count();
        assert!(hits > 20, "{hits} hits");
        let on_wall = flags.iter().filter(|&&w| w).count();
        assert!(on_wall + 2 >= hits, "{on_wall} of {hits} hits on the wall");
    }

    #[test]
    fn a_person_is_never_a_wall_even_in_front_of_one() {
        let wall = Polygon::new(&[[-3.0, 2.0], [3.0, 2.0], [3.0, 2.2], [-3.0, 2.2]]).unwrap();
        let origin = Vector2::zeros();
        for (k, r) in [0.2, 0.25, 0.3].into_iter().enumerate() {
            for at in [1.0, 1.6, 2.0 - r - 0.05] {
                let c = [0.3 * k as f64, at];
                let person = Polygon::new(&regular_polygon(c, r, 8, 0.1)).unwrap();
                for world in [vec![person], vec![person, wall]] {
                    let rays = scan(&world, origin);
                    let flags = wall_of(&rays, origin);
                    for (ray, w) in rays.iter().zip(&flags) {
                        if let Some(p) = ray
                            && (p - Vector2::from(c)).norm() < r + 0.05
                        {
                            assert!(!w, "a hit of the person (r {r}, at {at}) on a wall");
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn an_empty_or_short_scan_has_no_wall() {
        let origin = Vector2::zeros();
        assert!(wall_of(&[], origin).is_empty());
        assert_eq!(wall_of(&[None, None], origin), vec![false, false]);
        assert_eq!(wall_of(&vec![None; 360], origin), vec![false; 360]);
    }
}
