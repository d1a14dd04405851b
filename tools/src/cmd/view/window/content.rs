//! What the viewer shows: a baked asset on a [`GpuScene`], or a plain mesh previewed flat as
//! `hce render` previews it; the level of each object for the frame's camera, refining only the
//! objects whose level changed, and what that cost.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context, Result};
use hce_format::ObjectKind;
use hce_geometry::lighting::Reconstruction;
use hce_geometry::refine::FlatRefinement;
use hce_runtime::asset::{Asset, AssetError};
use hce_runtime::gpu::{
    resolve_camera, Camera, CameraChoice, CameraSource, FlatKernel, FlatObject, FlatOutput,
    GpuContext, GpuScene, LevelChoice, LodParams, MeshDraw, SceneOptions,
};

use crate::cmd::render::{check_plain_level, plain_object, PlainView};

/// How levels are chosen each frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Levels {
    /// `None`: from the view with `lod`.
    pub forced: Option<u32>,
    pub lod: LodParams,
    /// Most fine triangles drawn, instances counted (as `hce render --max-triangles`).
    pub max_triangles: u64,
    /// Milliseconds of refinement per frame (wall time, GPU work waited for): level changes
    /// are recorded in pieces sized to it at the cost measured so far, over as many frames as
    /// they need (at least 1/[`MIN_PIECE`] of one refinement per frame); 0: every change at
    /// once.
    pub refine_budget_ms: f64,
}

/// One object as the panel and the statistics show it.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ObjectStats {
    pub name: String,
    pub kind: &'static str,
    pub level: u32,
    /// Fine triangles per instance.
    pub triangles: u64,
    pub instances: usize,
    /// Wall time of its last refinement, GPU work waited for, in milliseconds: the frames' wall
    /// times shared among the objects refined in them by work, summed over its pieces.
    pub refine_ms: f64,
    /// GPU time of its last refinement's dispatches (timestamp queries), in milliseconds,
    /// where the adapter has them, summed over its pieces.
    pub refine_gpu_ms: Option<f64>,
    /// Frames its last refinement was spread over.
    pub refine_frames: u32,
}

/// Least part of one refinement recorded in a frame whatever the budget (1/32 of its work):
/// a level change is drawn at most 32 frames after it starts.
pub const MIN_PIECE: u64 = 32;

/// Milliseconds per fine triangle of refinement work assumed before any has been measured
/// (lavapipe's order of magnitude; the first frame refines everything and measures it).
const FIRST_RATE_MS: f64 = 2e-4;

/// What one frame's level update did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Refined {
    /// Indices (into [`Content::objects`]) of the objects whose refinement finished this frame:
    /// their new level is drawn from this frame on.
    pub objects: Vec<usize>,
    /// Indices of the objects refined in part this frame, still drawn at their old level.
    pub working: Vec<usize>,
    /// The wall time of this frame's refinement work (the output buffers of refinements begun,
    /// one submission), GPU work waited for, in milliseconds.
    pub ms: f64,
    /// The GPU time of their dispatches (timestamp queries), where the adapter has them.
    pub gpu_ms: Option<f64>,
    /// Levels lowered for the triangle budget.
    pub notes: Vec<String>,
    /// Objects whose level should change and is not drawn yet (refine budget).
    pub pending: usize,
}

/// A running estimate of what refinement costs: the wall milliseconds of a frame's refinement
/// per fine triangle of its work (see `hce_runtime::gpu::RefineJob`), a running mean. Wall
/// times, because GPU timestamps are not there on every adapter and on lavapipe do not enclose
/// all of the work. A frame's fixed cost (uniforms, zeroing new buffers, submitting, waiting)
/// is part of the ratio, so the pieces it sizes settle where the fixed cost and the work
/// together fill the budget. Frames that refine objects not drawn yet (the first: every object
/// whole, with the driver's first-use costs) are left out.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct RefineCost {
    rate_ms: Option<f64>,
}

impl RefineCost {
    /// Work that fits `budget_ms`.
    fn work_within(&self, budget_ms: f64) -> u64 {
        (budget_ms / self.rate_ms.unwrap_or(FIRST_RATE_MS)) as u64
    }

    /// Takes in a frame that did `work` in `wall_ms`.
    fn measured(&mut self, work: u64, wall_ms: f64) {
        if work == 0 {
            return;
        }
        let rate = wall_ms / work as f64;
        self.rate_ms = Some(self.rate_ms.map_or(rate, |r| 0.5 * (r + rate)));
    }
}

