//! Applying baked HCE colours to a refined mesh on the CPU, exactly as the runtime's renderer
//! does. This is the reference the GPU kernels are tested against.
//!
//! Based on:
//! * Ravi Ramamoorthi and Pat Hanrahan. An efficient representation for irradiance environment
//!   maps. SIGGRAPH 2001 (a linear function of the normal carries irradiance; the model of
//!   [`crate::lighting`]).
//! * Michael F. Cohen and John R. Wallace. Radiosity and Realistic Image Synthesis. Academic
//!   Press, 1993, section 9.2 (nodal averaging of elements, T-vertices).
//! * Concheiro et al. Synthesis of multiresolution scenes with global illumination on a GPU.
//!   GRAPP 2012, section 4 (the nearest-normal rule).
//!
//! Two reconstructions (SPEC.md, Appendix G), and a third to compare them with:
//!
//! * [`Reconstruction::Smooth`] (the default): every corner of every level-`L` subtriangle gets
//!   the value of the field of [`crate::lighting`] at its lattice point, for its vertex's unit
//!   normal, read from the subtriangle's own coarse triangle; each vertex averages those values
//!   over its incident subtriangles weighted by their areas. Inside one smooth region all
//!   incident subtriangles give the same value; across a sharp edge or a fold of a flat object
//!   the refinement has one vertex per side ([`crate::split`], SPEC.md F.5), so each side keeps
//!   its own.
//! * [`Reconstruction::NearestNormal`], the paper's rule (Concheiro et al., "Synthesis of
//!   multiresolution scenes with global illumination on a GPU", GRAPP 2012, section 4): each
//!   level-`L` subtriangle follows its path down its coarse triangle's HCE tree, stopping at a
//!   leaf; it takes the colour of the representative normal with the largest dot product with its
//!   own face normal; each vertex averages the colours of its incident subtriangles weighted by
//!   their areas (across coarse-triangle borders, since refined vertices are shared there).
//! * [`Reconstruction::Gouraud`], for comparison only (not in SPEC.md): the smooth procedure
//!   over a table of each leaf's colour for its triangle's geometric normal, without slopes:
//!   classic radiosity shading of one colour per element (Cohen & Wallace 1993, section 9.2).

use hce_format::{rgb9e5, Object};

use crate::adaptive_flat::AdaptiveFlat;
use crate::lattice::subtriangle_cells;
pub use crate::lighting::Reconstruction;
use crate::lighting::{
    triangle_lighting, LightingError, LightingTable, TriangleLighting, EVAL_LATTICE_BITS,
    TREE_LATTICE_BITS,
};
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
    /// The object's records, trees or colours are inconsistent ([`LightingError`]).
    #[error(transparent)]
    Lighting(#[from] LightingError),
    #[error("object '{object}': subtriangle {face} has a vertex index out of range")]
    Index { object: String, face: usize },
}

/// Per refined vertex linear RGB colour of `object` drawn at `level` from `refined`, which must be
/// the subdivision of `object.mesh` to `level`, with the default (smooth) reconstruction.
///
/// Normals are compared in object space (the space of the control mesh). Vertices used by no
/// subtriangle, or whose incident subtriangles all have zero area, average without weights
/// (or are black when used by none).
pub fn apply_baked_colours(
    object: &Object,
    refined: &Refined,
    level: u32,
) -> Result<Vec<[f32; 3]>, ColourError> {
    apply_baked_colours_with(object, refined, level, Reconstruction::Smooth)
}

/// [`apply_baked_colours`] with the reconstruction chosen.
pub fn apply_baked_colours_with(
    object: &Object,
    refined: &Refined,
    level: u32,
    reconstruction: Reconstruction,
) -> Result<Vec<[f32; 3]>, ColourError> {
    check_refined(object, refined, level)?;
    match reconstruction {
        Reconstruction::Smooth | Reconstruction::Gouraud => {
            let table = LightingTable::build_with(object, reconstruction)?;
            smooth_colours(object, &table, refined, level)
        }
        Reconstruction::NearestNormal => nearest_normal_colours(object, refined, level),
    }
}

