//! `qp solve` on small npz files (`ldcbf_sim::studies::qpbench`): the static
//! instance for the controller's size, the dynamic one for any other.

mod common;
use common::small_qp;
use ldcbf_controller::qp::QpStatus;
use ldcbf_reference::DenseProblem;
use ldcbf_sim::studies::qpbench::{CSV_HEADER, SolveOptions, solve_file};

#[test]
fn solves_a_small_file_statically_and_any_other_size_dynamically() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("a.npz");
    small_qp().write_npz(&f).unwrap();
    let opts = |check| SolveOptions {
        repeat: 3,
        max_iter: 50,
        check,
    };
    let row = solve_file(&f, &opts(true)).unwrap();
    assert_eq!(row.status, QpStatus::Solved);
    assert_eq!(row.iterations, 1);
    assert_eq!(row.ldp_iterations, 1);
    assert_eq!(row.csv().split(',').count(), CSV_HEADER.split(',').count());
    // x = (0.5, 0.5, 1, 1, 1, 1): objective = 4 * (-1) + 2 * (0.25 - 1) = -5.5
    assert!((row.objective + 5.5).abs() < 1e-12, "{}", row.objective);
    assert!(
        row.csv()
            .starts_with(&format!("{},6,1,solved,1,", f.display()))
    );
    // n = 7 has no static instance: the dynamic one solves it (x = 0).
    let mut q = DenseProblem::inequalities(7, vec![0.0; 49], vec![0.0; 7], vec![], vec![]);
    for i in 0..7 {
        q.P[i * 7 + i] = 1.0;
    }
    let g = dir.path().join("b.npz");
    q.write_npz(&g).unwrap();
    let row = solve_file(&g, &opts(false)).unwrap();
    assert_eq!(
        (row.path, row.status, row.clarabel),
        ("dynamic", QpStatus::Solved, None)
    );
    let e = solve_file(&dir.path().join("missing.npz"), &opts(false))
        .unwrap_err()
        .to_string();
    assert!(e.contains("missing.npz"), "{e}");
}
