//! Link-time proof that the controller's public entry points cannot panic.
//!
//! Every input below comes from `read_volatile` on a static the optimiser knows
//! nothing about, so no branch of the controller can be constant-folded away:
//! configuration, sizes of the obstacle list and of every vertex list, every
//! coordinate, and whether the warm-start memory is reset. The binary is linked
//! with `panic-never`, whose panic handler calls an undefined symbol: if any
//! panicking branch survives optimisation, the link fails. See `README.md`.
#![no_std]
#![no_main]

use core::ptr::{addr_of, addr_of_mut, read_volatile, write_volatile};

use cortex_m_rt::entry;
use ldcbf_controller::nalgebra::Vector2;
use ldcbf_controller::nalgebra::{SMatrix, SVector};
use ldcbf_controller::{
    Config, Controller, ConvexPolygon, CycleInput, CycleOutput, DenseQp, DualActiveSet, LdpSolver,
    PaperController, QpSettings, Side, constraint_capacity,
};

#[cfg(not(feature = "never"))]
use panic_halt as _;
#[cfg(feature = "never")]
use panic_never as _;

/// Vertex capacity of the obstacles (the firmware's).
const V: usize = 8;
/// Obstacles handed to `step`: more than the controller's capacity (8), so the
/// truncation path is live.
const NPOLY: usize = 12;
/// Points per obstacle vertex list: more than `V`, so `TooManyVertices` is live.
const NPTS: usize = 10;

/// Opaque input words. Nothing writes them: the optimiser must assume any bits.
static mut RAW: [f64; 64] = [0.0; 64];
/// Opaque obstacle point lists.
static mut PTS: [[[f64; 2]; NPTS]; NPOLY] = [[[0.0; 2]; NPTS]; NPOLY];
/// Variables and rows of the least-distance path's QP (LIPMWALK's sizes).
const LNV: usize = 16;
const LNC: usize = 32;
/// Opaque QP data: H, G, q, h, prefer, sizes.
static mut QPRAW: [f64; LNV * LNV + LNC * LNV + LNV + 2 * LNC + 2] =
    [0.0; LNV * LNV + LNC * LNV + LNV + 2 * LNC + 2];

/// Opaque obstacle velocities (any bits, any count up to `NPOLY`).
static mut VEL: [[f64; 2]; NPOLY] = [[0.0; 2]; NPOLY];

/// Opaque velocity uncertainty radii (any bits, any count up to `NPOLY`).
static mut RAD: [f64; NPOLY] = [0.0; NPOLY];

/// Opaque candidate lists for `Controller::step` (any indices, in or out of range).
static mut CAND: [u32; 16] = [0; 16];

/// Outputs, written so that nothing is dead code.
static mut OUT: [f64; 16] = [0.0; 16];

fn raw() -> [f64; 64] {
    // SAFETY: plain volatile read of a static that is never referenced.
    unsafe { read_volatile(addr_of!(RAW)) }
}

fn points() -> [[[f64; 2]; NPTS]; NPOLY] {
    // SAFETY: as above.
    unsafe { read_volatile(addr_of!(PTS)) }
}

fn publish(v: [f64; 16]) {
    // SAFETY: plain volatile write of a static that is never referenced.
    unsafe { write_volatile(addr_of_mut!(OUT), v) }
}

/// Never reached (the default configuration and the triangle are valid).
fn stop() -> ! {
    loop {
        core::hint::spin_loop();
    }
}

/// An opaque length in `0..=max` (any bits: NaN and negative give 0).
fn len(x: f64, max: usize) -> usize {
    (x as usize).min(max)
}

/// A configuration in which every field is opaque. `Controller::new` validates
/// it; when that fails the default is used, so both paths are linked.
fn config(r: &[f64; 64]) -> Config {
    Config {
        gravity: r[30],
        com_height: r[31],
        step_duration: r[32],
        vx_min: r[33],
        vx_max: r[34],
        vy_min: r[35],
        vy_max: r[36],
        l_max: r[37],
        alpha: r[38],
        omega_max: r[39],
        gamma: r[40],
        delta: r[41],
        r_active: r[42],
        foot_clearance: if r[43] > 0.0 { Some(r[44]) } else { None },
        body_radius: r[54],
        foot_length: r[55],
        foot_width: r[56],
        heading_freeze_radius: r[45],
        max_iter: r[46] as u32,
        max_iter_cycle: r[47] as u32,
        relax_bisections: r[48] as u32,
        max_gait_relaxation: r[51],
        capture_fraction: if r[52] > 0.0 { Some(r[53]) } else { None },
        warm_start: r[49] > 0.0,
        tol_primal: r[50],
        turn_vertex_normals: r[57] > 0.0,
        velocity_margin: r[59] > 0.0,
        person_speed_max: r[60],
        person_accel_max: r[61],
        person_reach_time: r[63],
    }
}

fn input<'a>(
    r: &[f64; 64],
    obstacles: &'a [ConvexPolygon<V>],
    velocities: &'a [Vector2<f64>],
    radii: &'a [f64],
) -> CycleInput<'a, V> {
    CycleInput {
        com_position: Vector2::new(r[0], r[1]),
        com_velocity: Vector2::new(r[2], r[3]),
        heading: r[4],
        turning_rate: r[5],
        stance_foot: Vector2::new(r[6], r[7]),
        stance_side: if r[8] > 0.0 { Side::Right } else { Side::Left },
        time_in_step: r[9],
        goal: Vector2::new(r[10], r[11]),
        obstacles,
        obstacle_velocities: velocities,
        obstacle_velocity_radii: radii,
        speed_cap: ldcbf_controller::NO_SPEED_CAP,
    }
}

