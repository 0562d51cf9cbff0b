//! Hostile values through the C API: every tolerance bounded as the
//! controller bounds it, no OK with a non-finite output, and `last_error`
//! cleared by a success.

use super::*;

#[test]
fn absurd_tolerances_are_refused_naming_the_field() {
    for tol in [1e300, 1e-3, 0.0, -1e-12, f64::NAN, f64::INFINITY] {
        let mut s = storage();
        let ctl = init(&mut s);
        let mut cfg = default_config();
        cfg.tol_primal = tol;
        assert_eq!(
            unsafe { ldcbf_configure(ctl, &cfg) },
            LdcbfResult::InvalidConfig,
            "tol_primal = {tol}"
        );
        assert!(last_error(ctl).contains("`tol_primal`"), "{tol}");
    }
}

#[test]
fn lip_propagate_never_returns_ok_with_non_finite_outputs() {
    let mut s = storage();
    let ctl = configured(&mut s, &default_config());
    let (p, v, f) = ([0.1, -0.2], [0.3, 0.05], [0.0, 0.1]);
    let call = |tau: f64, p1: &mut [f64; 2], v1: &mut [f64; 2]| unsafe {
        ldcbf_lip_propagate(
            ctl,
            p.as_ptr(),
            v.as_ptr(),
            f.as_ptr(),
            tau,
            p1.as_mut_ptr(),
            v1.as_mut_ptr(),
        )
    };
    // beta = sqrt(9.81 / 0.8) = 3.5 1/s: cosh(beta tau) overflows near
    // tau = 710 / 3.5 = 203 s.
    for tau in [1.0, 100.0, -100.0, 200.0] {
        let (mut p1, mut v1) = ([0.0; 2], [0.0; 2]);
        assert_eq!(call(tau, &mut p1, &mut v1), LdcbfResult::Ok, "tau {tau}");
        assert!(p1.iter().chain(&v1).all(|x| x.is_finite()), "tau {tau}");
    }
    for tau in [227.0, -227.0, 1e6, 1e300, f64::MAX] {
        let (mut p1, mut v1) = ([7.0; 2], [7.0; 2]);
        assert_eq!(
            call(tau, &mut p1, &mut v1),
            LdcbfResult::InvalidArgument,
            "tau {tau}"
        );
        assert_eq!((p1, v1), ([7.0; 2], [7.0; 2]), "nothing written, tau {tau}");
    }
}

#[test]
fn a_success_clears_the_last_error() {
    let mut s = storage();
    let ctl = init(&mut s);
    let mut bad = default_config();
    bad.gamma = 2.0;
    assert_eq!(
        unsafe { ldcbf_configure(ctl, &bad) },
        LdcbfResult::InvalidConfig
    );
    assert!(last_error(ctl).contains("`gamma`"));
    assert_eq!(
        unsafe { ldcbf_configure(ctl, &default_config()) },
        LdcbfResult::Ok
    );
    assert_eq!(last_error(ctl), "no error");
    // A refused step, then a step that runs.
    let mut input = input_at_rest();
    input.stance_side = 7;
    let mut out = sentinel();
    assert_eq!(
        step(ctl, &input, &[], &[], &mut out),
        LdcbfResult::InvalidArgument
    );
    assert!(last_error(ctl).contains("stance_side"));
    assert_eq!(
        step(ctl, &input_at_rest(), &[], &[], &mut out),
        LdcbfResult::Ok
    );
    assert_eq!(last_error(ctl), "no error");
}
