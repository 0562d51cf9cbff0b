//! Memory footprint of the controller at the paper's configuration. `size_of` is
//! deterministic, so it is asserted: the whole controller (model, factored
//! Hessian, QP workspace, warm-start memory) must fit the 16 KiB RAM budget of
//! the onboard target with room to spare. An embedded target holds it in a
//! `static` initialised with the constant `Controller::UNCONFIGURED` and
//! configures it in place (as `firmware/` does), so it is never on the stack.

use ldcbf_controller::{Config, CycleOutput, PaperController};

/// Compiles only if the unconfigured controller is a constant.
static UNCONFIGURED: PaperController = PaperController::UNCONFIGURED;

#[test]
fn paper_controller_fits_in_static_memory() {
    let controller = core::mem::size_of::<PaperController>();
    let output = core::mem::size_of::<CycleOutput<3>>();
    println!(
        "size_of::<PaperController>() = {controller} bytes; size_of::<CycleOutput<3>>() = {output} bytes"
    );
    assert!(
        controller <= 8 * 1024,
        "PaperController is {controller} bytes"
    );
    assert!(output <= 1024, "CycleOutput is {output} bytes");
    assert!(!UNCONFIGURED.is_configured());
    let mut c = UNCONFIGURED.clone();
    c.configure(Config::default()).unwrap();
    assert!(c.is_configured());
}
