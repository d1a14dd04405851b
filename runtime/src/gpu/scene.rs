//! GPU resources for a loaded [`Asset`], on a device and queue the caller owns: per object, its
//! sections uploaded once, refinement to a level (forced, or chosen from the view by
//! [`choose_level`]) into output buffers that are reused while the level does not grow, and the
//! buffers to draw (positions, normals, colours, indices) or to read back.
//!
//! A refinement writes a second set of buffers while the object keeps drawing its current ones,
//! and is swapped in only when complete. [`GpuScene::refine_all`] and [`GpuScene::refine_to`]
//! refine every object whose level changed in one submission; a viewer that must not stall a
//! frame on a large level change starts the refinements with [`GpuScene::begin_refine`] and
//! records them in pieces, a frame's worth at a time, with [`GpuScene::refine_batch`] (work in
//! fine triangles, [`RefineJob`]): `hce view` does.
//!
//! Each object is refined by one of these paths (one variant of a private enum per object):
//!
//! * **Flat** objects ([`ObjectKind::Flat`]) by the [`FlatKernel`], colours from their HCE
//!   trees, no smoothing, whatever level the view asks for. By default they are drawn from their
//!   trees (SPEC.md F.7.1, [`SceneOptions::flat_refinement`]): one triangle per radiosity
//!   element plus those its finer neighbours need, the field the baker found with a fraction
//!   of the triangles. With [`FlatRefinement::Uniform`] they are split 1-to-4 to their tree
//!   depth (F.7.2, the level at which every element has its own triangles: a coarser level
//!   would blur the baked lighting and a finer one adds nothing), bounded by the object's size
//!   ([`flat_level`]); that level is also the one reported for an adaptive object.
//! * **Multiresolution** objects by the [`LoopKernel`] ([`MultiresPath::Gpu`], the default):
//!   Loop subdivision of every coarse triangle's patch, subtriangle colours decoded from the HCE
//!   tree by normal, area-weighted vertex colours, all in compute shaders.
//!   [`MultiresPath::CpuReference`] does the same on the CPU ([`hce_geometry::subdivide`] and
//!   [`hce_geometry::colour`]) and uploads the result: it is the reference the kernel is checked
//!   against, kept as an explicit option (never a silent fallback).
//!
//! The small objects of either kernel that [`GpuScene::refine_batch`] refines whole in one call
//! are refined together, one dispatch per step of the kernel for all of them
//! ([`SceneOptions::batch`], `batch.rs`), into the same bytes.
//!
//! # A viewer loop
//!
//! ```no_run
//! use hce_runtime::asset::Asset;
//! use hce_runtime::gpu::{
//!     Camera, ContextOptions, GpuContext, GpuScene, LevelChoice, LodParams, SceneOptions,
//! };
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let asset = Asset::open("baked.glb")?;
//! // A viewer usually owns its device already: `GpuContext::from_existing(&adapter, &device,
//! // &queue)` wraps it.
//! let ctx = GpuContext::new(&ContextOptions::default())?;
//! let mut scene = GpuScene::new(&ctx, &asset, &SceneOptions::default())?;
//! let mut camera = Camera { eye: [0.0, 1.0, 3.0], target: [0.0, 0.5, 0.0], fov_y_degrees: 45.0 };
//! for _frame in 0..3 {
//!     camera.eye[2] -= 0.5; // the user walks in
//!     // Re-refine only the objects whose level changed; buffers are reused unless they grow.
//!     scene.refine_all(
//!         &ctx,
//!         &LevelChoice::Auto { camera, viewport_height: 720, lod: LodParams::default() },
//!     )?;
//!     for draw in scene.draws() {
//!         // Bind draw.positions (stride 12) and draw.colours (stride 16, linear RGBA) as
//!         // vertex buffers, draw.indices as a u32 index buffer, draw.transform as the model
//!         // matrix, and draw draw.index_count indices with no lighting: the colours are the
//!         // baked lighting.
//!         let _ = (draw.positions, draw.colours, draw.indices, draw.transform);
//!     }
//! }
//! # Ok(())
//! # }
//! ```

use glam::{Mat4, Vec3};
use hce_format::{Object, ObjectKind};

use super::batch::{BatchObject, Pool, PoolInput, PoolKernel, BATCH_MAX_FINE, OBJECT_MAX_FINE};
use super::framing::{auto_scene_camera, Placement};
use super::lod::{choose_level, Camera, LodParams};
use super::render::{render_draws, MeshDraw, RenderParams, RenderedImage};
use super::util::{check_size, read_back, span, PassTimer};
use super::{
    FlatKernel, FlatObject, FlatOutput, Framing, GpuContext, GpuError, LoopKernel, LoopObject,
    LoopOutput, RefineJob,
};
use crate::asset::{Asset, Bounds};
use hce_geometry::lighting::Reconstruction;
pub use hce_geometry::refine::FlatRefinement;
use hce_geometry::subdivide::{subdivide_into, Refined};

/// How multiresolution objects are refined.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum MultiresPath {
    /// The GPU Loop kernel ([`LoopKernel`], levels up to [`hce_geometry::subdivide::MAX_LOOP_LEVEL`]).
    #[default]
    Gpu,
    /// CPU Loop subdivision and CPU colour application, uploaded as buffers (levels up to
    /// [`hce_geometry::subdivide::MAX_LOOP_LEVEL`]). The reference for checking the GPU kernel.
    CpuReference,
}

/// Options of [`GpuScene::new`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SceneOptions {
    pub multires: MultiresPath,
    /// A flat object is refined to its tree depth up to this level whatever its size, and
    /// deeper only within [`SceneOptions::flat_max_triangles`] ([`flat_level`]). Default 7
    /// (16 384 fine triangles per coarse one).
    pub flat_max_level: u32,
    /// A flat object deeper than [`SceneOptions::flat_max_level`] is refined further, to its
    /// tree depth, while it stays within this many fine triangles ([`flat_level`]). Default
    /// 2^22: a floor of two coarse triangles to level 10, Teatime's table of 44 to level 8.
    pub flat_max_triangles: u64,
    /// How baked colours become vertex colours (SPEC.md, Appendix G). Default: smooth.
    pub reconstruction: Reconstruction,
    /// Refine the small objects that [`GpuScene::refine_batch`] refines whole in one call
    /// together, the flat ones and the multiresolution ones each in one dispatch per step of
    /// their kernel for all of them, instead of three dispatches per object (their tables are
    /// copied once into pooled buffers). The output is the same bytes. Default `true`; `false`
    /// is the per-object path it is checked against.
    pub batch: bool,
    /// The most fine triangles one batch refines, the size of the pooled outputs: a call that
    /// refines more refines them in several batches. Default [`BATCH_MAX_FINE`] (2^20).
    pub batch_fine: u64,
    /// How flat objects are refined (SPEC.md F.7): from their trees (the default, F.7.1) or
    /// uniformly to [`flat_level`] (F.7.2).
    pub flat_refinement: FlatRefinement,
}

