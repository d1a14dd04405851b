//! ARCHITECTURE.md's code map says what each crate never depends on; this test reads the
//! dependency graph from `cargo metadata` (normal dependencies, transitively, with the
//! workspace's features resolved) and checks it. Each rule below is also checked to appear in
//! its crate's row of the table, so the page and the test cannot drift apart silently.

use serde_json::Value;
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;
use std::process::Command;

/// `(crate, packages it never depends on, the words of its ARCHITECTURE.md row that say so)`.
const RULES: &[(&str, &[&str], &[&str])] = &[
    (
        "hce-format",
        &[
            "wgpu",
            "glam",
            "hce-geometry",
            "hce-meshio",
            "hce-runtime",
            "hce-bake",
            "hce-tools",
            "hce-samples",
        ],
        &["wgpu", "glam", "geometry", "the other hce crates"],
    ),
    (
        "hce-geometry",
        &["wgpu", "gltf", "tobj", "hce-meshio"],
        &["files", "wgpu", "gltf", "tobj"],
    ),
    (
        "hce-meshio",
        &["wgpu", "hce-bake", "obvhs", "hce-geometry", "hce-runtime"],
        &["wgpu", "the solver", "hce-geometry"],
    ),
    (
        "hce-runtime",
        &["hce-bake", "hce-tools"],
        &["hce-bake", "hce-tools", "readers and writers"],
    ),
    (
        "hce-bake",
        &["hce-tools", "hce-runtime"],
        &["hce-tools", "hce-runtime"],
    ),
    (
        "hce-samples",
        &[
            "hce-format",
            "hce-geometry",
            "hce-meshio",
            "hce-runtime",
            "hce-bake",
            "hce-tools",
        ],
        &["the other hce crates"],
    ),
];

