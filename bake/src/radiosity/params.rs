//! The solver's parameters (the `hce bake` flags of the same names) and their ranges.

use hce_format::MAX_TREE_DEPTH;

use crate::BakeError;

/// Most visibility rays per link accepted (beyond it a bake would take days, not hours).
pub const MAX_VISIBILITY_RAYS: u32 = 4096;

/// Solver parameters (the `hce bake` flags of the same names).
#[derive(Clone, Debug, PartialEq)]
pub struct BakeParams {
    /// Refinement threshold: a link is refined while its estimated transported power exceeds
    /// this fraction of the scene's reference power (emitted plus directly received). Default
    /// 1e-4.
    pub bf_epsilon: f32,
    /// Elements are not split below this fraction of their object's area, or of a sixteenth of
    /// the scene's area if that is larger. Default 1e-5. (It was a fraction of the whole
    /// scene's area, which in a room kept every triangle of a 1000-triangle object whole: the
    /// objects' leaves were their coarse triangles, whatever `max_level` said. The sixteenth
    /// bounds the cost in scenes of many small objects: Chesstime bakes in 1.2x the time,
    /// against 3.5x with each object's own area.)
    pub min_area_fraction: f32,
    /// Deepest element level below a coarse triangle that the power-based refinement reaches,
    /// at most [`hce_format::MAX_TREE_DEPTH`] (the element tree is the HCE tree). Default 4.
    pub max_level: u32,
    /// Deepest level that the rules judged against a receiver's own radiance reach: where a
    /// shadow edge crosses the receiver, or an occluder next to it shades it unevenly. At
    /// least `max_level`, at most [`hce_format::MAX_TREE_DEPTH`]. Default 7: a shadow on the
    /// floor of a room of two coarse triangles is resolved to a hundred-and-twenty-eighth of
    /// the room, without refining the rest of the room as finely. (At 6 the floor's leaves
    /// were as wide as the legs of an object standing on it, and its contact shadows came out
    /// faint and wide: spot's room 2.4% against a path tracer over the whole image, 1.7% at 7.)
    /// Where a light's shadow is narrower than a flat receiver of this level (an object
    /// close above it: Teatime's spoon, the base of its teapot), two levels deeper, down to a
    /// sixteenth of the least element area (`Ctx::narrow_shadow_splittable`).
    pub detail_level: u32,
    /// Jittered rays per link (and per element and light) for visibility; 0 disables
    /// occlusion. A link that brings a large share of its receiver's light takes up to four
    /// times as many (sixteen from a light to a receiver of `detail_level` or deeper), so that
    /// their noise stays under 2% of the receiver's radiance. Default 8.
    pub visibility_rays: u32,
    /// Iterate gather and push-pull until the relative change of the solution drops below
    /// this. Default 1e-4.
    pub tolerance: f32,
    /// Upper bound on gather iterations per solve. Default 200.
    pub max_iterations: u32,
    /// Link refinement passes, each followed by a solve (the first refines against emission
    /// and direct light). Default 2.
    pub refine_passes: u32,
    /// A cluster acts as one source only while its bounding radius is below this fraction of
    /// its distance to the receiver (the Barnes-Hut opening criterion). Default 0.5.
    pub cluster_opening: f32,
    /// Store each colour at its element's corners too (SPEC.md A.10), gathered at those
    /// points, which the runtime reads in place of the elements' means. Default true: on the
    /// Cornell box against Cycles 1.18% error instead of 1.84%, for files about 3.5 times as
    /// large.
    pub corner_colours: bool,
}

impl BakeParams {
    /// Checks that every parameter lies in its range; the error names the one that does not.
    pub fn validate(&self) -> Result<(), BakeError> {
        if self.max_level > MAX_TREE_DEPTH {
            return Err(BakeError::InvalidParameter(format!(
                "max_level {} exceeds {MAX_TREE_DEPTH}, the deepest HCE tree a file may hold (SPEC.md B.2)",
                self.max_level
            )));
        }
        if self.detail_level > MAX_TREE_DEPTH || self.detail_level < self.max_level {
            return Err(BakeError::InvalidParameter(format!(
                "detail_level {} must lie between max_level {} and {MAX_TREE_DEPTH}, the deepest HCE tree a file may hold (SPEC.md B.2)",
                self.detail_level, self.max_level
            )));
        }
        if self.visibility_rays > MAX_VISIBILITY_RAYS {
            return Err(BakeError::InvalidParameter(format!(
                "visibility_rays {} exceeds {MAX_VISIBILITY_RAYS}",
                self.visibility_rays
            )));
        }
        let positive = |x: f32| x.is_finite() && x > 0.0;
        if !positive(self.bf_epsilon)
            || !positive(self.tolerance)
            || !positive(self.cluster_opening)
        {
            return Err(BakeError::InvalidParameter(
                "bf_epsilon, tolerance and cluster_opening must be positive and finite".into(),
            ));
        }
        Ok(())
    }

    /// The parameters as the JSON object text stored in the container's metadata.
    pub fn to_json(&self) -> String {
        serde_json::json!({
            "bf_epsilon": self.bf_epsilon,
            "min_area_fraction": self.min_area_fraction,
            "max_level": self.max_level,
            "detail_level": self.detail_level,
            "visibility_rays": self.visibility_rays,
            "tolerance": self.tolerance,
            "max_iterations": self.max_iterations,
            "refine_passes": self.refine_passes,
            "cluster_opening": self.cluster_opening,
            "corner_colours": self.corner_colours,
        })
        .to_string()
    }
}

impl Default for BakeParams {
    fn default() -> Self {
        BakeParams {
            bf_epsilon: 1e-4,
            min_area_fraction: 1e-5,
            max_level: 4,
            detail_level: 7,
            visibility_rays: 8,
            tolerance: 1e-4,
            max_iterations: 200,
            refine_passes: 2,
            cluster_opening: 0.5,
            corner_colours: true,
        }
    }
}