impl Default for SceneOptions {
    fn default() -> Self {
        Self {
            multires: MultiresPath::default(),
            flat_max_level: 7,
            flat_max_triangles: 1 << 22,
            reconstruction: Reconstruction::default(),
            batch: true,
            batch_fine: BATCH_MAX_FINE,
            flat_refinement: FlatRefinement::default(),
        }
    }
}

/// The level each multiresolution object is refined to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LevelChoice {
    /// This level for every multiresolution object.
    Fixed(u32),
    /// [`choose_level`] for the instance nearest to `camera` on a viewport
    /// `viewport_height` pixels high.
    Auto {
        camera: Camera,
        viewport_height: u32,
        lod: LodParams,
    },
}

/// Output buffers of the CPU path, shaped like the kernels' outputs.
struct CpuOutput {
    level: u32,
    vertex_count: u32,
    triangle_count: u32,
    positions: wgpu::Buffer,
    normals: wgpu::Buffer,
    colours: wgpu::Buffer,
    indices: wgpu::Buffer,
}

/// A refinement under way into buffers of its own (the object's current ones are still drawn).
struct Next<O> {
    level: u32,
    out: O,
    job: RefineJob,
}

/// The kernels whose small objects are batched, each with its pool.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Flat,
    Loop,
}

/// How one object is refined, with its uploaded data, its current output, the refinement under
/// way (if any) and the buffers of the output before, kept for the next refinement.
enum Refiner {
    Flat {
        object: Box<FlatObject>,
        out: Option<FlatOutput>,
        next: Option<Next<FlatOutput>>,
        spare: Option<FlatOutput>,
    },
    Loop {
        object: Box<LoopObject>,
        out: Option<LoopOutput>,
        next: Option<Next<LoopOutput>>,
        spare: Option<LoopOutput>,
    },
    CpuReference {
        reconstruction: Reconstruction,
        object: Box<Object>,
        scratch: Refined,
        out: Option<CpuOutput>,
    },
}

impl Refiner {
    /// The refinement under way of an object of kernel `kind`.
    fn next_of(&self, kind: Kind) -> Option<&Next<super::RefinedOutput>> {
        match (self, kind) {
            (Refiner::Flat { next, .. }, Kind::Flat) | (Refiner::Loop { next, .. }, Kind::Loop) => {
                next.as_ref()
            }
            _ => None,
        }
    }

    fn next_of_mut(&mut self, kind: Kind) -> Option<&mut Next<super::RefinedOutput>> {
        match (self, kind) {
            (Refiner::Flat { next, .. }, Kind::Flat) | (Refiner::Loop { next, .. }, Kind::Loop) => {
                next.as_mut()
            }
            _ => None,
        }
    }
}

/// The level a flat object of `coarse_triangles` triangles whose deepest leaf is at
/// `tree_depth` is drawn at, whatever level the view asks for: its tree depth, where every
/// leaf of its bake has its own fine triangles and the light is drawn as the baker found it,
/// up to `max_level` (the [`SceneOptions::flat_max_level`]) always, and deeper only while the
/// object stays within `max_triangles` fine triangles
/// ([`SceneOptions::flat_max_triangles`]).
///
/// The baker splits elements below its detail level along the edges of contact shadows
/// (levels 8 and 9 of a room's floor): drawn at level 7, each fine triangle blurred them over
/// four leaves, and under a teapot resting on the floor the umbra took twice the path
/// tracer's direct light (measured in commit 6d41b1e). Every coarse triangle of an
/// object is refined alike, so the triangle bound keeps an object of many coarse triangles
/// from growing fourfold a level for the sake of a few: Teatime's table (44 triangles, depth 8)
/// is drawn at level 8, 2 883 584 fine triangles, where its contact shadows are.
///
/// `web/src/scene.js` (`flatLevel`) is its twin.
pub fn flat_level(
    tree_depth: u32,
    coarse_triangles: u64,
    max_level: u32,
    max_triangles: u64,
) -> u32 {
    let mut level = tree_depth.min(max_level);
    while level < tree_depth
        && level < hce_geometry::decode::MAX_PATH_LEVEL
        && coarse_triangles.saturating_mul(1 << (2 * (level + 1))) <= max_triangles
    {
        level += 1;
    }
    level
}

/// One object of the scene on the GPU: what the level choice needs, its instances and its
/// refiner.
struct GpuObject {
    name: String,
    kind: ObjectKind,
    coarse_triangles: u64,
    tree_depth: u32,
    bounds: Bounds,
    mean_edge_length: f32,
    instances: Vec<Mat4>,
    refiner: Refiner,
}

impl GpuObject {
    /// The triangles of an adaptive flat object (SPEC.md F.7.1), which do not depend on the
    /// level; `None` for the others.
    fn adaptive_triangles(&self) -> Option<u64> {
        match &self.refiner {
            Refiner::Flat { object, .. } => object.adaptive_counts().map(|(_, f)| u64::from(f)),
            _ => None,
        }
    }
}

/// The buffers of a refined object, ready to draw.
#[derive(Clone, Copy, Debug)]
pub struct ObjectBuffers<'a> {
    pub level: u32,
    pub vertex_count: u32,
    pub triangle_count: u32,
    /// `x, y, z` f32 per vertex (stride 12), object space.
    pub positions: &'a wgpu::Buffer,
    /// Unit `x, y, z` f32 per vertex (stride 12) on the Loop paths. `None` for flat objects,
    /// whose shared vertices have no single normal; they are drawn unlit anyway.
    pub normals: Option<&'a wgpu::Buffer>,
    /// Linear `r, g, b, 1` f32 per vertex (stride 16): the baked lighting.
    pub colours: &'a wgpu::Buffer,
    /// `u32` ×3 per fine triangle, counter-clockwise.
    pub indices: &'a wgpu::Buffer,
}

