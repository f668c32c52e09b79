//! `docs/scenes.md` has a row for every key of the scene schema, in the section of its table,
//! and no row for a key the schema does not take.
//!
//! The keys come from the parser, not from a list kept here. Each table gets a bogus key `zz`
//! added to a scene that parses; the parser refuses it with serde's "unknown field `zz`,
//! expected one of `a`, `b`, ..." (or "expected `a`", or "expected `a` or `b`"), which names
//! every key the table takes. Only the public parse functions and TOML are used, so the schema's
//! Rust types may change shape freely while the TOML keys stay.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use perifrac_scene::{Scene, ShellScene};

/// The bogus key added to each table.
const BOGUS: &str = "zz";

/// Which parser reads a scene.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    Tet,
    Shell,
}

/// The smallest tet scene: a box, one material, a duration.
const TET: &str = r#"
[mesh]
primitive = "box"
size = [1.0, 0.1, 0.1]
resolution = 4

[[material]]
young = 1e9
poisson = 0.25
density = 1000.0

[simulation]
duration = 0.001
"#;

/// The smallest thin-shell scene: a sphere, its material, a duration.
const SHELL: &str = r#"
[shell]
surface = "sphere"
radius = 0.03
thickness = 5e-4

[[material]]
young = 70e9
poisson = 0.22
density = 2500.0

[simulation]
duration = 0.001
"#;

/// One table of the schema and the scenes that show its keys.
struct Table {
    /// The section of `docs/scenes.md` that lists its keys: `## ` and then this.
    heading: &'static str,
    kind: Kind,
    /// Where the table sits in a scene, as TOML keys; an array of tables stands for its last
    /// element.
    path: &'static [&'static str],
    /// Scenes that parse and hold the table at `path`: one per variant whose keys differ (a
    /// material's keys may one day depend on its `model`). The section lists the union.
    bases: Vec<String>,
}

fn with(base: &str, extra: &str) -> String {
    format!("{base}\n{extra}\n")
}

/// A second material, in a region.
const REGION_MATERIAL: &str = "[[material]]\nyoung = 1e9\npoisson = 0.25\ndensity = 1000.0\n\
                               region = { min = [0.0, 0.0, 0.0], max = [0.5, 0.1, 0.1] }";
const ANCHOR: &str = "[[anchor]]\nregion = { min = [0.0, 0.0, 0.0], max = [0.2, 0.1, 0.1] }";
const VELOCITY: &str =
    "[[velocity]]\nlinear = [1.0, 0.0, 0.0]\nregion = { min = [0.5, 0.0, 0.0], max = [1.0, 0.1, 0.1] }";
const PRECRACK: &str = "[[precrack]]\npoint = [0.5, 0.05, 0.05]\nnormal = [1.0, 0.0, 0.0]\n\
                        region = { min = [0.4, 0.0, 0.0], max = [0.6, 0.1, 0.05] }";
const LOAD: &str =
    "[[load]]\npressure = 1e3\nregion = { min = [0.9, 0.0, 0.0], max = [1.0, 0.1, 0.1] }";
const BALL: &str = "[[ball]]\ncenter = [0.5, 0.05, 1.0]\nradius = 0.1";

/// The tables of tet scenes.
fn tet_tables() -> Vec<Table> {
    let t = |heading: &'static str, path: &'static [&'static str], bases: Vec<String>| Table {
        heading,
        kind: Kind::Tet,
        path,
        bases,
    };
    let xu = TET.replace("[[material]]\n", "[[material]]\nmodel = \"xu\"\n");
    vec![
        t("[mesh]", &["mesh"], vec![TET.into()]),
        t("[[material]]", &["material"], vec![TET.into(), xu.clone()]),
        t(
            "[material.region]",
            &["material", "region"],
            vec![with(TET, REGION_MATERIAL)],
        ),
        t(
            "[simulation]",
            &["simulation"],
            vec![
                TET.into(),
                xu.replace(
                    "[simulation]\n",
                    "[simulation]\nintegrator = \"implicit\"\n",
                ),
            ],
        ),
        t("[[ground]]", &["ground"], vec![with(TET, "[[ground]]")]),
        t("[[ball]]", &["ball"], vec![with(TET, BALL)]),
        t("[[anchor]]", &["anchor"], vec![with(TET, ANCHOR)]),
        t(
            "[anchor.region]",
            &["anchor", "region"],
            vec![with(TET, ANCHOR)],
        ),
        t("[[velocity]]", &["velocity"], vec![with(TET, VELOCITY)]),
        t(
            "[velocity.region]",
            &["velocity", "region"],
            vec![with(TET, VELOCITY)],
        ),
        t("[[precrack]]", &["precrack"], vec![with(TET, PRECRACK)]),
        t("[[load]]", &["load"], vec![with(TET, LOAD)]),
        t("[load.region]", &["load", "region"], vec![with(TET, LOAD)]),
        t(
            "[precrack.region]",
            &["precrack", "region"],
            vec![with(TET, PRECRACK)],
        ),
        t(
            "[output]",
            &["output"],
            vec![with(TET, "[output]\nframes = 2")],
        ),
    ]
}

