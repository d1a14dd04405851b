//! The node hierarchy of a glTF 2.0 scene (glTF 2.0 specification, 3.5 "Nodes and
//! Hierarchy"): which scene is shown, which nodes it holds, in what order, and where each one
//! is in the world.
//!
//! Every reader of hce that places glTF meshes goes through [`walk`]: the baker's scene
//! importer (`scene`), the mesh readers of `hce subdivide` and of `hce render`'s preview
//! (`import`, `plain`) and the runtime's asset loader, so a mesh
//! lands in the same place, bit for bit, whichever of them reads it. It works on the JSON
//! (`serde_json`), not on the `gltf` crate's document, so that the runtime gets it without that
//! crate and its image decoders.
//!
//! # Rules
//!
//! * The scene is `scene`, else the first of `scenes`; a file without scenes shows every node
//!   that is no node's child, in index order.
//! * Nodes are met depth first from each root in order, a node before its children, children in
//!   order.
//! * A node's local transform is its `matrix` (column-major) when present, else
//!   `T · R · S` from `translation`, `rotation` (a unit quaternion `x, y, z, w`) and `scale`,
//!   defaulting to no translation, no rotation and unit scale. `T · R · S` is computed with the
//!   operations, in the order, of the `gltf` crate's `Transform::matrix`, which the baker used
//!   before this walk existed: the same file gives the same bytes. The world transform is the
//!   parent's world transform times the local one.
//! * glTF nodes form trees: one parent per node, no cycles. A node reached a second time is not
//!   followed again; it is listed in [`SceneWalk::repeated`], and each caller says whether that
//!   is a warning (the baker, the runtime) or an error (the mesh readers).
//!
//! Everything read is checked, and a problem is a [`GraphError`] naming the JSON location:
//! a scene, node or mesh index out of range, a list that is not a list of indices, a transform
//! that is not the right count of finite numbers (after conversion to `f32`), a rotation of
//! (nearly) zero length.

use glam::Mat4;
use serde_json::Value;

/// A scene graph that cannot be walked.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{location}: {message}")]
pub struct GraphError {
    /// The JSON path at fault, e.g. `nodes[3].rotation`.
    pub location: String,
    pub message: String,
}

fn err(location: impl Into<String>, message: impl Into<String>) -> GraphError {
    GraphError {
        location: location.into(),
        message: message.into(),
    }
}

/// One node of the scene, met once.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeVisit {
    /// Index in the file's `nodes`.
    pub node: usize,
    /// The node's `mesh`, checked to be an index of `meshes`.
    pub mesh: Option<usize>,
    /// Node space to world space.
    pub world: Mat4,
}

/// The nodes of a scene in walk order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SceneWalk {
    pub visits: Vec<NodeVisit>,
    /// Nodes reached a second time (through a cycle or a second parent), in the order met;
    /// they were not followed again.
    pub repeated: Vec<usize>,
}

impl SceneWalk {
    /// The nodes that carry a mesh, in walk order.
    pub fn mesh_instances(&self) -> impl Iterator<Item = (NodeVisit, usize)> + '_ {
        self.visits.iter().filter_map(|v| v.mesh.map(|m| (*v, m)))
    }

    /// What is wrong with a node in [`SceneWalk::repeated`], in one wording for every caller.
    pub fn repeated_message(node: usize) -> String {
        format!(
            "nodes[{node}] is reached twice in the hierarchy; glTF nodes must form trees (one \
             parent per node, no cycles)"
        )
    }

    /// One warning per repeated node, for callers that walk on.
    pub fn repeated_warnings(&self) -> impl Iterator<Item = String> + '_ {
        self.repeated.iter().map(|&n| {
            format!(
                "{}; the second instance is ignored",
                Self::repeated_message(n)
            )
        })
    }
}

