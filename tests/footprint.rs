//! Memory footprint of the controller at the paper's configuration. `size_of` is
//! deterministic, so it is asserted: the whole controller (model, factored
//! Hessian, QP workspace, warm-start memory) must fit the 16 KiB RAM budget of
//! the onboard target with room to spare.

use ldcbf_controller::{CycleOutput, PaperController};

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
}