/// One draw of a frame: an object's buffers and one of its instances' transforms.
#[derive(Clone, Copy, Debug)]
pub struct SceneDraw<'a> {
    pub object: usize,
    pub positions: &'a wgpu::Buffer,
    pub colours: &'a wgpu::Buffer,
    pub indices: &'a wgpu::Buffer,
    pub index_count: u32,
    /// Object to world.
    pub transform: Mat4,
}

impl<'a> From<&SceneDraw<'a>> for MeshDraw<'a> {
    fn from(d: &SceneDraw<'a>) -> Self {
        Self {
            positions: d.positions,
            colours: d.colours,
            indices: d.indices,
            index_count: d.index_count,
            transform: d.transform,
        }
    }
}

/// A refined object copied back to the CPU.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ObjectMesh {
    pub level: u32,
    /// `x, y, z` per vertex.
    pub positions: Vec<f32>,
    /// Unit `x, y, z` per vertex (Loop paths only).
    pub normals: Option<Vec<f32>>,
    /// Linear `r, g, b, 1` per vertex.
    pub colours: Vec<f32>,
    pub indices: Vec<u32>,
}

/// An asset's GPU resources. See the module documentation.
pub struct GpuScene {
    objects: Vec<GpuObject>,
    flat: Option<FlatKernel>,
    /// The small flat objects' tables and the small multiresolution objects', pooled for
    /// batched refinement.
    flat_pool: Option<Pool>,
    loop_pool: Option<Pool>,
    loop_kernel: Option<LoopKernel>,
    flat_max_level: u32,
    flat_max_triangles: u64,
    bounds: Option<Bounds>,
}

fn invalid(name: &str, reason: impl std::fmt::Display) -> GpuError {
    GpuError::InvalidObject {
        object: name.to_owned(),
        reason: reason.to_string(),
    }
}

/// A vertex or index buffer at least `bytes` long: `slot`'s when it is large enough.
fn ensure_buffer(
    ctx: &GpuContext,
    slot: Option<wgpu::Buffer>,
    label: &'static str,
    bytes: u64,
    usage: wgpu::BufferUsages,
) -> Result<wgpu::Buffer, GpuError> {
    let bytes = check_size(ctx, label, bytes)?;
    match slot {
        Some(b) if b.size() >= bytes => Ok(b),
        _ => Ok(ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: bytes,
            usage: usage | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        })),
    }
}

/// The scale by which `m` can at most lengthen an edge (its largest column norm).
fn max_scale(m: &Mat4) -> f32 {
    [m.x_axis, m.y_axis, m.z_axis]
        .iter()
        .map(|c| c.truncate().length())
        .fold(0.0, f32::max)
}

impl GpuScene {
    /// Uploads every object of `asset` (validated by [`Asset::open`]; the kernels check their
    /// tables again before upload). Nothing is refined yet: call [`GpuScene::refine_all`] or
    /// [`GpuScene::refine`].
    pub fn new(ctx: &GpuContext, asset: &Asset, options: &SceneOptions) -> Result<Self, GpuError> {
        let mut flat = None;
        let mut loop_kernel = None;
        let mut objects = Vec::with_capacity(asset.objects.len());
        for o in &asset.objects {
            let refiner = match (o.kind(), options.multires) {
                (ObjectKind::Flat, _) => {
                    let kernel = flat.get_or_insert_with(|| FlatKernel::new(ctx));
                    let object = kernel.upload(
                        ctx,
                        &o.object,
                        options.reconstruction,
                        options.flat_refinement,
                    )?;
                    Refiner::Flat {
                        object: Box::new(object),
                        out: None,
                        next: None,
                        spare: None,
                    }
                }
                (ObjectKind::Multiresolution, MultiresPath::Gpu) => {
                    let kernel = loop_kernel.get_or_insert_with(|| LoopKernel::new(ctx));
                    Refiner::Loop {
                        object: Box::new(kernel.upload(ctx, &o.object, options.reconstruction)?),
                        out: None,
                        next: None,
                        spare: None,
                    }
                }
                (ObjectKind::Multiresolution, MultiresPath::CpuReference) => {
                    Refiner::CpuReference {
                        reconstruction: options.reconstruction,
                        object: Box::new(o.object.clone()),
                        scratch: Refined::default(),
                        out: None,
                    }
                }
            };
            objects.push(GpuObject {
                name: o.name().to_owned(),
                kind: o.kind(),
                coarse_triangles: o.object.triangles.len() as u64,
                tree_depth: o.tree_depth,
                bounds: o.bounds,
                mean_edge_length: o.mean_edge_length,
                instances: o.instances.iter().map(|i| i.transform).collect(),
                refiner,
            });
        }
        let flat_pool = match &flat {
            Some(kernel) if options.batch => {
                let flats: Vec<Option<PoolInput<'_>>> = objects
                    .iter()
                    .map(|o| match &o.refiner {
                        Refiner::Flat { object, .. } => Some(PoolInput::from(&**object)),
                        _ => None,
                    })
                    .collect();
                Pool::new(ctx, PoolKernel::Flat(kernel), &flats, options.batch_fine)?
            }
            _ => None,
        };
        let loop_pool = match &loop_kernel {
            Some(kernel) if options.batch => {
                let loops: Vec<Option<PoolInput<'_>>> = objects
                    .iter()
                    .map(|o| match &o.refiner {
                        Refiner::Loop { object, .. } => Some(PoolInput::from(&**object)),
                        _ => None,
                    })
                    .collect();
                Pool::new(ctx, PoolKernel::Loop(kernel), &loops, options.batch_fine)?
            }
            _ => None,
        };
        Ok(Self {
            objects,
            flat,
            flat_pool,
            loop_pool,
            loop_kernel,
            flat_max_level: options.flat_max_level,
            flat_max_triangles: options.flat_max_triangles,
            bounds: asset.bounds(),
        })
    }

    pub fn object_count(&self) -> usize {
        self.objects.len()
    }

    /// World bounds of everything drawn.
    pub fn bounds(&self) -> Option<Bounds> {
        self.bounds
    }

    pub fn object_name(&self, object: usize) -> Option<&str> {
        self.objects.get(object).map(|o| o.name.as_str())
    }

    pub fn object_kind(&self, object: usize) -> Option<ObjectKind> {
        self.objects.get(object).map(|o| o.kind)
    }

    /// How many times `object` is drawn (its instances in the scene).
    pub fn instance_count(&self, object: usize) -> usize {
        self.objects.get(object).map_or(0, |o| o.instances.len())
    }

