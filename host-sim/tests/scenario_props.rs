//! Property tests of the scenario parser and the `--set` override paths:
//! random TOML documents (known and unknown keys, values of every type,
//! nesting, extreme numbers) and random dotted keys and values never panic;
//! each ends in a scenario or in one error naming a field, of bounded length.

use std::path::Path;

use ldcbf_sim::scenario::{LoadOptions, ScenarioError, parse_str};
use proptest::prelude::*;

/// Key names the parser knows (top level and inside tables; `generator` left
/// out: a random count would spend the test's time drawing polygons), and a
/// few it does not.
const NAMES: &[&str] = &[
    "name",
    "description",
    "start",
    "x",
    "y",
    "heading",
    "stance",
    "goal",
    "time_limit",
    "success_radius",
    "stuck_window",
    "planner",
    "perception",
    "seed",
    "controller",
    "delta",
    "gamma",
    "gravity",
    "step_duration",
    "max_iter",
    "tol_primal",
    "obstacles",
    "vertices",
    "regular",
    "center",
    "radius",
    "sides",
    "hull",
    "robot",
    "body_radius",
    "lidar",
    "range",
    "rrt_star",
    "iterations",
    "disturbance",
    "push_time",
    "zzz",
    "",
];

fn name() -> impl Strategy<Value = String> {
    prop_oneof![
        4 => proptest::sample::select(NAMES).prop_map(str::to_string),
        1 => "[a-z_]{1,12}",
    ]
}

fn number() -> impl Strategy<Value = toml::Value> {
    prop_oneof![
        (-10.0f64..10.0).prop_map(toml::Value::Float),
        proptest::sample::select(vec![
            0.0,
            -0.0,
            1e-300,
            1e300,
            -1e308,
            1e6,
            1e7,
            f64::NAN,
            f64::INFINITY
        ])
        .prop_map(toml::Value::Float),
        any::<i64>().prop_map(toml::Value::Integer),
        (0i64..40).prop_map(toml::Value::Integer),
    ]
}

fn value() -> impl Strategy<Value = toml::Value> {
    let leaf = prop_oneof![
        4 => number(),
        1 => any::<bool>().prop_map(toml::Value::Boolean),
        1 => "[a-z_ \"\\\\]{0,8}".prop_map(toml::Value::String),
    ];
    leaf.prop_recursive(5, 48, 6, |inner| {
        prop_oneof![
            proptest::collection::vec(inner.clone(), 0..5).prop_map(toml::Value::Array),
            proptest::collection::btree_map(name(), inner, 0..5)
                .prop_map(|m| toml::Value::Table(m.into_iter().collect())),
        ]
    })
}

/// The shipped `simple` scenario, the valid base of the documents.
fn simple() -> toml::Table {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios/simple.toml");
    toml::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

/// One error: a field (or a `(...)` location), a message, a short line.
/// (Found by these properties: an empty key, `"" = 1` or `--set =1`, was
/// named as the field ``; see the named tests below.)
fn check_error(e: &ScenarioError) {
    assert!(!e.field.is_empty(), "{e}");
    assert!(!e.message.is_empty(), "{e}");
    assert!(
        e.to_string().len() < 1200,
        "{} bytes: {e}",
        e.to_string().len()
    );
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 192,
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    /// The base document with random keys replaced or added (at the top level
    /// or in a table), serialised as TOML and parsed.
    #[test]
    fn random_documents_parse_or_fail_with_one_error(
        edits in proptest::collection::vec((name(), proptest::option::of(name()), value()), 1..6)
    ) {
        let mut doc = simple();
        for (k, sub, v) in edits {
            match sub {
                None => { doc.insert(k, v); }
                Some(s) => {
                    let t = doc.entry(k).or_insert_with(|| toml::Value::Table(toml::Table::new()));
                    if let Some(t) = t.as_table_mut() {
                        t.insert(s, v);
                    }
                }
            }
        }
        // A value TOML cannot write (e.g. a table inside an array after a
        // plain value) is not a document: nothing to parse.
        if let Ok(text) = toml::to_string(&doc)
            && let Err(e) = parse_str(&text, "p.toml", &LoadOptions::default())
        {
            check_error(&e);
        }
    }

    /// Random `--set` keys (dotted names, empty parts, many parts) and values
    /// (TOML or not) on the valid base.
    #[test]
    fn random_overrides_apply_or_fail_with_one_error(
        sets in proptest::collection::vec(
            (
                proptest::collection::vec(name(), 1..12).prop_map(|p| p.join(".")),
                prop_oneof![
                    value().prop_map(|v| v.to_string()),
                    "[\\[\\]{}=,.0-9a-z\" ]{0,24}",
                ],
            ),
            1..4,
        )
    ) {
        let text = toml::to_string(&simple()).unwrap();
        let opts = LoadOptions { seed: None, sets };
        if let Err(e) = parse_str(&text, "p.toml", &opts) {
            check_error(&e);
        }
    }
}

#[test]
fn an_empty_key_is_named_as_such() {
    let text = format!("\"\" = 1\n{}", toml::to_string(&simple()).unwrap());
    let e = parse_str(&text, "p.toml", &LoadOptions::default()).unwrap_err();
    assert_eq!(e.field, "\"\"", "{e}");
    let text = toml::to_string(&simple()).unwrap();
    let e = parse_str(&text, "p.toml", &LoadOptions::with_sets(&[("", "1")])).unwrap_err();
    assert_eq!(e.field, "\"\"", "{e}");
}
