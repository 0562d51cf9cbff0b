//! Unit tests of the occupancy map.

use super::*;
use crate::sense::{Lidar, LidarParams, free_tolerance};
use crate::world::square;

fn v(x: f64, y: f64) -> Vector2<f64> {
    Vector2::new(x, y)
}

fn map(params: MapParams) -> OccupancyMap {
    OccupancyMap::new(params, v(-2.0, -2.0), v(2.0, 2.0)).unwrap()
}

#[test]
fn traversal_visits_every_cell_a_segment_crosses_in_order() {
    let mut m = map(MapParams {
        resolution: 0.5,
        padding: 0.0,
        ..MapParams::default()
    });
    let mut seen = Vec::new();
    let d = v(1.0, 0.5).normalize();
    m.traverse(v(-1.9, -1.9), d, 2.0, |m, k| {
        seen.push((k % m.width, k / m.width))
    });
    // From cell (0, 0) along slope 1/2: the cells crossed, 4-connected.
    assert_eq!(seen[0], (0, 0));
    for w in seen.windows(2) {
        let (a, b) = (w[0], w[1]);
        assert_eq!(a.0.abs_diff(b.0) + a.1.abs_diff(b.1), 1, "{seen:?}");
    }
    let end = v(-1.9, -1.9) + d * 2.0;
    assert_eq!(*seen.last().unwrap(), m.cell_of(end).unwrap(), "{seen:?}");
    // A segment starting outside the map is clipped to it.
    let mut n = 0;
    m.traverse(v(-3.0, 0.1), v(1.0, 0.0), 10.0, |_, _| n += 1);
    assert_eq!(n, m.width);
}

/// In a box that does not grow, rays that run off the map clear up to its
/// outermost ring, which stays unknown: a frontier piece stands at the box's edge (where a wall
/// beyond the box would be), and none covers a cell seen free.
#[test]
fn the_map_ends_in_a_frontier_at_its_edge() {
    let mut m = map(MapParams {
        resolution: 0.1,
        padding: 0.0,
        unknown_radius: 1.0,
        grow: false,
        ..MapParams::default()
    });
    // At (1.45, 0.05), 0.55 m from the map's edge x = 2; 8 rays, none hits.
    let o = v(1.45, 0.05);
    m.update(o, 0.0, &[None; 8], 3.0, 0.03, 0.0);
    let last = m.width - 1;
    let (_, j) = m.cell_of(o).unwrap();
    assert_eq!(m.state(last, j), CellState::Unknown);
    assert_eq!(m.state(last - 1, j), CellState::Free);
    let pieces = m.pieces(o, 1.0);
    let edge = m.centre(last, j);
    assert!(
        pieces.iter().any(|p| {
            ldcbf_controller::closest_point_point_polygon(&edge, p).signed_distance <= 0.0
        }),
        "no piece at the edge: {pieces:?}"
    );
    let inner = m.centre(last - 1, j);
    assert!(pieces.iter().all(|p| {
        ldcbf_controller::closest_point_point_polygon(&inner, p).signed_distance > 0.0
    }));
}

#[test]
fn a_hit_marks_its_cell_and_the_ray_clears_the_cells_before_it() {
    let p = MapParams {
        resolution: 0.1,
        ..MapParams::default()
    };
    let mut m = map(p);
    let o = v(0.05, 0.05);
    // Ray 0 of 4 (along +x) hits at x = 1.05; the others miss within 1 m.
    let rays = [Some(v(1.05, 0.05)), None, None, None];
    m.update(o, 0.0, &rays, 1.0, 0.03, 0.0);
    assert_eq!(m.state_at(v(1.05, 0.05)), CellState::Occupied);
    for x in [0.05, 0.35, 0.95] {
        assert_eq!(m.state_at(v(x, 0.05)), CellState::Free, "x = {x}");
    }
    assert_eq!(
        m.state_at(v(0.05, 0.95)),
        CellState::Free,
        "a missed ray clears to its range"
    );
    assert_eq!(
        m.state_at(v(0.05, 1.25)),
        CellState::Unknown,
        "beyond the range"
    );
    assert_eq!(
        m.state_at(v(1.55, 0.05)),
        CellState::Unknown,
        "behind the hit"
    );
    // The obstacle moved away: rays now pass through its cell, which turns
    // free after a few scans (clamped: never more than it takes).
    let rays = [Some(v(1.85, 0.05)), None, None, None];
    let mut scans = 0;
    while m.state_at(v(1.05, 0.05)) == CellState::Occupied {
        m.update(o, 0.0, &rays, 2.0, 0.03, 0.0);
        scans += 1;
        assert!(scans < 10);
    }
    assert!(scans >= 2, "one miss does not erase a hit ({scans})");
    // Clamping: after many more hits it still clears in a bounded number.
    for _ in 0..100 {
        m.update(
            o,
            0.0,
            &[Some(v(1.05, 0.05)), None, None, None],
            1.0,
            0.03,
            0.0,
        );
    }
    let (i, j) = m.cell_of(v(1.05, 0.05)).unwrap();
    assert!(m.log_odds(i, j) <= logit(0.971) + 1e-6);
    let mut scans = 0;
    while m.state_at(v(1.05, 0.05)) == CellState::Occupied {
        m.update(o, 0.0, &rays, 2.0, 0.03, 0.0);
        scans += 1;
    }
    assert!(scans <= 9, "{scans}");
}