/// `cargo metadata`'s output for the workspace.
fn metadata() -> Value {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    // The host's dependencies only: the graph this machine builds, all of it already fetched.
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    let version = Command::new(rustc).arg("-vV").output().expect("rustc runs");
    let host = String::from_utf8_lossy(&version.stdout)
        .lines()
        .find_map(|l| l.strip_prefix("host: ").map(str::to_string))
        .expect("rustc -vV names the host");
    let out = Command::new(cargo)
        .current_dir(&root)
        .args(["metadata", "--format-version", "1", "--offline"])
        .args(["--filter-platform", &host])
        .output()
        .expect("cargo metadata runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("cargo metadata prints JSON")
}

/// Per workspace package name, the names of every package it depends on through normal
/// (non-dev, non-build) dependencies, transitively.
fn normal_closure(m: &Value) -> BTreeMap<String, BTreeSet<String>> {
    closure(m, |kind| kind.is_null())
}

/// Per workspace package name, the workspace packages it names as dev-dependencies (directly).
fn dev_dependencies(m: &Value) -> BTreeMap<String, BTreeSet<String>> {
    let members: BTreeSet<&str> = m["workspace_members"]
        .as_array()
        .unwrap()
        .iter()
        .map(|id| id.as_str().unwrap())
        .collect();
    let name_of = names(m);
    let mut out = BTreeMap::new();
    for node in m["resolve"]["nodes"].as_array().unwrap() {
        let id = node["id"].as_str().unwrap();
        if !members.contains(id) {
            continue;
        }
        let dev: BTreeSet<String> = node["deps"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|d| {
                let pkg = d["pkg"].as_str().unwrap();
                pkg != id
                    && members.contains(pkg)
                    && d["dep_kinds"]
                        .as_array()
                        .unwrap()
                        .iter()
                        .any(|k| k["kind"] == "dev")
            })
            .map(|d| name_of[d["pkg"].as_str().unwrap()].to_string())
            .collect();
        out.insert(name_of[id].to_string(), dev);
    }
    out
}

fn names(m: &Value) -> BTreeMap<&str, &str> {
    m["packages"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| (p["id"].as_str().unwrap(), p["name"].as_str().unwrap()))
        .collect()
}

/// Per workspace package name, every package it reaches through dependencies whose kind
/// `follow` accepts, transitively.
fn closure(m: &Value, follow: impl Fn(&Value) -> bool) -> BTreeMap<String, BTreeSet<String>> {
    let name_of = names(m);
    let mut edges: BTreeMap<&str, Vec<&str>> = BTreeMap::new();
    for node in m["resolve"]["nodes"].as_array().unwrap() {
        let id = node["id"].as_str().unwrap();
        let normal = node["deps"].as_array().unwrap().iter().filter(|d| {
            d["dep_kinds"]
                .as_array()
                .unwrap()
                .iter()
                .any(|k| follow(&k["kind"]))
        });
        edges.insert(id, normal.map(|d| d["pkg"].as_str().unwrap()).collect());
    }
    let mut out = BTreeMap::new();
    for id in m["workspace_members"].as_array().unwrap() {
        let id = id.as_str().unwrap();
        let mut seen = BTreeSet::new();
        let mut stack = vec![id];
        while let Some(p) = stack.pop() {
            for &d in edges.get(p).map(Vec::as_slice).unwrap_or(&[]) {
                if seen.insert(d) {
                    stack.push(d);
                }
            }
        }
        out.insert(
            name_of[id].to_string(),
            seen.iter().map(|d| name_of[d].to_string()).collect(),
        );
    }
    out
}

#[test]
fn no_crate_depends_on_what_architecture_md_forbids() {
    let closure = normal_closure(&metadata());
    assert!(closure.len() >= 8, "{} workspace members", closure.len());
    // The graph is read, not empty: the runtime reaches wgpu and the format crate.
    assert!(closure["hce-runtime"].contains("wgpu"));
    assert!(closure["hce-runtime"].contains("hce-format"));
    let mut broken = Vec::new();
    for (krate, never, _) in RULES {
        let deps = closure
            .get(*krate)
            .unwrap_or_else(|| panic!("{krate} is not a workspace member"));
        for n in *never {
            if deps.contains(*n) {
                broken.push(format!("{krate} depends on {n}"));
            }
        }
    }
    assert!(broken.is_empty(), "{broken:#?}");
}

/// The crates' order (ARCHITECTURE.md: "Dependencies point one way"): no crate depends, even
/// transitively, on one later in this list.
const ORDER: &[&str] = &[
    "hce-format",
    "hce-geometry",
    "hce-meshio",
    "hce-runtime",
    "hce-bake",
    "hce-tools",
];

#[test]
fn dependencies_point_one_way() {
    let closure = normal_closure(&metadata());
    let mut broken = Vec::new();
    for (i, krate) in ORDER.iter().enumerate() {
        for later in &ORDER[i + 1..] {
            if closure[*krate].contains(*later) {
                broken.push(format!("{krate} depends on {later}"));
            }
        }
    }
    assert!(broken.is_empty(), "{broken:#?}");
    // The order is a real one: each crate after the format reaches the format.
    for krate in &ORDER[1..] {
        assert!(closure[*krate].contains("hce-format"), "{krate}");
    }
}

/// A crate's tests may use a crate above it (geometry's read meshes through meshio), but never one
/// that depends on the crate under test: that would be a cycle, the crate built twice, and
/// a forbidden edge hidden in a test.
#[test]
fn no_dev_dependency_closes_a_cycle() {
    let m = metadata();
    let closure = normal_closure(&m);
    let dev = dev_dependencies(&m);
    // The graph is read: geometry's tests take meshio.
    assert!(dev["hce-geometry"].contains("hce-meshio"), "{dev:?}");
    let mut cycles = Vec::new();
    for (krate, devs) in &dev {
        for d in devs {
            if closure[d].contains(krate) {
                cycles.push(format!(
                    "{krate} dev-depends on {d}, which depends on {krate}"
                ));
            }
        }
    }
    assert!(cycles.is_empty(), "{cycles:#?}");
}

/// hce-runtime takes hce-meshio without its features (no readers, no writers), so that a viewer
/// does not link tobj, image decoders or the OBJ writer. Features unify across the workspace,
/// so the resolved graph cannot show this; the manifest does.
#[test]
fn the_runtime_takes_meshio_without_features() {
    let m = metadata();
    let runtime = m["packages"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["name"] == "hce-runtime")
        .expect("hce-runtime is a package");
    let meshio: Vec<&Value> = runtime["dependencies"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|d| d["name"] == "hce-meshio" && d["kind"].is_null())
        .collect();
    assert_eq!(meshio.len(), 1, "{meshio:?}");
    assert_eq!(meshio[0]["features"], serde_json::json!([]));
    // Not its default features (`import`, `export`) either.
    assert_eq!(meshio[0]["uses_default_features"], false);
}

#[test]
fn the_rules_are_the_ones_architecture_md_states() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../ARCHITECTURE.md");
    let text = std::fs::read_to_string(path).unwrap();
    for (krate, _, words) in RULES {
        let row = text
            .lines()
            .find(|l| l.starts_with(&format!("| {krate} |")))
            .unwrap_or_else(|| panic!("no row for {krate} in ARCHITECTURE.md"));
        let never = row.rsplit('|').nth(1).unwrap_or("");
        for w in *words {
            assert!(never.contains(w), "{krate}: {w:?} not in {never:?}");
        }
    }
}
