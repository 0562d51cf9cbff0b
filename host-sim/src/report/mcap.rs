//! `run.mcap`: a run as an MCAP log that Foxglove opens without plugins
//! (docs/foxglove.md says which panel shows which topic).
//!
//! Every message is JSON (`message_encoding = "json"`) with a JSON Schema
//! (`schema encoding = "jsonschema"`) named after Foxglove's well-known
//! schemas (`foxglove.SceneUpdate`, `foxglove.PosesInFrame`,
//! `foxglove.FrameTransform`), except the cycle diagnostics, our own
//! `ldcbf.CycleDiagnostics`. The schemas list only the fields written.
//! Log time, publish time and every `timestamp` are the simulated time (ns
//! from the start of the run). World frame `world` (m, rad), the CoM frame
//! `com`; z = 0 is the ground.
//!
//! The topics, with their message counts ([`expected_counts`]):
//!
//! | topic | schema | messages |
//! |---|---|---|
//! | `/tf` | `foxglove.FrameTransform` | `world -> com` at the samples of `trajectory.csv` |
//! | `/com_path` | `foxglove.PosesInFrame` | the CoM path so far (one pose per 50 ms; past 4,096 poses, 204.8 s, every second one, and so on: `MAX_PATH_POSES`), at each footstep |
//! | `/footsteps` | `foxglove.SceneUpdate` | one per footstep: its footprint (entity `foot_K`) |
//! | `/obstacles` | `foxglove.SceneUpdate` | once at t = 0: the true map's polygons |
//! | `/goal` | `foxglove.SceneUpdate` | once at t = 0: the goal and the planner's subgoals |
//! | `/perceived_obstacles` | `foxglove.SceneUpdate` | one per recorded LiDAR scan: the inferred polygons |
//! | `/half_planes` | `foxglove.SceneUpdate` | one per cycle: the active LDCBF half-planes |
//! | `/plan` | `foxglove.SceneUpdate` | one per cycle: the planned feet and predicted CoM |
//! | `/diagnostics` | `ldcbf.CycleDiagnostics` | one per cycle: status, source, solver figures |
//!
//! The per-cycle scene updates first delete everything on their topic, so the
//! 3D panel shows the current cycle only.

use std::collections::BTreeMap;
use std::io::BufWriter;
use std::path::Path;

use ldcbf_controller::Side;
use ldcbf_controller::nalgebra::Vector2;
use serde_json::{Value, json};

use crate::sim::{CycleRecord, SimResult};

/// The world frame id.
pub const WORLD_FRAME: &str = "world";
/// The CoM frame id (child of [`WORLD_FRAME`] on `/tf`).
pub const COM_FRAME: &str = "com";
/// 1 kHz samples between two poses of `/com_path` (50 ms).
pub const PATH_EVERY: usize = 50;

/// The topics of `run.mcap` and their schema names, in channel order.
pub const CHANNELS: [(&str, &str); 9] = [
    ("/tf", "foxglove.FrameTransform"),
    ("/com_path", "foxglove.PosesInFrame"),
    ("/footsteps", "foxglove.SceneUpdate"),
    ("/obstacles", "foxglove.SceneUpdate"),
    ("/goal", "foxglove.SceneUpdate"),
    ("/perceived_obstacles", "foxglove.SceneUpdate"),
    ("/half_planes", "foxglove.SceneUpdate"),
    ("/plan", "foxglove.SceneUpdate"),
    ("/diagnostics", "ldcbf.CycleDiagnostics"),
];

const TF: usize = 0;
const COM_PATH: usize = 1;
const FOOTSTEPS: usize = 2;
const OBSTACLES: usize = 3;
const GOAL: usize = 4;
const PERCEIVED: usize = 5;
const HALF_PLANES: usize = 6;
const PLAN: usize = 7;
const DIAGNOSTICS: usize = 8;

/// Messages per topic of [`CHANNELS`] that [`write_mcap`] writes for `r`
/// with `/tf` at the samples of `trajectory.csv` (every `every`-th and the
/// last; `every` = 0 counts as 1).
pub fn expected_counts(r: &SimResult, every: usize) -> [usize; 9] {
    let every = every.max(1);
    let cycles = r.cycles.len();
    // The samples of `trajectory.csv`: every `every`-th and the last.
    let n = r.samples.len();
    [
        n.div_ceil(every) + usize::from(n > 0 && !(n - 1).is_multiple_of(every)),
        r.footsteps.len(),
        r.footsteps.len(),
        1,
        1,
        r.scans.len(),
        cycles,
        cycles,
        cycles,
    ]
}

