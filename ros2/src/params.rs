//! The node's parameters from a YAML file in ROS 2's parameter-file layout
//! (`<node name>: ros__parameters: {...}`, nested maps for dotted names), as
//! `ros2 run ... --ros-args --params-file FILE` would read it. Example:
//! `ros2/config/ldcbf_nav.yaml`.

use std::path::Path;

use anyhow::{Context, Result, bail};
use yaml_rust2::{Yaml, YamlLoader};

/// The node's name in the parameter file and on the graph.
pub const NODE_NAME: &str = "ldcbf_nav";

/// Topic names of the node.
#[derive(Clone, Debug, PartialEq)]
pub struct Topics {
    /// In: `geometry_msgs/PoseStamped`.
    pub goal: String,
    /// In: `nav_msgs/Odometry`.
    pub odom: String,
    /// In: `ldcbf_msgs/GaitState`.
    pub gait_state: String,
    /// In (with `perception: lidar`): `sensor_msgs/LaserScan`.
    pub scan: String,
    /// Out: `ldcbf_msgs/FootstepCommand`.
    pub command: String,
    /// Out: `nav_msgs/Path`.
    pub footsteps: String,
    /// Out: `visualization_msgs/MarkerArray`.
    pub markers: String,
    /// Out: `diagnostic_msgs/DiagnosticArray`.
    pub diagnostics: String,
}

/// Everything the node reads from its parameter file.
#[derive(Clone, Debug, PartialEq)]
pub struct Params {
    /// Scenario name (`scenarios/<name>.toml`) or path of a scenario file: its
    /// obstacles are the known map, its `[controller]` and `[robot]` tables
    /// the controller's `Config`.
    pub map: String,
    /// `--set key=value` overrides of the scenario (e.g.
    /// `controller.max_iterations=50`), as `ldcbf-sim run --set`.
    pub sets: Vec<(String, String)>,
    /// Plan among the obstacles perceived in `/scan` (`perception: lidar`,
    /// with the map scenario's `[lidar]` settings) instead of the map's
    /// (`perception: map`).
    pub lidar: bool,
    /// World frame id of the inputs and outputs.
    pub frame_id: String,
    /// DDS domain id (`ROS_DOMAIN_ID`).
    pub domain_id: u16,
    /// Use the loopback interface only (as `ROS_LOCALHOST_ONLY=1`).
    pub localhost_only: bool,
    /// Topic names.
    pub topics: Topics,
}

impl Default for Params {
    fn default() -> Self {
        Params {
            map: "simple".into(),
            sets: Vec::new(),
            lidar: false,
            frame_id: "map".into(),
            domain_id: 0,
            localhost_only: false,
            topics: Topics {
                goal: "/goal_pose".into(),
                odom: "/odom".into(),
                gait_state: "/gait_state".into(),
                scan: "/scan".into(),
                command: "/footstep_command".into(),
                footsteps: "/footsteps".into(),
                markers: "/markers".into(),
                diagnostics: "/diagnostics".into(),
            },
        }
    }
}

fn field<'a>(file: &str, map: &'a Yaml, key: &str, name: &str) -> Result<Option<&'a Yaml>> {
    match map {
        Yaml::Hash(h) => Ok(h.get(&Yaml::String(key.into()))),
        _ => bail!("{file}: {name}: expected a map"),
    }
}

fn string(file: &str, v: &Yaml, name: &str) -> Result<String> {
    v.as_str()
        .map(str::to_string)
        .with_context(|| format!("{file}: {name}: expected a string"))
}

impl Params {
    /// Parses the text of a parameter file named `file`; keys not given keep
    /// their defaults, unknown keys are errors (naming the file and the key).
    pub fn parse(file: &str, text: &str) -> Result<Params> {
        let docs = YamlLoader::load_from_str(text).with_context(|| format!("{file}: not YAML"))?;
        let root = docs.first().with_context(|| format!("{file}: empty"))?;
        let node = field(file, root, NODE_NAME, "the top level")?
            .with_context(|| format!("{file}: no `{NODE_NAME}:` node"))?;
        let p = field(file, node, "ros__parameters", NODE_NAME)?
            .with_context(|| format!("{file}: {NODE_NAME}: no `ros__parameters:`"))?;
        let mut out = Params::default();
        let Yaml::Hash(h) = p else {
            bail!("{file}: {NODE_NAME}.ros__parameters: expected a map");
        };
        for (k, v) in h {
            let key = k.as_str().unwrap_or("?");
            let name = format!("{NODE_NAME}.ros__parameters.{key}");
            match key {
                "map" => out.map = string(file, v, &name)?,
                "frame_id" => out.frame_id = string(file, v, &name)?,
                "perception" => {
                    out.lidar = match string(file, v, &name)?.as_str() {
                        "map" => false,
                        "lidar" => true,
                        other => bail!("{file}: {name}: expected map or lidar, got {other}"),
                    }
                }
                "domain_id" => {
                    out.domain_id = v
                        .as_i64()
                        .and_then(|d| u16::try_from(d).ok())
                        .filter(|d| *d <= 232)
                        .with_context(|| format!("{file}: {name}: expected 0..=232"))?
                }
                "localhost_only" => {
                    out.localhost_only = v
                        .as_bool()
                        .with_context(|| format!("{file}: {name}: expected true or false"))?
                }
                "sets" => {
                    let list = v
                        .as_vec()
                        .with_context(|| format!("{file}: {name}: expected a list"))?;
                    for s in list {
                        let s = string(file, s, &name)?;
                        let (a, b) = s
                            .split_once('=')
                            .with_context(|| format!("{file}: {name}: `{s}` is not key=value"))?;
                        out.sets.push((a.trim().into(), b.trim().into()));
                    }
                }
                "topics" => {
                    let Yaml::Hash(t) = v else {
                        bail!("{file}: {name}: expected a map");
                    };
                    for (tk, tv) in t {
                        let tkey = tk.as_str().unwrap_or("?");
                        let tname = format!("{name}.{tkey}");
                        let slot = match tkey {
                            "goal" => &mut out.topics.goal,
                            "odom" => &mut out.topics.odom,
                            "gait_state" => &mut out.topics.gait_state,
                            "scan" => &mut out.topics.scan,
                            "command" => &mut out.topics.command,
                            "footsteps" => &mut out.topics.footsteps,
                            "markers" => &mut out.topics.markers,
                            "diagnostics" => &mut out.topics.diagnostics,
                            _ => bail!("{file}: {tname}: unknown topic"),
                        };
                        *slot = string(file, tv, &tname)?;
                        if !slot.starts_with('/') {
                            bail!("{file}: {tname}: expected an absolute name (`/...`)");
                        }
                    }
                }
                _ => bail!("{file}: {name}: unknown parameter"),
            }
        }
        Ok(out)
    }

    /// Reads and parses a parameter file.
    pub fn load(path: &Path) -> Result<Params> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("{}: cannot read", path.display()))?;
        Params::parse(&path.display().to_string(), &text)
    }
}
