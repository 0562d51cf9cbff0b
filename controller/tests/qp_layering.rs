//! The files of the QP solver, `controller/src/qp/`, and its neighbours in
//! one-way layers (docs/architecture.md): a file's code may name only files
//! of a lower layer, never one of its own layer or above. Comments are not
//! read (a doc line may say which file uses this one), nor are the unit
//! tests (`qp/tests*`, and a file's `#[cfg(test)] mod` at its end).
//!
//! A file is named by a path (`super::FILE`, `crate::qp::FILE`; root
//! re-exports are for users outside the module, so `super::Name` of an
//! item fails) or by an item defined in one file only (a method such as
//! `solve_with` called on the solver, which no path shows).
//!
//! The solver stack, lowest first: `linalg`, `solution`; `active_set` (the
//! dual iteration over any factor); `qp` (its files below); `ldp` (the
//! least-distance path on top of the QP's data).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The files of `qp/` and their layers, lowest first; the module root
/// `qp.rs` stands above them all.
const QP_FILES: [(&str, u32); 21] = [
    // The data: settings and size thresholds, the factor's updates, the
    // rows a factor resumes from.
    ("settings", 0),
    ("updates", 0),
    ("kept", 0),
    // The QP, its bound rows and row spans, the Hessian's factor `L^-1`,
    // the row norms; the checks every solve starts with, the hot start's
    // Gram factor.
    ("dense", 1),
    ("bounds", 2),
    ("solver", 2),
    ("spans", 3),
    ("norms", 3),
    ("start", 4),
    ("gram", 4),
    // The factor of the active set, the hot start's guess on it, one step
    // of the iteration on it.
    ("orthogonal", 5),
    ("guess", 6),
    ("step", 7),
    // One solve: its resumed start, where it keeps the factor, the solve.
    ("resolve", 8),
    ("store", 8),
    ("dual", 9),
    // Above one solve: the probes, the proximal outer loop, the entry
    // points, the controller's backend trait.
    ("reprobe", 10),
    ("proximal", 11),
    ("solve", 12),
    ("backend", 13),
    ("tests", 99),
];

/// The modules of the crate a file of the solver stack may name, by the
/// stack's layer: `active_set` (and its `active_set/` files), `qp`, `ldp`.
const STACK: [(&str, &[&str]); 3] = [
    ("active_set", &["linalg", "solution", "active_set"]),
    ("qp", &["linalg", "solution", "active_set", "qp"]),
    ("ldp", &["linalg", "solution", "active_set", "qp", "ldp"]),
];

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

fn qp_layer(file: &str) -> Option<u32> {
    QP_FILES.iter().find(|(f, _)| *f == file).map(|&(_, l)| l)
}

/// The code of a file: each line with its comment cut off, and nothing
/// from the file's own unit tests on (`#[cfg(test)]` before `mod`).
fn code_lines(text: &str) -> Vec<String> {
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        let next = lines.get(i + 1).map_or("", |l| l.trim_start());
        if line.trim() == "#[cfg(test)]" && next.starts_with("mod ") {
            break;
        }
        out.push(line.split("//").next().unwrap_or("").to_string());
    }
    out
}

fn ident(s: &str) -> String {
    s.chars()
        .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
        .collect()
}

/// The first name after each `prefix` in `code` (`prefix::NAME`, and each
/// first name of a `prefix::{A, B::c}` group), where `prefix` is not the
/// tail of a longer path or name.
fn named_after(code: &str, prefix: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(i) = rest.find(prefix) {
        let before = rest[..i].chars().last();
        rest = &rest[i + prefix.len()..];
        if before.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_' || c == ':') {
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

/// The items (`fn`, `struct`, `enum`, `trait`, `type`, `const`, macro)
/// that `code` defines.
fn defined(code: &[String]) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    for line in code {
        let words: Vec<&str> = line
            .split(|c: char| !(c.is_ascii_alphanumeric() || c == '_' || c == '!'))
            .filter(|w| !w.is_empty())
            .collect();
        for pair in words.windows(2) {
            if matches!(
                pair[0],
                "fn" | "struct" | "enum" | "trait" | "type" | "const" | "macro_rules!"
            ) {
                out.insert(ident(pair[1]));
            }
        }
    }
    out
}

/// The words (names) of a line of code.
fn words(line: &str) -> impl Iterator<Item = &str> {
    line.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .filter(|w| !w.is_empty())
}

/// Whether an item's name is distinctive enough to be read as naming its
/// file wherever it stands: a type (`CamelCase`) or a name with an
/// underscore (`solve_with`), not a file's own name; short names (`n`,
/// `nv`, `slack`) are also locals and fields everywhere.
fn distinctive(w: &str) -> bool {
    w.len() >= 4
        && (w.contains('_') || w.starts_with(|c: char| c.is_ascii_uppercase()))
        && qp_layer(w).is_none()
}

/// `(file, code)` of every `.rs` file of `qp/` but the unit tests'.
fn qp_sources() -> Vec<(String, Vec<String>)> {
    let dir = src().join("qp");
    let mut out = Vec::new();
    for e in std::fs::read_dir(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display())) {
        let p = e.unwrap().path();
        if p.is_dir() {
            continue; // qp/tests/: the unit tests
        }
        let stem = p.file_stem().unwrap().to_string_lossy().into_owned();
        let text = std::fs::read_to_string(&p).unwrap();
        out.push((stem, code_lines(&text)));
    }
    out.sort();
    out
}

