//! Unit tests of the reference: Clarabel and our solver on hand-made problems,
//! the agreement contract, and the npz layout.

use std::path::Path;

use ldcbf_controller::QpStatus;

use super::npz::parse_npy_f64;
use super::*;

fn small() -> DenseProblem {
    // min (x-1)^2 + (y-2)^2  s.t. x + y <= 1
    DenseProblem::inequalities(
        2,
        vec![2.0, 0.0, 0.0, 2.0],
        vec![-2.0, -4.0],
        vec![1.0, 1.0],
        vec![1.0],
    )
}

#[test]
fn clarabel_and_own_agree_on_a_hand_problem() {
    let p = small();
    let r = solve_clarabel(&p);
    assert_eq!(r.status, RefStatus::Solved);
    assert!((r.x[0] - 0.0).abs() < 1e-8 && (r.x[1] - 1.0).abs() < 1e-8);
    let own = solve_own::<2, 4>(&p, 20).unwrap();
    let a = compare(&p, &own, &r);
    assert!(a.holds(), "{a:?}");
    let k = kkt(&p, own.x.as_slice(), &own.lambda.as_slice()[..p.m]);
    assert!(k.max() < 1e-12, "{k:?}");
}

#[test]
fn infeasible_agreement() {
    let p = DenseProblem::inequalities(
        2,
        vec![2.0, 0.0, 0.0, 2.0],
        vec![0.0, 0.0],
        vec![1.0, 0.0, -1.0, 0.0],
        vec![-1.0, -1.0],
    );
    let r = solve_clarabel(&p);
    assert_eq!(r.status, RefStatus::Infeasible);
    let own = solve_own::<2, 4>(&p, 20).unwrap();
    assert_eq!(own.status, QpStatus::Infeasible);
    let a = compare(&p, &own, &r);
    assert!(a.feasibility_agrees && !a.both_solved && a.holds());
}

#[test]
fn disagreement_is_detected() {
    let p = small();
    let r = solve_clarabel(&p);
    let mut own = solve_own::<2, 4>(&p, 20).unwrap();
    own.x[0] += 1e-5;
    assert!(!compare(&p, &own, &r).holds());
    own.status = QpStatus::Infeasible;
    assert!(!compare(&p, &own, &r).feasibility_agrees);
}

#[test]
fn npz_round_trip() {
    let p = DenseProblem::inequalities(
        2,
        vec![2.0, 0.5, 0.5, 1.0],
        vec![-1.0, 0.25],
        vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0],
        vec![0.1, 0.2, 0.3],
    );
    let path = std::env::temp_dir().join(format!("ldcbf_ref_{}.npz", std::process::id()));
    p.write_npz(&path).unwrap();
    let back = DenseProblem::from_npz(&path).unwrap();
    std::fs::remove_file(&path).unwrap();
    assert_eq!(back, p);
}

#[test]
fn npy_headers_are_checked_against_the_data() {
    let npy = |descr: &str, shape: &str, data: &[u8]| {
        let mut h = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
        h.push('\n');
        let mut b = b"\x93NUMPY\x01\x00".to_vec();
        b.extend_from_slice(&(h.len() as u16).to_le_bytes());
        b.extend_from_slice(h.as_bytes());
        b.extend_from_slice(data);
        b
    };
    let two: Vec<u8> = [1.5f64, -2.0]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let (shape, fortran, v) = parse_npy_f64(&npy("<f8", "(2,)", &two)).unwrap();
    assert_eq!((shape, fortran, v), (vec![2], false, vec![1.5, -2.0]));
    let be: Vec<u8> = [1.5f64, -2.0]
        .iter()
        .flat_map(|v| v.to_be_bytes())
        .collect();
    assert_eq!(
        parse_npy_f64(&npy(">f8", "(1, 2)", &be)).unwrap().2,
        vec![1.5, -2.0]
    );
    for (b, msg) in [
        (npy("<f8", "(3,)", &two), "does not match the 16 bytes"),
        (npy("<f8", "(1,)", &two), "does not match the 16 bytes"),
        (
            npy("<f8", "(4294967296, 4294967296)", &two),
            "does not match",
        ),
        (npy("<f4", "(4,)", &two), "dtype '<f4' is not float64"),
        (npy("<f8", "(x,)", &two), "malformed `shape`"),
        (
            b"\x93NUMPY\x01\x00\xff\x00{".to_vec(),
            "truncated or malformed .npy header",
        ),
        (b"PK\x03\x04".to_vec(), "not an .npy array"),
    ] {
        let e = parse_npy_f64(&b).unwrap_err();
        assert!(e.contains(msg), "{e}");
    }
}

