//! The cost of a control cycle against the size of the known map (issue 14,
//! part 2), at the simulator's configuration (`RobotController`: N = 3, 8
//! obstacles, foot rows).
//!
//! # The maps and the cycles
//!
//! The cycles are the closed loop `random@0` (the paper's random test, seed 0:
//! 8 polygons, (0, 0) to (10, 10)), run in-process as `ldcbf-sim deadline`
//! runs it and rebuilt from its logs (`ldcbf_sim::studies::replay`). The map of size
//! `n` is those 8 polygons followed by `n - 8` small filler polygons (0.1-0.4
//! m across, 3-6 vertices, seeded) at the density, 10,000 per 110 m x
//! 110 m, in a square around the walk but outside the box [-6, 16]² m: farther
//! than `r_active` (4 m) from every `p_0` of the walk. So every map gives
//! exactly the cycles of the 8-polygon map (checked before timing: the outputs
//! on every map, with the index and with the full scan, are the logged ones
//! bit for bit), and the times differ only by what the map's size costs.
//!
//! Two ways to run a cycle:
//!
//! * `indexed`: `Controller::obstacle_query`, the candidates
//!   (`ldcbf_sim::world::obstacle_index::Candidates`: the R-tree queried 0.5 m
//!   beyond `r_active` around `p_0`, the list reused while it covers later
//!   cycles) and `Controller::step` on them: what the simulator does with a
//!   known map;
//! * `queried`: the same with the R-tree queried every cycle
//!   (`ObstacleIndex::candidates_into`, sorted indices), no reuse;
//! * `full`: `Controller::step` on the whole map (before issue 14).
//!
//! One criterion iteration is one cycle, walking through the run in order with
//! the warm start carried (criterion's estimate is the mean per cycle).
//!
//! # Per-cycle table (printed first)
//!
//! `R` passes over the run (`MAP_SCALING_PASSES`, default 30; 1 under `cargo
//! test --benches`), `Instant` around each cycle (query and step), each
//! cycle's time the minimum over the passes; printed per map size and mode:
//! median, p99 (and max) over the cycles, and the `indexed` median relative to
//! the full scan's on the 8-polygon map, i.e. to `step` before issue 14 (the
//! issue's target: at most 1.5 at 100,000 polygons).
//!
//! # Perceived obstacles (LiDAR)
//!
//! The cycles of `crowded@0` (LiDAR: each cycle's obstacles are those inferred
//! from its scan, a few per cycle), two ways: `step` on the perceived list
//! (what the simulator does), and an index rebuilt from the list each cycle,
//! queried, then `step` on the candidates. Same timing as the table.
//!
//! `cargo bench --bench map_scaling` (all); `cargo bench --bench map_scaling --
//! none` prints the tables alone.

use std::hint::black_box;
use std::time::Instant;

use criterion::{BenchmarkId, Criterion};
use ldcbf_controller::{CycleOutput, RobotController};
use ldcbf_sim::sim::HORIZON;
use ldcbf_sim::studies::deadline::Case;
use ldcbf_sim::studies::replay::{Recording, record_case};
use ldcbf_sim::world::Polygon;
use ldcbf_sim::world::obstacle_index::{Candidates, ObstacleIndex};

/// Map sizes of the table (the first is the recorded map itself).
const SIZES: [usize; 5] = [8, 10, 1_000, 10_000, 100_000];

/// Filler density, polygons per m² (the 10,000 over 110 m x 110 m).
const DENSITY: f64 = 10_000.0 / (110.0 * 110.0);

/// The box no filler touches, m: the walk (0..10 m) plus 6 m.
const CLEAR: [f64; 2] = [-6.0, 16.0];

/// Default number of timed passes of the tables.
const DEFAULT_PASSES: usize = 30;

/// SplitMix64: a small seeded generator, the same on every platform.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
    fn unif(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
}

/// `base` followed by `n - base.len()` fillers (see the module docs).
fn map_of(base: &[Polygon], n: usize) -> Vec<Polygon> {
    let mut map = base.to_vec();
    let fillers = n.saturating_sub(base.len());
    // The square holds the fillers at DENSITY around the clear box grown by
    // 0.5 m (so that even 2 fillers have room outside the box).
    let clear_area = (CLEAR[1] - CLEAR[0] + 1.0).powi(2);
    let side = (fillers as f64 / DENSITY + clear_area).sqrt();
    let (lo, hi) = (5.0 - side / 2.0, 5.0 + side / 2.0);
    let mut rng = Rng(n as u64);
    while map.len() < n {
        let (cx, cy) = (rng.unif(lo, hi), rng.unif(lo, hi));
        let r = rng.unif(0.05, 0.2);
        if cx + r > CLEAR[0] && cx - r < CLEAR[1] && cy + r > CLEAR[0] && cy - r < CLEAR[1] {
            continue;
        }
        let k = 3 + (rng.next() * 4.0) as usize;
        let pts: Vec<[f64; 2]> = (0..k)
            .map(|_| {
                let a = rng.unif(0.0, std::f64::consts::TAU);
                let rr = r * rng.unif(0.5, 1.0);
                [cx + rr * a.cos(), cy + rr * a.sin()]
            })
            .collect();
        if let Ok(p) = Polygon::hull(&pts) {
            map.push(p);
        }
    }
    map
}

