//! The node on DDS (ros2-client over RustDDS): topics with ROS 2's naming
//! (`rt/<name>`, `<pkg>::msg::dds_::<Type>_`), the QoS, and the loop that
//! hands messages to [`NavNode`] and publishes what it returns.
//!
//! QoS (docs/ros2.md): `/odom` and `/scan` are sensor data, best effort, keep last 5 (a
//! lost sample is replaced by the next); `/goal_pose`, `/gait_state` and every
//! output are reliable, keep last 10, volatile.

use std::time::{Duration, Instant};

use anyhow::{Context as _, Result};
use ros2_client::dds::rustdds::{DomainParticipantBuilder, Topic};
use ros2_client::{
    Context, MessageTypeName, Name, Node, NodeName, NodeOptions, Publisher, QosProfile,
    Subscription,
    qos::{Durability, History, WhenFull},
};

use crate::msgs::{
    DiagnosticArray, FootstepCommand, GaitState, LaserScan, MarkerArray, Odometry, Path,
    PoseStamped,
};
use crate::node::{CycleMessages, NavNode};
use crate::params::{NODE_NAME, Params};

/// A message's ROS 2 interface: its package, its type name and the QoS of the
/// topics that carry it (the one place that maps a message to them).
pub trait Interface: ros2_client::Message {
    /// The interface package, e.g. `nav_msgs`.
    const PACKAGE: &'static str;
    /// The type name within the package, e.g. `Odometry`.
    const TYPE: &'static str;
    /// The QoS of its topics, publisher and subscriber alike.
    fn qos() -> QosProfile;
}

macro_rules! interfaces {
    ($($t:ident: $pkg:literal, $qos:ident;)*) => {$(
        impl ros2_client::Message for $t {}
        impl Interface for $t {
            const PACKAGE: &'static str = $pkg;
            const TYPE: &'static str = stringify!($t);
            fn qos() -> QosProfile {
                $qos()
            }
        }
    )*};
}
interfaces! {
    LaserScan: "sensor_msgs", sensor_qos;
    Odometry: "nav_msgs", sensor_qos;
    GaitState: "ldcbf_msgs", reliable_qos;
    PoseStamped: "geometry_msgs", reliable_qos;
    FootstepCommand: "ldcbf_msgs", reliable_qos;
    Path: "nav_msgs", reliable_qos;
    MarkerArray: "visualization_msgs", reliable_qos;
    DiagnosticArray: "diagnostic_msgs", reliable_qos;
}

/// Sensor data: best effort, keep last 5, volatile.
pub fn sensor_qos() -> QosProfile {
    QosProfile::subscription_default()
        .reliability_best_effort()
        .durability(Durability::Volatile)
        .history(History::KeepLast { depth: 5 })
}

/// Goals, gait states, commands and visuals: reliable, keep last 10, volatile.
pub fn reliable_qos() -> QosProfile {
    QosProfile::publisher_default()
        .reliability_reliable(WhenFull::DEFAULT)
        .durability(Durability::Volatile)
        .history(History::KeepLast { depth: 10 })
}

/// A ROS 2 context on `domain_id`; with `localhost_only`, on the loopback
/// interface only.
pub fn context(domain_id: u16, localhost_only: bool) -> Result<Context> {
    let mut b = DomainParticipantBuilder::new(domain_id);
    if localhost_only {
        b = b.with_only_networks([std::net::Ipv4Addr::LOCALHOST]);
    }
    let dp = b.build().context("cannot create the DDS participant")?;
    Context::from_domain_participant(dp).context("cannot create the ROS 2 context")
}

/// A node named `name` in namespace `/`.
pub fn node(ctx: &Context, name: &str) -> Result<Node> {
    ctx.new_node(
        NodeName::new("/", name).context("node name")?,
        NodeOptions::new().enable_rosout(false),
    )
    .context("cannot create the node")
}

/// The topic `name` of type `pkg/msg/ty`.
pub fn topic(node: &mut Node, name: &str, pkg: &str, ty: &str, qos: &QosProfile) -> Result<Topic> {
    let (ns, base) = name.rsplit_once('/').unwrap_or(("", name));
    let ns = if ns.is_empty() { "/" } else { ns };
    let n = Name::new(ns, base).with_context(|| format!("topic name {name}"))?;
    node.create_topic(&n, MessageTypeName::new(pkg, ty), qos)
        .with_context(|| format!("cannot create topic {name}"))
}

/// A subscription to `name`, with `M`'s type and QoS ([`Interface`]).
pub fn subscribe<M: Interface + 'static + serde::de::DeserializeOwned>(
    node: &mut Node,
    name: &str,
) -> Result<Subscription<M>> {
    let qos = M::qos();
    let t = topic(node, name, M::PACKAGE, M::TYPE, &qos)?;
    node.create_subscription(&t, Some(qos))
        .with_context(|| format!("cannot subscribe to {name}"))
}

/// A publisher on `name`, with `M`'s type and QoS ([`Interface`]).
pub fn advertise<M: Interface + serde::Serialize>(
    node: &mut Node,
    name: &str,
) -> Result<Publisher<M>> {
    let qos = M::qos();
    let t = topic(node, name, M::PACKAGE, M::TYPE, &qos)?;
    node.create_publisher(&t, Some(qos))
        .with_context(|| format!("cannot publish on {name}"))
}

/// Takes every waiting message of `sub` (errors of single samples are
/// reported on stderr and skipped).
pub fn drain<M: 'static + serde::de::DeserializeOwned>(sub: &Subscription<M>) -> Vec<M> {
    let mut out = Vec::new();
    loop {
        match sub.take() {
            Ok(Some((m, _))) => out.push(m),
            Ok(None) => return out,
            Err(e) => {
                eprintln!("ldcbf-ros2: dropped a sample: {e:?}");
                return out;
            }
        }
    }
}