#[test]
fn wrong_size_is_an_error() {
    assert!(small().to_fixed::<3, 4>().is_err());
    assert!(
        DenseProblem::from_npz(Path::new("/nonexistent.npz"))
            .unwrap_err()
            .to_string()
            .contains("/nonexistent.npz")
    );
}

// ------------------------------------------------------------ every member

/// `min (x-1)^2 + (y-2)^2` with the rows and bounds given.
fn two_var(A: Vec<f64>, b: Vec<f64>, lb: Vec<f64>, ub: Vec<f64>) -> DenseProblem {
    DenseProblem {
        me: b.len(),
        A,
        b,
        lb,
        ub,
        ..DenseProblem::inequalities(
            2,
            vec![2.0, 0.0, 0.0, 2.0],
            vec![-2.0, -4.0],
            vec![],
            vec![],
        )
    }
}

/// The numpy-written fixtures of `tests/data/make_fixtures.py`.
fn fixture(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

/// Float64 members `(key, shape, data)` of an npz file.
type Members<'a> = Vec<(&'a str, &'a [u64], &'a [f64])>;

/// Writes float64 members `(key, shape, data)` to an npz file.
fn write_members(path: &Path, members: &[(&str, &[u64], &[f64])]) {
    use npyz::WriterBuilder;
    let mut npz = npyz::npz::NpzWriter::create(path).unwrap();
    for (key, shape, data) in members {
        let mut w = npz
            .array::<f64>(key, Default::default())
            .unwrap()
            .default_dtype()
            .shape(shape)
            .begin_nd()
            .unwrap();
        w.extend(data.iter().copied()).unwrap();
        w.finish().unwrap();
    }
}

fn temp_npz(tag: &str) -> std::path::PathBuf {
    std::env::temp_dir().join(format!("ldcbf_ref_{tag}_{}.npz", std::process::id()))
}

#[test]
fn npz_round_trip_of_every_member() {
    let inf = f64::INFINITY;
    let full = DenseProblem {
        n: 3,
        m: 1,
        me: 2,
        P: vec![4.0, 1.0, 0.0, 1.0, 3.0, 0.5, 0.0, 0.5, 2.0],
        q: vec![1.0, -2.0, 0.5],
        G: vec![1.0, 1.0, 1.0],
        h: vec![1.0],
        A: vec![1.0, -1.0, 2.0, 0.0, 1.0, 1.0],
        b: vec![0.5, 0.3],
        lb: vec![-inf, -1.0, 0.0],
        ub: vec![1.0, inf, 2.0],
    };
    let bounds_only = DenseProblem {
        m: 0,
        G: vec![],
        h: vec![],
        me: 0,
        A: vec![],
        b: vec![],
        lb: vec![],
        ..full.clone()
    };
    for (tag, p) in [("full", full), ("bounds", bounds_only)] {
        let path = temp_npz(tag);
        p.write_npz(&path).unwrap();
        let back = DenseProblem::from_npz(&path);
        std::fs::remove_file(&path).unwrap();
        assert_eq!(back.unwrap(), p, "{tag}");
    }
}