/// A map, its index and the run's cycles on it.
struct Map {
    n: usize,
    map: Vec<Polygon>,
    index: ObstacleIndex,
}

/// Cycle `i` of `rec` on `map`: query, candidates (reused while they cover
/// the cycle), `step` on the candidates.
fn indexed(
    ctl: &mut RobotController,
    rec: &Recording,
    i: usize,
    m: &Map,
    candidates: &mut Candidates,
) -> CycleOutput<HORIZON> {
    let mut input = rec.input(i).expect("cycle");
    input.obstacles = &m.map;
    match ctl.obstacle_query(&input) {
        Ok(q) => ctl.step(&input, Some(candidates.update(&m.index, &q))),
        Err(_) => ctl.step(&input, Some(&[])),
    }
}

/// Cycle `i` of `rec` on `map`: query, the R-tree queried, `step` on the candidates.
fn queried(
    ctl: &mut RobotController,
    rec: &Recording,
    i: usize,
    m: &Map,
    candidates: &mut Vec<u32>,
) -> CycleOutput<HORIZON> {
    let mut input = rec.input(i).expect("cycle");
    input.obstacles = &m.map;
    match ctl.obstacle_query(&input) {
        Ok(q) => m.index.candidates_into(&q, candidates),
        Err(_) => candidates.clear(),
    }
    ctl.step(&input, Some(candidates))
}

/// Cycle `i` of `rec` on `map`, the whole map scanned.
fn full(ctl: &mut RobotController, rec: &Recording, i: usize, m: &Map) -> CycleOutput<HORIZON> {
    let mut input = rec.input(i).expect("cycle");
    input.obstacles = &m.map;
    ctl.step(&input, None)
}

/// Every cycle's output, indexed and full, is the logged one.
fn check(rec: &Recording, m: &Map) {
    let mut a = rec.controller().unwrap();
    let mut b = rec.controller().unwrap();
    let mut c = rec.controller().unwrap();
    let mut cand = Vec::new();
    let mut cache = Candidates::default();
    for i in 0..rec.len() {
        let logged = format!("{:?}", rec.outputs[i]);
        let out = indexed(&mut a, rec, i, m, &mut cache);
        assert_eq!(format!("{out:?}"), logged, "indexed, n = {} cycle {i}", m.n);
        let out = queried(&mut c, rec, i, m, &mut cand);
        assert_eq!(format!("{out:?}"), logged, "queried, n = {} cycle {i}", m.n);
        let out = full(&mut b, rec, i, m);
        assert_eq!(format!("{out:?}"), logged, "full, n = {} cycle {i}", m.n);
    }
}

/// Per-cycle minimum over `passes` passes of `f(ctl, i)`, ns (`start` is
/// called before each pass).
fn per_cycle(
    rec: &Recording,
    passes: usize,
    mut start: impl FnMut(),
    mut f: impl FnMut(&mut RobotController, usize) -> CycleOutput<HORIZON>,
) -> Vec<u64> {
    let mut best = vec![u64::MAX; rec.len()];
    for _ in 0..passes {
        start();
        let mut ctl = rec.controller().unwrap();
        for (i, b) in best.iter_mut().enumerate() {
            let t0 = Instant::now();
            black_box(f(&mut ctl, i));
            *b = (*b).min(t0.elapsed().as_nanos() as u64);
        }
    }
    best
}

/// (median, p99, max) of `v`, ns.
fn stats(v: &[u64]) -> (u64, u64, u64) {
    let mut s = v.to_vec();
    s.sort_unstable();
    let q = |p: f64| s[((s.len() - 1) as f64 * p).round() as usize];
    (q(0.5), q(0.99), *s.last().unwrap())
}