enum Source {
    Baked {
        asset: Box<Asset>,
        scene: Box<GpuScene>,
        /// What refinement has cost so far, to size the next frame's pieces.
        cost: RefineCost,
    },
    Plain(Box<Plain>),
}

/// A plain mesh with the flat kernel that previews it.
struct Plain {
    object: Box<hce_format::Object>,
    view: PlainView,
    kernel: FlatKernel,
    uploaded: FlatObject,
    out: Option<FlatOutput>,
}

/// A file opened in the viewer.
pub struct Content {
    pub path: PathBuf,
    source: Source,
    pub bounds: ([f32; 3], [f32; 3]),
    pub objects: Vec<ObjectStats>,
    pub reconstruction: Reconstruction,
    flat: FlatRefinement,
}

fn kind_name(kind: Option<ObjectKind>) -> &'static str {
    match kind {
        Some(ObjectKind::Multiresolution) => "multiresolution",
        Some(ObjectKind::Flat) => "flat",
        None => "?",
    }
}

/// A file read and checked on the CPU, before any window or adapter: a bad file is reported
/// with its exit status even where no window could open.
pub enum FileData {
    Baked(Box<Asset>),
    Plain(Box<hce_format::Object>),
}

impl FileData {
    /// Reads `path`: a baked asset, or any other mesh previewed flat (as `hce render` does).
    pub fn read(path: &Path) -> Result<Self> {
        let is_obj = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("obj"));
        if !is_obj {
            match Asset::open(path) {
                Ok(asset) => {
                    for w in &asset.warnings {
                        eprintln!("warning: {w}");
                    }
                    if asset.bounds().is_none() {
                        bail!("{}: the asset has nothing to draw", path.display());
                    }
                    return Ok(Self::Baked(Box::new(asset)));
                }
                Err(AssetError::NotBaked { .. }) => {
                    println!(
                        "{}: no baked lighting; previewing the plain mesh flat",
                        path.display()
                    );
                }
                Err(e) => return Err(e.into()),
            }
        }
        Ok(Self::Plain(Box::new(plain_object(path)?)))
    }
}

impl Content {
    /// Uploads `data`, read from `path`, with `reconstruction`.
    pub fn upload(
        ctx: &GpuContext,
        path: &Path,
        data: FileData,
        reconstruction: Reconstruction,
        flat: FlatRefinement,
    ) -> Result<Self> {
        match data {
            FileData::Baked(asset) => Self::baked(ctx, path, *asset, reconstruction, flat),
            FileData::Plain(object) => Self::plain(ctx, path, *object, reconstruction, flat),
        }
    }

    fn baked(
        ctx: &GpuContext,
        path: &Path,
        asset: Asset,
        reconstruction: Reconstruction,
        flat: FlatRefinement,
    ) -> Result<Self> {
        let bounds = asset
            .bounds()
            .with_context(|| format!("{}: the asset has nothing to draw", path.display()))?;
        let scene = GpuScene::new(
            ctx,
            &asset,
            &SceneOptions {
                reconstruction,
                flat_refinement: flat,
                ..Default::default()
            },
        )?;
        let objects = (0..scene.object_count())
            .map(|i| ObjectStats {
                name: scene.object_name(i).unwrap_or("?").to_owned(),
                kind: kind_name(scene.object_kind(i)),
                level: 0,
                triangles: 0,
                instances: scene.instance_count(i),
                refine_ms: 0.0,
                refine_gpu_ms: None,
                refine_frames: 0,
            })
            .collect();
        Ok(Self {
            path: path.to_owned(),
            source: Source::Baked {
                asset: Box::new(asset),
                scene: Box::new(scene),
                cost: RefineCost::default(),
            },
            bounds: (bounds.min, bounds.max),
            objects,
            reconstruction,
            flat,
        })
    }

    fn plain(
        ctx: &GpuContext,
        path: &Path,
        object: hce_format::Object,
        reconstruction: Reconstruction,
        flat: FlatRefinement,
    ) -> Result<Self> {
        // A plain mesh has no trees: it is previewed at its level, uniformly (`flat` is kept
        // for the next file).
        let view = PlainView::new(&object)?;
        let kernel = FlatKernel::new(ctx);
        let uploaded = kernel.upload(ctx, &object, reconstruction, FlatRefinement::Uniform)?;
        let objects = vec![ObjectStats {
            name: object.name.clone(),
            kind: "plain mesh, previewed flat",
            level: 0,
            triangles: 0,
            instances: 1,
            refine_ms: 0.0,
            refine_gpu_ms: None,
            refine_frames: 0,
        }];
        Ok(Self {
            path: path.to_owned(),
            bounds: view.bounds,
            source: Source::Plain(Box::new(Plain {
                object: Box::new(object),
                view,
                kernel,
                uploaded,
                out: None,
            })),
            objects,
            reconstruction,
            flat,
        })
    }