/// The tables of thin-shell scenes that have their own section.
fn shell_tables() -> Vec<Table> {
    let s = |heading: &'static str, path: &'static [&'static str], bases: Vec<String>| Table {
        heading,
        kind: Kind::Shell,
        path,
        bases,
    };
    vec![
        s("Thin shells: [shell]", &["shell"], vec![SHELL.into()]),
        s(
            "Thin shells: [[material]]",
            &["material"],
            vec![SHELL.into()],
        ),
        s(
            "Thin shells: [simulation]",
            &["simulation"],
            vec![
                SHELL.into(),
                SHELL.replace("[simulation]\n", "[simulation]\nintegrator = \"newmark\"\n"),
            ],
        ),
        s(
            "Thin shells: [output]",
            &["output"],
            vec![with(SHELL, "[output]\nframes = 2")],
        ),
    ]
}

/// Thin-shell tables that `docs/scenes.md` says take the keys of the tet scenes' table with
/// this heading, each with a shell scene that holds it.
fn shared_tables() -> Vec<(&'static str, &'static [&'static str], String)> {
    type Shared = (&'static str, &'static [&'static str], String);
    let ball = "[[ball]]\ncenter = [0.0, 0.0, 1.0]\nradius = 0.1";
    let anchor = "[[anchor]]\nregion = { min = [-1.0, -1.0, -1.0], max = [1.0, 1.0, 0.0] }";
    let velocity =
        "[[velocity]]\nlinear = [0.0, 0.0, -1.0]\nregion = { min = [-1.0, -1.0, -1.0], max = [1.0, 1.0, 1.0] }";
    let load =
        "[[load]]\npressure = 1e3\nregion = { min = [-1.0, -1.0, -1.0], max = [1.0, 1.0, 1.0] }";
    let shared: Vec<Shared> = vec![
        ("[[load]]", &["load"], with(SHELL, load)),
        ("[load.region]", &["load", "region"], with(SHELL, load)),
        (
            "[[ground]]",
            &["ground"],
            with(SHELL, "[[ground]]\npoint = [0.0, 0.0, -1.0]"),
        ),
        ("[[ball]]", &["ball"], with(SHELL, ball)),
        ("[[anchor]]", &["anchor"], with(SHELL, anchor)),
        (
            "[anchor.region]",
            &["anchor", "region"],
            with(SHELL, anchor),
        ),
        ("[[velocity]]", &["velocity"], with(SHELL, velocity)),
        (
            "[velocity.region]",
            &["velocity", "region"],
            with(SHELL, velocity),
        ),
    ];
    shared
}

/// The parser's message for `text`, or `None` when it parses.
fn parse_error(kind: Kind, text: &str) -> Option<String> {
    let path = Path::new("scene_docs.toml");
    match kind {
        Kind::Tet => Scene::parse(text, path).err().map(|e| e.to_string()),
        Kind::Shell => ShellScene::parse(text, path).err().map(|e| e.to_string()),
    }
}

/// The table at `path` in `root`; an array of tables stands for its last element.
fn table_at<'a>(root: &'a mut toml::Table, path: &[&str]) -> &'a mut toml::Table {
    let mut table = root;
    for key in path {
        let value = table
            .get_mut(*key)
            .unwrap_or_else(|| panic!("the base scene has no `{key}` on the way to {path:?}"));
        table = match value {
            toml::Value::Table(t) => t,
            toml::Value::Array(items) => items
                .last_mut()
                .and_then(toml::Value::as_table_mut)
                .unwrap_or_else(|| panic!("`{key}` in the base scene is not an array of tables")),
            other => panic!("`{key}` in the base scene is {other:?}, not a table"),
        };
    }
    table
}

/// The keys serde lists after "unknown field `zz`, expected ...", in `message`.
fn expected_keys(message: &str) -> Option<BTreeSet<String>> {
    let start = message.find(&format!("unknown field `{BOGUS}`"))?;
    let rest = &message[start + "unknown field ``".len() + BOGUS.len()..];
    if rest.contains("there are no fields") {
        return Some(BTreeSet::new());
    }
    let rest = &rest[rest.find("expected")?..];
    // every other backtick opens a key: `a`, `b` or `c`
    Some(
        rest.split('`')
            .skip(1)
            .step_by(2)
            .map(str::to_string)
            .collect(),
    )
}

/// Every key the table at `path` of `base` takes: serde's list when `zz` is added there, and
/// the keys `base` itself sets there (the parser took them; an enum's tag is one such key that
/// serde does not list).
fn keys_of(kind: Kind, base: &str, path: &[&str]) -> BTreeSet<String> {
    if let Some(message) = parse_error(kind, base) {
        panic!("the base scene of {path:?} does not parse: {message}\n{base}");
    }
    let mut root: toml::Table = base.parse().expect("the base scene is TOML");
    let table = table_at(&mut root, path);
    let mut keys: BTreeSet<String> = table.keys().cloned().collect();
    table.insert(BOGUS.into(), toml::Value::Integer(1));
    let text = toml::to_string(&root).expect("the scene serialises");
    let message = parse_error(kind, &text)
        .unwrap_or_else(|| panic!("{path:?} took the bogus key `{BOGUS}`:\n{text}"));
    let listed = expected_keys(&message).unwrap_or_else(|| {
        panic!(
            "{path:?}: expected serde's \"unknown field `{BOGUS}`, expected ...\", got: {message}"
        )
    });
    keys.extend(listed);
    keys
}

/// The union of the keys over a table's bases.
fn table_keys(table: &Table) -> BTreeSet<String> {
    table
        .bases
        .iter()
        .flat_map(|base| keys_of(table.kind, base, table.path))
        .collect()
}

/// `docs/scenes.md` read as sections (the text after `## `) and the keys their table rows name
/// in the first column, in backticks. Only a table whose header's first cell is `key` lists
/// keys (a table of values, such as the presets', does not). A section without rows maps to an
/// empty set.
fn doc_sections(text: &str) -> BTreeMap<String, BTreeSet<String>> {
    let mut sections: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    let mut current: Option<String> = None;
    let mut in_code = false;
    let mut other_table = false;
    for (n, line) in text.lines().enumerate() {
        if !line.trim_start().starts_with('|') {
            other_table = false;
        } else if line.trim_start().starts_with("| ")
            && !line.contains("| key |")
            && text
                .lines()
                .nth(n + 1)
                .is_some_and(|next| next.trim_start().starts_with("|---"))
        {
            other_table = true;
        }
        if other_table {
            continue;
        }
        if line.trim_start().starts_with("```") {
            in_code = !in_code;
            continue;
        }
        if in_code {
            continue;
        }
        if let Some(heading) = line.strip_prefix("## ") {
            let heading = heading.trim().to_string();
            sections.entry(heading.clone()).or_default();
            current = Some(heading);
            continue;
        }
        if line.starts_with("# ") {
            current = None;
            continue;
        }
        let Some(row) = line.trim().strip_prefix('|') else {
            continue;
        };
        let first = row.split('|').next().unwrap_or("").trim();
        if first == "key" || first.starts_with("---") {
            continue;
        }
        let key = first
            .strip_prefix('`')
            .and_then(|k| k.strip_suffix('`'))
            .unwrap_or_else(|| {
                panic!(
                    "docs/scenes.md:{}: a row's first cell is not a key in backticks: {line}",
                    n + 1
                )
            });
        let Some(section) = &current else {
            panic!("docs/scenes.md:{}: a key row outside any section", n + 1);
        };
        sections
            .get_mut(section)
            .expect("the section was entered")
            .insert(key.to_string());
    }
    sections
}

fn scenes_md() -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/scenes.md");
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// What is wrong between the schema's keys in `schema` (heading to keys) and the page's rows.
fn mismatches(
    schema: &BTreeMap<&str, BTreeSet<String>>,
    doc: &BTreeMap<String, BTreeSet<String>>,
) -> Vec<String> {
    let mut problems = Vec::new();
    for (heading, keys) in schema {
        let Some(rows) = doc.get(*heading) else {
            problems.push(format!(
                "no section `## {heading}` (its keys: {})",
                keys.iter().cloned().collect::<Vec<_>>().join(", ")
            ));
            continue;
        };
        for key in keys.difference(rows) {
            problems.push(format!("`{key}` is missing from section `## {heading}`"));
        }
        for key in rows.difference(keys) {
            problems.push(format!(
                "section `## {heading}` has a row for `{key}`, which the schema does not take"
            ));
        }
    }
    for (heading, rows) in doc {
        if !rows.is_empty() && !schema.contains_key(heading.as_str()) {
            problems.push(format!(
                "section `## {heading}` has key rows but names no table of the schema"
            ));
        }
    }
    problems
}

#[test]
fn serde_lists_the_keys_of_a_table() {
    // The three shapes of serde's list, on a table of one, two and many keys.
    let keys = |m: &str| expected_keys(m).map(|k| k.into_iter().collect::<Vec<_>>());
    assert_eq!(
        keys("s.toml:3:1: unknown field `zz`, expected `region`"),
        Some(vec!["region".to_string()])
    );
    assert_eq!(
        keys("unknown field `zz`, expected `min` or `max`"),
        Some(vec!["max".to_string(), "min".to_string()])
    );
    assert_eq!(
        keys("unknown field `zz`, expected one of `a`, `b`, `c`"),
        Some(vec!["a".to_string(), "b".to_string(), "c".to_string()])
    );
    assert_eq!(
        keys("unknown field `zz`, there are no fields"),
        Some(vec![])
    );
    assert_eq!(keys("missing field `density`"), None);
    // And the parser says it that way: a region has two keys.
    let region = keys_of(Kind::Tet, &with(TET, ANCHOR), &["anchor", "region"]);
    assert_eq!(region.into_iter().collect::<Vec<_>>(), ["max", "min"]);
}

#[test]
fn every_scene_key_has_a_row_in_docs_scenes_md() {
    let tables: Vec<Table> = tet_tables().into_iter().chain(shell_tables()).collect();
    let schema: BTreeMap<&str, BTreeSet<String>> =
        tables.iter().map(|t| (t.heading, table_keys(t))).collect();
    let problems = mismatches(&schema, &doc_sections(&scenes_md()));
    assert!(
        problems.is_empty(),
        "docs/scenes.md and the scene schema disagree:\n  {}",
        problems.join("\n  ")
    );
}

#[test]
fn every_top_level_table_has_a_case_here() {
    // A table added to the schema needs a case above (and so a section in docs/scenes.md).
    for (kind, base, tables) in [
        (Kind::Tet, TET, tet_tables()),
        (
            Kind::Shell,
            SHELL,
            shell_tables()
                .into_iter()
                .chain(
                    shared_tables()
                        .into_iter()
                        .map(|(heading, path, base)| Table {
                            heading,
                            kind: Kind::Shell,
                            path,
                            bases: vec![base],
                        }),
                )
                .collect(),
        ),
    ] {
        let covered: BTreeSet<&str> = tables
            .iter()
            .filter(|t| t.path.len() == 1)
            .map(|t| t.path[0])
            .collect();
        for table in keys_of(kind, base, &[]) {
            assert!(
                covered.contains(table.as_str()),
                "{kind:?} scenes have a table `{table}` that scene_docs.rs does not check: add a \
                 case and a section of docs/scenes.md"
            );
        }
    }
}

#[test]
fn shell_colliders_anchors_and_velocities_take_the_tet_scenes_keys() {
    // docs/scenes.md says so instead of listing them twice.
    let tet: BTreeMap<&str, BTreeSet<String>> = tet_tables()
        .iter()
        .map(|t| (t.heading, table_keys(t)))
        .collect();
    for (heading, path, base) in shared_tables() {
        let shell = keys_of(Kind::Shell, &base, path);
        assert_eq!(
            Some(&shell),
            tet.get(heading),
            "thin-shell {heading} takes other keys than the tet scenes' {heading}: give it a \
             section `## Thin shells: {heading}` in docs/scenes.md and a case here"
        );
    }
}
