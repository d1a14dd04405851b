//! Stage 2: enriched hierarchical radiosity.
//!
//! Hanrahan, Salzman & Aupperle, "A rapid hierarchical radiosity algorithm" (SIGGRAPH 1991):
//! elements are coarse triangles split 1-to-4 (children Top, Left, Center, Right as in
//! `hce_format::model`); a link between a receiver and a source is refined, splitting the
//! larger of the two, while its brightness-weighted estimate (form factor × source radiance ×
//! receiver area, as power) exceeds `bf_epsilon` times the scene's reference power. Two more
//! rules bound a link's error rather than its power: for near pairs, a receiver over which
//! the form factor varies is split, and a source whose radiance varies in the previous
//! solution is split (that error weighed against every receiver that makes it: the whole
//! coarse receiver triangle, so that a finely split receiver cannot hide it; and the coarse
//! triangles of the same object around it that see the source
//! from about the same place, so that a finely tessellated object cannot either). Every leaf
//! is drawn, so two rules judge a link against the radiance of its receiver rather than the
//! scene's power: a receiver over which the link's form factor bends more than a linear
//! function follows is split, and so is one that a shadow edge crosses (partial visibility),
//! or that an occluder right next to it shades unevenly (an object resting on it, whose
//! shadow edge every link shares). A link's visibility is the kernel-weighted fraction of its
//! rays that are clear.
//! A link's coefficient is linear over its receiver (its values at the three corners), so that
//! push hands each leaf the form factor over its own part (in a closed furnace, constant links
//! left leaves by a wall 13% too bright). The system is solved
//! by gathering over links and push-pull, and links are refined again against the solution.
//! Instead of linking every pair of input triangles up front, receivers start from
//! the top of a cluster hierarchy ([`cluster`], after Smits et al. 1994) and open
//! clusters by the same oracle, which culls pairs that face away or lie behind each other.
//!
//! Enrichment (Padrón et al. 2010): every element of a multiresolution object stores one
//! radiance per normal of its root triangle's set; gathering evaluates the receiver cosine
//! with each normal, while an element acting as a source radiates with its geometric normal
//! (the value for n0). Punctual lights add direct illumination through shadow rays.
//!
//! Quantities are outgoing radiance `L` (see [`crate::scene`]); a receiver gathers
//! `Q = Σ F·L_src + H_direct / π` and a leaf has `L = L_e + ρ·Q`, the area average over the
//! element. As a source an element sends its reflected light from its open part only (the
//! part not shut in under other geometry, such as the floor under a block standing on it):
//! `L_src = L_e + (L − L_e) / open`.
//!
//! Determinism: work is split per root triangle, every random number is seeded from element
//! ids, and every sum runs in a fixed order, so the result does not depend on the thread count.
//!
//! ## Layers
//!
//! Each file names only files of the layers below its own (a file's methods on
//! [`Ctx`](context::Ctx) are
//! called only from above it too):
//!
//! 1. Geometry and data, which know no `Ctx`: [`element`] (keys of the 1-to-4 split),
//!    [`cluster`] (the cluster hierarchy and the parts a link reads of a cluster),
//!    [`formfactor`] (point-to-polygon form factors), [`params`], [`links`] (what a link
//!    holds), [`parallel_walk`] (a root's refinement in parts run in parallel), and the rules'
//!    pure decisions [`power`], [`factor_variation`], [`shadow_edge`].
//! 2. The state: [`context`] (`Ctx`, what every part reads, and what it answers directly).
//! 3. Readings of the scene, each an `impl Ctx` block: [`surface`] (a multiresolution object's
//!    refined surface under its coarse triangles), then [`direct`] (punctual lights),
//!    [`enclosure`] (what a closed leaf's form factors sum to), [`link_visibility`] (a link's
//!    rays), [`bend`]; [`prepare`] (`Ctx::new`); [`coefficients`] (a link's form factors,
//!    linear over its receiver) and [`tree`] (one root's element tree, push);
//!    [`source_radiance`] (what a link reads of a source element), then [`cluster_reading`]
//!    (of a cluster, and of any source).
//! 4. The refinement rules judged by the geometry: [`narrow_shadow`], [`near_occluder`], then
//!    [`self_shade`]; and [`source_variation`], [`solution`] (what the bake hands back).
//! 5. The steps: [`refine`] walks the (receiver, source) pairs of one root, asking each rule in
//!    turn; [`gather`] (gather, push-pull, Jacobi iterations); [`point_values`] (after the
//!    last solve, the light at every leaf's corners: the points the runtime reads it at).
//! 6. [`schedule`]: the passes, and the parallel work of each.

mod bend;
pub(crate) mod cluster;
mod cluster_reading;
mod coefficients;
mod context;
mod direct;
pub(crate) mod element;
mod enclosure;
mod factor_variation;
pub(crate) mod formfactor;
mod gather;
mod link_visibility;
mod links;
mod narrow_shadow;
mod near_occluder;
mod parallel_walk;
mod params;
mod point_values;
mod power;
mod prepare;
mod refine;
mod schedule;
mod self_shade;
mod shadow_edge;
mod solution;
mod source_radiance;
mod source_variation;
mod surface;
mod tree;

pub use params::{BakeParams, MAX_VISIBILITY_RAYS};
pub use schedule::{bake, bake_with_progress, Progress};
pub use solution::{BakeResult, BakeStats, ObjectSolution, TriangleSolution};
