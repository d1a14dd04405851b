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
        "hce-reference",
        &["hce-bake", "wgpu", "hce-runtime", "hce-tools"],
        &["hce-bake", "wgpu", "hce-runtime", "hce-tools"],
    ),
    (
        "hce-refined",
        &["wgpu", "hce-bake", "hce-runtime", "hce-tools"],
        &["wgpu", "hce-bake", "hce-runtime", "hce-tools"],
    ),
    (
        "hce-bake",
        &["hce-tools", "hce-runtime"],
        &["hce-tools", "hce-runtime"],
    ),
    (
        "hce-wasm",
        &["hce-bake", "hce-reference", "hce-tools"],
        &["hce-bake", "hce-reference", "hce-tools"],
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
    let members = workspace_members(m);
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

/// The package ids of the workspace's members.
fn workspace_members(m: &Value) -> BTreeSet<&str> {
    m["workspace_members"]
        .as_array()
        .unwrap()
        .iter()
        .map(|id| id.as_str().unwrap())
        .collect()
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
    "hce-reference",
    "hce-refined",
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

/// The path tracer is the solver's yardstick only while it shares none of its code: not even its
/// tests may reach hce-bake (they would check the solver against itself).
#[test]
fn the_reference_tests_never_reach_the_solver() {
    let m = metadata();
    let closure = normal_closure(&m);
    let dev = dev_dependencies(&m);
    let tests = &dev["hce-reference"];
    // The graph is read: the reference's tests import the Cornell box through meshio.
    assert!(tests.contains("hce-meshio"), "{tests:?}");
    let reached: Vec<&String> = tests
        .iter()
        .filter(|d| *d == "hce-bake" || closure[*d].contains("hce-bake"))
        .collect();
    assert!(
        reached.is_empty(),
        "hce-reference's tests reach hce-bake through {reached:?}"
    );
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

/// Every crate's modules import each other one way only: no two modules use each other,
/// directly or around a circle. Within each module (the crate root first), its submodules are
/// taken whole, everything below them included, and an edge goes from one to another when any
/// code of the first names an item of the second through `crate::`, `super::` or `self::`
/// paths (`use` items and paths in code, through `pub use` re-exports to where the item is
/// defined). A module and its own submodules are one unit and may use each other; code under
/// `#[cfg(test)]` is left out, as are paths inside macro invocations.
#[test]
fn no_module_circle_within_a_crate() {
    let m = metadata();
    let members = workspace_members(&m);
    let mut circles = Vec::new();
    let mut modules = 0;
    let mut edges = 0;
    for p in m["packages"].as_array().unwrap() {
        if !members.contains(p["id"].as_str().unwrap()) {
            continue;
        }
        for t in p["targets"].as_array().unwrap() {
            let kinds = t["kind"].as_array().unwrap();
            if !kinds.iter().any(|k| k == "lib" || k == "bin") {
                continue;
            }
            let name = format!(
                "{} ({})",
                p["name"].as_str().unwrap(),
                t["name"].as_str().unwrap()
            );
            let graph = module_graph(Path::new(t["src_path"].as_str().unwrap()));
            modules += graph.modules;
            edges += graph.edges.len();
            circles.extend(graph.circles().into_iter().map(|c| format!("{name}: {c}")));
        }
    }
    // The sources were read: the workspace has well over a hundred modules and their edges.
    assert!(
        modules > 100 && edges > 100,
        "{modules} modules, {edges} edges"
    );
    assert!(
        circles.is_empty(),
        "module circles:\n{}",
        circles.join("\n")
    );
}

/// The circle finder itself, on a small crate with one circle and one one-way edge.
#[test]
fn a_module_circle_is_found_and_named() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path();
    std::fs::write(
        src.join("lib.rs"),
        "mod a;\nmod b;\nmod c;\npub use c::Thing;\n",
    )
    .unwrap();
    std::fs::write(src.join("a.rs"), "use crate::b::f;\npub fn g() { f() }\n").unwrap();
    // `b` reaches `a` through the root's re-export of `c`, which `c` defines... and `a` itself.
    std::fs::write(
        src.join("b.rs"),
        "pub fn f() { let _ = crate::Thing; super::a::g(); }\n#[cfg(test)]\nmod tests { use crate::a::*; }\n",
    )
    .unwrap();
    std::fs::write(
        src.join("c.rs"),
        "pub struct Thing;\n#[cfg(test)]\nuse crate::a::g;\n",
    )
    .unwrap();
    let graph = module_graph(&src.join("lib.rs"));
    assert_eq!(graph.modules, 4);
    let circles = graph.circles();
    assert_eq!(circles.len(), 1, "{circles:?}");
    assert!(circles[0].starts_with("a → b → a"), "{}", circles[0]);
    assert!(circles[0].contains("`super::a::g`"), "{}", circles[0]);
    // b → c through the root's `pub use`; nothing under `#[cfg(test)]` counts (c → a would be
    // a second circle).
    assert!(graph.edges.contains_key(&(vec![], "b".into(), "c".into())));
    assert!(!graph.edges.contains_key(&(vec![], "c".into(), "a".into())));
}

/// A crate's module tree and the edges between sibling units.
struct ModuleGraph {
    modules: usize,
    /// `(parent, from child, to child)` → the first path that makes the edge, with its file.
    edges: BTreeMap<(Vec<String>, String, String), String>,
}

impl ModuleGraph {
    /// Each circle (a strongly connected set of siblings), as `a → b → a` with the paths that
    /// make each step.
    fn circles(&self) -> Vec<String> {
        let mut by_parent: BTreeMap<&Vec<String>, BTreeMap<&str, Vec<&str>>> = BTreeMap::new();
        for (parent, from, to) in self.edges.keys() {
            by_parent
                .entry(parent)
                .or_default()
                .entry(from)
                .or_default()
                .push(to);
        }
        let mut out = Vec::new();
        for (parent, graph) in by_parent {
            let mut done = BTreeSet::new();
            for &start in graph.keys() {
                if done.contains(start) {
                    continue;
                }
                if let Some(circle) = circle_through(start, &graph) {
                    done.extend(circle.iter().copied());
                    let steps: Vec<String> = circle
                        .iter()
                        .zip(circle.iter().cycle().skip(1))
                        .map(|(a, b)| {
                            self.edges[&(parent.clone(), a.to_string(), b.to_string())].clone()
                        })
                        .collect();
                    let mut names: Vec<&str> = circle.clone();
                    names.push(circle[0]);
                    let prefix = if parent.is_empty() {
                        String::new()
                    } else {
                        format!("in {}: ", parent.join("::"))
                    };
                    out.push(format!(
                        "{prefix}{} ({})",
                        names.join(" → "),
                        steps.join("; ")
                    ));
                }
            }
        }
        out
    }
}

/// The shortest circle from `start` back to itself, if any (breadth first).
fn circle_through<'a>(
    start: &'a str,
    graph: &BTreeMap<&'a str, Vec<&'a str>>,
) -> Option<Vec<&'a str>> {
    let mut came_from: BTreeMap<&str, &str> = BTreeMap::new();
    let mut queue = std::collections::VecDeque::from([start]);
    while let Some(at) = queue.pop_front() {
        for &next in graph.get(at).map(Vec::as_slice).unwrap_or(&[]) {
            if next == start {
                let mut path = vec![at];
                while let Some(&p) = came_from.get(path.last().unwrap()) {
                    path.push(p);
                }
                path.reverse();
                return Some(path);
            }
            if next != start && !came_from.contains_key(next) {
                came_from.insert(next, at);
                queue.push_back(next);
            }
        }
    }
    None
}

