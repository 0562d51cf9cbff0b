//! The people who react, inside the closed loop: their crowd
//! ([`crate::world::crowd::Crowd`]) is stepped every plant tick, seeing the
//! robot's body (its CoM and the plant's CoM velocity) when they see the
//! robot, and the true map ([`MovingMap`]) is put at their state, so that
//! the LiDAR, the oracle's obstacles and velocities, the clearances and the
//! contacts all read the people where they are.

use ldcbf_controller::nalgebra::Vector2;

use crate::world::crowd::{Crowd, RobotBody};
use crate::world::moving::MovingMap;

/// The crowd and where its people sit in the map's obstacle list.
#[derive(Clone, Debug)]
pub(super) struct People {
    crowd: Crowd,
    /// Index in the map of the first person.
    from: usize,
}

impl People {
    /// The people of a scenario (the last obstacles of `world` from `from`),
    /// among the walls of `world` (its obstacles at rest); `None` without
    /// people.
    pub(super) fn new(
        people: &[crate::world::crowd::Person],
        world: &MovingMap,
        from: usize,
    ) -> Option<Self> {
        (!people.is_empty()).then(|| People {
            crowd: Crowd::new(people.to_vec(), world.rest_obstacles()),
            from,
        })
    }

    /// Steps the crowd (ticks of `dt`, s) up to time `t` (s), the robot at
    /// `robot`, and puts the people of `world` at their state.
    pub(super) fn advance(&mut self, t: f64, dt: f64, robot: &RobotBody, world: &mut MovingMap) {
        while self.crowd.time() + 0.5 * dt < t {
            self.crowd.step(dt, Some(robot));
        }
        let starts = self.crowd.people().iter().map(|p| p.start);
        for (k, ((p, v), s)) in self
            .crowd
            .positions()
            .iter()
            .zip(self.crowd.velocities())
            .zip(starts)
            .enumerate()
        {
            let shift: Vector2<f64> = p - s;
            world.place(self.from + k, shift, *v);
        }
    }
}
