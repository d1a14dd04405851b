//! One object refined to a level as the runtime draws it: Loop subdivision for
//! multiresolution objects ([`crate::subdivide`](mod@crate::subdivide)) with the vertices split
//! at sharp edges ([`crate::split`]), for flat ones either the adaptive refinement from their
//! trees ([`crate::adaptive_flat`], SPEC.md F.7.1) or the uniform linear 1-to-4 split
//! ([`crate::flat`], F.7.2) with the vertices split at folds, then its baked colours
//! ([`crate::colour`]). This is what `hce subdivide BAKED` writes (adaptive flat objects by
//! default) and what `hce render --cpu-reference` draws (uniform, as the GPU runtime).

use hce_format::{ControlMesh, Object, ObjectKind};

use crate::adaptive_flat::{refine_adaptive_flat, AdaptiveFlatError};
use crate::colour::ColourError;
use crate::flat::refine_flat_cpu;
use crate::incidence::FlatTopology;
use crate::normal::{face_normal, unit_or_up};
use crate::split::{SplitError, SplitTables};
use crate::subdivide::{subdivide, Refined, SubdivError};
use crate::tables::InvalidObject;

/// Why an object could not be refined; each cause keeps its type, so a caller can tell a level
/// out of range ([`SubdivError::Level`]) from a bad object.
#[derive(Debug, thiserror::Error)]
pub enum RefineError {
    /// Loop subdivision failed, or the level is out of range (for either kind of object).
    #[error(transparent)]
    Subdiv(#[from] SubdivError),
    /// The flat object's tables are inconsistent.
    #[error(transparent)]
    Object(#[from] InvalidObject),
    /// The baked colours could not be applied.
    #[error(transparent)]
    Colour(#[from] ColourError),
    /// The refined vertices could not be split where the surface folds (SPEC.md F.5).
    #[error(transparent)]
    Split(#[from] SplitError),
    /// The flat object could not be refined from its trees (SPEC.md F.7.1).
    #[error(transparent)]
    Adaptive(#[from] AdaptiveFlatError),
}

/// How a flat object is refined (SPEC.md F.7).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FlatRefinement {
    /// From its trees, one triangle per leaf plus those its finer neighbours need (F.7.1); the
    /// level does not apply. The default: the same field with a fraction of the triangles.
    #[default]
    Adaptive,
    /// Every coarse triangle split 1-to-4 to the level (F.7.2), as the GPU runtime draws it and
    /// the conformance suite records it.
    Uniform,
}

/// One object refined to a level: what the runtime draws, plus normals.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RefinedObject {
    /// The Loop or linear refinement (fine triangle `t · 4^level + path`). For a flat object
    /// refined adaptively (F.7.1) `level` is 0 and [`Refined::coarse_triangle`] and
    /// [`Refined::path`] do not apply: [`RefinedObject::triangle_start`] says which triangles
    /// belong to which coarse triangle.
    pub mesh: Refined,
    /// Linear radiosity per vertex of `mesh`, from [`crate::colour::apply_baked_colours`].
    pub colours: Vec<[f32; 3]>,
    /// The triangles of coarse triangle `t` are `triangle_start[t]..triangle_start[t + 1]`
    /// (`t · 4^level` for a uniform refinement).
    pub triangle_start: Vec<usize>,
}

impl RefinedObject {
    /// The triangles of the coarse triangles `coarse` (a primitive's range), in order.
    pub fn triangles_of(&self, coarse: std::ops::Range<usize>) -> std::ops::Range<usize> {
        let at = |t: usize| self.triangle_start[t.min(self.triangle_start.len() - 1)];
        at(coarse.start)..at(coarse.end)
    }
}

/// Refines `object` to `level` the way the runtime draws it: Loop subdivision for
/// multiresolution objects, the linear 1-to-4 split for flat ones; then its baked colours, with
/// the default (smooth) reconstruction.
pub fn refine_object(object: &Object, level: u32) -> Result<RefinedObject, RefineError> {
    refine_object_with(object, level, crate::lighting::Reconstruction::default())
}

/// [`refine_object`] with the colour reconstruction chosen.
pub fn refine_object_with(
    object: &Object,
    level: u32,
    reconstruction: crate::lighting::Reconstruction,
) -> Result<RefinedObject, RefineError> {
    refine_object_as(object, level, reconstruction, FlatRefinement::Uniform)
}

/// [`refine_object_with`] with the flat refinement chosen ([`FlatRefinement::Adaptive`] ignores
/// `level` for a flat object).
pub fn refine_object_as(
    object: &Object,
    level: u32,
    reconstruction: crate::lighting::Reconstruction,
    flat: FlatRefinement,
) -> Result<RefinedObject, RefineError> {
    if object.kind == ObjectKind::Flat && flat == FlatRefinement::Adaptive {
        return refine_adaptive(object, reconstruction);
    }
    let mesh = match object.kind {
        ObjectKind::Multiresolution => subdivide_split(&object.name, &object.mesh, level)?,
        ObjectKind::Flat => refine_linear(object, level)?,
    };
    let colours = crate::colour::apply_baked_colours_with(object, &mesh, level, reconstruction)?;
    let triangle_start = (0..=mesh.coarse_triangles)
        .map(|t| t << (2 * level))
        .collect();
    Ok(RefinedObject {
        mesh,
        colours,
        triangle_start,
    })
}

/// A flat object refined from its trees (SPEC.md F.7.1), coloured by G.4 at its points.
fn refine_adaptive(
    object: &Object,
    reconstruction: crate::lighting::Reconstruction,
) -> Result<RefinedObject, RefineError> {
    let adaptive = refine_adaptive_flat(object)?;
    let colours = crate::colour::adaptive_flat_colours(object, &adaptive, reconstruction)?;
    let mesh = &object.mesh;
    Ok(RefinedObject {
        triangle_start: adaptive
            .triangle_start
            .iter()
            .map(|&s| s as usize)
            .collect(),
        mesh: Refined {
            level: 0,
            positions: adaptive.positions,
            normals: adaptive.normals,
            indices: adaptive.indices,
            coarse_vertices: mesh.vertex_count(),
            // Edge ids are dense (validated by the refinement).
            coarse_edges: mesh.edges.iter().max().map_or(0, |&m| m as usize + 1),
            coarse_triangles: mesh.triangle_count(),
        },
        colours,
    })
}

/// Loop subdivision of a multiresolution object's control mesh to `level` with its vertices
/// split at sharp edges (SPEC.md F.5, F.6): the mesh the runtime draws and the reference
/// path-traces.
pub fn subdivide_split(name: &str, mesh: &ControlMesh, level: u32) -> Result<Refined, RefineError> {
    let mut refined = subdivide(mesh, level)?;
    SplitTables::new(name, mesh, ObjectKind::Multiresolution)?.apply(mesh, &mut refined)?;
    Ok(refined)
}

/// The flat kernel's CPU twin, as a [`Refined`]: vertices split where the surface folds
/// (SPEC.md F.5, F.7), normals per vertex, area-weighted over the fine triangles that use it.
fn refine_linear(object: &Object, level: u32) -> Result<Refined, RefineError> {
    if level > crate::subdivide::MAX_LOOP_LEVEL {
        return Err(SubdivError::Level(level).into());
    }
    let topo = FlatTopology::new(&object.name, &object.mesh)?;
    let flat = refine_flat_cpu(object, &topo, level);
    let positions: Vec<[f32; 3]> = flat
        .positions
        .chunks_exact(3)
        .map(|p| [p[0], p[1], p[2]])
        .collect();
    let indices: Vec<[u32; 3]> = flat
        .indices
        .chunks_exact(3)
        .map(|t| [t[0], t[1], t[2]])
        .collect();
    let mut normals = vec![[0f32; 3]; positions.len()];
    for t in &indices {
        let n = face_normal(t.map(|i| positions[i as usize]));
        for &i in t {
            for k in 0..3 {
                normals[i as usize][k] += n[k];
            }
        }
    }
    Ok(Refined {
        level,
        positions,
        normals: normals.into_iter().map(unit_or_up).collect(),
        indices,
        coarse_vertices: topo.vertex_count as usize,
        coarse_edges: topo.edge_count as usize,
        coarse_triangles: topo.triangle_count as usize,
    })
}