/// Simulated time in ns (times are >= 0; rounded to the ns).
fn nanos(t: f64) -> u64 {
    (t.max(0.0) * 1e9).round() as u64
}

fn stamp(t: f64) -> Value {
    let ns = nanos(t);
    json!({ "sec": ns / 1_000_000_000, "nsec": ns % 1_000_000_000 })
}

fn point(p: Vector2<f64>, z: f64) -> Value {
    json!({ "x": p.x, "y": p.y, "z": z })
}

/// A pose at `p` (height `z`) turned by `yaw` about z.
fn pose(p: Vector2<f64>, z: f64, yaw: f64) -> Value {
    let (s, c) = (0.5 * yaw).sin_cos();
    json!({ "position": point(p, z), "orientation": { "x": 0.0, "y": 0.0, "z": s, "w": c } })
}

fn color(r: f64, g: f64, b: f64, a: f64) -> Value {
    json!({ "r": r, "g": g, "b": b, "a": a })
}

fn side_color(side: Side) -> Value {
    match side {
        Side::Left => color(0.15, 0.45, 0.95, 0.9),
        Side::Right => color(0.95, 0.35, 0.15, 0.9),
    }
}

/// Line primitive types of `foxglove.LinePrimitive`.
const LINE_STRIP: u8 = 0;
const LINE_LOOP: u8 = 1;
const LINE_LIST: u8 = 2;

fn line(kind: u8, points: &[Vector2<f64>], thickness: f64, color: Value) -> Value {
    json!({
        "type": kind,
        "pose": pose(Vector2::zeros(), 0.0, 0.0),
        "thickness": thickness,
        "scale_invariant": false,
        "points": points.iter().map(|p| point(*p, 0.0)).collect::<Vec<_>>(),
        "color": color,
        "colors": [],
        "indices": [],
    })
}

/// Primitives of one entity.
#[derive(Default)]
struct Prims {
    lines: Vec<Value>,
    cubes: Vec<Value>,
    spheres: Vec<Value>,
}

fn entity(t: f64, id: &str, prims: Prims) -> Value {
    json!({
        "timestamp": stamp(t),
        "frame_id": WORLD_FRAME,
        "id": id,
        "lifetime": { "sec": 0, "nsec": 0 },
        "frame_locked": false,
        "metadata": [],
        "arrows": [],
        "cubes": prims.cubes,
        "spheres": prims.spheres,
        "cylinders": [],
        "lines": prims.lines,
        "triangles": [],
        "texts": [],
        "models": [],
    })
}

/// A scene update; `replace` first deletes every entity of the topic.
fn scene(t: f64, replace: bool, entities: Vec<Value>) -> Value {
    let deletions = if replace {
        vec![json!({ "timestamp": stamp(t), "type": 1, "id": "" })]
    } else {
        Vec::new()
    };
    json!({ "deletions": deletions, "entities": entities })
}

fn sphere(p: Vector2<f64>, diameter: f64, color: Value) -> Value {
    json!({
        "pose": pose(p, 0.0, 0.0),
        "size": { "x": diameter, "y": diameter, "z": diameter },
        "color": color,
    })
}

/// Entity `{prefix}_{j}`: the outline of the polygon with vertices `v`.
fn polygon(t: f64, prefix: &str, j: usize, v: &[Vector2<f64>]) -> Value {
    let prims = Prims {
        lines: vec![line(LINE_LOOP, v, 0.03, color(0.3, 0.3, 0.3, 1.0))],
        ..Prims::default()
    };
    entity(t, &format!("{prefix}_{j}"), prims)
}

/// `/half_planes`: each active half-plane's boundary (a 1.6 m segment through
/// its closest point `c`) and a 0.2 m tick along `eta` towards the safe side.
fn half_planes(c: &CycleRecord) -> Value {
    let mut pts = Vec::with_capacity(4 * c.half_planes.len());
    for hp in &c.half_planes {
        let (p, n) = (hp.half_plane.c, hp.half_plane.eta);
        let along = Vector2::new(-n.y, n.x) * 0.8;
        pts.extend([p - along, p + along, p, p + n * 0.2]);
    }
    let prims = Prims {
        lines: vec![line(LINE_LIST, &pts, 0.02, color(0.9, 0.1, 0.6, 0.9))],
        ..Prims::default()
    };
    scene(c.time, true, vec![entity(c.time, "half_planes", prims)])
}

