//! Flat refinement on the GPU (`flat.wgsl`), one of SPEC.md F.7's two:
//!
//! * the **adaptive** refinement (F.7.1, [`FlatKernel::upload`] with [`FlatRefinement::Adaptive`]): one triangle per leaf
//!   of the object's trees plus those its finer neighbours' corners need. Its connectivity
//!   depends on the trees alone, so the CPU lists it once at upload
//!   ([`hce_geometry::adaptive_flat`]: per vertex its coarse triangle and point, per triangle
//!   its leaf, points and indices, per vertex the corners that use it), and the kernel computes
//!   the positions, areas and colours from those lists with the CPU reference's arithmetic.
//!   This is how [`ObjectKind::Flat`](hce_format::ObjectKind::Flat) objects are drawn
//!   (Concheiro et al., GRAPP 2012: "flat" objects keep their element colours, unsmoothed).
//! * the **uniform** refinement (F.7.2, [`FlatKernel::upload`]): the linear 1-to-4 split of
//!   every coarse triangle to a level, the vertices split where the surface folds (F.5), HCE
//!   colours per fine triangle, and area-weighted vertex colours shared across the coarse edges
//!   that join: what the conformance suite records, and how `hce render` previews a plain mesh.
//!
//! Use: [`FlatKernel::new`] once per device, an upload once per object, then
//! [`FlatKernel::refine_into`] whenever the level changes (an adaptive object ignores the
//! level); it reuses the output buffers when they are large enough, so a viewer can refine
//! every frame without reallocating.

use hce_format::Object;

use super::bindings::{COARSE_POSITIONS, OUT_POSITIONS, TOPO};
use super::job::{Lanes, RefineJob, Step};
use super::outputs::{OutputShape, RefinedOutput};
use super::util::{
    check_size, compute_pipeline, pack_sections, shader_module, storage_init, LightingBuffers,
};
use super::wgsl::flat_source;
use super::{GpuContext, GpuError};
use hce_geometry::adaptive_flat::refine_adaptive_flat;
use hce_geometry::decode::MAX_PATH_LEVEL;
use hce_geometry::flat::{FlatTopology, RefinedMesh};
use hce_geometry::lighting::Reconstruction;
use hce_geometry::refine::FlatRefinement;
use hce_geometry::split::SplitTables;
use hce_geometry::tables::validate_tables;

/// The kernel's uniform block (`Params` in `flat.wgsl`).
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub(super) struct Params {
    pub(super) level: u32,
    pub(super) n: u32,
    pub(super) coarse_vertices: u32,
    pub(super) edge_count: u32,
    pub(super) triangle_count: u32,
    pub(super) interior_per_triangle: u32,
    pub(super) vertex_total: u32,
    pub(super) fine_total: u32,
    pub(super) tri_off: u32,
    pub(super) edges_off: u32,
    pub(super) edge_verts_off: u32,
    pub(super) edge_side_offsets_off: u32,
    pub(super) edge_sides_off: u32,
    pub(super) vertex_corner_offsets_off: u32,
    pub(super) vertex_corners_off: u32,
    /// 0 for the nearest-normal rule, 1 for the reconstructions that read the lighting table.
    pub(super) smooth_light: u32,
    pub(super) corner_copy_off: u32,
    pub(super) edge_copy_off: u32,
    /// The first vertex the split appends (the F.5 count), and its corner copies `X`.
    pub(super) split_base: u32,
    pub(super) split_copies: u32,
    /// The items of one dispatch (`range_first .. range_end`; see [`RefineJob`]).
    pub(super) range_first: u32,
    pub(super) range_end: u32,
    /// 1 for the adaptive refinement (SPEC.md F.7.1), and its lists' sections of `topo`
    /// ([`AdaptiveFlat::kernel_lists`](hce_geometry::adaptive_flat::AdaptiveFlat::kernel_lists)).
    pub(super) adaptive: u32,
    pub(super) sources_off: u32,
    pub(super) faces_off: u32,
    pub(super) indices_off: u32,
    pub(super) use_offsets_off: u32,
    pub(super) uses_off: u32,
}

/// The sections of `topo` (the split's incidence first, then the adaptive lists).
const SECTIONS: usize = 14;

/// The compiled pipelines of the three steps.
pub struct FlatKernel {
    /// The module, whose batched entry points [`Pool`](super::batch::Pool)
    /// compiles when a scene has objects to batch.
    module: wgpu::ShaderModule,
    positions: wgpu::ComputePipeline,
    faces: wgpu::ComputePipeline,
    colours: wgpu::ComputePipeline,
}