#[test]
fn a_hit_wins_over_a_miss_of_the_same_scan() {
    let mut m = map(MapParams {
        resolution: 0.2,
        ..MapParams::default()
    });
    // Two rays 1 degree apart: one hits at 1.1 m, the other passes
    // through the same cell to 1.9 m.
    let o = v(0.0, 0.0);
    let d0 = crate::sense::ray_direction(0.0, 0, 360);
    let d1 = crate::sense::ray_direction(0.0, 1, 360);
    let mut rays = vec![None; 360];
    rays[0] = Some(o + d0 * 1.1);
    rays[1] = Some(o + d1 * 1.9);
    m.update(o, 0.0, &rays, 3.0, 0.0, 0.0);
    assert_eq!(m.state_at(o + d0 * 1.1), CellState::Occupied);
}

#[test]
fn pieces_cover_every_occupied_cell_and_no_free_one() {
    let lidar_params = LidarParams::default();
    let mut lidar = Lidar::new(lidar_params.clone(), 7).unwrap();
    let obstacles = [square([1.0, 0.3], 0.2), square([-0.8, -0.9], 0.3)];
    let mut m = map(MapParams {
        resolution: 0.05,
        padding: 0.5,
        ..MapParams::default()
    });
    let tol = free_tolerance(&lidar_params);
    for k in 0..5 {
        let o = v(-0.5 + 0.1 * f64::from(k), 0.2);
        let rays = lidar.scan_rays(o, 0.0, &obstacles);
        m.update(o, 0.0, &rays, lidar_params.range, tol, 0.05);
    }
    let at = v(0.0, 0.2);
    let pieces = m.pieces(at, 3.0);
    assert!(!pieces.is_empty());
    let mut occupied = 0;
    for j in 0..m.height {
        for i in 0..m.width {
            let c = m.centre(i, j);
            let inside = pieces.iter().any(|p| p.contains(&c));
            match m.state(i, j) {
                CellState::Occupied => {
                    occupied += 1;
                    assert!(inside, "occupied cell {i} {j} left out");
                }
                CellState::Free => assert!(!inside, "free cell {i} {j} covered"),
                CellState::Unknown => {
                    if inside {
                        assert!(m.is_frontier(i, j) && (c - at).norm() <= 1.0);
                    }
                }
            }
        }
    }
    assert!(occupied > 10);
    // Both obstacles are seen: occupied cells on their faces.
    for ob in &obstacles {
        let near = (0..m.height)
            .flat_map(|j| (0..m.width).map(move |i| (i, j)))
            .filter(|&(i, j)| m.state(i, j) == CellState::Occupied)
            .any(|(i, j)| {
                ldcbf_controller::closest_point_point_polygon(&m.centre(i, j), ob)
                    .signed_distance
                    .abs()
                    < 0.03
            });
        assert!(near, "{:?}", ob.vertices());
    }
    // No piece contains the sensor.
    assert!(pieces.iter().all(|p| !p.contains(&at)));
}

#[test]
fn decay_forgets_and_bad_settings_name_their_field() {
    let mut m = map(MapParams {
        decay: 1.0,
        ..MapParams::default()
    });
    m.update(v(0.0, 0.0), 0.0, &[Some(v(0.5, 0.0))], 1.0, 0.0, 0.0);
    assert_eq!(m.state_at(v(0.5, 0.0)), CellState::Occupied);
    m.update(v(0.0, 0.0), 0.0, &[], 1.0, 0.0, 20.0);
    assert_eq!(m.state_at(v(0.5, 0.0)), CellState::Unknown);
    let bad = MapParams {
        p_hit: 0.4,
        ..MapParams::default()
    };
    assert_eq!(bad.validate().unwrap_err().field, "map.p_hit");
    let huge = MapParams {
        resolution: 0.001,
        padding: 100.0,
        ..MapParams::default()
    };
    assert!(OccupancyMap::new(huge, v(0.0, 0.0), v(1.0, 1.0)).is_err());
}