/// `/plan`: the planned feet `f_0 .. f_{N-1}` (spheres, colored by side) and
/// the predicted CoM `x_0 .. x_N` (a line strip).
fn plan(c: &CycleRecord) -> Value {
    let p = &c.output.plan;
    let mut side = p.first_side;
    let mut spheres = Vec::with_capacity(p.feet.len());
    for f in &p.feet {
        spheres.push(sphere(*f, 0.08, side_color(side)));
        side = side.opposite();
    }
    let mut com = vec![p.x0.position];
    com.extend(p.states.iter().map(|s| s.position));
    let prims = Prims {
        lines: vec![line(LINE_STRIP, &com, 0.02, color(0.1, 0.7, 0.2, 1.0))],
        spheres,
        ..Prims::default()
    };
    scene(c.time, true, vec![entity(c.time, "plan", prims)])
}

fn diagnostics(c: &CycleRecord) -> Value {
    let o = &c.output;
    // NaN and inf are not JSON numbers: written as null.
    let num = |x: f64| if x.is_finite() { json!(x) } else { Value::Null };
    json!({
        "timestamp": stamp(c.time),
        "cycle": c.index,
        "step": c.step,
        "stance": c.stance_side.name(),
        "time_in_step": c.time_in_step,
        "status": o.status.name(),
        "source": o.info.source.name(),
        "iterations": o.info.iterations,
        "active_set": o.info.active_set_size,
        "active_obstacles": o.info.active_obstacles,
        "obstacles_truncated": o.info.obstacles_truncated,
        "compute_ns": c.compute_ns,
        "max_violation": num(o.info.max_violation),
        "cost": num(o.info.cost),
        "min_h0": num(o.info.min_h0),
        "relax_gait": o.info.relax_gait,
        "relax_safety": o.info.relax_safety,
        "relax_capture": o.info.relax_capture,
        "foot_target": point(o.foot_target, 0.0),
        "turning_rate": o.turning_rate,
        "goal": point(c.goal, 0.0),
    })
}

/// Most poses of one `/com_path` message: the path so far at one pose per
/// [`PATH_EVERY`] samples (50 ms) while it has at most this many (204.8 s),
/// then every second of them, and so on (the spacing doubles each time the
/// path would exceed it). Bounds each message, so that the file grows with
/// the run's length, not with its square.
pub const MAX_PATH_POSES: usize = 4096;

/// One message: (log time ns, channel index, JSON bytes).
type Message = (u64, usize, Vec<u8>);

/// The JSON bytes of `v` (a `Value` of ours always serialises).
fn bytes(v: &impl serde::Serialize) -> Vec<u8> {
    serde_json::to_vec(v).unwrap_or_default()
}

/// `/com_path` and `/footsteps` at each footstep of `r`: the CoM path up to
/// the footstep (at most `max_poses` poses, [`MAX_PATH_POSES`]) and the
/// footprint.
fn footstep_messages(r: &SimResult, max_poses: usize) -> impl Iterator<Item = [Message; 2]> + '_ {
    let robot = &r.scenario.robot;
    let (len, wid) = (robot.foot_length.max(0.04), robot.foot_width.max(0.04));
    let mut path: Vec<Value> = Vec::new();
    let (mut next_sample, mut stride) = (0, PATH_EVERY);
    r.footsteps.iter().map(move |f| {
        // The CoM path up to the footstep's time.
        while next_sample < r.samples.len() && r.samples[next_sample].time <= f.time {
            if path.len() >= max_poses.max(2) {
                // Keep the poses at multiples of twice the spacing.
                let mut k = 0;
                path.retain(|_| {
                    k += 1;
                    k % 2 == 1
                });
                stride *= 2;
            }
            let s = &r.samples[next_sample];
            path.push(pose(s.position, 0.0, s.heading));
            next_sample += stride;
        }
        let msg = json!({ "timestamp": stamp(f.time), "frame_id": WORLD_FRAME, "poses": path });
        let cube = json!({
            "pose": pose(f.position, 0.01, f.heading),
            "size": { "x": len, "y": wid, "z": 0.02 },
            "color": side_color(f.side),
        });
        let prims = Prims {
            cubes: vec![cube],
            ..Prims::default()
        };
        let foot = entity(f.time, &format!("foot_{}", f.index), prims);
        let t = nanos(f.time);
        [
            (t, COM_PATH, bytes(&msg)),
            (t, FOOTSTEPS, bytes(&scene(f.time, false, vec![foot]))),
        ]
    })
}