#[test]
fn numpy_files_with_absent_and_empty_members_are_read() {
    let inf = f64::INFINITY;
    let full = DenseProblem::from_npz(&fixture("full.npz")).unwrap();
    assert_eq!((full.n, full.m, full.me), (3, 2, 2));
    // `A` is stored in Fortran order: read back row-major.
    assert_eq!(full.A, vec![1.0, -1.0, 2.0, 0.0, 1.0, 1.0]);
    assert_eq!(full.b, vec![0.5, 0.3]);
    assert_eq!(full.lb, vec![-inf, -1.0, 0.0]);
    assert_eq!(full.ub, vec![1.0, inf, 2.0]);
    let none = DenseProblem::from_npz(&fixture("none.npz")).unwrap();
    assert_eq!(
        none,
        DenseProblem::inequalities(3, full.P.clone(), full.q.clone(), vec![], vec![])
    );
    let empty = DenseProblem::from_npz(&fixture("empty.npz")).unwrap();
    assert_eq!(
        DenseProblem {
            ub: vec![],
            ..empty.clone()
        },
        none
    );
    assert_eq!(empty.ub, full.ub);
    // The external set: numpy's pickled None of another protocol.
    let lip = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/lipmwalk/LIPMWALK0.npz");
    let lip = DenseProblem::from_npz(&lip).unwrap();
    assert_eq!(
        (lip.n, lip.m, lip.me, lip.lb.len(), lip.ub.len()),
        (16, 32, 0, 0, 0)
    );
    for (name, msg) in [
        (
            "half_pair.npz",
            "half_pair.npz: key `G`: is a pickled None, but `h` is given (shape [2])",
        ),
        (
            "object.npz",
            "object.npz: key `lb`: dtype '|O' is not float64",
        ),
    ] {
        let e = DenseProblem::from_npz(&fixture(name))
            .unwrap_err()
            .to_string();
        assert!(e.contains(msg), "{e}");
    }
}