struct Outputs {
    command: Publisher<FootstepCommand>,
    footsteps: Publisher<Path>,
    markers: Publisher<MarkerArray>,
    diagnostics: Publisher<DiagnosticArray>,
}

impl Outputs {
    fn publish(&self, m: CycleMessages) -> Result<()> {
        let e = |what: &str| format!("cannot publish {what}");
        self.command
            .publish(m.command)
            .ok()
            .with_context(|| e("the command"))?;
        self.footsteps
            .publish(m.footsteps)
            .ok()
            .with_context(|| e("/footsteps"))?;
        self.markers
            .publish(m.markers)
            .ok()
            .with_context(|| e("the markers"))?;
        self.diagnostics
            .publish(m.diagnostics)
            .ok()
            .with_context(|| e("the diagnostics"))?;
        Ok(())
    }
}

/// Runs the node until `idle` passes without an input message (forever with
/// `None`). Returns the number of cycles run.
pub fn spin(params: &Params, mut nav: NavNode, idle: Option<Duration>) -> Result<u64> {
    let ctx = context(params.domain_id, params.localhost_only)?;
    let mut node = node(&ctx, NODE_NAME)?;
    let t = &params.topics;
    let goal: Subscription<PoseStamped> = subscribe(&mut node, &t.goal)?;
    let odom: Subscription<Odometry> = subscribe(&mut node, &t.odom)?;
    let gait: Subscription<GaitState> = subscribe(&mut node, &t.gait_state)?;
    let scan: Option<Subscription<LaserScan>> = if params.lidar {
        Some(subscribe(&mut node, &t.scan)?)
    } else {
        None
    };
    let out = Outputs {
        command: advertise(&mut node, &t.command)?,
        footsteps: advertise(&mut node, &t.footsteps)?,
        markers: advertise(&mut node, &t.markers)?,
        diagnostics: advertise(&mut node, &t.diagnostics)?,
    };
    let mut cycles = 0;
    let mut last_input = Instant::now();
    loop {
        let mut any = false;
        for g in drain(&goal) {
            any = true;
            if let Some(m) = nav.on_goal(&g) {
                out.publish(m)?;
                cycles += 1;
            }
        }
        // Scans and odometry before gait states: a gait state waits for them.
        for s in scan.as_ref().map(drain).unwrap_or_default() {
            any = true;
            if let Some(m) = nav.on_scan(s) {
                out.publish(m)?;
                cycles += 1;
            }
        }
        for o in drain(&odom) {
            any = true;
            if let Some(m) = nav.on_odom(o) {
                out.publish(m)?;
                cycles += 1;
            }
        }
        for g in drain(&gait) {
            any = true;
            if let Some(m) = nav.on_gait(g) {
                out.publish(m)?;
                cycles += 1;
            }
        }
        for line in nav.take_log() {
            eprintln!("ldcbf-ros2: {line}");
        }
        if any {
            last_input = Instant::now();
        } else if idle.is_some_and(|d| last_input.elapsed() > d) {
            return Ok(cycles);
        } else {
            std::thread::sleep(Duration::from_micros(200));
        }
    }
}

/// The robot stand-in on DDS ([`crate::robot`]): publishes `/goal_pose`,
/// `/odom`, `/scan` (LiDAR scenarios) and `/gait_state` with the node's topic names and QoS, waits for
/// each cycle's command (re-sending the cycle's messages every `retry` until
/// it comes; the node ignores a repeated gait state) and applies it, until
/// the walk ends. Fails when no command comes for `timeout`.
pub fn run_robot(
    params: &Params,
    mut robot: crate::robot::Robot,
    retry: Duration,
    timeout: Duration,
) -> Result<(crate::robot::End, u64)> {
    let ctx = context(params.domain_id, params.localhost_only)?;
    let mut node = node(&ctx, "ldcbf_robot")?;
    let t = &params.topics;
    let goal: Publisher<PoseStamped> = advertise(&mut node, &t.goal)?;
    let odom: Publisher<Odometry> = advertise(&mut node, &t.odom)?;
    let gait: Publisher<GaitState> = advertise(&mut node, &t.gait_state)?;
    let command: Subscription<FootstepCommand> = subscribe(&mut node, &t.command)?;
    let scan: Publisher<LaserScan> = advertise(&mut node, &t.scan)?;
    let mut cycles = 0;
    loop {
        let (o, g, sc) = robot.sense();
        let stamp = g.header.stamp;
        let started = Instant::now();
        let mut sent = None::<Instant>;
        let cmd = loop {
            if sent.is_none_or(|s| s.elapsed() > retry) {
                let e = |w: &str| format!("cannot publish {w}");
                goal.publish(robot.goal())
                    .ok()
                    .with_context(|| e("the goal"))?;
                odom.publish(o.clone())
                    .ok()
                    .with_context(|| e("the odometry"))?;
                if let Some(sc) = &sc {
                    scan.publish(sc.clone())
                        .ok()
                        .with_context(|| e("the scan"))?;
                }
                gait.publish(g.clone())
                    .ok()
                    .with_context(|| e("the gait state"))?;
                sent = Some(Instant::now());
            }
            if let Some(c) = drain(&command)
                .into_iter()
                .find(|c| c.header.stamp == stamp)
            {
                break c;
            }
            anyhow::ensure!(
                started.elapsed() < timeout,
                "no footstep command for t = {} s within {timeout:?} (is ldcbf-ros2 running on domain {}?)",
                robot.time(),
                params.domain_id
            );
            std::thread::sleep(Duration::from_micros(200));
        };
        robot.apply(&cmd);
        cycles += 1;
        if let Some(end) = robot.advance() {
            return Ok((end, cycles));
        }
    }
}