/// The `foxglove.SceneUpdate` of [`scene`] with `entities` serialised one at a
/// time as they are made (a map of many polygons is never one `Value`);
/// the same bytes (fields in the order `Value` writes them: sorted).
#[derive(serde::Serialize)]
struct LazyScene<I: Iterator<Item = Value> + Clone> {
    deletions: Vec<Value>,
    #[serde(serialize_with = "lazy_seq")]
    entities: I,
}

fn lazy_seq<S: serde::Serializer, I: Iterator<Item = Value> + Clone>(
    it: &I,
    s: S,
) -> Result<S::Ok, S::Error> {
    s.collect_seq(it.clone())
}

/// The scene of `polys` ([`polygons`]'s entities), written without holding
/// them all.
fn polygon_scene<'a>(
    t: f64,
    prefix: &'a str,
    polys: impl Iterator<Item = &'a [Vector2<f64>]> + Clone,
) -> Vec<u8> {
    let Value::Object(mut head) = scene(t, true, Vec::new()) else {
        return Vec::new();
    };
    bytes(&LazyScene {
        deletions: match head.remove("deletions") {
            Some(Value::Array(d)) => d,
            _ => Vec::new(),
        },
        entities: polys
            .enumerate()
            .map(move |(j, v)| polygon(t, prefix, j, v)),
    })
}

/// Every message of `r` in the order written: by log time, ties in channel
/// order, then in the order made. Each channel's messages are made in time
/// order; this merges them, making one message per channel at a time, so
/// that a long run is never held in memory whole.
fn messages(r: &SimResult, every: usize) -> impl Iterator<Item = Message> + '_ {
    let every = every.max(1);
    let n = r.samples.len();
    let tf = r
        .samples
        .iter()
        .enumerate()
        .filter(move |(i, _)| i.is_multiple_of(every) || i + 1 == n)
        .map(|(_, s)| {
            let (sz, cz) = (0.5 * s.heading).sin_cos();
            let tf = json!({
                "timestamp": stamp(s.time),
                "parent_frame_id": WORLD_FRAME,
                "child_frame_id": COM_FRAME,
                "translation": point(s.position, 0.0),
                "rotation": { "x": 0.0, "y": 0.0, "z": sz, "w": cz },
            });
            (nanos(s.time), TF, bytes(&tf))
        });
    let steps = footstep_messages(r, MAX_PATH_POSES).flatten();
    let map = std::iter::once_with(|| {
        let polys = r.scenario.obstacles.iter().map(|p| p.vertices());
        (0, OBSTACLES, polygon_scene(0.0, "obstacle", polys))
    });
    let goal = std::iter::once_with(|| {
        let nav = &r.navigation;
        let mut route = vec![r.scenario.start];
        route.extend(nav.subgoals.iter().copied());
        let mut spheres = vec![sphere(r.scenario.goal, 0.2, color(1.0, 0.8, 0.0, 1.0))];
        spheres.extend(
            nav.subgoals
                .iter()
                .map(|g| sphere(*g, 0.08, color(1.0, 0.8, 0.0, 0.6))),
        );
        let prims = Prims {
            lines: vec![line(LINE_STRIP, &route, 0.01, color(1.0, 0.8, 0.0, 0.6))],
            spheres,
            ..Prims::default()
        };
        let goal = scene(0.0, true, vec![entity(0.0, "goal", prims)]);
        (0, GOAL, bytes(&goal))
    });
    let seen = r.scans.iter().map(|s| {
        let t = r.cycles.get(s.cycle).map_or(0.0, |c| c.time);
        let polys = s.obstacles.iter().map(|p| p.vertices());
        (nanos(t), PERCEIVED, polygon_scene(t, "perceived", polys))
    });
    let cycles = r.cycles.iter().flat_map(|c| {
        let t = nanos(c.time);
        [
            (t, HALF_PLANES, bytes(&half_planes(c))),
            (t, PLAN, bytes(&plan(c))),
            (t, DIAGNOSTICS, bytes(&diagnostics(c))),
        ]
    });
    let streams: Vec<Box<dyn Iterator<Item = Message> + '_>> = vec![
        Box::new(tf),
        Box::new(steps),
        Box::new(map),
        Box::new(goal),
        Box::new(seen),
        Box::new(cycles),
    ];
    let mut heads: Vec<_> = streams.into_iter().map(Iterator::peekable).collect();
    std::iter::from_fn(move || {
        let next = heads
            .iter_mut()
            .enumerate()
            .filter_map(|(k, h)| h.peek().map(|&(t, ch, _)| ((t, ch), k)))
            .min()?;
        heads[next.1].next()
    })
}