/// Every known cell of the map, as (centre, log-odds).
fn known_cells(m: &OccupancyMap) -> Vec<(Vector2<f64>, f32)> {
    (0..m.height)
        .flat_map(|j| (0..m.width).map(move |i| (i, j)))
        .filter(|&(i, j)| m.state(i, j) != CellState::Unknown)
        .map(|(i, j)| (m.centre(i, j), m.log_odds(i, j)))
        .collect()
}

/// Whether every cell of the map's outermost ring is unknown.
fn ring_unknown(m: &OccupancyMap) -> bool {
    (0..m.height)
        .flat_map(|j| (0..m.width).map(move |i| (i, j)))
        .filter(|&(i, j)| i == 0 || j == 0 || i + 1 == m.width || j + 1 == m.height)
        .all(|(i, j)| m.state(i, j) == CellState::Unknown)
}

#[test]
fn growing_keeps_every_cell_at_its_world_position() {
    let mut m = map(MapParams {
        resolution: 0.1,
        padding: 0.0,
        ..MapParams::default()
    });
    // Hits and misses within 1.5 m of the centre: inside the first box.
    let rays: Vec<_> = (0..36)
        .map(|k| {
            (k % 3 == 0).then(|| v(0.05, 0.05) + crate::sense::ray_direction(0.0, k, 36) * 1.2)
        })
        .collect();
    m.update(v(0.05, 0.05), 0.0, &rays, 1.5, 0.03, 0.0);
    assert_eq!(m.grows(), 0, "the first box holds this scan");
    let before = known_cells(&m);
    assert!(before.iter().any(|c| c.1 > 0.0) && before.iter().any(|c| c.1 < 0.0));
    let (o, w, h) = (m.origin, m.width, m.height);
    assert_eq!(m.grow_to_cover(v(-5.0, -1.0), v(1.0, 6.0)), Growth::Grown);
    assert!(m.width > w && m.height > h);
    // The origin moved by whole cells to the left only (the box already
    // reached y = -1 m below).
    let shift = (o - m.origin) / m.resolution;
    assert!(
        shift.x > 0.0 && (shift.x - shift.x.round()).abs() < 1e-9,
        "{shift}"
    );
    assert_eq!(shift.y, 0.0);
    // Every known cell has the same log-odds at the same place; no new cell
    // is known.
    for (c, l) in &before {
        let (i, j) = m.cell_of(*c).unwrap();
        assert!((m.centre(i, j) - c).norm() < 1e-9);
        assert_eq!(m.log_odds(i, j), *l, "at {c}");
    }
    assert_eq!(known_cells(&m).len(), before.len());
    // The asked box is inside the inner cells.
    for p in [v(-5.0, -1.0), v(1.0, 6.0)] {
        let (i, j) = m.cell_of(p).unwrap();
        assert!(i >= 1 && j >= 1 && i + 1 < m.width && j + 1 < m.height);
    }
    // Covered already: nothing changes.
    assert_eq!(m.grow_to_cover(v(-1.0, -1.0), v(1.0, 1.0)), Growth::Covered);
    assert_eq!(m.grows(), 1);
}

/// The box grows with a scan that leaves it: free space then ends in a
/// frontier where the rays end, not at the box's edge, and no ray reaches
/// the box's outermost ring.
#[test]
fn a_grown_map_ends_in_a_frontier_where_the_rays_end() {
    let mut m = map(MapParams {
        resolution: 0.1,
        padding: 0.0,
        unknown_radius: 3.5,
        ..MapParams::default()
    });
    // At (1.45, 0.05), 0.55 m from the first box's edge x = 2; 8 rays of
    // 3 m, none hits.
    let o = v(1.45, 0.05);
    m.update(o, 0.0, &[None; 8], 3.0, 0.03, 0.0);
    assert_eq!(m.grows(), 1);
    assert!(ring_unknown(&m));
    // The first box's edge cell is cleared; the ray along +x ends at 4.45.
    assert_eq!(m.state_at(v(1.95, 0.05)), CellState::Free);
    assert_eq!(m.state_at(v(4.35, 0.05)), CellState::Free);
    let end = v(4.55, 0.05);
    assert_eq!(m.state_at(end), CellState::Unknown);
    let (i, j) = m.cell_of(end).unwrap();
    assert!(i + 1 < m.width, "beyond the rays the map goes on");
    assert!(m.is_frontier(i, j));
    let pieces = m.pieces(o, 3.5);
    let at = |p: Vector2<f64>| {
        pieces
            .iter()
            .any(|q| ldcbf_controller::closest_point_point_polygon(&p, q).signed_distance <= 0.0)
    };
    assert!(at(m.centre(i, j)), "no piece where the ray ends");
    assert!(!at(v(1.95, 0.05)), "a piece at the first box's edge");
}