/// An object's tables on the GPU, validated.
pub struct FlatObject {
    pub(crate) topology: FlatTopology,
    /// Where the refined vertices split (SPEC.md F.5): its slot lists are the incidence the
    /// kernel gathers over.
    split: SplitTables,
    pub(super) coarse_positions: wgpu::Buffer,
    pub(super) topo: wgpu::Buffer,
    section_offsets: [u32; SECTIONS],
    /// The adaptive refinement's vertex and triangle counts (SPEC.md F.7.1), whose lists `topo`
    /// holds; `None` for the uniform refinement.
    adaptive: Option<(u32, u32)>,
    /// The baked lighting and how vertex colours are reconstructed from it.
    pub(super) lighting: LightingBuffers,
}

impl FlatObject {
    /// The adaptive refinement's vertex and triangle counts (SPEC.md F.7.1); `None` for an
    /// object uploaded for the uniform refinement.
    pub fn adaptive_counts(&self) -> Option<(u32, u32)> {
        self.adaptive
    }
}

/// Output buffers of a flat refinement: [`RefinedOutput`] without normals.
pub type FlatOutput = RefinedOutput;

/// Timing of one refinement, when asked for.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct KernelTiming {
    /// GPU time between timestamps around the three dispatches, when the adapter supports
    /// timestamp queries.
    pub gpu_seconds: Option<f64>,
    /// GPU time of each of the three dispatches, when the kernel times them separately (the
    /// Loop kernel does: patches, faces, vertex colours).
    pub step_seconds: Option<[f64; 3]>,
}

impl FlatKernel {
    pub fn new(ctx: &GpuContext) -> Self {
        let module = shader_module(ctx, "hce flat", flat_source());
        Self {
            positions: compute_pipeline(ctx, &module, "positions_main"),
            faces: compute_pipeline(ctx, &module, "faces_main"),
            colours: compute_pipeline(ctx, &module, "colours_main"),
            module,
        }
    }

    /// The pipeline of one of the module's entry points (the batched ones included).
    pub(super) fn pipeline(&self, ctx: &GpuContext, entry: &str) -> wgpu::ComputePipeline {
        compute_pipeline(ctx, &self.module, entry)
    }

    /// Validates `object` (tables and topology) and uploads it with its colours reconstructed
    /// by `reconstruction`, for `refinement`: the adaptive one (SPEC.md F.7.1), whose lists
    /// are built here from the trees on the CPU (once: they depend on nothing else), or the
    /// uniform one (F.7.2).
    pub fn upload(
        &self,
        ctx: &GpuContext,
        object: &Object,
        reconstruction: Reconstruction,
        refinement: FlatRefinement,
    ) -> Result<FlatObject, GpuError> {
        validate_tables(object)?;
        let topology = FlatTopology::new(&object.name, &object.mesh)?;
        // The split where the surface folds (SPEC.md F.5): its slot lists replace the
        // topology's vertex and edge incidence, so each region gathers its own side only.
        let split = SplitTables::from_topology(&object.mesh, &topology, object.kind);
        let [edge_slots, edge_sides, corner_slots, corner_corners, corner_copy, edge_copy, _] =
            split.tables();
        let lists = if refinement == FlatRefinement::Adaptive {
            let mesh = refine_adaptive_flat(object).map_err(|e| GpuError::InvalidObject {
                object: object.name.clone(),
                reason: e.to_string(),
            })?;
            Some(mesh.kernel_lists())
        } else {
            None
        };
        let empty = Vec::new();
        let list = |k: usize| lists.as_ref().map_or(&empty, |l| &l.sections[k]);
        let (packed, section_offsets) = pack_sections(
            ctx,
            [
                &object.mesh.triangles,
                &object.mesh.edges,
                &topology.edge_verts,
                edge_slots,
                edge_sides,
                corner_slots,
                corner_corners,
                corner_copy,
                edge_copy,
                list(0),
                list(1),
                list(2),
                list(3),
                list(4),
            ],
        )?;
        check_size(
            ctx,
            "coarse positions",
            object.mesh.positions.len() as u64 * 4,
        )?;
        Ok(FlatObject {
            lighting: LightingBuffers::upload(ctx, object, reconstruction)?,
            coarse_positions: storage_init(ctx, "coarse positions", &object.mesh.positions),
            topo: storage_init(ctx, "topology", &packed),
            section_offsets,
            adaptive: lists.map(|l| (l.vertices, l.triangles)),
            topology,
            split,
        })
    }

    /// Refines `object` to `level` into `out`, reallocating only when `out` is too small (or
    /// absent), in one submission. With `measure`, returns the GPU time of the three
    /// dispatches when the adapter has timestamp queries (this waits for the GPU).
    pub fn refine_into(
        &self,
        ctx: &GpuContext,
        object: &FlatObject,
        level: u32,
        out: &mut Option<FlatOutput>,
        measure: bool,
    ) -> Result<KernelTiming, GpuError> {
        let job = self.begin(ctx, object, level, out)?;
        let times = job.submit_whole(ctx, "hce flat timing", measure)?;
        Ok(KernelTiming {
            gpu_seconds: times.map(|(total, _)| total),
            step_seconds: None,
        })
    }

