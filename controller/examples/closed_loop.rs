//! A closed loop in one file: the paper's controller walks a simulated robot
//! from the origin to a goal 4 m away, around one obstacle in its way.
//!
//! ```sh
//! cargo run --release -p ldcbf-controller --example closed_loop
//! ```
//!
//! The robot is a stand-in for the simulator's plant (`host-sim/src/plant/`):
//! the linear inverted pendulum of `docs/maths.md` §1 in closed form, stepping
//! every 0.4 s onto the last commanded foot target. The controller runs at
//! 20 Hz (8 cycles per step). Every quantity is in the world frame, SI units.

use ldcbf_controller::nalgebra::Vector2;
use ldcbf_controller::{
    Config, ConvexPolygon, CycleInput, PaperController, Side, closest_point_point_polygon,
};

/// The robot's measured state: what the controller is given each cycle.
struct Robot {
    /// CoM position, m.
    position: Vector2<f64>,
    /// CoM velocity, m/s.
    velocity: Vector2<f64>,
    /// Heading, rad.
    heading: f64,
    /// Turning rate in force during this step, rad/s.
    turning_rate: f64,
    /// Stance foot position, m.
    stance_foot: Vector2<f64>,
    /// Stance side.
    stance_side: Side,
    /// Time already spent in this step, s.
    time_in_step: f64,
}

impl Robot {
    /// The LIP flow over `dt` seconds on the stance foot, per axis:
    /// `p'' = beta^2 (p - f)` with `beta = sqrt(g / H)`.
    fn advance(&mut self, dt: f64, beta: f64) {
        let (c, s) = ((beta * dt).cosh(), (beta * dt).sinh());
        let offset = self.position - self.stance_foot;
        self.position = self.stance_foot + c * offset + (s / beta) * self.velocity;
        self.velocity = beta * s * offset + c * self.velocity;
        self.heading += self.turning_rate * dt;
        self.time_in_step += dt;
    }
}

/// The controller's input for this cycle (the one place it is built).
fn cycle_input<'a>(
    robot: &Robot,
    goal: Vector2<f64>,
    obstacles: &'a [ConvexPolygon<8>],
) -> CycleInput<'a, 8> {
    CycleInput {
        com_position: robot.position,
        com_velocity: robot.velocity,
        heading: robot.heading,
        turning_rate: robot.turning_rate,
        stance_foot: robot.stance_foot,
        stance_side: robot.stance_side,
        time_in_step: robot.time_in_step,
        goal,
        obstacles,
        obstacle_velocities: &[], // every obstacle at rest
        obstacle_velocity_radii: &[],
        speed_cap: ldcbf_controller::NO_SPEED_CAP,
    }
}

fn main() {
    let config = Config::default(); // the paper's Table I
    let beta = (config.gravity / config.com_height).sqrt();
    let step = config.step_duration;
    let dt = step / 8.0; // 20 Hz
    let mut controller = PaperController::new(config).expect("the defaults are valid");

    let goal = Vector2::new(4.0, 0.0);
    // A square turned by 45 degrees, a little below the straight line: its
    // slanted face deflects the walk to the left.
    let corners = [[1.6, -0.15], [2.0, -0.55], [2.4, -0.15], [2.0, 0.25]];
    let obstacles = [ConvexPolygon::<8>::hull(&corners).expect("a valid convex polygon")];

    let mut robot = Robot {
        position: Vector2::zeros(),
        velocity: Vector2::zeros(),
        heading: 0.0,
        turning_rate: 0.0,
        stance_foot: Vector2::zeros(),
        stance_side: Side::Left,
        time_in_step: 0.0,
    };
    let mut min_clearance = f64::INFINITY;
    for cycle in 0..8 * 60 {
        let out = controller.step(&cycle_input(&robot, goal, &obstacles), None);
        robot.advance(dt, beta);
        let clearance = closest_point_point_polygon(&robot.position, &obstacles[0]).signed_distance;
        min_clearance = min_clearance.min(clearance);
        if robot.time_in_step >= step - 1e-9 {
            // Step end: the swing foot lands on the target, the sides swap.
            robot.stance_foot = out.foot_target;
            robot.stance_side = robot.stance_side.opposite();
            robot.turning_rate = out.turning_rate;
            robot.time_in_step = 0.0;
            let steps = (cycle + 1) / 8;
            if steps % 5 == 0 {
                println!(
                    "step {steps:2}: CoM ({:5.2}, {:5.2}) m, cycle {}, command {}, {} QP iterations",
                    robot.position.x,
                    robot.position.y,
                    out.status,
                    out.info.source,
                    out.info.iterations,
                );
            }
        }
        if (robot.position - goal).norm() <= 0.15 {
            println!(
                "goal reached after {:.2} s; CoM at least {min_clearance:.3} m from the obstacle \
                 (sampled at 20 Hz)",
                (cycle + 1) as f64 * dt
            );
            return;
        }
    }
    eprintln!("goal not reached in 60 steps");
    std::process::exit(1);
}