    /// The level `choice` gives `object` (flat objects: [`flat_level`], whatever `choice`).
    pub fn level_for(&self, object: usize, choice: &LevelChoice) -> Option<u32> {
        let o = self.objects.get(object)?;
        if o.kind == ObjectKind::Flat {
            return Some(flat_level(
                o.tree_depth,
                o.coarse_triangles,
                self.flat_max_level,
                self.flat_max_triangles,
            ));
        }
        Some(match choice {
            LevelChoice::Fixed(level) => *level,
            LevelChoice::Auto {
                camera,
                viewport_height,
                lod,
            } => o
                .instances
                .iter()
                .map(|m| {
                    let b = o.bounds.transformed(m);
                    let edge = o.mean_edge_length * max_scale(m);
                    choose_level(b.min, b.max, edge, camera, *viewport_height, lod)
                })
                .max()
                .unwrap_or(lod.min_level),
        })
    }

    /// Fine triangles of `object` at `level` (per instance); an adaptive flat object's, whatever
    /// the level.
    pub fn triangles_at(&self, object: usize, level: u32) -> u64 {
        self.objects.get(object).map_or(0, |o| {
            o.adaptive_triangles()
                .unwrap_or(o.coarse_triangles << (2 * level.min(31)))
        })
    }

    /// The level `object` is refined to now, if it has been refined.
    pub fn level(&self, object: usize) -> Option<u32> {
        self.buffers(object).map(|b| b.level)
    }

    /// The level `choice` gives every object that has instances (`None` for the others),
    /// lowered to keep at most `max_triangles` fine triangles drawn, instances counted: the
    /// object drawing the most triangles loses a level first. A [`LevelChoice::Fixed`] level is
    /// not lowered (flat objects' are); when that is not enough, the error says so. Returns the
    /// levels and a note per level lowered.
    pub fn levels_within(
        &self,
        choice: &LevelChoice,
        max_triangles: u64,
    ) -> Result<(Vec<Option<u32>>, Vec<String>), GpuError> {
        let forced = matches!(choice, LevelChoice::Fixed(_));
        let mut levels: Vec<Option<u32>> = (0..self.objects.len())
            .map(|i| {
                (!self.objects[i].instances.is_empty())
                    .then(|| self.level_for(i, choice))
                    .flatten()
            })
            .collect();
        let drawn =
            |i: usize, l: u32| self.triangles_at(i, l) * self.objects[i].instances.len() as u64;
        let total = |levels: &[Option<u32>]| -> u64 {
            levels
                .iter()
                .enumerate()
                .filter_map(|(i, l)| l.map(|l| drawn(i, l)))
                .sum()
        };
        let mut notes = Vec::new();
        while total(&levels) > max_triangles {
            // Lower the object with the most triangles drawn; a forced level is not lowered.
            let worst = levels
                .iter()
                .enumerate()
                .filter(|(i, l)| {
                    let o = &self.objects[*i];
                    // An adaptive flat object draws its trees whatever its level.
                    l.is_some_and(|l| l > 0)
                        && (!forced || o.kind == ObjectKind::Flat)
                        && o.adaptive_triangles().is_none()
                })
                .max_by_key(|(i, l)| drawn(*i, l.unwrap_or(0)))
                .map(|(i, _)| i);
            let Some(i) = worst else {
                return Err(GpuError::InvalidParams(format!(
                    "{} triangles at the requested level exceed the budget of {max_triangles}; \
                     choose a lower level or raise the budget",
                    total(&levels)
                )));
            };
            if let Some(l) = levels[i].as_mut() {
                *l -= 1;
                notes.push(format!(
                    "{}: level lowered to {l} to stay under {max_triangles} triangles",
                    self.objects[i].name
                ));
            }
        }
        Ok((levels, notes))
    }

    /// Refines every object that has instances to the level `choice` gives it. Returns the
    /// levels, `None` for objects not drawn.
    pub fn refine_all(
        &mut self,
        ctx: &GpuContext,
        choice: &LevelChoice,
    ) -> Result<Vec<Option<u32>>, GpuError> {
        let levels: Vec<Option<u32>> = (0..self.objects.len())
            .map(|i| {
                (!self.objects[i].instances.is_empty())
                    .then(|| self.level_for(i, choice))
                    .flatten()
            })
            .collect();
        self.refine_to(ctx, &levels)?;
        Ok(levels)
    }

    /// Refines object `i` to `levels[i]` for every `Some`: every refinement recorded in one
    /// command encoder and one submission.
    pub fn refine_to(&mut self, ctx: &GpuContext, levels: &[Option<u32>]) -> Result<(), GpuError> {
        let mut work = Vec::new();
        for (i, level) in levels.iter().enumerate() {
            if let Some(level) = *level {
                if self.begin_refine(ctx, i, level)? {
                    work.push((i, u64::MAX));
                }
            }
        }
        self.refine_batch(ctx, &work, false)?;
        Ok(())
    }

    /// Refines one object to `level`. Does nothing when it is already there; reuses its output
    /// buffers when they are large enough.
    pub fn refine(&mut self, ctx: &GpuContext, object: usize, level: u32) -> Result<(), GpuError> {
        self.refine_timed(ctx, object, level, false).map(|_| ())
    }

    /// [`GpuScene::refine`], which with `measure` returns the GPU time of the kernels' dispatches
    /// in seconds when the adapter has timestamp queries (waiting for the GPU); `None` without
    /// `measure` or timestamps, on the CPU reference path, and when the object was already at
    /// `level`.
    pub fn refine_timed(
        &mut self,
        ctx: &GpuContext,
        object: usize,
        level: u32,
        measure: bool,
    ) -> Result<Option<f64>, GpuError> {
        if !self.begin_refine(ctx, object, level)? {
            return Ok(None);
        }
        let report = self.refine_batch(ctx, &[(object, u64::MAX)], measure)?;
        Ok(report.first().and_then(|r| r.gpu_seconds))
    }

