// The obstacles' velocities of the firmware's second and third passes
// (moving obstacles), m/s, world frame, one per obstacle of `recorded.rs` (in
// its order). Both passes replay the same recorded inputs, which do not react
// to the motion. In the second pass the obstacles move away from the recorded
// path (the diagonal from (0, 0) to (10, 10)) or along it, at 0.1 to 0.2 m/s:
// the cost of the moving-obstacle rows on ordinary cycles. In the third they
// walk into the recorded path at 0.3 to 0.6 m/s: the replayed robot keeps
// walking into them, so many cycles are infeasible and run the priority
// scheme with the give-way policy (firmware/README.md). Shared by the
// firmware, the host test (`tests/firmware_qemu.rs`) and the benchmark
// `paper_config/step/warm-moving` (second pass only).

/// Velocity of each recorded obstacle in the second pass, m/s.
pub const VELOCITIES: [[f64; 2]; 6] = [
    [-0.1, 0.15],
    [-0.15, 0.1],
    [0.1, -0.1],
    [0.15, -0.1],
    [-0.1, 0.1],
    [-0.05, 0.15],
];

/// Velocity of each recorded obstacle in the third pass (walking into the
/// recorded path), m/s.
pub const WALK_INTO: [[f64; 2]; 6] = [
    [0.3, -0.2],
    [-0.4, 0.0],
    [0.0, 0.5],
    [0.2, 0.2],
    [-0.3, 0.3],
    [0.0, -0.6],
];
