//! Applying baked HCE colours to a refined mesh on the CPU, exactly as the runtime's renderer
//! does (Concheiro et al., "Synthesis of multiresolution scenes with global illumination on a
//! GPU", GRAPP 2012, section 4): each level-`L` subtriangle follows its path down its coarse
//! triangle's HCE tree, stopping at a leaf; it takes the colour of the representative normal with
//! the largest dot product with its own face normal; each vertex averages the colours of its
//! incident subtriangles weighted by their areas (across coarse-triangle borders, since refined
//! vertices are shared there).

use hce_format::{rgb9e5, Object, Tree, TreeError};

use crate::subdivide::Refined;

/// Errors of colour application: the object and the refined mesh do not belong together, or the
/// object's tables are inconsistent.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ColourError {
    #[error(
        "object '{object}': the refined mesh has {refined} coarse triangles but the object has \
         {records} triangle records; subdivide the object's own control mesh"
    )]
    TriangleCount {
        object: String,
        refined: usize,
        records: usize,
    },
    #[error(
        "object '{object}': the refined mesh is level {refined}, not the requested level {level}"
    )]
    Level {
        object: String,
        refined: u32,
        level: u32,
    },
    #[error("object '{object}', triangle {triangle}: {what}; re-bake the file")]
    Record {
        object: String,
        triangle: usize,
        what: String,
    },
    #[error("object '{object}', triangle {triangle}: bad HCE tree: {source}")]
    Tree {
        object: String,
        triangle: usize,
        #[source]
        source: TreeError,
    },
    #[error("object '{object}': subtriangle {face} has a vertex index out of range")]
    Index { object: String, face: usize },
}

/// Per refined vertex linear RGB colour of `object` drawn at `level` from `refined`, which must be
/// the subdivision of `object.mesh` to `level`.
///
/// Normals are compared in object space (the space of the control mesh). Vertices used by no
/// subtriangle, or whose incident subtriangles all have zero area, average without weights
/// (or are black when used by none).
pub fn apply_baked_colours(
    object: &Object,
    refined: &Refined,
    level: u32,
) -> Result<Vec<[f32; 3]>, ColourError> {
    let name = || object.name.clone();
    if refined.level != level {
        return Err(ColourError::Level {
            object: name(),
            refined: refined.level,
            level,
        });
    }
    let coarse = refined.coarse_triangles;
    if coarse != object.triangles.len() || refined.indices.len() != coarse << (2 * level) {
        return Err(ColourError::TriangleCount {
            object: name(),
            refined: coarse,
            records: object.triangles.len(),
        });
    }
    let record_err = |triangle: usize, what: String| ColourError::Record {
        object: name(),
        triangle,
        what,
    };
    let n = refined.positions.len();
    let mut sum = vec![[0.0f64; 3]; n];
    let mut weight = vec![0.0f64; n];
    let mut plain = vec![[0.0f64; 3]; n];
    let mut plain_count = vec![0u32; n];
    let per = 1usize << (2 * level);
    for (t, rec) in object.triangles.iter().enumerate() {
        let ns = rec.normal_start as usize;
        let nc = rec.normal_count as usize;
        let normals = ns
            .checked_add(nc)
            .filter(|_| nc >= 1)
            .and_then(|end| object.normals.get(ns..end))
            .ok_or_else(|| {
                record_err(
                    t,
                    format!(
                        "normals {ns}+{nc} lie outside the {} stored normals",
                        object.normals.len()
                    ),
                )
            })?;
        let tree = Tree::new(&object.bits, object.bit_len, u64::from(rec.bits_start)).map_err(
            |source| ColourError::Tree {
                object: name(),
                triangle: t,
                source,
            },
        )?;
        let nodes = tree.node_count() as usize;
        let cs = rec.colour_start as usize;
        let colours = nodes
            .checked_mul(nc)
            .and_then(|len| cs.checked_add(len))
            .and_then(|end| object.colours.get(cs..end))
            .ok_or_else(|| {
                record_err(
                    t,
                    format!(
                        "{nodes} nodes x {nc} colours from {cs} lie outside the {} stored colours",
                        object.colours.len()
                    ),
                )
            })?;
        for f in t * per..(t + 1) * per {
            let tri = refined.indices[f];
            let p = tri
                .iter()
                .map(|&i| refined.positions.get(i as usize).copied())
                .collect::<Option<Vec<_>>>()
                .ok_or_else(|| ColourError::Index {
                    object: name(),
                    face: f,
                })?;
            let e1 = sub(p[1], p[0]);
            let e2 = sub(p[2], p[0]);
            let c = cross(e1, e2);
            let area = 0.5 * dot(c, c).sqrt();
            let (node, _) = tree.find_path(level, u64::from(refined.path(f)));
            // Largest dot product with the (unnormalised) face normal: the same argmax as with
            // the unit normal. Ties keep the first normal, the geometric one.
            let mut best = 0;
            let mut best_dot = f64::NEG_INFINITY;
            for (j, nrm) in normals.iter().enumerate() {
                let d = dot(c, nrm.map(f64::from));
                if d > best_dot {
                    best_dot = d;
                    best = j;
                }
            }
            let rgb = rgb9e5::decode(colours[node as usize * nc + best]).map(f64::from);
            for &i in &tri {
                let i = i as usize;
                for k in 0..3 {
                    sum[i][k] += area * rgb[k];
                    plain[i][k] += rgb[k];
                }
                weight[i] += area;
                plain_count[i] += 1;
            }
        }
    }
    Ok((0..n)
        .map(|i| {
            if weight[i] > 0.0 {
                sum[i].map(|s| (s / weight[i]) as f32)
            } else if plain_count[i] > 0 {
                plain[i].map(|s| (s / f64::from(plain_count[i])) as f32)
            } else {
                [0.0; 3]
            }
        })
        .collect())
}

fn sub(a: [f32; 3], b: [f32; 3]) -> [f64; 3] {
    [0, 1, 2].map(|k| f64::from(a[k]) - f64::from(b[k]))
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
