// The obstacles' velocities of the firmware's second pass (moving obstacles),
// m/s, world frame, one per obstacle of `recorded.rs` (in its order). The
// second pass replays the same recorded inputs, which do not react to the
// motion, so the obstacles move away from the recorded path (the diagonal
// from (0, 0) to (10, 10)) or along it, at 0.1 to 0.2 m/s: a replay in which
// they walk into the recorded path measures people walking into a robot that
// does not react, not the controller (firmware/README.md). Shared by the
// firmware, the host test (`tests/firmware_qemu.rs`) and the benchmark
// `paper_config/step/warm-moving`.

/// Velocity of each recorded obstacle in the second pass, m/s.
pub const VELOCITIES: [[f64; 2]; 6] = [
    [-0.1, 0.15],
    [-0.15, 0.1],
    [0.1, -0.1],
    [0.15, -0.1],
    [-0.1, 0.1],
    [-0.05, 0.15],
];
