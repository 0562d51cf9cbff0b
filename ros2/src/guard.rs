//! What the node refuses and how it tells: the counters of refused inputs
//! ([`Rejections`], published in `/diagnostics`), the log lines the DDS loop
//! prints, and the clock the input stamps make ([`Clock`]), which notices a
//! stamp that goes back in time.
//!
//! **Clock jumps.** As `robot_localization` does (the last stamp per topic,
//! `last_message_times_`), the node compares each input's stamp with the
//! newest one seen on its topic (`/odom`, `/gait_state`, `/scan`): the stamps
//! of one publisher never decrease (DDS keeps a writer's order, and a
//! best-effort reader drops an older sample). `robot_localization` then
//! ignores the older message, which alone lets one far-future stamp silence
//! a topic for good; the node treats it as `tf2_ros::Buffer` treats ROS
//! time going back ("Detected jump back in time. Clearing TF buffer.") and
//! as `robot_localization`'s ROS 1 `reset_on_time_jump`: a jump back (a
//! simulation restarted, a bag replayed, a peer's clock set back, or a
//! far-future stamp before it), which it logs, counts and answers by a
//! reset (it forgets the odometry, the scan, the waiting gait state, the
//! last stamp planned on, the people it tracks and the known map's time
//! origin), then takes the message as the first of the new timeline. So a
//! far-future stamp costs the cycles up to the next message of its topic,
//! never more.

use crate::msgs::Time;

/// The input topics whose stamps make the node's clock.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Topic {
    /// `/odom`.
    Odom,
    /// `/gait_state`.
    Gait,
    /// `/scan`.
    Scan,
}

impl Topic {
    /// The default topic name, for the log.
    pub fn name(self) -> &'static str {
        match self {
            Topic::Odom => "/odom",
            Topic::Gait => "/gait_state",
            Topic::Scan => "/scan",
        }
    }
}

/// The newest stamp of each input topic (module docs).
#[derive(Clone, Debug, Default)]
pub struct Clock {
    newest: [Option<Time>; 3],
}

impl Clock {
    /// Takes `stamp` on `topic`; `Some(newest)` when it is older than the
    /// newest stamp seen there (a jump back: the clock then restarts from
    /// `stamp`, every other topic forgotten).
    pub fn observe(&mut self, topic: Topic, stamp: Time) -> Option<Time> {
        let slot = topic as usize;
        let jumped = self.newest[slot].filter(|t| stamp < *t);
        if jumped.is_some() {
            self.newest = [None; 3];
        }
        self.newest[slot] = Some(self.newest[slot].map_or(stamp, |t| t.max(stamp)));
        jumped
    }
}

/// Seconds from `from` to `to` (negative when `to` is earlier).
pub fn seconds_between(from: Time, to: Time) -> f64 {
    let s = |t: Time| f64::from(t.sec) + f64::from(t.nanosec) * 1e-9;
    s(to) - s(from)
}

/// Counts of refused inputs, by class (each also logged).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Rejections {
    /// Scans refused ([`crate::scan::check`]: rays, metadata, stamp).
    pub scans: u64,
    /// Gait states refused (stance side, stamp).
    pub gait_states: u64,
    /// Odometry refused (stamp).
    pub odometry: u64,
    /// Clock jumps back (each a reset).
    pub clock_jumps: u64,
}

impl Rejections {
    /// `(key, count)` for `/diagnostics`.
    pub fn values(&self) -> [(&'static str, u64); 4] {
        [
            ("rejected_scans", self.scans),
            ("rejected_gait_states", self.gait_states),
            ("rejected_odometry", self.odometry),
            ("clock_jumps_back", self.clock_jumps),
        ]
    }

    /// All refusals and resets.
    pub fn total(&self) -> u64 {
        self.scans + self.gait_states + self.odometry + self.clock_jumps
    }
}

/// Whether the `count`-th event of a class is logged: the first 10, then
/// each power of two (a flood of bad messages does not flood the log; the
/// count is in `/diagnostics`).
pub fn logged(count: u64) -> bool {
    count <= 10 || count.is_power_of_two()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn t(sec: i32) -> Time {
        Time { sec, nanosec: 0 }
    }

    #[test]
    fn a_stamp_back_on_its_topic_is_a_jump_and_restarts_the_clock() {
        let mut c = Clock::default();
        assert_eq!(c.observe(Topic::Gait, t(5)), None);
        assert_eq!(c.observe(Topic::Odom, t(6)), None);
        // The same stamp again is a repeat, not a jump.
        assert_eq!(c.observe(Topic::Gait, t(5)), None);
        // Other topics are not compared.
        assert_eq!(c.observe(Topic::Scan, t(1)), None);
        // A far-future stamp, then normal ones: one jump, then normal again.
        assert_eq!(c.observe(Topic::Gait, t(i32::MAX)), None);
        assert_eq!(c.observe(Topic::Gait, t(7)), Some(t(i32::MAX)));
        assert_eq!(c.observe(Topic::Gait, t(8)), None);
        // The jump forgot the other topics: /odom at 2 (< 6) is no jump.
        assert_eq!(c.observe(Topic::Odom, t(2)), None);
    }

    #[test]
    fn the_log_thins_out_a_flood() {
        let n = (1..=100_000).filter(|&k| logged(k)).count();
        assert_eq!(n, 10 + 13); // 1..=10, then 16, 32, ..., 65536
    }
}