    /// Starts refining `object` to `level` without recording any GPU work: the refinement
    /// writes buffers of its own, and the object keeps drawing its current ones until
    /// [`GpuScene::refine_batch`] has recorded the last piece. Returns whether a refinement is
    /// under way: started now, or before for `level` or for a level strictly between the
    /// drawn one and `level` (a step towards it, kept so that a level that keeps changing
    /// still lands; [`GpuScene::refine_progress`] says which). When the object is already at
    /// `level` a refinement under way is dropped and this returns `false`; on the CPU
    /// reference path the object is refined at once and this returns `false`.
    pub fn begin_refine(
        &mut self,
        ctx: &GpuContext,
        object: usize,
        level: u32,
    ) -> Result<bool, GpuError> {
        let count = self.objects.len();
        let o = self.objects.get_mut(object).ok_or_else(|| {
            GpuError::InvalidParams(format!("object {object} does not exist ({count} objects)"))
        })?;
        let name = o.name.clone();
        match &mut o.refiner {
            Refiner::Flat {
                object,
                out,
                next,
                spare,
            } => {
                let kernel = self
                    .flat
                    .as_ref()
                    .ok_or_else(|| invalid(&name, "the flat kernel was not created"))?;
                begin_next(out, next, spare, level, |spare| {
                    kernel.begin(ctx, object, level, spare)
                })
            }
            Refiner::Loop {
                object,
                out,
                next,
                spare,
            } => {
                let kernel = self
                    .loop_kernel
                    .as_ref()
                    .ok_or_else(|| invalid(&name, "the Loop kernel was not created"))?;
                begin_next(out, next, spare, level, |spare| {
                    kernel.begin(ctx, object, level, spare)
                })
            }
            Refiner::CpuReference {
                reconstruction,
                object,
                scratch,
                out,
            } => {
                if out.as_ref().is_some_and(|b| b.level == level) {
                    return Ok(false);
                }
                if level > hce_geometry::subdivide::MAX_LOOP_LEVEL {
                    return Err(GpuError::LevelTooHigh {
                        level,
                        max: hce_geometry::subdivide::MAX_LOOP_LEVEL,
                    });
                }
                subdivide_into(&object.mesh, level, scratch).map_err(|e| invalid(&name, e))?;
                hce_geometry::split::SplitTables::new(&name, &object.mesh, object.kind)
                    .map_err(|e| invalid(&name, e))?
                    .apply(&object.mesh, scratch)
                    .map_err(|e| invalid(&name, e))?;
                let colours = hce_geometry::colour::apply_baked_colours_with(
                    object,
                    scratch,
                    level,
                    *reconstruction,
                )
                .map_err(|e| invalid(&name, e))?;
                *out = Some(upload_cpu(ctx, out.take(), scratch, &colours, level)?);
                Ok(false)
            }
        }
    }

    /// The refinement under way for `object`: its level, the work not recorded yet and the
    /// work of the whole refinement, in fine triangles per step ([`RefineJob::work_left`]).
    pub fn refine_progress(&self, object: usize) -> Option<(u32, u64, u64)> {
        let job = |level: u32, job: &RefineJob| (level, job.work_left(), job.total_work());
        match &self.objects.get(object)?.refiner {
            Refiner::Flat { next, .. } => next.as_ref().map(|n| job(n.level, &n.job)),
            Refiner::Loop { next, .. } => next.as_ref().map(|n| job(n.level, &n.job)),
            Refiner::CpuReference { .. } => None,
        }
    }

