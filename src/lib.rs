//! Workspace root package: hosts the cross-crate integration tests in `tests/`
//! and the benchmarks in `benches/`, and the fixtures they share ([`fixtures`]).

pub mod fixtures {
    //! Shared test and benchmark fixtures: the `paper` scenario's obstacles and a
    //! miniature closed loop that records controller cycles (as the
    //! simulator's [`RecordedInput`]).
    //!
    //! The loop is the simulator's in miniature (`host-sim/src/sim/mod.rs` is the
    //! full one): the controller runs at 20 Hz (8 cycles per 0.4 s step) on the exact
    //! state, the LIP is integrated in closed form over each 50 ms, and at each
    //! step end the swing foot lands on the last `foot_target`, the stance side
    //! flips and the last `turning_rate` takes effect for the new step.

    /// A recorded cycle's input: the simulator's type (its replay's), with the
    /// goal in it and obstacle list 0 (goal and obstacles are fixed per walk).
    pub use ldcbf_controller::RecordedInput;
    use ldcbf_controller::nalgebra::Vector2;
    use ldcbf_controller::{Config, Controller, ConvexPolygon, CycleOutput, Side};

    /// Goal of the `paper` scenario, m (world).
    pub const PAPER_GOAL: [f64; 2] = [10.0, 10.0];

    /// Obstacle point sets of the `paper` scenario (each obstacle is the
    /// convex hull of its points), m (world).
    pub const PAPER_OBSTACLES: [&[[f64; 2]]; 6] = [
        &[[2.0, 7.5], [1.5, 7.0], [1.8, 6.5]],
        &[[4.0, 6.5], [4.3, 6.8], [4.7, 6.5], [4.5, 6.2], [4.1, 6.2]],
        &[[7.0, 7.0], [7.5, 7.5], [8.0, 7.0], [7.5, 6.5]],
        &[[6.0, 2.5], [6.5, 2.0], [7.0, 2.5]],
        &[[1.5, 3.0], [1.8, 3.3], [2.2, 3.0], [2.0, 2.6], [1.6, 2.6]],
        &[[2.5, 3.5], [2.8, 3.8], [3.2, 3.5], [3.0, 3.1], [2.6, 3.1]],
    ];

    /// The `paper` obstacles as polygons of capacity `V`.
    pub fn paper_obstacles<const V: usize>() -> Vec<ConvexPolygon<V>> {
        PAPER_OBSTACLES
            .iter()
            .map(|s| ConvexPolygon::hull(s).expect("the paper obstacles are valid"))
            .collect()
    }

    /// A robot with a body and feet: the simulator's `[robot]` defaults
    /// (body radius 0.25 m, feet 0.22 x 0.10 m) with the foot-clearance rows
    /// on (clearance 0 m), the rest [`Config::default`].
    pub fn robot_config() -> Config {
        Config {
            body_radius: 0.25,
            foot_length: 0.22,
            foot_width: 0.10,
            foot_clearance: Some(0.0),
            ..Config::default()
        }
    }

    /// Cycle `i` of an open-loop walk (inputs that do not react to the
    /// commands): the CoM moves at (0.2, 0.15) m/s from the origin, heading
    /// 0.6 rad, 20 Hz, 8 cycles a step from the left foot, the stance foot
    /// 0.05 m beside the CoM, toward the goal (4, 5) m, among obstacle
    /// list 0. World frame.
    pub fn open_loop_walk(i: u32) -> RecordedInput {
        let t = f64::from(i) * 0.05;
        let side = if (i / 8).is_multiple_of(2) {
            Side::Left
        } else {
            Side::Right
        };
        RecordedInput {
            com_position: Vector2::new(0.2 * t, 0.15 * t),
            com_velocity: Vector2::new(0.2, 0.15),
            heading: 0.6,
            turning_rate: 0.0,
            stance_foot: Vector2::new(0.2 * t, 0.15 * t - 0.05 * side.sign()),
            stance_side: side,
            time_in_step: f64::from(i % 8) * 0.05,
            goal: Vector2::new(4.0, 5.0),
            obstacles: 0,
            speed_cap: ldcbf_controller::NO_SPEED_CAP,
        }
    }

    /// Walks from [`RecordedInput::at_rest`] toward `goal` with a fresh controller of
    /// the given sizes (default configuration, iteration budgets scaled by
    /// `Config::with_budgets_for_horizon`), for at most `max_steps` steps or
    /// until the CoM is within 0.15 m of the goal; returns every cycle's input and
    /// output, in order.
    pub fn walk<
        const N: usize,
        const NV: usize,
        const NC: usize,
        const NOBS: usize,
        const V: usize,
    >(
        obstacles: &[ConvexPolygon<V>],
        goal: Vector2<f64>,
        max_steps: usize,
    ) -> Vec<(RecordedInput, CycleOutput<N>)> {
        // Budgets scaled for the horizon (unchanged at N = 3).
        let config = Config::default().with_budgets_for_horizon(N);
        let mut ctl = Controller::<N, NV, NC, NOBS>::new(config).expect("valid config");
        let lip = *ctl.lip();
        let t_step = ctl.config().step_duration;
        let dt = t_step / 8.0;
        let mut c = RecordedInput::at_rest(goal);
        let mut out = Vec::new();
        for _ in 0..8 * max_steps {
            let cmd = ctl.step(&c.input(obstacles), None);
            out.push((c, cmd));
            let (p, v) = lip.propagate(&c.com_position, &c.com_velocity, &c.stance_foot, dt);
            c.com_position = p;
            c.com_velocity = v;
            c.heading += c.turning_rate * dt;
            c.time_in_step += dt;
            if c.time_in_step >= t_step - 1e-9 {
                c.time_in_step = 0.0;
                c.stance_foot = cmd.foot_target;
                c.stance_side = c.stance_side.opposite();
                c.turning_rate = cmd.turning_rate;
            }
            if (c.com_position - goal).norm() < 0.15 {
                break;
            }
        }
        out
    }
}
