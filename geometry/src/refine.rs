//! One object refined to a level as the runtime draws it: Loop subdivision for
//! multiresolution objects ([`crate::subdivide`](mod@crate::subdivide)) with the vertices split
//! at sharp edges ([`crate::split`]), the linear 1-to-4
//! split for flat ones ([`crate::flat`], SPEC.md A.7) with the vertices split at folds, then
//! its baked colours
//! ([`crate::colour`]). This is what `hce subdivide BAKED` writes and what
//! `hce render --cpu-reference` draws.

use hce_format::{ControlMesh, Object, ObjectKind};

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
}

/// One object refined to a level: what the runtime draws, plus normals.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RefinedObject {
    /// The Loop or linear refinement (fine triangle `t · 4^level + path`).
    pub mesh: Refined,
    /// Linear radiosity per vertex of `mesh`, from [`crate::colour::apply_baked_colours`].
    pub colours: Vec<[f32; 3]>,
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
    let mesh = match object.kind {
        ObjectKind::Multiresolution => subdivide_split(&object.name, &object.mesh, level)?,
        ObjectKind::Flat => refine_linear(object, level)?,
    };
    let colours = crate::colour::apply_baked_colours_with(object, &mesh, level, reconstruction)?;
    Ok(RefinedObject { mesh, colours })
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
