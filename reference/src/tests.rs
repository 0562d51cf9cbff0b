//! Unit tests of the reference: Clarabel and our solver on hand-made problems,
//! the agreement contract, and the npz layout.

use std::path::Path;

use ldcbf_controller::QpStatus;

use super::npz::parse_npy_f64;
use super::*;

fn small() -> DenseProblem {
    // min (x-1)^2 + (y-2)^2  s.t. x + y <= 1
    DenseProblem {
        n: 2,
        m: 1,
        P: vec![2.0, 0.0, 0.0, 2.0],
        q: vec![-2.0, -4.0],
        G: vec![1.0, 1.0],
        h: vec![1.0],
    }
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
    let p = DenseProblem {
        n: 2,
        m: 2,
        P: vec![2.0, 0.0, 0.0, 2.0],
        q: vec![0.0, 0.0],
        G: vec![1.0, 0.0, -1.0, 0.0],
        h: vec![-1.0, -1.0],
    };
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
    let p = DenseProblem {
        n: 2,
        m: 3,
        P: vec![2.0, 0.5, 0.5, 1.0],
        q: vec![-1.0, 0.25],
        G: vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0],
        h: vec![0.1, 0.2, 0.3],
    };
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
            .0
            .contains("/nonexistent.npz")
    );
}
