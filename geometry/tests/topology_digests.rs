//! The whole output of `build_control_mesh` is pinned: every table of the control mesh, the
//! maps back to the welded input and the report, for every mesh of `tests/data` (and of
//! `HCE_EXTRA_MESHES`, when set) under every crease and non-manifold mode. The tables are what
//! the baker stores and both Loop kernels read, so a refactoring of the topology steps must
//! leave these FNV-1a digests unchanged; a deliberate change of the tables rewrites
//! `tests/data/topology_digests.txt` with `HCE_UPDATE_GOLDEN=1` (with `HCE_EXTRA_MESHES` set, so
//! that the shared meshes keep their lines).

mod common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use hce_geometry::topology::{
    build_control_mesh, Creases, NonManifold, Topology, TopologyConfig, TopologyError,
};

const MODES: &[(Creases, NonManifold)] = &[
    (Creases::None, NonManifold::Split),
    (Creases::Auto, NonManifold::Split),
    (Creases::Angle(30.0), NonManifold::Split),
    (Creases::Angle(60.0), NonManifold::Split),
    (Creases::None, NonManifold::Refuse),
    (Creases::Auto, NonManifold::Refuse),
    (Creases::Angle(30.0), NonManifold::Refuse),
    (Creases::Angle(60.0), NonManifold::Refuse),
];

const FNV_START: u64 = 0xcbf29ce484222325;

fn fnv(h: &mut u64, bytes: &[u8]) {
    for &b in bytes {
        *h ^= b as u64;
        *h = h.wrapping_mul(0x100000001b3);
    }
}

/// Each section hashed with its length first, so that a word moving between sections shows.
fn words(h: &mut u64, w: impl ExactSizeIterator<Item = u32>) {
    fnv(h, &(w.len() as u64).to_le_bytes());
    for x in w {
        fnv(h, &x.to_le_bytes());
    }
}

fn digest(result: &Result<Topology, TopologyError>) -> u64 {
    let mut h = FNV_START;
    match result {
        Err(e) => fnv(&mut h, format!("error {e:?}").as_bytes()),
        Ok(t) => {
            let m = &t.mesh;
            words(&mut h, m.positions.iter().map(|x| x.to_bits()));
            for table in [
                &m.triangles,
                &m.ring_offsets,
                &m.ring,
                &m.vertex_flags,
                &m.spoke_flags,
                &m.corner_spokes,
                &m.neighbours,
                &m.edges,
                &t.control_to_welded,
                &t.triangle_source,
            ] {
                words(&mut h, table.iter().copied());
            }
            words(&mut h, t.triangle_flipped.iter().map(|&f| f as u32));
            fnv(&mut h, format!("{:?}", t.report).as_bytes());
        }
    }
    h
}

fn data() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data")
}

fn digests_file() -> PathBuf {
    data().join("topology_digests.txt")
}

fn objs(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "obj"))
        .collect();
    v.sort();
    v
}

/// `mesh creases non_manifold` → `digest vertices triangles` for every mesh in `dir`.
fn compute(dir: &Path, out: &mut BTreeMap<String, String>) {
    for path in objs(dir) {
        let name = path.file_stem().unwrap().to_string_lossy().into_owned();
        let input = hce_meshio::load_mesh(&path).unwrap();
        let w = hce_geometry::weld(&input.positions, 0.0);
        let tris = w.triangles(&input.triangles);
        for &(creases, non_manifold) in MODES {
            let config = TopologyConfig {
                creases,
                non_manifold,
            };
            let r = build_control_mesh(
                &w.positions,
                &tris,
                input.corner_normals.as_deref(),
                &config,
            );
            let sizes = match &r {
                Ok(t) => format!("V={} F={}", t.report.vertices, t.report.triangles),
                Err(_) => "refused".to_string(),
            };
            out.insert(
                format!("{name} {creases:?} {non_manifold:?}"),
                format!("{:016x} {sizes}", digest(&r)),
            );
        }
    }
}

fn pinned() -> BTreeMap<String, String> {
    let text = std::fs::read_to_string(digests_file()).unwrap_or_default();
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.is_empty())
        .map(|l| {
            let (k, v) = l.split_once(" = ").expect("`key = value` lines");
            (k.to_string(), v.to_string())
        })
        .collect()
}

#[test]
fn control_mesh_tables_are_unchanged() {
    let mut now = BTreeMap::new();
    compute(&data(), &mut now);
    let extra = std::env::var_os("HCE_EXTRA_MESHES");
    match &extra {
        Some(dir) => compute(Path::new(dir), &mut now),
        None => eprintln!(
            "HCE_EXTRA_MESHES is not set: checking the topology digests of tests/data only"
        ),
    }
    let mut want = pinned();
    if std::env::var("HCE_UPDATE_GOLDEN").is_ok_and(|v| v == "1") {
        assert!(
            extra.is_some(),
            "set HCE_EXTRA_MESHES too, so that the shared meshes keep their lines"
        );
        let mut s = String::from(
            "# Written by `HCE_UPDATE_GOLDEN=1 HCE_EXTRA_MESHES=... cargo test -p hce-geometry --test topology_digests`.\n# mesh creases non_manifold = FNV-1a of the whole Topology, sizes\n",
        );
        for (k, v) in &now {
            s.push_str(&format!("{k} = {v}\n"));
        }
        std::fs::write(digests_file(), s).unwrap();
        return;
    }
    if extra.is_none() {
        let ours: Vec<String> = objs(&data())
            .iter()
            .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
            .collect();
        want.retain(|k, _| ours.iter().any(|n| k.split(' ').next() == Some(n)));
    }
    assert_eq!(now.len(), want.len(), "cases: {:?}", now.keys());
    let mut differ = Vec::new();
    for (k, v) in &now {
        match want.get(k) {
            Some(w) if w == v => {}
            Some(w) => differ.push(format!("{k}: pinned {w}, now {v}")),
            None => differ.push(format!("{k}: not pinned (now {v})")),
        }
    }
    assert!(differ.is_empty(), "{}", differ.join("\n"));
}
