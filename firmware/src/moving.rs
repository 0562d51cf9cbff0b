// The obstacles' velocities of the firmware's second pass (moving obstacles),
// m/s, world frame, one per obstacle of `recorded.rs` (in its order): the
// recorded cycles are replayed again with the obstacles moving at walking
// speeds. Shared by the firmware and the host test (`tests/firmware_qemu.rs`).

/// Velocity of each recorded obstacle in the second pass, m/s.
pub const VELOCITIES: [[f64; 2]; 6] = [
    [0.3, -0.2],
    [-0.4, 0.0],
    [0.0, 0.5],
    [0.2, 0.2],
    [-0.3, 0.3],
    [0.0, -0.6],
];