/// One source file's module: its path in the crate and the crate paths its code names.
struct SourceModule {
    path: Vec<String>,
    file: String,
    /// Absolute paths (without `crate`), each with the text it was written as.
    uses: Vec<(Vec<String>, String)>,
    /// Names re-exported by `pub use`, each with the absolute path it stands for.
    reexports: BTreeMap<String, Vec<String>>,
}

/// Reads the crate rooted at `root` (its `lib.rs`, `main.rs` or bin file) and builds its graph.
fn module_graph(root: &Path) -> ModuleGraph {
    let mut files = Vec::new();
    read_module(root, root.parent().unwrap(), Vec::new(), &mut files);
    let known: BTreeMap<Vec<String>, usize> = files
        .iter()
        .enumerate()
        .map(|(i, f)| (f.path.clone(), i))
        .collect();
    let mut edges = BTreeMap::new();
    for f in &files {
        for (target, text) in &f.uses {
            let Some(to) = resolve(target, &files, &known, 0) else {
                continue;
            };
            let common = f.path.iter().zip(&to).take_while(|(a, b)| a == b).count();
            // A module and its own submodules (or ancestors) are one unit.
            if common == f.path.len() || common == to.len() {
                continue;
            }
            edges
                .entry((
                    f.path[..common].to_vec(),
                    f.path[common].clone(),
                    to[common].clone(),
                ))
                .or_insert_with(|| format!("{} names `{text}`", f.file));
        }
    }
    ModuleGraph {
        modules: files.len(),
        edges,
    }
}