/// Walks the scene a viewer shows (see the module documentation for the rules).
pub fn walk(json: &Value) -> Result<SceneWalk, GraphError> {
    let nodes: &[Value] = match json.get("nodes") {
        None => &[],
        Some(n) => n.as_array().ok_or_else(|| err("nodes", "not an array"))?,
    };
    let mesh_count = match json.get("meshes") {
        None => 0,
        Some(m) => m
            .as_array()
            .ok_or_else(|| err("meshes", "not an array"))?
            .len(),
    };
    let scenes = match json.get("scenes") {
        None => None,
        Some(s) => Some(s.as_array().ok_or_else(|| err("scenes", "not an array"))?),
    };
    let scene = match json.get("scene") {
        None => scenes.filter(|s| !s.is_empty()).map(|_| 0),
        Some(s) => Some(
            s.as_u64()
                .and_then(|s| usize::try_from(s).ok())
                .ok_or_else(|| err("scene", "not an index"))?,
        ),
    };
    let roots = match scene {
        Some(s) => {
            let sc = scenes
                .and_then(|list| list.get(s))
                .ok_or_else(|| err("scene", format!("scene {s} does not exist")))?;
            match sc.get("nodes") {
                Some(n) => indices(n, &format!("scenes[{s}].nodes"), nodes.len(), "node")?,
                None => Vec::new(),
            }
        }
        None => {
            let mut is_child = vec![false; nodes.len()];
            for (i, n) in nodes.iter().enumerate() {
                if let Some(c) = n.get("children") {
                    for c in indices(c, &format!("nodes[{i}].children"), nodes.len(), "node")? {
                        is_child[c] = true;
                    }
                }
            }
            (0..nodes.len()).filter(|&i| !is_child[i]).collect()
        }
    };
    // An explicit stack and a visited set: a file whose nodes do not form trees must not
    // overflow the stack, loop forever or multiply instances exponentially.
    let mut seen = vec![false; nodes.len()];
    let mut out = SceneWalk::default();
    let mut stack: Vec<(usize, Mat4)> = roots
        .into_iter()
        .rev()
        .map(|n| (n, Mat4::IDENTITY))
        .collect();
    while let Some((node, parent)) = stack.pop() {
        if std::mem::replace(&mut seen[node], true) {
            out.repeated.push(node);
            continue;
        }
        let n = &nodes[node];
        let world = parent * local_transform(n, node)?;
        let mesh = match n.get("mesh") {
            None => None,
            Some(m) => Some(
                m.as_u64()
                    .and_then(|m| usize::try_from(m).ok())
                    .filter(|&m| m < mesh_count)
                    .ok_or_else(|| {
                        err(
                            format!("nodes[{node}].mesh"),
                            format!("{m} is not a mesh index (the file has {mesh_count})"),
                        )
                    })?,
            ),
        };
        out.visits.push(NodeVisit { node, mesh, world });
        if let Some(c) = n.get("children") {
            let children = indices(c, &format!("nodes[{node}].children"), nodes.len(), "node")?;
            stack.extend(children.into_iter().rev().map(|c| (c, world)));
        }
    }
    Ok(out)
}

/// A list of indices below `len`.
fn indices(v: &Value, at: &str, len: usize, what: &str) -> Result<Vec<usize>, GraphError> {
    let list = v
        .as_array()
        .ok_or_else(|| err(at, format!("not an array of {what} indices")))?;
    list.iter()
        .enumerate()
        .map(|(k, i)| {
            i.as_u64()
                .and_then(|i| usize::try_from(i).ok())
                .filter(|&i| i < len)
                .ok_or_else(|| {
                    err(
                        format!("{at}[{k}]"),
                        format!("{i} is not a {what} index (the file has {len})"),
                    )
                })
        })
        .collect()
}

/// A JSON number as `f32`, converted as `serde` converts it for the `gltf` crate: integers
/// straight to `f32`, other numbers through `f64`.
fn as_f32(x: &Value) -> Option<f32> {
    let x = x.as_number()?;
    if let Some(u) = x.as_u64() {
        Some(u as f32)
    } else if let Some(i) = x.as_i64() {
        Some(i as f32)
    } else {
        x.as_f64().map(|f| f as f32)
    }
}

/// `N` finite numbers under `key`, if the node has the key.
fn numbers<const N: usize>(
    node: &Value,
    index: usize,
    key: &str,
) -> Result<Option<[f32; N]>, GraphError> {
    let Some(v) = node.get(key) else {
        return Ok(None);
    };
    let list: Option<Vec<f32>> = v.as_array().and_then(|a| {
        a.iter()
            .map(|x| as_f32(x).filter(|x| x.is_finite()))
            .collect()
    });
    match list.and_then(|l| <[f32; N]>::try_from(l).ok()) {
        Some(l) => Ok(Some(l)),
        None => Err(err(
            format!("nodes[{index}].{key}"),
            format!("must be {N} finite numbers"),
        )),
    }
}