/// The JSON Schema of a schema name of [`CHANNELS`] (the fields written).
fn schema(name: &str) -> Value {
    let num = json!({ "type": "number" });
    let int = json!({ "type": "integer" });
    let string = json!({ "type": "string" });
    let obj = |title: &str, props: Value| json!({ "title": title, "type": "object", "properties": props });
    let arr = |items: Value| json!({ "type": "array", "items": items });
    let time = obj("time", json!({ "sec": int, "nsec": int }));
    let vec3 = obj("foxglove.Vector3", json!({ "x": num, "y": num, "z": num }));
    let quat = obj(
        "foxglove.Quaternion",
        json!({ "x": num, "y": num, "z": num, "w": num }),
    );
    let col = obj(
        "foxglove.Color",
        json!({ "r": num, "g": num, "b": num, "a": num }),
    );
    let pose = obj(
        "foxglove.Pose",
        json!({ "position": vec3, "orientation": quat }),
    );
    let shape = |title: &str| obj(title, json!({ "pose": pose, "size": vec3, "color": col }));
    let line = obj(
        "foxglove.LinePrimitive",
        json!({
            "type": int, "pose": pose, "thickness": num, "scale_invariant": { "type": "boolean" },
            "points": arr(vec3.clone()), "color": col, "colors": arr(col.clone()),
            "indices": arr(int.clone()),
        }),
    );
    let empty = arr(json!({ "type": "object" }));
    match name {
        "foxglove.FrameTransform" => obj(
            name,
            json!({
                "timestamp": time, "parent_frame_id": string, "child_frame_id": string,
                "translation": vec3, "rotation": quat,
            }),
        ),
        "foxglove.PosesInFrame" => obj(
            name,
            json!({ "timestamp": time, "frame_id": string, "poses": arr(pose) }),
        ),
        "foxglove.SceneUpdate" => {
            let deletion = obj(
                "foxglove.SceneEntityDeletion",
                json!({ "timestamp": time, "type": int, "id": string }),
            );
            let entity = obj(
                "foxglove.SceneEntity",
                json!({
                    "timestamp": time, "frame_id": string, "id": string,
                    "lifetime": obj("duration", json!({ "sec": int, "nsec": int })),
                    "frame_locked": { "type": "boolean" }, "metadata": empty,
                    "arrows": empty, "cubes": arr(shape("foxglove.CubePrimitive")),
                    "spheres": arr(shape("foxglove.SpherePrimitive")), "cylinders": empty,
                    "lines": arr(line), "triangles": empty, "texts": empty, "models": empty,
                }),
            );
            obj(
                name,
                json!({ "deletions": arr(deletion), "entities": arr(entity) }),
            )
        }
        _ => {
            let maybe = json!({ "type": ["number", "null"] });
            obj(
                name,
                json!({
                    "timestamp": time, "cycle": int, "step": int, "stance": string,
                    "time_in_step": num, "status": string, "source": string,
                    "iterations": int, "active_set": int, "active_obstacles": int,
                    "obstacles_truncated": { "type": "boolean" }, "compute_ns": int,
                    "max_violation": maybe, "cost": maybe, "min_h0": maybe,
                    "relax_gait": num, "relax_safety": num, "relax_capture": num,
                    "foot_target": vec3, "turning_rate": num, "goal": vec3,
                }),
            )
        }
    }
}

