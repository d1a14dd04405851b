//! One object refined on the CPU, for pages whose renderer has no WebGPU (a WebGL2 backend, or
//! a browser without `navigator.gpu`): [`hce_geometry::refine::refine_object_as`], the code
//! `hce subdivide` runs on a baked file, so the positions are that command's bit for bit.

use hce_geometry::refine::refine_object_as;

use crate::frame::{Reader, Writer};
use crate::{read_flat_refinement, read_object, read_reconstruction};

/// Refines one object as `hce subdivide BAKED --level L` does: Loop subdivision for a
/// multiresolution object; for a flat one its adaptive refinement (SPEC.md F.7.1, whatever the
/// level) or the linear split to the level (F.7.2, `--flat uniform`); the vertices split at
/// sharp edges and folds (F.5), the baked light evaluated at every refined vertex. Request:
/// `u32` index (names the object in messages), the object as [`crate::load`] writes it from
/// `name` to `corner_colours`, `u32` level (0 to 6), `u32` reconstruction (0 smooth, 1 nearest, 2
/// Gouraud), `u32` flat refinement (0 adaptive, 1 uniform).
///
/// Result: `u32` level of the triangles' numbering (0 for an adaptive flat object), `floats`
/// positions, normals (3 per vertex, unit) and colours (3 per vertex, linear radiance,
/// unclamped), `words` indices (3 per triangle), triangle starts (per coarse triangle its first
/// triangle, then the count: `t · 4^level` for a uniform refinement).
pub fn refine(request: &[u32]) -> Result<Vec<u32>, String> {
    let mut r = Reader::new(request);
    let index = r.u32()?;
    let object = read_object(&mut r).map_err(|e| format!("objects[{index}]: {e}"))?;
    let level = r.u32()?;
    let reconstruction = read_reconstruction(&mut r)?;
    let flat = read_flat_refinement(&mut r)?;
    // The checks the GPU upload makes first, so a damaged object is refused with the same
    // message on either path.
    hce_geometry::tables::validate_tables(&object).map_err(|e| format!("objects[{index}]: {e}"))?;
    let refined = refine_object_as(&object, level, reconstruction, flat)
        .map_err(|e| format!("objects[{index}] '{}': {e}", object.name))?;
    let mesh = &refined.mesh;
    let starts = refined
        .triangle_start
        .iter()
        .map(|&s| u32::try_from(s))
        .collect::<Result<Vec<_>, _>>()
        .map_err(|_| format!("objects[{index}]: more than 2^32 triangles"))?;
    let mut w = Writer::default();
    w.u32(mesh.level);
    w.floats(mesh.positions.as_flattened());
    w.floats(mesh.normals.as_flattened());
    w.floats(refined.colours.as_flattened());
    w.words(mesh.indices.as_flattened());
    w.words(&starts);
    Ok(w.finish())
}