/// A node's local transform: `matrix`, else `T · R · S`.
pub fn local_transform(node: &Value, index: usize) -> Result<Mat4, GraphError> {
    if let Some(m) = numbers::<16>(node, index, "matrix")? {
        return Ok(Mat4::from_cols_array(&m));
    }
    let t = numbers::<3>(node, index, "translation")?.unwrap_or([0.0; 3]);
    let r = numbers::<4>(node, index, "rotation")?.unwrap_or([0.0, 0.0, 0.0, 1.0]);
    let s = numbers::<3>(node, index, "scale")?.unwrap_or([1.0; 3]);
    if glam::Vec4::from(r).length() < 1e-6 {
        return Err(err(
            format!("nodes[{index}].rotation"),
            "is not a unit quaternion",
        ));
    }
    Ok(Mat4::from_cols_array_2d(&trs(t, r, s)))
}

/// `T · R · S` as columns, with the `gltf` crate's operations in its order (its
/// `Matrix4::from_quaternion` and `Mul`), so that the result is the same to the bit. The
/// quaternion is used as given: glTF requires it to be unit.
fn trs(t: [f32; 3], r: [f32; 4], s: [f32; 3]) -> [[f32; 4]; 4] {
    let [x, y, z, w] = r;
    let (x2, y2, z2) = (x + x, y + y, z + z);
    let (xx2, xy2, xz2) = (x2 * x, x2 * y, x2 * z);
    let (yy2, yz2, zz2) = (y2 * y, y2 * z, z2 * z);
    let (sy2, sz2, sx2) = (y2 * w, z2 * w, x2 * w);
    let rotation = [
        [1.0 - yy2 - zz2, xy2 + sz2, xz2 - sy2, 0.0],
        [xy2 - sz2, 1.0 - xx2 - zz2, yz2 + sx2, 0.0],
        [xz2 + sy2, yz2 - sx2, 1.0 - xx2 - yy2, 0.0],
        [0.0, 0.0, 0.0, 1.0],
    ];
    let translation = [
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.0],
        [t[0], t[1], t[2], 1.0],
    ];
    let scale = [
        [s[0], 0.0, 0.0, 0.0],
        [0.0, s[1], 0.0, 0.0],
        [0.0, 0.0, s[2], 0.0],
        [0.0, 0.0, 0.0, 1.0],
    ];
    mul(&mul(&translation, &rotation), &scale)
}