    /// The same file uploaded again with another reconstruction (the CPU data is kept).
    pub fn with_reconstruction(self, ctx: &GpuContext, r: Reconstruction) -> Result<Self> {
        let path = self.path.clone();
        let data = match self.source {
            Source::Baked { asset, .. } => FileData::Baked(asset),
            Source::Plain(p) => FileData::Plain(p.object),
        };
        Self::upload(ctx, &path, data, r, self.flat)
    }

    /// The camera `choice` gives on a view of aspect `aspect`, and where it came from.
    pub fn start_camera(&self, choice: CameraChoice, aspect: f32) -> Result<(Camera, String)> {
        match &self.source {
            Source::Baked { asset, .. } => {
                let (camera, source) = resolve_camera(asset, choice, aspect)?;
                let text = match source {
                    CameraSource::Scene(name) => format!("the scene's camera '{name}'"),
                    CameraSource::Auto(p) => format!("automatic ({p:?})"),
                    CameraSource::Explicit => "as given".to_owned(),
                };
                Ok((camera, text))
            }
            Source::Plain(p) => match choice {
                CameraChoice::Explicit(c) => Ok((c, "as given".to_owned())),
                CameraChoice::Scene => bail!(
                    "--camera scene: {} is previewed as a plain mesh, without its cameras",
                    self.path.display()
                ),
                CameraChoice::Auto | CameraChoice::SceneOrAuto => Ok((
                    p.view.auto_camera(&p.object, aspect),
                    "automatic".to_owned(),
                )),
            },
        }
    }