    /// Records up to the given work (fine triangles, [`RefineJob::encode`]; `u64::MAX` for the
    /// rest) of each listed object's refinement under way ([`GpuScene::begin_refine`]) in one
    /// command encoder and one submission, and swaps in the refinements whose last piece it
    /// recorded: their new level is drawn from the next draw submitted, never a partial one.
    /// Objects with no refinement under way are skipped. With `measure`, each object's GPU
    /// time of the pieces of this batch where the adapter has timestamp queries (waiting for
    /// the GPU); flat objects refined together share their dispatches' time in proportion to
    /// their fine triangles.
    ///
    /// Small objects refined whole here (work at least [`RefineJob::total_work`], nothing
    /// recorded before) are refined together, one dispatch per step for all the flat ones and
    /// one for all the multiresolution ones, when there are two or more of a kind
    /// ([`SceneOptions::batch`]); the others with their own dispatches.
    pub fn refine_batch(
        &mut self,
        ctx: &GpuContext,
        work: &[(usize, u64)],
        measure: bool,
    ) -> Result<Vec<BatchReport>, GpuError> {
        let mut timer =
            PassTimer::new(ctx, "hce refine timing", 3 * work.len() as u32 + 1, measure);
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("hce refine"),
            });
        let mut reports = Vec::with_capacity(work.len());
        // Per report, its timer passes and its share of their time.
        let mut passes = Vec::with_capacity(work.len());
        let mut batched = self.batch_pooled(ctx, &mut encoder, work, &mut timer, Kind::Flat)?;
        batched.extend(self.batch_pooled(ctx, &mut encoder, work, &mut timer, Kind::Loop)?);
        let mut in_batch = vec![false; self.objects.len()];
        for b in &batched {
            in_batch[b.object] = true;
            reports.push(BatchReport {
                object: b.object,
                work: b.work,
                finished: true,
                batched: true,
                gpu_seconds: None,
            });
            passes.push((b.pass.map_or(0..0, |p| p..p + 1), b.share));
        }
        for &(i, amount) in work {
            if in_batch.get(i) == Some(&true) {
                continue;
            }
            let Some(o) = self.objects.get_mut(i) else {
                continue;
            };
            let job = match &mut o.refiner {
                Refiner::Flat { next: Some(n), .. } => &mut n.job,
                Refiner::Loop { next: Some(n), .. } => &mut n.job,
                _ => continue,
            };
            let encoded = job.encode(ctx, &mut encoder, amount, Some(&mut timer))?;
            reports.push(BatchReport {
                object: i,
                work: encoded.work,
                finished: job.is_done(),
                batched: false,
                gpu_seconds: None,
            });
            passes.push((encoded.passes, 1.0));
        }
        if reports.is_empty() {
            return Ok(reports);
        }
        timer.resolve(ctx, &mut encoder);
        ctx.queue.submit([encoder.finish()]);
        if let Some(stamps) = timer.read_stamps(ctx)? {
            // From an object's first piece's start to its last piece's end ([`span`]).
            for (r, (p, share)) in reports.iter_mut().zip(&passes) {
                if !p.is_empty() {
                    r.gpu_seconds = Some(span(&stamps, p.clone()) * share);
                }
            }
        }
        // Submitted: the finished refinements are drawn from now on, the buffers they replace
        // kept for the next ones.
        for r in reports.iter().filter(|r| r.finished) {
            match &mut self.objects[r.object].refiner {
                Refiner::Flat {
                    out, next, spare, ..
                } => finish_next(out, next, spare),
                Refiner::Loop {
                    out, next, spare, ..
                } => finish_next(out, next, spare),
                Refiner::CpuReference { .. } => {}
            }
        }
        Ok(reports)
    }

    /// Records in batches ([`Pool::encode`]) the objects of `work` of kind `kind` that are
    /// pooled, refined whole by this call (nothing recorded before) to at most
    /// [`OBJECT_MAX_FINE`] fine triangles, when there are two or more; marks their jobs
    /// recorded. Each batch takes as many as fit [`SceneOptions::batch_fine`]; all but the last
    /// are submitted at once in encoders of their own (a batch's table is written to the queue,
    /// so the next batch may be recorded only once it is submitted), the last goes into
    /// `encoder` (which holds only earlier batches' work when this is called). Returns each
    /// object with its work, its batch's timer pass and its share of the batch's work.
    fn batch_pooled(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        work: &[(usize, u64)],
        timer: &mut PassTimer,
        kind: Kind,
    ) -> Result<Vec<Batched>, GpuError> {
        let pool = match kind {
            Kind::Flat => self.flat_pool.as_mut(),
            Kind::Loop => self.loop_pool.as_mut(),
        };
        let Some(pool) = pool else {
            return Ok(Vec::new());
        };
        let mut seen = vec![false; self.objects.len()];
        let mut chosen = Vec::new();
        for &(i, amount) in work {
            let Some(n) = self.objects.get(i).and_then(|o| o.refiner.next_of(kind)) else {
                continue;
            };
            if !seen[i]
                && pool.holds(i)
                && n.job.is_untouched()
                && amount >= n.job.total_work()
                && u64::from(n.out.triangle_count) <= OBJECT_MAX_FINE
            {
                seen[i] = true;
                chosen.push(BatchObject {
                    object: i,
                    params: n.job.params(),
                    out: &n.out,
                });
            }
        }
        // The batches: (first object, end, timer pass).
        let mut batches = Vec::new();
        let mut first = 0;
        while chosen.len() - first >= 2 {
            let rest = &chosen[first..];
            let n = pool.fitting(rest.iter().map(|b| b.out.triangle_count));
            if n < 2 {
                break;
            }
            // Each kind has its pool, so the last batch of each can go into `encoder`.
            let pass = if n == rest.len() {
                pool.encode(ctx, encoder, &rest[..n], Some(&mut *timer))?
            } else {
                let mut own = ctx
                    .device
                    .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                        label: Some("hce batch"),
                    });
                let pass = pool.encode(ctx, &mut own, &rest[..n], Some(&mut *timer))?;
                ctx.queue.submit([own.finish()]);
                pass
            };
            batches.push((first, first + n, pass));
            first += n;
        }
        let faces: Vec<(usize, u64)> = chosen
            .iter()
            .map(|b| (b.object, u64::from(b.out.triangle_count)))
            .collect();
        let mut batched = Vec::with_capacity(faces.len());
        for (start, end, pass) in batches {
            let total: u64 = faces[start..end].iter().map(|&(_, f)| f).sum();
            for &(i, f) in &faces[start..end] {
                if let Some(n) = self.objects[i].refiner.next_of_mut(kind) {
                    batched.push(Batched {
                        object: i,
                        work: n.job.recorded_elsewhere(),
                        pass,
                        share: f as f64 / total.max(1) as f64,
                    });
                }
            }
        }
        Ok(batched)
    }

    /// The current buffers of `object`, `None` before its first refinement.
    pub fn buffers(&self, object: usize) -> Option<ObjectBuffers<'_>> {
        match &self.objects.get(object)?.refiner {
            Refiner::Flat { out, .. } => out.as_ref().map(|o| ObjectBuffers {
                level: o.level,
                vertex_count: o.vertex_count,
                triangle_count: o.triangle_count,
                positions: &o.positions,
                normals: None,
                colours: &o.colours,
                indices: &o.indices,
            }),
            Refiner::Loop { out, .. } => out.as_ref().map(|o| ObjectBuffers {
                level: o.level,
                vertex_count: o.vertex_count,
                triangle_count: o.triangle_count,
                positions: &o.positions,
                normals: o.normals.as_ref(),
                colours: &o.colours,
                indices: &o.indices,
            }),
            Refiner::CpuReference { out, .. } => out.as_ref().map(|o| ObjectBuffers {
                level: o.level,
                vertex_count: o.vertex_count,
                triangle_count: o.triangle_count,
                positions: &o.positions,
                normals: Some(&o.normals),
                colours: &o.colours,
                indices: &o.indices,
            }),
        }
    }

    /// Copies `object`'s refined mesh back to the CPU.
    pub fn read_back(&self, ctx: &GpuContext, object: usize) -> Result<ObjectMesh, GpuError> {
        let b = self.buffers(object).ok_or_else(|| {
            GpuError::InvalidParams(format!("object {object} has not been refined"))
        })?;
        let (v, f) = (b.vertex_count as usize, b.triangle_count as usize);
        Ok(ObjectMesh {
            level: b.level,
            positions: read_back(ctx, b.positions, 3 * v)?,
            normals: b.normals.map(|n| read_back(ctx, n, 3 * v)).transpose()?,
            colours: read_back(ctx, b.colours, 4 * v)?,
            indices: read_back(ctx, b.indices, 3 * f)?,
        })
    }

    /// One draw per instance of every refined object.
    pub fn draws(&self) -> Vec<SceneDraw<'_>> {
        let mut out = Vec::new();
        for (i, o) in self.objects.iter().enumerate() {
            let Some(b) = self.buffers(i) else { continue };
            for &transform in &o.instances {
                out.push(SceneDraw {
                    object: i,
                    positions: b.positions,
                    colours: b.colours,
                    indices: b.indices,
                    index_count: b.triangle_count * 3,
                    transform,
                });
            }
        }
        out
    }

    /// Fine triangles drawn per frame at the current levels, instances counted.
    pub fn drawn_triangles(&self) -> u64 {
        self.draws()
            .iter()
            .map(|d| u64::from(d.index_count / 3))
            .sum()
    }

    /// Draws the refined scene headless with `camera` (no lighting: the colours are the baked
    /// lighting) and reads the image back.
    pub fn render(
        &self,
        ctx: &GpuContext,
        camera: Camera,
        params: &RenderParams,
    ) -> Result<RenderedImage, GpuError> {
        let bounds = self
            .bounds
            .ok_or_else(|| GpuError::InvalidParams("the asset has nothing to draw".into()))?;
        let draws: Vec<MeshDraw<'_>> = self
            .draws()
            .iter()
            .map(|d| MeshDraw {
                positions: d.positions,
                colours: d.colours,
                indices: d.indices,
                index_count: d.index_count,
                transform: d.transform,
            })
            .collect();
        render_draws(
            ctx,
            &draws,
            (bounds.min, bounds.max),
            &RenderParams {
                framing: Framing::Camera(camera),
                ..*params
            },
        )
    }
}