#[test]
fn at_its_bound_the_map_keeps_its_box_or_grows_exactly() {
    // 40 x 40 cells; the scan below needs 67 x 65 exactly, 87 x 105 with
    // the slack.
    let scan = |max_cells: usize| {
        let mut m = map(MapParams {
            resolution: 0.1,
            padding: 0.0,
            max_cells,
            ..MapParams::default()
        });
        m.update(v(1.45, 0.05), 0.0, &[None; 8], 3.0, 0.03, 0.0);
        m
    };
    let m = scan(2000);
    assert_eq!(
        (m.width, m.height, m.grows(), m.refused_grows()),
        (40, 40, 0, 1)
    );
    // Kept: the rays stop at the edge, which stays a frontier.
    let (_, j) = m.cell_of(v(1.45, 0.05)).unwrap();
    assert_eq!(m.state(39, j), CellState::Unknown);
    assert_eq!(m.state(38, j), CellState::Free);
    assert!(ring_unknown(&m));
    let m = scan(5000);
    assert_eq!(
        (m.width, m.height, m.grows(), m.refused_grows()),
        (67, 65, 1, 0)
    );
    assert!(ring_unknown(&m));
    let m = scan(10_000);
    assert_eq!((m.width, m.height), (87, 105));
    let bad = MapParams {
        max_cells: 0,
        ..MapParams::default()
    };
    assert_eq!(bad.validate().unwrap_err().field, "map.max_cells");
}

/// `hit_overrides_misses`: a cell cleared to the clamp by many scans is
/// occupied after one scan that hits it (without the rule one hit leaves it
/// free), and three scans of misses clear it again.
#[test]
fn a_hit_is_occupied_whatever_misses_came_before() {
    for overrides in [true, false] {
        let mut m = map(MapParams {
            resolution: 0.1,
            hit_overrides_misses: overrides,
            ..MapParams::default()
        });
        let o = v(0.05, 0.05);
        let cell = v(1.05, 0.05);
        // Ten scans whose ray 0 passes through the cell to a wall at 1.85 m.
        let far = [Some(v(1.85, 0.05)), None, None, None];
        for _ in 0..10 {
            m.update(o, 0.0, &far, 2.0, 0.03, 0.0);
        }
        let (i, j) = m.cell_of(cell).unwrap();
        assert!(m.log_odds(i, j) <= logit(0.1192) + 1e-6, "clamped free");
        // One scan hits something in it.
        m.update(o, 0.0, &[Some(cell), None, None, None], 2.0, 0.03, 0.0);
        let expect = if overrides {
            CellState::Occupied
        } else {
            CellState::Free
        };
        assert_eq!(m.state_at(cell), expect, "overrides = {overrides}");
        if overrides {
            assert!((m.log_odds(i, j) - logit(0.7)).abs() < 1e-6);
            for scans in 1..=3 {
                m.update(o, 0.0, &far, 2.0, 0.03, 0.0);
                let want = if scans < 3 {
                    CellState::Occupied
                } else {
                    CellState::Free
                };
                assert_eq!(m.state_at(cell), want, "after {scans} misses");
            }
        }
    }
}

/// The exception of `hit_overrides_misses`: a hit within `hit_noise_band`
/// of an occupied cell (a noise hit in front of a wall's face) counts as
/// usual, so a cell cleared to the clamp stays free after it.
#[test]
fn a_hit_next_to_an_occupied_cell_counts_as_usual() {
    let mut m = map(MapParams {
        resolution: 0.025,
        ..MapParams::default()
    });
    let o = v(0.0125, 0.0125);
    // A wall cell at x = 1.0125 (hit in three scans), and the cell two in
    // front of it cleared to the clamp by rays ending at the wall.
    let wall = [Some(v(1.0125, 0.0125)), None, None, None];
    for _ in 0..10 {
        m.update(o, 0.0, &wall, 2.0, 0.03, 0.0);
    }
    let ghost = v(0.9625, 0.0125);
    assert_eq!(m.state_at(ghost), CellState::Free);
    // A noise hit lands in it (3 cm band = 2 cells): it stays free.
    m.update(o, 0.0, &[Some(ghost), None, None, None], 2.0, 0.03, 0.0);
    assert_eq!(m.state_at(ghost), CellState::Free);
    // Three cells in front, beyond the band: the hit is an obstacle.
    let far = v(0.9375, 0.0125);
    m.update(o, 0.0, &[Some(far), None, None, None], 2.0, 0.03, 0.0);
    assert_eq!(m.state_at(far), CellState::Occupied);
    let bad = MapParams {
        hit_noise_band: -0.1,
        ..MapParams::default()
    };
    assert_eq!(bad.validate().unwrap_err().field, "map.hit_noise_band");
}