/// Column-major `a · b`, each column summed left to right as the `gltf` crate sums it.
fn mul(a: &[[f32; 4]; 4], b: &[[f32; 4]; 4]) -> [[f32; 4]; 4] {
    std::array::from_fn(|j| {
        std::array::from_fn(|i| {
            a[0][i] * b[j][0] + a[1][i] * b[j][1] + a[2][i] * b[j][2] + a[3][i] * b[j][3]
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn close(a: Mat4, b: Mat4) -> bool {
        a.abs_diff_eq(b, 1e-6)
    }

    #[test]
    fn trs_and_matrix_nodes_compose_down_the_hierarchy() {
        // Node 0 (TRS: turned a quarter about y, scaled 2, moved +x 10) holds node 1 (a
        // column-major matrix moving +z 1) which holds the mesh; node 2 uses the mesh too.
        let q = std::f32::consts::FRAC_1_SQRT_2;
        let json = json!({
            "scene": 0,
            "scenes": [{ "nodes": [0, 2] }],
            "nodes": [
                { "children": [1], "translation": [10, 0, 0], "rotation": [0, q, 0, q],
                  "scale": [2, 2, 2] },
                { "mesh": 0, "matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,1,1] },
                { "mesh": 0, "translation": [0, -3, 0] }
            ],
            "meshes": [{ "primitives": [] }]
        });
        let w = walk(&json).unwrap();
        assert_eq!(
            w.visits.iter().map(|v| v.node).collect::<Vec<_>>(),
            vec![0, 1, 2]
        );
        assert!(w.repeated.is_empty());
        let instances: Vec<_> = w.mesh_instances().collect();
        assert_eq!(
            instances.len(),
            2,
            "a mesh used by two nodes is placed twice"
        );
        let p = instances[0].0.world.transform_point3(glam::Vec3::ZERO);
        // Local +z 1, scaled to 2, turned a quarter about y to +x 2, moved to x = 12.
        assert!((p - glam::Vec3::new(12.0, 0.0, 0.0)).length() < 1e-5, "{p}");
        let expect = Mat4::from_translation(glam::Vec3::new(10.0, 0.0, 0.0))
            * Mat4::from_quat(glam::Quat::from_rotation_y(std::f32::consts::FRAC_PI_2))
            * Mat4::from_scale(glam::Vec3::splat(2.0))
            * Mat4::from_translation(glam::Vec3::Z);
        assert!(close(instances[0].0.world, expect));
        assert_eq!(
            instances[1].0.world,
            Mat4::from_translation(glam::Vec3::new(0.0, -3.0, 0.0))
        );
        assert_eq!((instances[0].1, instances[1].1), (0, 0));
    }

    #[test]
    fn nodes_that_are_not_trees_are_walked_once_and_reported() {
        // 0 → 1 → 0 is a cycle; 2 is a second parent of 1.
        let json = json!({
            "scenes": [{ "nodes": [0, 2] }],
            "nodes": [{ "children": [1] }, { "children": [0], "mesh": 0 }, { "children": [1] }],
            "meshes": [{}]
        });
        let w = walk(&json).unwrap();
        assert_eq!(
            w.visits.iter().map(|v| v.node).collect::<Vec<_>>(),
            vec![0, 1, 2]
        );
        assert_eq!(w.repeated, vec![0, 1]);
        let warnings: Vec<String> = w.repeated_warnings().collect();
        assert!(
            warnings[0].starts_with("nodes[0] is reached twice"),
            "{warnings:?}"
        );
    }

    #[test]
    fn without_scenes_every_parentless_node_is_a_root() {
        let json = json!({
            "nodes": [{ "translation": [1, 0, 0] }, { "children": [0] }, {}],
        });
        let w = walk(&json).unwrap();
        assert_eq!(
            w.visits.iter().map(|v| v.node).collect::<Vec<_>>(),
            vec![1, 0, 2]
        );
        // `scene` names the scene even when it is not the first.
        let json = json!({
            "scene": 1,
            "scenes": [{ "nodes": [0] }, { "nodes": [1] }],
            "nodes": [{}, {}]
        });
        assert_eq!(walk(&json).unwrap().visits[0].node, 1);
        assert!(walk(&json!({})).unwrap().visits.is_empty());
    }

    #[test]
    fn bad_graphs_are_errors_with_a_location() {
        let cases = [
            (
                json!({ "scenes": [{ "nodes": [7] }], "nodes": [{}] }),
                "scenes[0].nodes[0]",
            ),
            (json!({ "scene": 2, "scenes": [] }), "scene"),
            (
                json!({ "nodes": [{ "matrix": [1, 2] }] }),
                "nodes[0].matrix",
            ),
            (
                json!({ "nodes": [{ "translation": [1e39, 0, 0] }] }),
                "nodes[0].translation",
            ),
            (
                json!({ "nodes": [{ "rotation": [0, 0, 0, 0] }] }),
                "nodes[0].rotation",
            ),
            (
                json!({ "nodes": [{ "mesh": 1 }], "meshes": [{}] }),
                "nodes[0].mesh",
            ),
            (
                json!({ "nodes": [{ "children": [0.5] }] }),
                "nodes[0].children[0]",
            ),
            (json!({ "nodes": {} }), "nodes"),
        ];
        for (json, location) in cases {
            let e = walk(&json).unwrap_err();
            assert_eq!(e.location, location, "{e}");
        }
    }

    #[cfg(feature = "import")]
    #[test]
    fn trs_matches_the_gltf_crate_to_the_bit() {
        // Pseudo-random TRS values (a fixed LCG): the baker placed meshes with the `gltf`
        // crate's matrices before this walk, and bakes must not change by a bit.
        let mut state = 0x1234_5678_u32;
        let mut next = || {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (state >> 8) as f32 / (1u32 << 24) as f32 * 4.0 - 2.0
        };
        for _ in 0..2000 {
            let t = [next(), next(), next()];
            let q = glam::Vec4::new(next(), next(), next(), next()).normalize();
            let s = [next(), next(), next()];
            let ours = trs(t, q.to_array(), s);
            let theirs = gltf::scene::Transform::Decomposed {
                translation: t,
                rotation: q.to_array(),
                scale: s,
            }
            .matrix();
            let bits = |m: [[f32; 4]; 4]| m.map(|c| c.map(f32::to_bits));
            assert_eq!(bits(ours), bits(theirs), "t {t:?} r {q} s {s:?}");
        }
    }
}