#[test]
fn bad_members_are_rejected_naming_the_key() {
    let p: &[f64] = &[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
    let q: &[f64] = &[0.0; 3];
    let row: &[f64] = &[1.0, 2.0, 3.0];
    let cases: Vec<(Members, &str)> = vec![
        (
            vec![("A", &[1, 2], &[1.0, 2.0]), ("b", &[1], &[0.0])],
            "key `A` has shape [1, 2], expected [me, 3]",
        ),
        (
            vec![("A", &[1, 3], row), ("b", &[2], &[0.0, 1.0])],
            "key `b` has shape [2], expected [1] (the rows of `A`)",
        ),
        (
            vec![("A", &[1, 3], row)],
            "key `b`: is missing, but `A` is given (shape [1, 3])",
        ),
        (
            vec![("G", &[0, 3], &[]), ("h", &[1], &[1.0])],
            "key `G`: is empty, but `h` is given (shape [1])",
        ),
        (
            vec![("lb", &[2], &[0.0, 0.0])],
            "key `lb` has shape [2], expected [3] (the size of `P`)",
        ),
        (
            vec![("ub", &[1, 3], row)],
            "key `ub` has shape [1, 3], expected [3] (the size of `P`)",
        ),
        (
            vec![("lb", &[3], &[0.0, f64::NAN, 0.0])],
            "key `lb`: entry [1] is NaN",
        ),
        (
            vec![("lb", &[3], &[0.0, f64::INFINITY, 0.0])],
            "key `lb`: entry [1] is +inf",
        ),
        (
            vec![("ub", &[3], &[0.0, f64::NEG_INFINITY, 0.0])],
            "key `ub`: entry [1] is -inf",
        ),
        (
            vec![
                ("A", &[1, 3], &[1.0, 2.0, f64::INFINITY]),
                ("b", &[1], &[0.0]),
            ],
            "key `A`: entry [0, 2] is infinite",
        ),
        (
            vec![("G", &[1, 3], row), ("h", &[1], &[f64::NAN])],
            "key `h`: entry [0] is NaN",
        ),
        (
            vec![
                ("lb", &[3], &[0.0, 2.0, 0.0]),
                ("ub", &[3], &[1.0, 1.0, 1.0]),
            ],
            "key `lb`: lb[1] = 2 is above ub[1] = 1",
        ),
    ];
    let path = temp_npz("bad");
    for (extra, msg) in cases {
        let mut members: Members = vec![("P", &[3, 3], p), ("q", &[3], q)];
        members.extend(extra);
        write_members(&path, &members);
        let e = DenseProblem::from_npz(&path).unwrap_err().to_string();
        assert!(
            e.starts_with(&path.display().to_string()) && e.contains(msg),
            "{e}\nwanted {msg}"
        );
    }
    std::fs::remove_file(&path).unwrap();
    // The same checks on a problem in memory name the field.
    let mut bad = two_var(vec![], vec![], vec![0.0, 0.0], vec![1.0, -1.0]);
    let e = bad.validate().unwrap_err().to_string();
    assert_eq!(e, "field `lb`: lb[1] = 0 is above ub[1] = -1");
    bad.ub = vec![1.0];
    assert!(
        bad.validate()
            .unwrap_err()
            .to_string()
            .contains("field `ub` has 1 entries, expected 2")
    );
    assert_eq!(solve_clarabel(&bad).status, RefStatus::Failed);
}

#[test]
fn stacked_rows_come_in_order_and_split_back() {
    let inf = f64::INFINITY;
    let p = DenseProblem {
        n: 3,
        m: 1,
        me: 1,
        P: vec![1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
        q: vec![0.0; 3],
        G: vec![4.0, 5.0, 6.0],
        h: vec![7.0],
        A: vec![1.0, 2.0, 3.0],
        b: vec![8.0],
        lb: vec![-inf, 0.5, 1.0],
        ub: vec![2.0, inf, 3.0],
    };
    let st = p.stacked();
    assert_eq!((st.n, st.me, st.m, p.rows()), (3, 1, 6, 6));
    use RowOrigin::*;
    assert_eq!(
        st.origin,
        vec![Eq(0), Ineq(0), Upper(0), Upper(2), Lower(1), Lower(2)]
    );
    #[rustfmt::skip]
    let g = vec![
        1.0, 2.0, 3.0,
        4.0, 5.0, 6.0,
        1.0, 0.0, 0.0,
        0.0, 0.0, 1.0,
        0.0, -1.0, 0.0,
        0.0, 0.0, -1.0,
    ];
    assert_eq!(st.G, g);
    assert_eq!(st.h, vec![8.0, 7.0, 2.0, 3.0, -0.5, -1.0]);
    assert!(st.origin[0].is_equality() && !st.origin[1].is_equality());
    let y = st
        .split_multipliers(&[10.0, 20.0, 30.0, 40.0, 50.0, 60.0])
        .unwrap();
    assert_eq!(y.eq, vec![10.0]);
    assert_eq!(y.ineq, vec![20.0]);
    assert_eq!(y.upper, vec![30.0, 0.0, 40.0]);
    assert_eq!(y.lower, vec![0.0, 50.0, 60.0]);
    assert_eq!(y.z_box(), vec![30.0, -50.0, -20.0]);
    assert!(st.split_multipliers(&[1.0; 5]).is_err());
    // x = (2, 0.5, 1): the bounds hold; the equality row is off by
    // 2 + 1 + 3 - 8 = -2, the inequality by 8 + 2.5 + 6 - 7 = 9.5.
    assert_eq!(p.max_violation(&[2.0, 0.5, 1.0]), 9.5);
    assert!(p.max_violation(&[0.0; 2]).is_nan());
}

#[test]
fn equalities_and_bounds_are_solved_with_signed_multipliers() {
    // x + y = 1, y <= 0.5: x = y = 0.5; 2(x - 1) + y_eq = 0 gives y_eq = 1,
    // 2(y - 2) + y_eq + u = 0 gives u = 2.
    let p = two_var(vec![1.0, 1.0], vec![1.0], vec![], vec![f64::INFINITY, 0.5]);
    let r = solve_clarabel(&p);
    assert_eq!(r.status, RefStatus::Solved);
    assert!(r.polished);
    let close = |a: &[f64], b: &[f64]| a.iter().zip(b).all(|(u, v)| (u - v).abs() < 1e-9);
    assert!(close(&r.x, &[0.5, 0.5]), "{:?}", r.x);
    assert!(close(&r.z, &[1.0, 2.0]), "{:?}", r.z);
    let k = kkt_stacked(&p, &r.x, &r.z).unwrap();
    assert!(k.max() < 1e-12, "{k:?}");
    // x + y = 4, x <= 1.2: x = 1.2, y = 2.8; 2(y - 2) + y_eq = 0 gives a
    // negative y_eq = -1.6, which the polish keeps (free sign), and
    // 2(x - 1) + y_eq + u = 0 gives u = 1.2.
    let p = two_var(vec![1.0, 1.0], vec![4.0], vec![], vec![1.2, f64::INFINITY]);
    let r = solve_clarabel(&p);
    assert_eq!(r.status, RefStatus::Solved);
    assert!(r.polished);
    assert!(
        close(&r.x, &[1.2, 2.8]) && close(&r.z, &[-1.6, 1.2]),
        "{:?} {:?}",
        r.x,
        r.z
    );
    let k = kkt_stacked(&p, &r.x, &r.z).unwrap();
    assert!(k.max() < 1e-12 && k.dual == 0.0, "{k:?}");
    assert!(kkt_stacked(&p, &r.x, &[]).is_err());
    // The numpy fixture with every member.
    let p = DenseProblem::from_npz(&fixture("full.npz")).unwrap();
    let r = solve_clarabel(&p);
    assert_eq!(r.status, RefStatus::Solved);
    assert_eq!(r.z.len(), p.rows());
    let k = kkt_stacked(&p, &r.x, &r.z).unwrap();
    assert!(k.max() < 1e-9, "{k:?}");
}

#[test]
fn farkas_certificates_are_checked() {
    // x + y = 3 with x <= 1, y <= 1: y = (-1, 1, 1) gives G'y = 0, h'y = -1.
    let p = two_var(vec![1.0, 1.0], vec![3.0], vec![], vec![1.0, 1.0]);
    let st = p.stacked();
    assert!(farkas_holds(&st, &[-1.0, 1.0, 1.0], 1e-12));
    assert!(farkas_holds(&st, &[-1e-6, 1e-6, 1e-6], 1e-12), "scale-free");
    let f = farkas_residuals(&st, &[-1.0, 1.0, 1.0]).unwrap();
    assert_eq!((f.sign, f.stationarity), (0.0, 0.0));
    assert!((f.objective + 0.2).abs() < 1e-15, "{f:?}"); // -1 / (3 + 1 + 1)
    assert!(!farkas_holds(&st, &[1.0, -1.0, -1.0], 1e-9), "wrong signs");
    assert!(!farkas_holds(&st, &[-1.0, 1.0, 0.5], 1e-9), "G'y != 0");
    assert!(!farkas_holds(&st, &[0.0; 3], 1e-9) && !farkas_holds(&st, &[1.0], 1e-9));
    let r = solve_clarabel(&p);
    assert_eq!(r.status, RefStatus::Infeasible);
    assert!(
        farkas_holds(&st, &r.z, 1e-9),
        "{:?}",
        farkas_residuals(&st, &r.z)
    );
    // Our answer as slices: a good certificate agrees, a bad one does not.
    let own = |status, x: &'static [f64], y: &'static [f64]| Candidate {
        status,
        x,
        y,
        objective: f64::NAN,
    };
    let a = compare_stacked(&p, &own(QpStatus::Infeasible, &[], &[-2.0, 2.0, 2.0]), &r);
    assert!(a.holds() && a.certificate == Some(true), "{a:?}");
    let a = compare_stacked(&p, &own(QpStatus::Infeasible, &[], &[0.0, 1.0, 1.0]), &r);
    assert!(!a.holds() && a.certificate == Some(false), "{a:?}");
    let a = compare_stacked(&p, &own(QpStatus::Solved, &[1.0, 2.0], &[]), &r);
    assert!(!a.holds() && !a.feasibility_agrees);
}

#[test]
fn stacked_agreement_of_solved_problems() {
    let p = two_var(vec![1.0, 1.0], vec![1.0], vec![], vec![f64::INFINITY, 0.5]);
    let r = solve_clarabel(&p);
    let mut x = r.x.clone();
    let cand = |x: &[f64]| {
        compare_stacked(
            &p,
            &Candidate {
                status: QpStatus::Solved,
                x,
                y: &r.z,
                objective: p.objective(x),
            },
            &r,
        )
    };
    let a = cand(&x);
    assert!(
        a.holds() && a.both_solved && a.certificate.is_none(),
        "{a:?}"
    );
    assert_eq!((a.dx, a.objective), (0.0, 0.0));
    x[0] += 2e-6;
    let a = cand(&x);
    assert!(!a.holds() && a.primal() > 1e-6, "{a:?}");
    assert!(!cand(&x[..1]).holds(), "x of the wrong length");
    let a = compare_stacked(
        &p,
        &Candidate {
            status: QpStatus::IterationLimit,
            x: &r.x,
            y: &r.z,
            objective: r.objective,
        },
        &r,
    );
    assert!(!a.holds());
}

#[test]
fn bounds_reach_our_fixed_size_solver_as_rows() {
    // min (x-1)^2 + (y-2)^2, x + y <= 1, 0.25 <= x, y <= 0.5: x = y = 0.5.
    let p = DenseProblem {
        lb: vec![0.25, f64::NEG_INFINITY],
        ub: vec![f64::INFINITY, 0.5],
        ..small()
    };
    assert_eq!(p.rows(), 3);
    let own = solve_own::<2, 4>(&p, 20).unwrap();
    let r = solve_clarabel(&p);
    assert!(compare(&p, &own, &r).holds());
    let y = &own.lambda.as_slice()[..p.rows()];
    let c = Candidate {
        status: own.status,
        x: own.x.as_slice(),
        y,
        objective: own.objective,
    };
    assert!(compare_stacked(&p, &c, &r).holds());
    assert!(kkt_stacked(&p, own.x.as_slice(), y).unwrap().max() < 1e-12);
    assert!(kkt(&p, own.x.as_slice(), own.lambda.as_slice()).max() < 1e-12);
    let m = p.stacked().split_multipliers(y).unwrap();
    assert!(m.upper[1] > 0.0 && m.lower == vec![0.0, 0.0]);
    assert!(
        solve_own::<2, 2>(&p, 20).is_err(),
        "3 rows do not fit NC = 2"
    );
    // Equality rows reach the solver as equalities (`me`); the static
    // instance holds them from 16 variables on, the dynamic one always.
    let eq = two_var(vec![1.0, 1.0], vec![1.0], vec![], vec![]);
    let (_, qp) = eq.to_fixed::<2, 4>().unwrap();
    assert_eq!((qp.m, qp.me), (1, 1));
    let own = solve_own::<2, 4>(&eq, 20).unwrap();
    assert_eq!(own.status, QpStatus::NumericalError);
    let own = crate::solve_own_dyn(&eq, 20).unwrap();
    assert_eq!(own.status, QpStatus::Solved);
    // min (x-1)^2 + (y-2)^2 with x + y = 1: x = 0, y = 1, multiplier 2.
    assert!((own.x[0]).abs() < 1e-14 && (own.x[1] - 1.0).abs() < 1e-14);
    assert!((own.lambda[0] - 2.0).abs() < 1e-12);
}