fn summary<const N: usize>(o: &CycleOutput<N>) -> [f64; 16] {
    let last = o.plan.states.last().map_or(0.0, |s| s.position.x);
    [
        o.foot_target.x,
        o.foot_target.y,
        o.turning_rate,
        o.info.cost,
        o.info.max_violation,
        o.info.min_h0,
        o.info.relax_gait,
        o.info.relax_safety + o.info.relax_capture,
        f64::from(o.info.iterations),
        f64::from(o.info.active_obstacles),
        o.status.name().len() as f64,
        o.info.source.name().len() as f64,
        last,
        f64::from(u8::from(o.info.obstacles_truncated)),
        f64::from(u8::from(o.info.time_clamped)),
        f64::from(u8::from(o.info.inside_obstacle)),
    ]
}

/// A controller with room for the foot-clearance rows (`PaperController` has none).
type FootController = Controller<3, 6, { constraint_capacity(3, 8, true) }, 8>;

#[entry]
fn main() -> ! {
    let r = raw();
    let cfg = config(&r);
    let mut paper = match PaperController::new(cfg) {
        Ok(c) => c,
        Err(_) => match PaperController::new(Config::default()) {
            Ok(c) => c,
            Err(_) => stop(),
        },
    };
    let mut foot = match FootController::new(cfg) {
        Ok(c) => c,
        Err(_) => match FootController::new(Config::default()) {
            Ok(c) => c,
            Err(_) => stop(),
        },
    };
    loop {
        let r = raw();
        let pts = points();
        // Obstacles: validated vertex lists or hulls of point sets, opaque sizes.
        let mut polys = [match ConvexPolygon::<V>::new(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]) {
            Ok(p) => p,
            Err(_) => stop(),
        }; NPOLY];
        let mut n = 0;
        for (i, list) in pts.iter().enumerate() {
            let k = len(r[12 + i % 8], NPTS);
            let list = &list[..k];
            let made = if r[20 + i % 8] > 0.0 {
                ConvexPolygon::<V>::hull(list)
            } else {
                ConvexPolygon::<V>::new(list)
            };
            if let (Ok(p), Some(slot)) = (made, polys.get_mut(n)) {
                *slot = p;
                n += 1;
            }
        }
        let obstacles = &polys[..n.min(len(r[28], NPOLY))];
        if r[29] > 0.0 {
            paper.reset();
            foot.reset();
        }
        // Reconfiguration in place, of a used controller and of an
        // unconfigured one (whose steps hold).
        if r[52] > 0.0 {
            let _ = paper.configure(config(&r));
        }
        if r[53] > 0.0 {
            foot = FootController::UNCONFIGURED;
            let _ = foot.configure(config(&r));
        }
        // SAFETY: plain volatile read of a static that is never referenced.
        let vel = unsafe { read_volatile(addr_of!(VEL)) }.map(|[x, y]| Vector2::new(x, y));
        // SAFETY: plain volatile read of a static that is never referenced.
        let rad = unsafe { read_volatile(addr_of!(RAD)) };
        let inp = input(
            &r,
            obstacles,
            &vel[..len(r[58], NPOLY)],
            &rad[..len(r[62], NPOLY)],
        );
        let a = paper.step(&inp, None);
        let b = foot.step(&inp, None);
        let mut out = summary(&a);
        for (o, x) in out.iter_mut().zip(summary(&b)) {
            *o += x;
        }
        // The large-map path: the query and a step among opaque candidates.
        // SAFETY: plain volatile read of a static that is never referenced.
        let cand = unsafe { read_volatile(addr_of!(CAND)) };
        let among = paper.step(&inp, Some(&cand[..len(r[57], cand.len())]));
        for (o, x) in out.iter_mut().zip(summary(&among)) {
            *o += x;
        }
        if let Ok(q) = foot.obstacle_query(&inp) {
            out[1] += q.center.x + q.center.y + q.padded_radius();
        }
        // The least-distance path (`LdpSolver`) on an opaque QP.
        // SAFETY: plain volatile read of a static that is never referenced.
        let d = unsafe { read_volatile(addr_of!(QPRAW)) };
        let hess = SMatrix::<f64, LNV, LNV>::from_fn(|i, j| d[i * LNV + j]);
        let o = LNV * LNV + LNV + LNC * LNV;
        let settings = QpSettings {
            max_iter: len(d[o + 2 * LNC + 1], 10_000) as u32,
            ..QpSettings::default()
        };
        if let Ok(solver) = DualActiveSet::<LNV, LNC>::new(&hess, settings) {
            let o = LNV * LNV;
            let mut qp = DenseQp::<LNV, LNC>::with_q(SVector::from_fn(|i, _| d[o + i]));
            let o = o + LNV;
            let m = len(d[o + LNC * LNV + 2 * LNC], LNC);
            for k in 0..m {
                let g = SVector::<f64, LNV>::from_fn(|i, _| d[o + k * LNV + i]);
                let _ = qp.push_row(&g, d[o + LNC * LNV + k]);
            }
            let o = o + LNC * LNV;
            let h = SVector::<f64, LNC>::from_fn(|i, _| d[o + i]);
            let mut prefer = [false; LNC];
            for (p, x) in prefer.iter_mut().zip(&d[o + LNC..o + 2 * LNC]) {
                *p = *x > 0.0;
            }
            let ldp = LdpSolver::prepare(&solver, &qp);
            let loaded = ldp.load(&qp.q, &h);
            let sol = ldp.solve(&loaded, &prefer);
            out[0] += sol.x[0] + sol.lambda[LNC - 1] + sol.objective;
        }
        publish(out);
    }
}