    /// Prepares the refinement of `object` to `level` into `out` (reallocated only when too
    /// small or absent) without recording anything: the returned job records the three steps
    /// in pieces ([`RefineJob::encode`]), over one submission or many. `out` holds the refined
    /// mesh once every piece has been submitted; until then it must not be drawn.
    pub fn begin(
        &self,
        ctx: &GpuContext,
        object: &FlatObject,
        level: u32,
        out: &mut Option<FlatOutput>,
    ) -> Result<RefineJob, GpuError> {
        let shape = shape(object, level)?;
        let o = RefinedOutput::prepare(ctx, out, level, shape)?;
        let (v, f) = (shape.vertices, shape.triangles);

        let t = &object.topology;
        let s = object.section_offsets;
        let adaptive = object.adaptive.is_some();
        // The uniform lattice's level; the adaptive lists have none.
        let level = if adaptive { 0 } else { level };
        let n = 1u32 << level;
        let params = Params {
            level,
            n,
            coarse_vertices: t.vertex_count,
            edge_count: t.edge_count,
            triangle_count: t.triangle_count,
            interior_per_triangle: if n < 2 { 0 } else { (n - 1) * (n - 2) / 2 },
            vertex_total: v,
            fine_total: f,
            tri_off: s[0],
            edges_off: s[1],
            edge_verts_off: s[2],
            edge_side_offsets_off: s[3],
            edge_sides_off: s[4],
            vertex_corner_offsets_off: s[5],
            vertex_corners_off: s[6],
            smooth_light: object.lighting.smooth_flag(),
            corner_copy_off: s[7],
            edge_copy_off: s[8],
            split_base: if adaptive {
                v
            } else {
                v - object.split.appended(level) as u32
            },
            split_copies: if adaptive { 0 } else { object.split.copies },
            range_first: 0,
            range_end: u32::MAX,
            adaptive: u32::from(adaptive),
            sources_off: s[9],
            faces_off: s[10],
            indices_off: s[11],
            use_offsets_off: s[12],
            uses_off: s[13],
        };
        // The bindings (hce_bindings.wgsl) each step reads or writes.
        let steps = vec![
            Step {
                pipeline: self.positions.clone(),
                bindings: vec![
                    (COARSE_POSITIONS, object.coarse_positions.clone()),
                    (TOPO, object.topo.clone()),
                    (OUT_POSITIONS, o.positions.clone()),
                ],
                items: u64::from(v),
                lanes: Lanes::PerItem,
            },
            Step::faces(&self.faces, &object.topo, o, &object.lighting),
            Step::colours(&self.colours, &object.topo, o, &object.lighting),
        ];
        RefineJob::new(
            ctx,
            "hce flat",
            &params,
            std::mem::offset_of!(Params, range_first) / 4,
            u64::from(f),
            steps,
        )
    }
}

/// What a refinement of `object` to `level` writes, checked to fit 32-bit indices (an
/// adaptive object: its lists' counts, whatever the level).
fn shape(object: &FlatObject, level: u32) -> Result<OutputShape, GpuError> {
    if let Some((v, f)) = object.adaptive {
        return OutputShape::new(v.into(), f.into(), false);
    }
    if level > MAX_PATH_LEVEL {
        return Err(GpuError::LevelTooHigh {
            level,
            max: MAX_PATH_LEVEL,
        });
    }
    OutputShape::new(
        object.topology.refined_vertex_count(level) + object.split.appended(level),
        object.topology.refined_triangle_count(level),
        false,
    )
}

/// One-shot convenience: upload `object`, refine it to `level` and read the mesh back.
pub fn refine_flat(ctx: &GpuContext, object: &Object, level: u32) -> Result<RefinedMesh, GpuError> {
    refine_flat_with(ctx, object, level, Reconstruction::default())
}

/// [`refine_flat`] with the colour reconstruction chosen.
pub fn refine_flat_with(
    ctx: &GpuContext,
    object: &Object,
    level: u32,
    reconstruction: Reconstruction,
) -> Result<RefinedMesh, GpuError> {
    let kernel = FlatKernel::new(ctx);
    let uploaded = kernel.upload(ctx, object, reconstruction, FlatRefinement::Uniform)?;
    let mut out = None;
    kernel.refine_into(ctx, &uploaded, level, &mut out, false)?;
    out.expect("refine_into allocates").read_back(ctx)
}

/// One-shot convenience: upload `object`, refine it adaptively (SPEC.md F.7.1) and read the
/// mesh back (its level 0).
pub fn refine_flat_adaptive(
    ctx: &GpuContext,
    object: &Object,
    reconstruction: Reconstruction,
) -> Result<RefinedMesh, GpuError> {
    let kernel = FlatKernel::new(ctx);
    let uploaded = kernel.upload(ctx, object, reconstruction, FlatRefinement::Adaptive)?;
    let mut out = None;
    kernel.refine_into(ctx, &uploaded, 0, &mut out, false)?;
    out.expect("refine_into allocates").read_back(ctx)
}