/// Writes `run.mcap` of `r` to `path` (zstd chunks; `/tf` at the samples of
/// `trajectory.csv`: every `every`-th 1 kHz sample and the last).
pub fn write_mcap(r: &SimResult, path: &Path, every: usize) -> std::io::Result<()> {
    let file = BufWriter::new(std::fs::File::create(path)?);
    let mut w = ::mcap::Writer::new(file).map_err(std::io::Error::other)?;
    let mut ids = [0u16; CHANNELS.len()];
    for (k, (topic, name)) in CHANNELS.iter().enumerate() {
        let data = serde_json::to_vec(&schema(name)).map_err(std::io::Error::other)?;
        let sid = w
            .add_schema(name, "jsonschema", &data)
            .map_err(std::io::Error::other)?;
        ids[k] = w
            .add_channel(sid, topic, "json", &BTreeMap::new())
            .map_err(std::io::Error::other)?;
    }
    let mut seq = [0u32; CHANNELS.len()];
    for (t, ch, data) in messages(r, every) {
        let header = ::mcap::records::MessageHeader {
            channel_id: ids[ch],
            sequence: seq[ch],
            log_time: t,
            publish_time: t,
        };
        seq[ch] += 1;
        w.write_to_known_channel(&header, &data)
            .map_err(std::io::Error::other)?;
    }
    w.finish().map_err(std::io::Error::other)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::{LoadOptions, load};
    use crate::sim::{SimOptions, run};

    /// Read back with the `mcap` crate's reader: every channel with its
    /// schema, the expected count per topic, log times in order, JSON bodies
    /// with the fields Foxglove reads.
    #[test]
    fn run_mcap_reads_back() {
        let sc = load("simple", &LoadOptions::default()).unwrap();
        let r = run(&sc, SimOptions::default()).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("run.mcap");
        write_mcap(&r, &path, 10).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let mut counts: BTreeMap<String, usize> = BTreeMap::new();
        let mut last = 0;
        for m in ::mcap::MessageStream::new(&bytes).unwrap() {
            let m = m.unwrap();
            let schema = m.channel.schema.as_ref().unwrap();
            let (_, name) = CHANNELS
                .iter()
                .find(|(t, _)| *t == m.channel.topic)
                .unwrap();
            assert_eq!(
                (schema.name.as_str(), schema.encoding.as_str()),
                (*name, "jsonschema")
            );
            assert_eq!(m.channel.message_encoding, "json");
            assert!(m.log_time >= last, "log times in order");
            last = m.log_time;
            let v: Value = serde_json::from_slice(&m.data).unwrap();
            if name == &"foxglove.SceneUpdate" {
                assert!(v["entities"].is_array() && v["deletions"].is_array());
            } else {
                assert!(v["timestamp"]["sec"].is_u64());
            }
            *counts.entry(m.channel.topic.clone()).or_default() += 1;
        }
        let want = expected_counts(&r, 10);
        for (k, (topic, _)) in CHANNELS.iter().enumerate() {
            assert_eq!(counts.get(*topic).copied().unwrap_or(0), want[k], "{topic}");
        }
        assert!(want[6] > 10 && want[2] > 3, "a real walk: {want:?}");
        assert!(last >= nanos(r.cycles.last().unwrap().time));
    }

    /// A long run's `/com_path` grew with the square of its length (the whole
    /// path at every footstep; 14 GB of memory for 500 s). Each message now
    /// holds at most the cap: the path so far at one pose per 50 ms, then at
    /// twice the spacing each time it would exceed the cap, always from the
    /// start to the footstep. Checked with a small cap on a short walk.
    #[test]
    fn com_path_messages_stay_within_their_cap() {
        let sc = load("simple", &LoadOptions::default()).unwrap();
        let r = run(&sc, SimOptions::default()).unwrap();
        let cap = 16;
        let mut widened = 0;
        for (f, [(_, ch, data), _]) in r.footsteps.iter().zip(footstep_messages(&r, cap)) {
            assert_eq!(ch, COM_PATH);
            let v: Value = serde_json::from_slice(&data).unwrap();
            let poses = v["poses"].as_array().unwrap();
            assert!(
                !poses.is_empty() && poses.len() <= cap,
                "{} poses",
                poses.len()
            );
            // The samples up to the footstep, and the spacing that fits them.
            let last = r.samples.iter().rposition(|s| s.time <= f.time).unwrap();
            let mut stride = PATH_EVERY;
            while last / stride + 1 > cap {
                stride *= 2;
            }
            widened += usize::from(stride > PATH_EVERY);
            assert_eq!(poses.len(), last / stride + 1, "footstep at {} s", f.time);
            for (j, p) in poses.iter().enumerate() {
                let s = &r.samples[j * stride];
                let xy = (p["position"]["x"].as_f64(), p["position"]["y"].as_f64());
                assert_eq!(xy, (Some(s.position.x), Some(s.position.y)), "pose {j}");
            }
        }
        assert!(widened > 10, "the cap was reached: {widened}");
        // The shipped runs stay below the real cap (their files unchanged).
        assert!(r.samples.len() < MAX_PATH_POSES * PATH_EVERY);
    }
}