/// Every arrow against the layers among `files` (`(file, code)` of
/// `qp/`): `(file, line, named, why)`.
fn qp_violations(files: &[(String, Vec<String>)]) -> Vec<(String, usize, String, String)> {
    // Items defined in exactly one file, by name.
    let mut owners: BTreeMap<String, Vec<&str>> = BTreeMap::new();
    for (file, code) in files {
        for name in defined(code) {
            owners.entry(name).or_default().push(file);
        }
    }
    let mut out = Vec::new();
    for (file, code) in files {
        let Some(own) = qp_layer(file) else {
            out.push((file.clone(), 0, file.clone(), "not in QP_FILES".into()));
            continue;
        };
        if file == "tests" {
            continue;
        }
        for (i, line) in code.iter().enumerate() {
            // (the file named, what names it, by a path)
            let mut named: Vec<(String, String, bool)> = Vec::new();
            for prefix in ["super::", "crate::qp::"] {
                for n in named_after(line, prefix) {
                    named.push((n.clone(), n, true));
                }
            }
            for w in words(line).filter(|w| distinctive(w)) {
                if let Some([owner]) = owners.get(w).map(Vec::as_slice)
                    && owner != file
                {
                    named.push((owner.to_string(), w.to_string(), false));
                }
            }
            for (name, by, by_path) in named {
                let why = match qp_layer(&name) {
                    None if by_path => format!(
                        "`{name}` is not a file of qp/: name the file that defines it \
                         (the root's re-exports are for users outside qp)"
                    ),
                    None => continue,
                    Some(_) if name == *file => continue,
                    Some(l) if l < own => continue,
                    Some(l) if l == own => {
                        format!("`{file}` and `{name}` share layer {l}: no arrow between them")
                    }
                    Some(l) => format!("`{name}` (layer {l}) is above `{file}` (layer {own})"),
                };
                let by = if by_path {
                    by
                } else {
                    format!("{by} ({name}.rs)")
                };
                out.push((file.clone(), i + 1, by, why));
            }
        }
    }
    out.sort();
    out.dedup();
    out
}

#[test]
fn every_qp_file_names_only_files_below_it() {
    let files = qp_sources();
    assert!(files.len() >= 20, "only {} files read", files.len());
    let bad: Vec<String> = qp_violations(&files)
        .into_iter()
        .map(|(f, l, n, why)| format!("src/qp/{f}.rs:{l}: {n}: {why}"))
        .collect();
    assert!(
        bad.is_empty(),
        "arrows against the layers:\n{}",
        bad.join("\n")
    );
    // Every file of the table exists.
    for (f, _) in QP_FILES {
        assert!(files.iter().any(|(g, _)| g == f), "QP_FILES: no qp/{f}.rs");
    }
}

#[test]
fn the_solver_stack_reads_one_way() {
    let root = src();
    let mut bad = Vec::new();
    for (module, allowed) in STACK {
        let mut paths = vec![root.join(format!("{module}.rs"))];
        let dir = root.join(module);
        if dir.is_dir() {
            let mut stack = vec![dir];
            while let Some(d) = stack.pop() {
                for e in std::fs::read_dir(&d).unwrap() {
                    let p = e.unwrap().path();
                    if p.is_dir() {
                        stack.push(p);
                    } else if p.extension().is_some_and(|x| x == "rs") {
                        paths.push(p);
                    }
                }
            }
        }
        for p in paths {
            let rel = p.strip_prefix(&root).unwrap().display().to_string();
            if rel.contains("tests") {
                continue; // unit tests may use anything
            }
            let text = std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{rel}: {e}"));
            for (i, line) in code_lines(&text).iter().enumerate() {
                for name in named_after(line, "crate::") {
                    if !allowed.contains(&name.as_str()) {
                        bad.push(format!(
                            "src/{rel}:{}: crate::{name}: `{module}` may name only {allowed:?}",
                            i + 1
                        ));
                    }
                }
            }
        }
    }
    assert!(
        bad.is_empty(),
        "arrows against the stack:\n{}",
        bad.join("\n")
    );
}

#[test]
fn the_check_sees_upward_sideways_and_root_arrows() {
    let file = |name: &str, text: &str| (name.to_string(), code_lines(text));
    let files = [
        file(
            "settings",
            "use super::solver::DualActiveSetOf; // up\n\
             // use super::dual::x; (a comment)\n\
             use super::{updates::givens_drop, kept::Kept};\n",
        ),
        file("updates", "pub(super) fn givens_drop() {}\n"),
        file("kept", "pub(super) struct Kept;\n"),
        file(
            "solver",
            "pub struct DualActiveSetOf;\nuse super::DenseQpOf;\n\
             fn f() { self.solve_with(); }\n",
        ),
        file("dual", "fn solve_with() {}\nuse crate::qp::settings::X;\n"),
        file("spans", "use super::norms::y;\n"),
        file(
            "gram",
            "fn factor_gram() {}\n#[cfg(test)]\nmod tests {\n use super::dual::z;\n}\n",
        ),
    ];
    let v = qp_violations(&files);
    let got: Vec<(&str, usize, &str)> = v
        .iter()
        .map(|(f, l, n, _)| (f.as_str(), *l, n.as_str()))
        .collect();
    assert_eq!(
        got,
        [
            ("settings", 1, "DualActiveSetOf (solver.rs)"),
            ("settings", 1, "solver"),
            ("settings", 3, "Kept (kept.rs)"),
            ("settings", 3, "givens_drop (updates.rs)"),
            ("settings", 3, "kept"),
            ("settings", 3, "updates"),
            ("solver", 2, "DenseQpOf"),
            ("solver", 3, "solve_with (dual.rs)"),
            ("spans", 1, "norms"),
        ],
        "{v:?}"
    );
}
