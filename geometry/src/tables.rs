//! The one validation of what refinement and colouring index in an object, beyond the format's
//! own rules: record ranges into normals and colours, trees decodable by the format's codec,
//! word counts consistent. Every consumer (the CPU refinement, the colour reconstruction, the
//! GPU kernels before upload) calls [`validate_tables`], so a malformed table is an error here
//! and never an out-of-bounds read.

use hce_format::tree::decode_shape;
use hce_format::{Object, TreeError};

/// An object whose tables cannot be refined or coloured, with the reason.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("object {object}: {reason}")]
pub struct InvalidObject {
    /// The object's name.
    pub object: String,
    /// What is wrong, and where.
    pub reason: String,
}

/// What validation learnt about an object's trees.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TreeSummary {
    /// Deepest leaf over all triangles (0 when every tree is a single root).
    pub max_depth: u32,
    /// Total tree nodes over all triangles.
    pub nodes: u64,
}

/// Checks everything the colour kernels index, so that a malformed table is an error here and
/// never an out-of-bounds read on the GPU: record ranges into normals and colours, every tree's
/// bits inside `bit_len`, trees decodable by the format's codec (so no deeper than
/// [`hce_format::MAX_TREE_DEPTH`]), word counts consistent. Work is bounded by `bit_len` (trees
/// together may not claim more nodes than there are bits).
pub fn validate_tables(object: &Object) -> Result<TreeSummary, InvalidObject> {
    let err = |reason: String| InvalidObject {
        object: object.name.clone(),
        reason,
    };
    let f = object.mesh.triangle_count();
    if object.triangles.len() != f {
        return Err(err(format!(
            "{} triangle records for {f} triangles; re-bake the asset",
            object.triangles.len()
        )));
    }
    if object.bit_len > object.bits.len() as u64 * 32 {
        return Err(err(format!(
            "bit_len {} exceeds the {} bits stored",
            object.bit_len,
            object.bits.len() as u64 * 32
        )));
    }
    if object.bits.len() as u64 > u64::from(u32::MAX) / 32 {
        return Err(err("HCE bitstream longer than 2^32 bits".into()));
    }
    let mut summary = TreeSummary::default();
    for (t, r) in object.triangles.iter().enumerate() {
        let ctx = |what: String| err(format!("triangle {t}: {what}"));
        if r.normal_count == 0 {
            return Err(ctx(
                "normal_count is 0 (needs at least the geometric normal)".into(),
            ));
        }
        if u64::from(r.normal_start) + u64::from(r.normal_count) > object.normals.len() as u64 {
            return Err(ctx(format!(
                "normals {}..+{} outside the {} stored",
                r.normal_start,
                r.normal_count,
                object.normals.len()
            )));
        }
        let shape = decode_shape(&object.bits, object.bit_len, u64::from(r.bits_start)).map_err(
            |e| match e {
                TreeError::Truncated { bit, bit_len, .. } => ctx(format!(
                    "tree runs past the end of the bitstream (bit {bit} of {bit_len})"
                )),
                e => ctx(e.to_string()),
            },
        )?;
        let total = u64::from(shape.node_count);
        let depth = shape.depth;
        if summary.nodes + total > object.bit_len {
            return Err(err(format!(
                "trees claim more nodes than the {} bits of the bitstream",
                object.bit_len
            )));
        }
        summary.nodes += total;
        summary.max_depth = summary.max_depth.max(depth);
        let colours_needed = u64::from(r.colour_start) + total * u64::from(r.normal_count);
        if colours_needed > object.colours.len() as u64 {
            return Err(ctx(format!(
                "colours up to {colours_needed} needed but {} stored",
                object.colours.len()
            )));
        }
    }
    Ok(summary)
}