fn check_refined(object: &Object, refined: &Refined, level: u32) -> Result<(), ColourError> {
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
    if level > EVAL_LATTICE_BITS - 1 {
        return Err(ColourError::Level {
            object: name(),
            refined: refined.level,
            level: EVAL_LATTICE_BITS - 1,
        });
    }
    Ok(())
}

/// Area-weighted vertex averages of per-corner colours.
struct VertexAverage {
    sum: Vec<[f64; 3]>,
    weight: Vec<f64>,
    plain: Vec<[f64; 3]>,
    plain_count: Vec<u32>,
}

impl VertexAverage {
    fn new(n: usize) -> Self {
        VertexAverage {
            sum: vec![[0.0; 3]; n],
            weight: vec![0.0; n],
            plain: vec![[0.0; 3]; n],
            plain_count: vec![0; n],
        }
    }

    fn add(&mut self, i: usize, area: f64, rgb: [f64; 3]) {
        for ((s, p), c) in self.sum[i].iter_mut().zip(&mut self.plain[i]).zip(rgb) {
            *s += area * c;
            *p += c;
        }
        self.weight[i] += area;
        self.plain_count[i] += 1;
    }

    fn finish(self) -> Vec<[f32; 3]> {
        (0..self.sum.len())
            .map(|i| {
                if self.weight[i] > 0.0 {
                    self.sum[i].map(|s| (s / self.weight[i]) as f32)
                } else if self.plain_count[i] > 0 {
                    self.plain[i].map(|s| (s / f64::from(self.plain_count[i])) as f32)
                } else {
                    [0.0; 3]
                }
            })
            .collect()
    }
}

fn fine_triangle(
    object: &Object,
    refined: &Refined,
    f: usize,
) -> Result<([u32; 3], [[f32; 3]; 3]), ColourError> {
    let tri = refined.indices[f];
    let mut p = [[0.0f32; 3]; 3];
    for (slot, &i) in p.iter_mut().zip(&tri) {
        *slot = *refined
            .positions
            .get(i as usize)
            .ok_or_else(|| ColourError::Index {
                object: object.name.clone(),
                face: f,
            })?;
    }
    Ok((tri, p))
}

fn area_of(p: [[f32; 3]; 3]) -> f64 {
    let c = cross(sub(p[1], p[0]), sub(p[2], p[0]));
    0.5 * dot(c, c).sqrt()
}

/// SPEC.md G.4: per subtriangle corner the field at its lattice point for the vertex's normal,
/// averaged at the vertex weighted by subtriangle area.
fn smooth_colours(
    object: &Object,
    table: &LightingTable,
    refined: &Refined,
    level: u32,
) -> Result<Vec<[f32; 3]>, ColourError> {
    let cells = subtriangle_cells(level);
    let shift = EVAL_LATTICE_BITS - level;
    let per = 1usize << (2 * level);
    let mut avg = VertexAverage::new(refined.positions.len());
    for t in 0..object.triangles.len() {
        for (path, cell) in cells.iter().enumerate() {
            let f = t * per + path;
            let (tri, p) = fine_triangle(object, refined, f)?;
            let area = area_of(p);
            for (&v, q) in tri.iter().zip(cell) {
                let normal = refined.normals.get(v as usize).copied().unwrap_or([0.0; 3]);
                let rgb = table.evaluate(t, q[0] << shift, q[1] << shift, normal);
                avg.add(v as usize, area, rgb.map(f64::from));
            }
        }
    }
    Ok(avg.finish())
}