/// The module that defines what the absolute path `target` names: its longest prefix that is
/// a module, followed through that module's `pub use` of the next name.
fn resolve(
    target: &[String],
    files: &[SourceModule],
    known: &BTreeMap<Vec<String>, usize>,
    depth: usize,
) -> Option<Vec<String>> {
    let len = (0..=target.len())
        .rev()
        .find(|&n| known.contains_key(&target[..n]))?;
    let module = &files[known[&target[..len]]];
    match target.get(len).and_then(|name| module.reexports.get(name)) {
        Some(source) if depth < 8 => {
            let mut next = source.clone();
            next.extend_from_slice(&target[len + 1..]);
            resolve(&next, files, known, depth + 1).or(Some(module.path.clone()))
        }
        _ => Some(module.path.clone()),
    }
}

fn read_module(file: &Path, dir: &Path, path: Vec<String>, out: &mut Vec<SourceModule>) {
    let text = std::fs::read_to_string(file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
    let parsed = syn::parse_file(&text).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
    // Submodules of `a.rs` live in `a/`; those of `lib.rs`, `main.rs` and `mod.rs` beside them.
    let stem = file.file_stem().unwrap().to_str().unwrap();
    let child_dir = if path.is_empty() || stem == "mod" {
        dir.to_path_buf()
    } else {
        dir.join(stem)
    };
    let mut visitor = PathVisitor {
        module: path.clone(),
        inline: Vec::new(),
        uses: Vec::new(),
        reexports: BTreeMap::new(),
        children: Vec::new(),
    };
    syn::visit::Visit::visit_file(&mut visitor, &parsed);
    let workspace = Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap();
    let shown = file
        .strip_prefix(workspace)
        .unwrap_or(file)
        .display()
        .to_string();
    // A relative `pub use x::Name` re-exports from a submodule only when `x` is one.
    let children: BTreeSet<&String> = visitor.children.iter().map(|(n, _)| n).collect();
    let reexports = visitor
        .reexports
        .into_iter()
        .filter(|(_, (source, relative))| !relative || children.contains(&source[0]))
        .map(|(name, (source, relative))| {
            let mut abs = if relative { path.clone() } else { Vec::new() };
            abs.extend(source);
            (name, abs)
        })
        .collect();
    out.push(SourceModule {
        path: path.clone(),
        file: shown,
        uses: visitor.uses,
        reexports,
    });
    for (name, at) in visitor.children {
        let mut child = path.clone();
        child.push(name.clone());
        let file = match at {
            Some(p) => file.parent().unwrap().join(p),
            None => {
                let flat = child_dir.join(format!("{name}.rs"));
                if flat.exists() {
                    flat
                } else {
                    child_dir.join(&name).join("mod.rs")
                }
            }
        };
        let dir = file.parent().unwrap().to_path_buf();
        read_module(&file, &dir, child, out);
    }
}

/// Collects a file's crate paths, its `pub use` names and its `mod x;` declarations.
struct PathVisitor {
    module: Vec<String>,
    /// Names of the inline modules (`mod x { ... }`) being visited.
    inline: Vec<String>,
    uses: Vec<(Vec<String>, String)>,
    /// `pub use` names: the path each stands for, absolute or (`true`) relative to the module.
    reexports: BTreeMap<String, (Vec<String>, bool)>,
    /// `mod x;` declarations, with their `#[path]` when they have one.
    children: Vec<(String, Option<String>)>,
}

fn is_cfg_test(attrs: &[syn::Attribute]) -> bool {
    attrs.iter().any(|a| {
        a.path().is_ident("cfg") && a.parse_args::<syn::Ident>().is_ok_and(|i| i == "test")
    })
}

impl PathVisitor {
    /// `segments` as an absolute path (without `crate`) when it starts with `crate`, `super` or
    /// `self`.
    fn absolute(&self, segments: &[String]) -> Option<Vec<String>> {
        let mut here: Vec<String> = self.module.iter().chain(&self.inline).cloned().collect();
        match segments.first()?.as_str() {
            "crate" => Some(segments[1..].to_vec()),
            "self" => {
                here.extend_from_slice(&segments[1..]);
                Some(here)
            }
            "super" => {
                let supers = segments.iter().take_while(|s| *s == "super").count();
                here.truncate(here.len().checked_sub(supers)?);
                here.extend_from_slice(&segments[supers..]);
                Some(here)
            }
            _ => None,
        }
    }

    fn add(&mut self, segments: Vec<String>) {
        if let Some(abs) = self.absolute(&segments) {
            self.uses.push((abs, segments.join("::")));
        }
    }
}

/// Each path of a `use` tree with the name it binds (`None` for a glob).
fn flatten_use(
    tree: &syn::UseTree,
    prefix: &mut Vec<String>,
    out: &mut Vec<(Vec<String>, Option<String>)>,
) {
    match tree {
        syn::UseTree::Path(p) => {
            prefix.push(p.ident.to_string());
            flatten_use(&p.tree, prefix, out);
            prefix.pop();
        }
        syn::UseTree::Name(n) if n.ident == "self" => {
            out.push((prefix.clone(), prefix.last().cloned()));
        }
        syn::UseTree::Name(n) => {
            let mut p = prefix.clone();
            p.push(n.ident.to_string());
            out.push((p, Some(n.ident.to_string())));
        }
        syn::UseTree::Rename(r) => {
            let mut p = prefix.clone();
            p.push(r.ident.to_string());
            out.push((p, Some(r.rename.to_string())));
        }
        syn::UseTree::Glob(_) => out.push((prefix.clone(), None)),
        syn::UseTree::Group(g) => {
            for t in &g.items {
                flatten_use(t, prefix, out);
            }
        }
    }
}

impl<'ast> syn::visit::Visit<'ast> for PathVisitor {
    fn visit_item(&mut self, item: &'ast syn::Item) {
        let attrs: &[syn::Attribute] = match item {
            syn::Item::Const(i) => &i.attrs,
            syn::Item::Enum(i) => &i.attrs,
            syn::Item::Fn(i) => &i.attrs,
            syn::Item::Impl(i) => &i.attrs,
            syn::Item::Macro(i) => &i.attrs,
            syn::Item::Mod(i) => &i.attrs,
            syn::Item::Static(i) => &i.attrs,
            syn::Item::Struct(i) => &i.attrs,
            syn::Item::Trait(i) => &i.attrs,
            syn::Item::Type(i) => &i.attrs,
            syn::Item::Use(i) => &i.attrs,
            _ => &[],
        };
        if !is_cfg_test(attrs) {
            syn::visit::visit_item(self, item);
        }
    }

    fn visit_item_mod(&mut self, m: &'ast syn::ItemMod) {
        match &m.content {
            None => {
                let at = m
                    .attrs
                    .iter()
                    .find(|a| a.path().is_ident("path"))
                    .and_then(|a| match &a.meta {
                        syn::Meta::NameValue(nv) => match &nv.value {
                            syn::Expr::Lit(syn::ExprLit {
                                lit: syn::Lit::Str(s),
                                ..
                            }) => Some(s.value()),
                            _ => None,
                        },
                        _ => None,
                    });
                self.children.push((m.ident.to_string(), at));
            }
            Some((_, items)) => {
                self.inline.push(m.ident.to_string());
                for i in items {
                    self.visit_item(i);
                }
                self.inline.pop();
            }
        }
    }

    fn visit_item_use(&mut self, u: &'ast syn::ItemUse) {
        let mut paths = Vec::new();
        flatten_use(&u.tree, &mut Vec::new(), &mut paths);
        let public = !matches!(u.vis, syn::Visibility::Inherited) && self.inline.is_empty();
        for (segments, name) in paths {
            let abs = self.absolute(&segments);
            if let (true, Some(name)) = (public, name) {
                let source = match &abs {
                    Some(abs) => (abs.clone(), false),
                    None => (segments.clone(), true),
                };
                self.reexports.insert(name, source);
            }
            if abs.is_some() {
                self.add(segments);
            }
        }
    }

    fn visit_path(&mut self, p: &'ast syn::Path) {
        if p.segments.len() > 1 {
            self.add(p.segments.iter().map(|s| s.ident.to_string()).collect());
        }
        syn::visit::visit_path(self, p);
    }
}