fn table(rec: &Recording, maps: &[Map], lidar: &Recording, passes: usize) {
    println!(
        "\nmap_scaling: {} cycles of {}, {passes} passes, per-cycle minimum; ns",
        rec.len(),
        rec.label
    );
    println!(
        "| obstacles | indexed median | p99 | max | median / 8-polygon map's full scan | queried every cycle: median | p99 | full scan: median | p99 |"
    );
    println!("|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    let mut base = 0;
    for m in maps {
        // The full scan of the large maps takes long: fewer passes.
        let fp = if m.n >= 10_000 { passes.min(3) } else { passes };
        let fu = per_cycle(rec, fp, || {}, |c, i| full(c, rec, i, m));
        if base == 0 {
            base = stats(&fu).0;
        }
        let cache = std::cell::RefCell::new(Candidates::default());
        let ix = per_cycle(
            rec,
            passes,
            || cache.borrow_mut().clear(),
            |c, i| indexed(c, rec, i, m, &mut cache.borrow_mut()),
        );
        let mut cand = Vec::new();
        let qu = per_cycle(rec, passes, || {}, |c, i| queried(c, rec, i, m, &mut cand));
        let (med, p99, max) = stats(&ix);
        let (qmed, qp99, _) = stats(&qu);
        let (fmed, fp99, _) = stats(&fu);
        println!(
            "| {} | {med} | {p99} | {max} | {:.2} | {qmed} | {qp99} | {fmed} | {fp99} |",
            m.n,
            med as f64 / base as f64,
        );
    }
    // LiDAR: the perceived list scanned, or indexed per scan.
    let linear = per_cycle(
        lidar,
        passes,
        || {},
        |c, i| c.step(&lidar.input(i).unwrap(), None),
    );
    let mut cand = Vec::new();
    let rebuilt = per_cycle(
        lidar,
        passes,
        || {},
        |c, i| {
            let input = lidar.input(i).unwrap();
            let index = ObstacleIndex::new(input.obstacles).unwrap();
            match c.obstacle_query(&input) {
                Ok(q) => index.candidates_into(&q, &mut cand),
                Err(_) => cand.clear(),
            }
            c.step(&input, Some(&cand))
        },
    );
    let seen: Vec<usize> = (0..lidar.len())
        .map(|i| lidar.input(i).unwrap().obstacles.len())
        .collect();
    println!(
        "\n{} ({} cycles, LiDAR, {:.1} perceived obstacles per cycle on average, max {}):",
        lidar.label,
        lidar.len(),
        seen.iter().sum::<usize>() as f64 / seen.len() as f64,
        seen.iter().max().unwrap()
    );
    println!("| per cycle | median | p99 | max |");
    println!("|---|---:|---:|---:|");
    for (name, v) in [
        ("step on the perceived list", &linear),
        (
            "index rebuilt per scan + query + step on the candidates",
            &rebuilt,
        ),
    ] {
        let (a, b, c) = stats(v);
        println!("| {name} | {a} | {b} | {c} |");
    }
    println!();
}

fn main() {
    let bench_mode = std::env::args().any(|a| a == "--bench");
    let listing = std::env::args().any(|a| a == "--list");
    let passes = if bench_mode {
        std::env::var("MAP_SCALING_PASSES")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(DEFAULT_PASSES)
    } else {
        1
    };
    let case: Case = "random@0".parse().unwrap();
    let rec = record_case(&case, &[]).expect("random@0 runs");
    rec.verify().expect("the recording replays");
    let base = rec.obstacle_sets[0].clone();
    assert_eq!(base.len(), SIZES[0]);
    let maps: Vec<Map> = SIZES
        .iter()
        .map(|&n| {
            let map = map_of(&base, n);
            let index = ObstacleIndex::new(&map).unwrap();
            Map { n, map, index }
        })
        .collect();
    for m in &maps {
        check(&rec, m);
    }
    let lidar = record_case(&"crowded@0".parse().unwrap(), &[]).expect("crowded@0 runs");
    if passes > 0 && !listing {
        table(&rec, &maps, &lidar, passes);
    }
    let mut cr = Criterion::default().without_plots().configure_from_args();
    let mut g = cr.benchmark_group("map_scaling");
    g.warm_up_time(std::time::Duration::from_secs(1));
    g.measurement_time(std::time::Duration::from_secs(3));
    for m in &maps {
        let mut ctl = rec.controller().unwrap();
        let mut i = 0;
        let mut cache = Candidates::default();
        g.bench_with_input(BenchmarkId::new("indexed", m.n), m, |b, m| {
            b.iter(|| {
                if i == 0 {
                    ctl.reset();
                    cache.clear();
                }
                let out = indexed(&mut ctl, &rec, i, m, &mut cache);
                i = (i + 1) % rec.len();
                out
            })
        });
        let mut ctl = rec.controller().unwrap();
        let mut i = 0;
        let mut cand = Vec::new();
        g.bench_with_input(BenchmarkId::new("queried", m.n), m, |b, m| {
            b.iter(|| {
                if i == 0 {
                    ctl.reset();
                }
                let out = queried(&mut ctl, &rec, i, m, &mut cand);
                i = (i + 1) % rec.len();
                out
            })
        });
        if m.n <= 10_000 {
            let mut ctl = rec.controller().unwrap();
            let mut i = 0;
            g.bench_with_input(BenchmarkId::new("full", m.n), m, |b, m| {
                b.iter(|| {
                    if i == 0 {
                        ctl.reset();
                    }
                    let out = full(&mut ctl, &rec, i, m);
                    i = (i + 1) % rec.len();
                    out
                })
            });
        }
    }
    g.finish();
    cr.final_summary();
}
