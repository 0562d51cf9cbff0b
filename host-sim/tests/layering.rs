//! The rooms of `host-sim/src/` and their one-way arrows (docs/architecture.md):
//! a room's code may name (`crate::ROOM`) only rooms of a lower layer, never
//! one of its own layer or above, and no file climbs out of its room with
//! `super::super`. Comments are not read: a doc line may say which room uses
//! this one.
//!
//! Layers, lowest first:
//!
//! 0. `world`: polygons, the robot's body, map index, occupancy grid, generators;
//! 1. `sense` (LiDAR, DBSCAN), `plan` (RRT*), `plant` (the LIP, disturbances);
//! 2. `scenario`: the file loader, which reads the settings of the rooms below;
//! 3. `sim`: the closed loop;
//! 4. `report`: logs, summary, plots;
//! 5. `studies`: batch, robustness, deadline, replay, qp solve;
//! 6. `cli`: the command line and the `run` pipeline (`src/main.rs`, the
//!    binary, only calls `cli::main`).

use std::path::{Path, PathBuf};

/// Every room and its layer.
const ROOMS: [(&str, u32); 9] = [
    ("world", 0),
    ("sense", 1),
    ("plan", 1),
    ("plant", 1),
    ("scenario", 2),
    ("sim", 3),
    ("report", 4),
    ("studies", 5),
    ("cli", 6),
];

fn layer(room: &str) -> Option<u32> {
    ROOMS.iter().find(|(r, _)| *r == room).map(|&(_, l)| l)
}

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// The `.rs` files under `dir`, sorted.
fn sources(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap_or_else(|e| panic!("{}: {e}", d.display())) {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "rs") {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// The rooms a line of code names: `crate::ROOM`, and each first name of a
/// `crate::{A, B::c}` group. Anything after `//` is a comment and is skipped.
fn named_rooms(line: &str) -> Vec<String> {
    let code = line.split("//").next().unwrap_or("");
    let ident = |s: &str| -> String {
        s.chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
            .collect()
    };
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(i) = rest.find("crate::") {
        // `ldcbf_sim::...` or `my_crate::...` is not this crate's `crate::`.
        let before = rest[..i].chars().last();
        rest = &rest[i + "crate::".len()..];
        if before.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_') {
            continue;
        }
        if let Some(group) = rest.strip_prefix('{') {
            let inner = &group[..group.find('}').unwrap_or(group.len())];
            out.extend(
                inner
                    .split(',')
                    .map(|s| ident(s.trim()))
                    .filter(|s| !s.is_empty()),
            );
        } else {
            out.push(ident(rest));
        }
    }
    out
}

/// Every arrow of `text` (the source of a file in `room`) that is not allowed:
/// `(line number, named room or item, why)`.
fn violations(room: &str, text: &str) -> Vec<(usize, String, String)> {
    let own = layer(room).expect("a known room");
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let code = line.split("//").next().unwrap_or("");
        if code.contains("super::super") {
            // Could climb out of the room: rooms are named from `crate::`.
            out.push((
                i + 1,
                "super::super".into(),
                "name other modules by their `crate::` path".into(),
            ));
        }
        for name in named_rooms(line) {
            let why = match layer(&name) {
                None => format!(
                    "`crate::{name}` is not a room: name the room that holds it \
                     (root re-exports are for users outside the crate)"
                ),
                Some(_) if name == room => continue,
                Some(l) if l < own => continue,
                Some(l) if l == own => {
                    format!("`{room}` and `{name}` share layer {l}: no arrow between them")
                }
                Some(l) => format!("`{name}` (layer {l}) is above `{room}` (layer {own})"),
            };
            out.push((i + 1, name, why));
        }
    }
    out
}

#[test]
fn every_room_uses_only_rooms_below_it() {
    let root = src();
    let mut bad = Vec::new();
    let mut files = 0;
    for (room, _) in ROOMS {
        let dir = root.join(room);
        assert!(dir.is_dir(), "room {room}: no folder {}", dir.display());
        for f in sources(&dir) {
            files += 1;
            let text = std::fs::read_to_string(&f).unwrap();
            for (line, name, why) in violations(room, &text) {
                let rel = f.strip_prefix(&root).unwrap_or(&f).display().to_string();
                bad.push(format!("src/{rel}:{line}: crate::{name}: {why}"));
            }
        }
    }
    assert!(files > 20, "only {files} source files read");
    assert!(
        bad.is_empty(),
        "arrows against the layering:\n{}",
        bad.join("\n")
    );
}

#[test]
fn every_folder_and_module_is_a_known_room() {
    let root = src();
    for e in std::fs::read_dir(&root).unwrap() {
        let p = e.unwrap().path();
        let name = p.file_name().unwrap().to_string_lossy().into_owned();
        if p.is_dir() {
            assert!(layer(&name).is_some(), "src/{name}/ is not in ROOMS");
        } else {
            assert!(
                name == "lib.rs" || name == "main.rs",
                "src/{name}: code belongs in a room folder"
            );
        }
    }
    let lib = std::fs::read_to_string(root.join("lib.rs")).unwrap();
    let mods: Vec<&str> = lib
        .lines()
        .filter_map(|l| l.strip_prefix("pub mod ")?.strip_suffix(';'))
        .collect();
    let mut rooms: Vec<&str> = ROOMS.iter().map(|&(r, _)| r).collect();
    rooms.sort_unstable();
    assert_eq!(mods, rooms, "lib.rs's modules are the rooms");
}

#[test]
fn the_check_sees_upward_sideways_and_root_arrows() {
    let text = "use crate::world::Polygon;\n\
                use crate::sim::run; // up\n\
                // use crate::cli::app; (a comment)\n\
                let x = crate::{plan::Planner, plant::Plant};\n\
                use crate::Scenario;\n\
                use my_crate::sim;\n\
                use super::super::sim::run;\n";
    let v = violations("sense", text);
    let got: Vec<(usize, &str)> = v.iter().map(|(l, n, _)| (*l, n.as_str())).collect();
    assert_eq!(
        got,
        [
            (2, "sim"),
            (4, "plan"),
            (4, "plant"),
            (5, "Scenario"),
            (7, "super::super")
        ],
        "{v:?}"
    );
    assert!(
        violations(
            "cli",
            "use crate::world::robot;\nuse crate::studies::batch;"
        )
        .is_empty()
    );
}

/// `anyhow` is for the command line only (`cli/`, `main.rs`): the library's
/// rooms return typed errors (`thiserror` enums naming the file and field).
#[test]
fn anyhow_only_at_the_cli_edge() {
    let root = src();
    let mut bad = Vec::new();
    for (room, _) in ROOMS.iter().filter(|&&(r, _)| r != "cli") {
        for f in sources(&root.join(room)) {
            let text = std::fs::read_to_string(&f).unwrap();
            for (i, line) in text.lines().enumerate() {
                if line.split("//").next().unwrap_or("").contains("anyhow") {
                    let rel = f.strip_prefix(&root).unwrap_or(&f).display().to_string();
                    bad.push(format!("src/{rel}:{}: {}", i + 1, line.trim()));
                }
            }
        }
    }
    assert!(
        bad.is_empty(),
        "anyhow outside cli/ (return a typed error instead):\n{}",
        bad.join("\n")
    );
}