/// What [`GpuScene::refine_batch`] did for one object.
#[derive(Clone, Debug, PartialEq)]
pub struct BatchReport {
    pub object: usize,
    /// Work recorded, in fine triangles ([`RefineJob::encode`]).
    pub work: u64,
    /// Whether the refinement is complete and drawn from now on.
    pub finished: bool,
    /// Whether it was refined together with other objects of its kernel, one dispatch per step
    /// for all of them ([`SceneOptions::batch`]).
    pub batched: bool,
    /// GPU time of the pieces recorded, when measured with timestamp queries.
    pub gpu_seconds: Option<f64>,
}

/// An object [`GpuScene::batch_pooled`] recorded in a batch.
struct Batched {
    object: usize,
    /// Its work (see [`RefineJob`]).
    work: u64,
    /// The timer pass of its batch.
    pass: Option<u32>,
    /// Its share of the batch's fine triangles, and so of the batch's GPU time.
    share: f64,
}

/// Kernel output buffers that report their level.
trait Leveled {
    fn level(&self) -> u32;
}

impl Leveled for super::RefinedOutput {
    fn level(&self) -> u32 {
        self.level
    }
}

/// [`GpuScene::begin_refine`] for a kernel path: keeps a refinement under way whose level lies
/// between the drawn level (excluded) and `level` (included), a step towards it, so that a
/// level that keeps changing (a camera moving on) still lands step by step; drops any other
/// (its buffers become the spare ones) and starts one with `begin` (which refines into the
/// spare buffers, reallocating them if too small) unless the object is already at `level`.
fn begin_next<O: Leveled>(
    out: &Option<O>,
    next: &mut Option<Next<O>>,
    spare: &mut Option<O>,
    level: u32,
    begin: impl FnOnce(&mut Option<O>) -> Result<RefineJob, GpuError>,
) -> Result<bool, GpuError> {
    let drawn = out.as_ref().map(|o| o.level());
    if next.as_ref().is_some_and(|n| {
        n.level == level
            || drawn.is_some_and(|d| {
                d != level && (d < n.level && n.level < level || level < n.level && n.level < d)
            })
    }) {
        return Ok(true);
    }
    if let Some(dropped) = next.take() {
        *spare = Some(dropped.out);
    }
    if out.as_ref().is_some_and(|o| o.level() == level) {
        return Ok(false);
    }
    let job = begin(spare)?;
    let out = spare.take().expect("begin allocates the output");
    *next = Some(Next { level, out, job });
    Ok(true)
}

/// Swaps a finished refinement in: its buffers are drawn, the ones it replaces kept.
fn finish_next<O>(out: &mut Option<O>, next: &mut Option<Next<O>>, spare: &mut Option<O>) {
    if let Some(n) = next.take() {
        *spare = out.replace(n.out);
    }
}

/// Uploads a CPU-refined mesh into `old`'s buffers when they are large enough.
fn upload_cpu(
    ctx: &GpuContext,
    old: Option<CpuOutput>,
    refined: &Refined,
    colours: &[[f32; 3]],
    level: u32,
) -> Result<CpuOutput, GpuError> {
    let v = refined.positions.len() as u64;
    let f = refined.indices.len() as u64;
    let too_large = |what| GpuError::TooLarge {
        what,
        needed: v.max(f),
        limit: u64::from(u32::MAX),
    };
    let vertex_count = u32::try_from(v).map_err(|_| too_large("refined vertex count"))?;
    let triangle_count = u32::try_from(f).map_err(|_| too_large("refined triangle count"))?;
    let (p, n, c, i) = match old {
        Some(o) => (
            Some(o.positions),
            Some(o.normals),
            Some(o.colours),
            Some(o.indices),
        ),
        None => (None, None, None, None),
    };
    let vertex = wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::STORAGE;
    let positions = ensure_buffer(ctx, p, "refined positions", v * 12, vertex)?;
    let normals = ensure_buffer(ctx, n, "refined normals", v * 12, vertex)?;
    let colour_buf = ensure_buffer(ctx, c, "refined colours", v * 16, vertex)?;
    let indices = ensure_buffer(
        ctx,
        i,
        "refined indices",
        f * 12,
        wgpu::BufferUsages::INDEX | wgpu::BufferUsages::STORAGE,
    )?;
    let rgba: Vec<[f32; 4]> = colours.iter().map(|c| [c[0], c[1], c[2], 1.0]).collect();
    for (buffer, bytes) in [
        (
            &positions,
            bytemuck::cast_slice::<[f32; 3], u8>(&refined.positions),
        ),
        (&normals, bytemuck::cast_slice(&refined.normals)),
        (&colour_buf, bytemuck::cast_slice(&rgba)),
        (&indices, bytemuck::cast_slice(&refined.indices)),
    ] {
        if !bytes.is_empty() {
            ctx.queue.write_buffer(buffer, 0, bytes);
        }
    }
    Ok(CpuOutput {
        level,
        vertex_count,
        triangle_count,
        positions,
        normals,
        colours: colour_buf,
        indices,
    })
}

/// Which camera [`render_asset`] uses.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum CameraChoice {
    /// The scene's camera when the file has one, else [`CameraChoice::Auto`].
    #[default]
    SceneOrAuto,
    /// The scene's camera; an error when the file has none.
    Scene,
    /// Placed from the scene's geometry ([`auto_scene_camera`]): inside a closed room, in front
    /// of a box's opening, or outside an object.
    Auto,
    Explicit(Camera),
}

/// Where the camera of a render came from.
#[derive(Clone, Debug, PartialEq)]
pub enum CameraSource {
    /// The glTF camera node named here.
    Scene(String),
    Auto(Placement),
    Explicit,
}