    /// Chooses every object's level for `camera` on a viewport `viewport_height` pixels high
    /// and refines the objects whose level changed (only those): objects not drawn yet whole,
    /// the others in pieces within the refine budget, all of the frame's pieces in one
    /// submission, waited for so that the frame's refinement time is its own. An object keeps
    /// drawing its old level until its refinement is complete.
    pub fn update(
        &mut self,
        ctx: &GpuContext,
        camera: Camera,
        viewport_height: u32,
        levels: &Levels,
    ) -> Result<Refined> {
        // Levels chosen from the view also stay within the adapter's largest storage binding:
        // a refined object's largest buffers hold 16 bytes per fine triangle (the flat kernel's
        // face colours; indices take 12).
        let binding = ctx.device.limits().max_storage_buffer_binding_size;
        let levels = &Levels {
            max_triangles: levels.max_triangles.min(binding / 16),
            ..*levels
        };
        let mut refined = Refined::default();
        // GPU timestamps where the adapter has them (reading them waits, as the frame does).
        let measure = ctx.description.timestamps;
        match &mut self.source {
            Source::Baked { scene, cost, .. } => {
                let choice = match levels.forced {
                    Some(l) => LevelChoice::Fixed(l),
                    None => LevelChoice::Auto {
                        camera,
                        viewport_height,
                        lod: levels.lod,
                    },
                };
                let (wanted, notes) = scene.levels_within(&choice, levels.max_triangles)?;
                refined.notes = notes;
                // A refinement under way for every object whose level changes (kept while the
                // level asked for stays the same, dropped when the object's own level is asked
                // for again).
                // Timed from here: a refinement's output buffers are made as it begins.
                let t = Instant::now();
                for (i, level) in wanted.iter().enumerate() {
                    if let Some(level) = *level {
                        scene.begin_refine(ctx, i, level)?;
                    }
                }
                // Objects not drawn yet first and whole (there is nothing else to draw), then
                // refinements already begun, then the largest level changes.
                let mut jobs: Vec<(usize, Option<u32>, u64, u64, u32)> = (0..wanted.len())
                    .filter_map(|i| {
                        let (level, left, total) = scene.refine_progress(i)?;
                        Some((i, scene.level(i), left, total, level))
                    })
                    .collect();
                jobs.sort_by_key(|&(i, now, left, total, level)| {
                    (
                        now.is_some(),
                        left == total,
                        std::cmp::Reverse(now.map(|n| n.abs_diff(level))),
                        i,
                    )
                });
                // The work this frame's budget buys at the rate measured so far.
                let budget = levels.refine_budget_ms;
                let mut allowance = if budget > 0.0 {
                    cost.work_within(budget)
                } else {
                    u64::MAX
                };
                let whole_first = jobs.first().is_some_and(|j| j.1.is_none());
                let mut plan = Vec::new();
                for (k, &(i, now, left, total, _)) in jobs.iter().enumerate() {
                    let work = if now.is_none() {
                        left
                    } else if k == 0 || allowance > 0 {
                        // At least a 1/MIN_PIECE of the first refinement, so each one ends.
                        let least = if k == 0 { total.div_ceil(MIN_PIECE) } else { 1 };
                        left.min(allowance.max(least))
                    } else {
                        break;
                    };
                    allowance = allowance.saturating_sub(work);
                    plan.push((i, if work == left { u64::MAX } else { work }));
                    // Each object's share of the frame's time is counted from its first piece.
                    if left == total {
                        let s = &mut self.objects[i];
                        s.refine_ms = 0.0;
                        s.refine_gpu_ms = None;
                        s.refine_frames = 0;
                    }
                }
                let reports = scene.refine_batch(ctx, &plan, measure)?;
                ctx.wait()?;
                refined.ms = if reports.is_empty() {
                    0.0
                } else {
                    t.elapsed().as_secs_f64() * 1e3
                };
                let work: u64 = reports.iter().map(|r| r.work).sum();
                for r in &reports {
                    let s = &mut self.objects[r.object];
                    s.refine_ms += refined.ms * r.work as f64 / work.max(1) as f64;
                    s.refine_frames += 1;
                    if let Some(g) = r.gpu_seconds {
                        *s.refine_gpu_ms.get_or_insert(0.0) += g * 1e3;
                        *refined.gpu_ms.get_or_insert(0.0) += g * 1e3;
                    }
                    if r.finished {
                        let level = scene.level(r.object).unwrap_or(0);
                        s.level = level;
                        s.triangles = scene.triangles_at(r.object, level);
                        refined.objects.push(r.object);
                    } else {
                        refined.working.push(r.object);
                    }
                }
                if !whole_first {
                    cost.measured(work, refined.ms);
                }
                refined.objects.sort_unstable();
                refined.pending = wanted
                    .iter()
                    .enumerate()
                    .filter(|&(i, l)| l.is_some() && *l != scene.level(i))
                    .count();
            }
            Source::Plain(p) => {
                let Plain {
                    object,
                    view,
                    kernel,
                    uploaded,
                    out,
                } = &mut **p;
                let coarse = object.triangles.len() as u64;
                let level = match levels.forced {
                    Some(l) => check_plain_level(l, coarse, levels.max_triangles)?,
                    None => {
                        let (level, note) = view.level(
                            &camera,
                            viewport_height,
                            &levels.lod,
                            coarse,
                            levels.max_triangles,
                        );
                        refined.notes.extend(note);
                        level
                    }
                };
                if out.as_ref().map(|o| o.level) != Some(level) {
                    let t = Instant::now();
                    let timing = kernel.refine_into(ctx, uploaded, level, out, measure)?;
                    ctx.wait()?;
                    let ms = t.elapsed().as_secs_f64() * 1e3;
                    let s = &mut self.objects[0];
                    s.level = level;
                    s.triangles = out.as_ref().map_or(0, |o| u64::from(o.triangle_count));
                    s.refine_ms = ms;
                    s.refine_gpu_ms = timing.gpu_seconds.map(|g| g * 1e3);
                    s.refine_frames = 1;
                    refined.gpu_ms = s.refine_gpu_ms;
                    refined.objects.push(0);
                    refined.ms += ms;
                }
            }
        }
        Ok(refined)
    }

    /// The draws of the current levels.
    pub fn draws(&self) -> Vec<MeshDraw<'_>> {
        match &self.source {
            Source::Baked { scene, .. } => scene.draws().iter().map(MeshDraw::from).collect(),
            Source::Plain(p) => p
                .out
                .iter()
                .map(|o| MeshDraw {
                    positions: &o.positions,
                    colours: &o.colours,
                    indices: &o.indices,
                    index_count: o.triangle_count * 3,
                    transform: glam::Mat4::IDENTITY,
                })
                .collect(),
        }
    }

    /// Fine triangles drawn per frame, instances counted.
    pub fn drawn_triangles(&self) -> u64 {
        self.draws()
            .iter()
            .map(|d| u64::from(d.index_count / 3))
            .sum()
    }
}