/// Per vertex linear RGB colour of flat `object` drawn with its adaptive refinement `mesh`
/// (SPEC.md F.7.1): the field of G.4 at each triangle corner's point (on the 4096 lattice, moved
/// to the evaluation lattice), averaged at the vertex weighted by triangle area; with the
/// nearest-normal rule (G.5), each triangle's leaf colour for the normal nearest its own.
pub fn adaptive_flat_colours(
    object: &Object,
    mesh: &AdaptiveFlat,
    reconstruction: Reconstruction,
) -> Result<Vec<[f32; 3]>, ColourError> {
    if mesh.triangle_start.len() != object.triangles.len() + 1 {
        return Err(ColourError::TriangleCount {
            object: object.name.clone(),
            refined: mesh.triangle_start.len().saturating_sub(1),
            records: object.triangles.len(),
        });
    }
    let shift = EVAL_LATTICE_BITS - TREE_LATTICE_BITS;
    let table = match reconstruction {
        Reconstruction::Smooth | Reconstruction::Gouraud => {
            Some(LightingTable::build_with(object, reconstruction)?)
        }
        Reconstruction::NearestNormal => None,
    };
    let mut avg = VertexAverage::new(mesh.positions.len());
    for t in 0..object.triangles.len() {
        let lighting = triangle_lighting(object, t)?;
        let range = mesh.triangle_start[t] as usize..mesh.triangle_start[t + 1] as usize;
        for f in range {
            let tri = mesh.indices[f];
            let p = tri.map(|i| mesh.positions[i as usize]);
            let area = area_of(p);
            match &table {
                Some(table) => {
                    for (&v, q) in tri.iter().zip(&mesh.points[f]) {
                        let normal = mesh.normals[v as usize];
                        let rgb = table.evaluate(t, q[0] << shift, q[1] << shift, normal);
                        avg.add(v as usize, area, rgb.map(f64::from));
                    }
                }
                None => {
                    let c = cross(sub(p[1], p[0]), sub(p[2], p[0]));
                    let j = nearest_normal(lighting.normals, c);
                    let nc = lighting.normals.len();
                    let colour = lighting
                        .colours
                        .get(mesh.leaves[f] as usize * nc + j)
                        .copied()
                        .ok_or_else(|| ColourError::Index {
                            object: object.name.clone(),
                            face: f,
                        })?;
                    let rgb = rgb9e5::decode(colour).map(f64::from);
                    for &i in &tri {
                        avg.add(i as usize, area, rgb);
                    }
                }
            }
        }
    }
    Ok(avg.finish())
}

/// The normal of `normals` with the largest dot product with `face` (unnormalised): the same
/// argmax as with the unit normal. Ties keep the first normal, the geometric one.
fn nearest_normal(normals: &[[f32; 3]], face: [f64; 3]) -> usize {
    let mut best = 0;
    let mut best_dot = f64::NEG_INFINITY;
    for (j, nrm) in normals.iter().enumerate() {
        let d = dot(face, nrm.map(f64::from));
        if d > best_dot {
            best_dot = d;
            best = j;
        }
    }
    best
}

fn nearest_normal_colours(
    object: &Object,
    refined: &Refined,
    level: u32,
) -> Result<Vec<[f32; 3]>, ColourError> {
    let per = 1usize << (2 * level);
    let mut avg = VertexAverage::new(refined.positions.len());
    for t in 0..object.triangles.len() {
        let TriangleLighting {
            normals,
            tree,
            colours,
            ..
        } = triangle_lighting(object, t)?;
        let nc = normals.len();
        for f in t * per..(t + 1) * per {
            let (tri, p) = fine_triangle(object, refined, f)?;
            let c = cross(sub(p[1], p[0]), sub(p[2], p[0]));
            let area = 0.5 * dot(c, c).sqrt();
            let (node, _) = tree.find_path(level, u64::from(refined.path(f)));
            let best = nearest_normal(normals, c);
            let rgb = rgb9e5::decode(colours[node as usize * nc + best]).map(f64::from);
            for &i in &tri {
                avg.add(i as usize, area, rgb);
            }
        }
    }
    Ok(avg.finish())
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