/// Options of [`render_asset`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AssetRenderOptions {
    /// Image size in pixels. Default 800 × 600.
    pub width: u32,
    pub height: u32,
    pub camera: CameraChoice,
    /// Level of multiresolution objects. Default: chosen from the view with
    /// [`LodParams::default`].
    pub level: Option<u32>,
    pub lod: LodParams,
    /// Most fine triangles drawn (instances counted). Automatic levels are lowered, highest
    /// first, to stay under it; a fixed level above it is an error. Default 16 000 000.
    pub max_triangles: u64,
    pub scene: SceneOptions,
    /// Linear background colour. Default black.
    pub background: [f32; 3],
    /// Multisamples per pixel, as [`RenderParams::samples`]. Default 4.
    pub samples: u32,
}

impl Default for AssetRenderOptions {
    fn default() -> Self {
        Self {
            width: 800,
            height: 600,
            camera: CameraChoice::default(),
            level: None,
            lod: LodParams::default(),
            max_triangles: 16_000_000,
            scene: SceneOptions::default(),
            background: [0.0; 3],
            samples: 4,
        }
    }
}

/// What [`render_asset`] drew.
#[derive(Clone, Debug, PartialEq)]
pub struct AssetRender {
    pub image: RenderedImage,
    pub camera: Camera,
    pub camera_source: CameraSource,
    /// `(object name, kind, level, fine triangles per instance, instances)` per drawn object.
    pub objects: Vec<(String, ObjectKind, u32, u64, usize)>,
    /// Fine triangles drawn, instances counted.
    pub triangles: u64,
    /// Adjustments made (levels lowered for the triangle budget).
    pub notes: Vec<String>,
}

/// The camera `choice` gives for `asset`, on an image of aspect `aspect`.
pub fn resolve_camera(
    asset: &Asset,
    choice: CameraChoice,
    aspect: f32,
) -> Result<(Camera, CameraSource), GpuError> {
    let bounds = asset
        .bounds()
        .ok_or_else(|| GpuError::InvalidParams("the asset has nothing to draw".into()))?;
    let scene = asset.camera.as_ref().map(|c| {
        // The target only sets the direction; place it at the scene's scale.
        let reach = bounds.radius().max(1e-3);
        let target = Vec3::from(c.eye) + Vec3::from(c.forward) * reach;
        (
            Camera {
                eye: c.eye,
                target: target.into(),
                fov_y_degrees: c.fov_y_degrees,
            },
            CameraSource::Scene(c.name.clone()),
        )
    });
    let auto = || {
        let (camera, placement) =
            auto_scene_camera(&asset.world_triangles(), bounds.min, bounds.max, aspect);
        (camera, CameraSource::Auto(placement))
    };
    Ok(match choice {
        CameraChoice::SceneOrAuto => scene.unwrap_or_else(auto),
        CameraChoice::Scene => scene.ok_or_else(|| {
            GpuError::InvalidParams(format!(
                "{} has no perspective camera; use the automatic camera or give one",
                asset.path.display()
            ))
        })?,
        CameraChoice::Auto => auto(),
        CameraChoice::Explicit(c) => (c, CameraSource::Explicit),
    })
}

/// Renders a baked asset to an image: uploads it, picks the camera and each object's level,
/// keeps the triangle budget, refines and draws. `hce render` is this function plus file
/// output; to render several levels of one asset, use a [`GpuScene`] directly and call
/// [`GpuScene::refine_all`] and [`GpuScene::render`] per level.
pub fn render_asset(
    ctx: &GpuContext,
    asset: &Asset,
    options: &AssetRenderOptions,
) -> Result<AssetRender, GpuError> {
    if options.width == 0 || options.height == 0 {
        return Err(GpuError::InvalidParams(format!(
            "image size {}x{}: each side must be at least 1 pixel",
            options.width, options.height
        )));
    }
    let aspect = options.width as f32 / options.height as f32;
    let (camera, camera_source) = resolve_camera(asset, options.camera, aspect)?;
    let mut scene = GpuScene::new(ctx, asset, &options.scene)?;
    let choice = match options.level {
        Some(level) => LevelChoice::Fixed(level),
        None => LevelChoice::Auto {
            camera,
            viewport_height: options.height,
            lod: options.lod,
        },
    };
    let (levels, notes) = scene.levels_within(&choice, options.max_triangles)?;
    scene.refine_to(ctx, &levels)?;
    let image = scene.render(
        ctx,
        camera,
        &RenderParams {
            width: options.width,
            height: options.height,
            framing: Framing::Camera(camera),
            background: options.background,
            samples: options.samples,
        },
    )?;
    let objects = levels
        .iter()
        .enumerate()
        .filter_map(|(i, l)| {
            let o = &scene.objects[i];
            l.map(|l| {
                (
                    o.name.clone(),
                    o.kind,
                    l,
                    scene.triangles_at(i, l),
                    o.instances.len(),
                )
            })
        })
        .collect();
    Ok(AssetRender {
        image,
        camera,
        camera_source,
        objects,
        triangles: scene.drawn_triangles(),
        notes,
    })
}

#[cfg(test)]
mod tests {
    use super::flat_level;

    #[test]
    fn flat_objects_go_to_their_tree_depth_within_the_triangle_bound() {
        let (max_level, max_triangles) = (7, 1 << 22);
        // Shallow trees: the tree depth, whatever the size.
        assert_eq!(flat_level(0, 2, max_level, max_triangles), 0);
        assert_eq!(flat_level(5, 2, max_level, max_triangles), 5);
        assert_eq!(flat_level(7, 10_000, max_level, max_triangles), 7);
        // A room's floor of two triangles, split to level 9 along a contact shadow: level 9,
        // and no deeper than level 10 (2 · 4^10 < 2^22 < 2 · 4^11) for a deeper tree.
        assert_eq!(flat_level(9, 2, max_level, max_triangles), 9);
        assert_eq!(flat_level(12, 2, max_level, max_triangles), 10);
        assert_eq!(flat_level(12, 1, max_level, max_triangles), 11);
        assert_eq!(flat_level(8, 3, max_level, max_triangles), 8);
        // Teatime's table (44 triangles, depth 8): level 8 (44 · 4^8 < 2^22), not 9.
        assert_eq!(flat_level(8, 44, max_level, max_triangles), 8);
        assert_eq!(flat_level(9, 44, max_level, max_triangles), 8);
        // Many triangles: level 7 whatever the bound, no deeper.
        assert_eq!(flat_level(9, 300, max_level, max_triangles), 7);
        // No overflow and no level past what a path can name, however large the bound.
        assert_eq!(flat_level(15, u64::MAX, max_level, u64::MAX), 15);
        assert_eq!(flat_level(40, 1, max_level, u64::MAX), 15);
        assert_eq!(flat_level(9, 2, 9, 0), 9);
    }
}
