//! The node's parameters from a YAML file in ROS 2's parameter-file layout
//! (`<node name>: ros__parameters: {...}`, nested maps for dotted names), as
//! `ros2 run ... --ros-args --params-file FILE` would read it. Example:
//! `ros2/config/ldcbf_nav.yaml`.
//!
//! The node's section is `ldcbf_nav:`, `/ldcbf_nav:` or the wildcard `/**:`
//! (applied first; the node's own sections override it); sections of other
//! nodes are ignored, as ROS 2 ignores them. Refused before anything is
//! built: a file that is not a regular file of at most
//! [`ldcbf_sim::scenario::limits::MAX_FILE_BYTES`] (a device, a FIFO: the
//! simulator's rule for its input files), a YAML alias (`*name`, also `<<:`
//! merges: expanded, a few lines make gigabytes), nesting deeper than
//! [`MAX_DEPTH`], a second YAML document, two topics with one name (every
//! topic carries its own message type), a topic name that is not a ROS 2
//! name.

use std::path::Path;

use anyhow::{Context, Result, bail};
use yaml_rust2::parser::Parser;
use yaml_rust2::{Event, Yaml, YamlLoader};

/// The node's name in the parameter file and on the graph.
pub const NODE_NAME: &str = "ldcbf_nav";

/// Deepest nesting of maps and lists in a parameter file (the node's keys
/// need 4: `ldcbf_nav.ros__parameters.topics.goal`).
pub const MAX_DEPTH: usize = 16;

/// Checks the YAML events of `text` (named `file`) without building
/// anything: one document, no alias, at most [`MAX_DEPTH`] levels.
fn check_events(file: &str, text: &str) -> Result<()> {
    let mut parser = Parser::new_from_str(text);
    let (mut docs, mut depth) = (0usize, 0usize);
    loop {
        let (ev, mark) = parser
            .next_token()
            .map_err(|e| anyhow::anyhow!("{file}: not YAML: {e}"))?;
        let line = mark.line();
        match ev {
            Event::StreamEnd => return Ok(()),
            Event::DocumentStart => {
                docs += 1;
                if docs > 1 {
                    bail!(
                        "{file}: line {line}: a second YAML document (`---`); a parameter file has one"
                    );
                }
            }
            Event::Alias(_) => bail!(
                "{file}: line {line}: a YAML alias (`*name` or a `<<:` merge); \
                 parameter files may not use aliases"
            ),
            Event::MappingStart(..) | Event::SequenceStart(..) => {
                depth += 1;
                if depth > MAX_DEPTH {
                    bail!("{file}: line {line}: nested more than {MAX_DEPTH} levels deep");
                }
            }
            Event::MappingEnd | Event::SequenceEnd => depth = depth.saturating_sub(1),
            _ => {}
        }
    }
}

/// Whether `name` is an absolute ROS 2 topic name: `/` then tokens of
/// letters, digits and `_` separated by single `/`, none starting with a
/// digit, no trailing `/`.
pub fn valid_topic_name(name: &str) -> bool {
    let Some(rest) = name.strip_prefix('/') else {
        return false;
    };
    !rest.is_empty()
        && rest.split('/').all(|t| {
            t.chars()
                .next()
                .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
                && t.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
        })
}

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
    /// Parses the text of a parameter file named `file` (module docs); keys
    /// not given keep their defaults, unknown keys are errors (naming the
    /// file and the key).
    pub fn parse(file: &str, text: &str) -> Result<Params> {
        check_events(file, text)?;
        let docs = YamlLoader::load_from_str(text).with_context(|| format!("{file}: not YAML"))?;
        let root = docs.first().with_context(|| format!("{file}: empty"))?;
        let Yaml::Hash(top) = root else {
            bail!("{file}: the top level: expected a map of node names");
        };
        let ours = |k: &str| k == NODE_NAME || k.strip_prefix('/') == Some(NODE_NAME);
        // The wildcard first, then the node's own sections in file order.
        let sections: Vec<(&str, &Yaml)> = top
            .iter()
            .filter_map(|(k, v)| Some((k.as_str()?, v)))
            .filter(|(k, _)| *k == "/**")
            .chain(
                top.iter()
                    .filter_map(|(k, v)| Some((k.as_str()?, v)))
                    .filter(|(k, _)| ours(k)),
            )
            .collect();
        if sections.is_empty() {
            bail!("{file}: no `{NODE_NAME}:`, `/{NODE_NAME}:` or `/**:` section");
        }
        let mut out = Params::default();
        for (section, node) in sections {
            out.apply(file, section, node)?;
        }
        let t = &out.topics;
        let names = [
            ("goal", &t.goal),
            ("odom", &t.odom),
            ("gait_state", &t.gait_state),
            ("scan", &t.scan),
            ("command", &t.command),
            ("footsteps", &t.footsteps),
            ("markers", &t.markers),
            ("diagnostics", &t.diagnostics),
        ];
        for (i, (a, na)) in names.iter().enumerate() {
            if let Some((b, _)) = names[..i].iter().find(|(_, nb)| nb == na) {
                bail!(
                    "{file}: topics.{a} and topics.{b} are both {na}; every topic carries its own message type"
                );
            }
        }
        Ok(out)
    }

    /// Applies the section `section` (`node`: its `ros__parameters:` map).
    fn apply(&mut self, file: &str, section: &str, node: &Yaml) -> Result<()> {
        let out = self;
        let p = field(file, node, "ros__parameters", section)?
            .with_context(|| format!("{file}: {section}: no `ros__parameters:`"))?;
        let Yaml::Hash(h) = p else {
            bail!("{file}: {section}.ros__parameters: expected a map");
        };
        for (k, v) in h {
            let key = k.as_str().unwrap_or("?");
            let name = format!("{section}.ros__parameters.{key}");
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
                        if !valid_topic_name(slot) {
                            bail!(
                                "{file}: {tname}: `{}` is not an absolute ROS 2 topic name (`/name`, letters, digits and `_`)",
                                ldcbf_sim::scenario::limits::shorten(slot, 80)
                            );
                        }
                    }
                }
                "use_sim_time" => {
                    // ROS 2's standard parameter (often under `/**`): the
                    // node runs on its inputs' stamps either way.
                    v.as_bool()
                        .with_context(|| format!("{file}: {name}: expected true or false"))?;
                }
                _ => bail!("{file}: {name}: unknown parameter"),
            }
        }
        Ok(())
    }

    /// Reads and parses a parameter file: a regular file of at most
    /// [`ldcbf_sim::scenario::limits::MAX_FILE_BYTES`], UTF-8 (the
    /// simulator's rule for its input files).
    pub fn load(path: &Path) -> Result<Params> {
        use ldcbf_sim::scenario::limits::{MAX_FILE_BYTES, read_regular_file};
        let file = path.display().to_string();
        let bytes = read_regular_file(path, MAX_FILE_BYTES).map_err(|e| match e.kind() {
            std::io::ErrorKind::InvalidInput => anyhow::anyhow!("{file}: {e}"),
            _ => anyhow::anyhow!("{file}: cannot read: {e}"),
        })?;
        let text = String::from_utf8(bytes).map_err(|_| anyhow::anyhow!("{file}: not UTF-8"))?;
        Params::parse(&file, &text)
    }
}
