//! Loop subdivision with HCE colours on the GPU (`loop.wgsl`): how
//! [`ObjectKind::Multiresolution`](hce_format::ObjectKind::Multiresolution) objects are drawn
//! (Concheiro et al., "Synthesis of multiresolution scenes with global illumination on a GPU",
//! GRAPP 2012). The kernel is a port of the CPU reference, [`hce_geometry::subdivide`] followed by
//! [`hce_geometry::colour::apply_baked_colours`], reading the same adjacency tables:
//!
//! 1. The patches: each coarse triangle's local patch (grid, bands, corner rings) refined level
//!    by level in the CPU's order of arithmetic, then the positions and normals of the output
//!    vertices the triangle owns (each vertex has exactly one owner, so vertices shared across
//!    coarse edges are bitwise equal). Two kernels do this, chosen by [`PatchScheme`]:
//!    * `patch_wg_main` (`loop_workgroup.wgsl`): a workgroup of 64 invocations per 1 to 16
//!      triangles, the patches in workgroup memory, each level's lattice points, band points and
//!      ring points spread over the invocations with a barrier between levels. A square keeps
//!      only the lattice points i, j >= -1, i + j <= n + 1, so at level 5 a patch takes
//!      10.3 KiB plus its rings and fits the 16 KiB WebGPU guarantees; at lower levels several
//!      triangles share a workgroup so its invocations have work (`WG_TRIANGLES`). Each
//!      variant (level, triangles per workgroup, ring capacity) is compiled on first use.
//!    * `patch_main` (`loop.wgsl`): one invocation per triangle, the patch in a per-slot region
//!      of a storage buffer ("scratch"), striding over the triangles so the buffer holds at most
//!      [`SCRATCH_BUDGET`] bytes whatever the mesh. It serves level 6 (105 KiB per patch),
//!      valences whose rings do not fit, and software adapters: on lavapipe it is the faster
//!      of the two, because llvmpipe runs a shader with barriers as coroutines.
//! 2. `faces_main`, one invocation per fine triangle: indices in the CPU's numbering, area, and
//!    the HCE colour (tree node along the path, representative normal with the largest dot
//!    product with the face normal).
//! 3. `colours_main`, one invocation per output vertex: area-weighted mean colour of the incident
//!    fine triangles, across coarse edges and vertices.
//!
//! Each step is a pure gather or an owned write (no atomics), so the output does not depend on
//! scheduling, and both patch kernels compute every point with the same function of the
//! previous level, so they agree bit for bit with each other and with the CPU.
//!
//! Output numbering is exactly that of [`hce_geometry::subdivide`]:
//! `[V coarse][E edges × (M − 1)][F × interior]`, fine triangle `t · 4^L + path`.
//!
//! Use: [`LoopKernel::new`] once per device, [`LoopKernel::upload`] once per object, then
//! [`LoopKernel::refine_into`] whenever the level changes; it reuses the output buffers when they
//! are large enough, so a viewer can refine every frame without reallocating. The shape of the
//! API is that of [`FlatKernel`](super::FlatKernel).

use hce_format::{Object, ObjectKind};

use super::bindings::{COARSE_POSITIONS, OUT_NORMALS, OUT_POSITIONS, SCRATCH, TOPO};
use super::flat::KernelTiming;
use super::job::{Lanes, RefineJob, Step};
use super::outputs::{OutputShape, RefinedOutput};
use super::util::{
    check_size, compute_pipeline, compute_pipeline_with, pack_sections, shader_module,
    storage_init, storage_output, LightingBuffers, WORKGROUP,
};
use super::wgsl::{loop_batch_source, loop_source, loop_workgroup_source};
use super::{AdapterKind, GpuContext, GpuError};
use hce_geometry::flat::FlatTopology;
use hce_geometry::lighting::Reconstruction;
use hce_geometry::loop_tables::LoopKernelTables;
use hce_geometry::split::SplitTables;
use hce_geometry::subdivide::MAX_LOOP_LEVEL;
use hce_geometry::tables::validate_tables;

/// Upper bound of the scratch buffer (bytes): the number of coarse triangles refined at once is
/// this divided by one triangle's patch size (or the device's storage-binding limit, if lower).
pub(super) const SCRATCH_BUDGET: u64 = 256 << 20;

/// The kernel's uniform block (`Params` in `loop.wgsl`).
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub(super) struct Params {
    pub(super) level: u32,
    pub(super) m: u32,
    pub(super) coarse_vertices: u32,
    pub(super) edge_count: u32,
    pub(super) triangle_count: u32,
    pub(super) per_edge: u32,
    pub(super) per_tri: u32,
    pub(super) vertex_total: u32,
    pub(super) fine_total: u32,
    pub(super) slots: u32,
    pub(super) square_floats: u32,
    pub(super) ring_cap: u32,
    pub(super) offsets: [u32; SECTIONS],
    /// Always 1 (see `keep` in `loop.wgsl`).
    pub(super) exact: u32,
    /// 0 for the nearest-normal rule, 1 for the reconstructions that read the lighting table.
    pub(super) smooth_light: u32,
    /// The first vertex appended by the split at sharp edges (SPEC.md F.5): the F.5 count.
    pub(super) split_base: u32,
    /// Corner copies `X` of the split.
    pub(super) split_copies: u32,
    /// The items of one dispatch (`range_first .. range_end`; see [`RefineJob`]).
    pub(super) range_first: u32,
    pub(super) range_end: u32,
}

/// Sections packed into the `topo` buffer, in this order (see [`LoopKernel::upload`]).
pub(super) const SECTIONS: usize = 17;

/// Bits of the per-triangle flags word (`OWNS_EDGE` … in `loop.wgsl`), for the constants that
/// `hce_constants.wgsl` is checked against.
#[cfg(test)]
pub(super) use hce_geometry::loop_tables::{INTERIOR, OWNS_EDGE, OWNS_VERTEX, SHARP};

/// Triangles per workgroup the cooperative kernel aims for at levels 0 to 5 (halved while their
/// patches do not fit the workgroup memory): enough triangles that the 64 lanes have work at the
/// low levels, where one triangle has only a handful of points per step.
const WG_TRIANGLES: [u32; 6] = [16, 8, 4, 2, 1, 1];

/// Where step 1 keeps the patches. [`PatchScheme::Auto`] is what [`LoopKernel::new`] uses; the
/// others exist so that tests and benchmarks can exercise and compare both paths.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PatchScheme {
    /// On a hardware adapter, the workgroup kernel wherever the patches fit the device's
    /// workgroup memory (levels 0 to 5 unless the valences are extreme), the scratch kernel
    /// otherwise. On a software adapter (lavapipe), the scratch kernel, which is faster there.
    #[default]
    Auto,
    /// A workgroup refines one to 16 triangles at once, the patches in workgroup memory and
    /// each level's lattice points spread over its invocations (`loop_workgroup.wgsl`). Refining
    /// with this scheme where the patches do not fit is an error.
    Workgroup,
    /// One invocation per triangle, the patch in a storage-buffer scratch slot (`patch_main`):
    /// every level, any valence.
    Scratch,
}

/// The shape of one compiled variant of the workgroup kernel: its level, the triangles per
/// workgroup and the floats of one triangle's regions (the constants of `loop_workgroup.wgsl`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
struct WgShape {
    level: u32,
    tris: u32,
    square_a: u32,
    square_b: u32,
    ring: u32,
}

impl WgShape {
    /// The variant for `level` when a triangle's three rings hold at most `ring_points` points,
    /// or the bytes one triangle's patch needs when it does not fit `limit` (levels past 5 are
    /// never tried: their patches are over 27 KiB).
    fn new(level: u32, ring_points: u32, limit: u32) -> Result<Self, u64> {
        // A square of n segments holds rows of n + 4, n + 3, ... points (`wg_index`).
        let square = |n: u64| 3 * (n + 4) * (n + 5) / 2;
        let m = 1u64 << level.min(31);
        let one = 4 * (square(m) + square(m / 2) + 6 * u64::from(ring_points)) + 96;
        let Some(&wanted) = WG_TRIANGLES.get(level as usize) else {
            return Err(one);
        };
        let mut shape = Self {
            level,
            tris: wanted,
            square_a: square(m) as u32,
            square_b: if level == 0 { 0 } else { square(m / 2) as u32 },
            ring: 3 * ring_points,
        };
        while shape.tris > 1 && shape.bytes() > u64::from(limit) {
            shape.tris /= 2;
        }
        if shape.bytes() > u64::from(limit) {
            return Err(shape.bytes());
        }
        Ok(shape)
    }

    /// Workgroup memory of the variant: the patches and, per triangle, its corner table
    /// (`wg_corners` and `wg_ro`: three 7-word `Corner`s and three ring offsets).
    fn bytes(&self) -> u64 {
        u64::from(self.tris) * (4 * u64::from(self.square_a + self.square_b + 2 * self.ring) + 96)
    }

    /// The constants `loop_workgroup.wgsl` expects ahead of it.
    fn header(&self) -> String {
        format!(
            "const WG_LEVEL: u32 = {}u;\nconst WG_TRIS: u32 = {}u;\nconst WG_SQ_A: u32 = {}u;\n\
             const WG_SQ_B: u32 = {}u;\nconst WG_RING: u32 = {}u;\n",
            self.level, self.tris, self.square_a, self.square_b, self.ring
        )
    }
}

/// The header of every workgroup variant a device with 32 KiB of workgroup memory compiles
/// for triangles whose three rings hold 12 points (a regular mesh), by level, for the WGSL
/// tests.
#[cfg(test)]
pub(super) fn workgroup_headers() -> Vec<(String, String)> {
    (0..=hce_geometry::subdivide::MAX_LOOP_LEVEL)
        .filter_map(|level| WgShape::new(level, 12, 32 * 1024).ok())
        .map(|shape| {
            (
                format!("loop workgroup level {}", shape.level),
                shape.header(),
            )
        })
        .collect()
}

/// How one refinement runs step 1.
enum PatchPlan {
    Workgroup(WgShape),
    /// Floats per square, bytes per slot and slots in flight.
    Scratch {
        square_floats: u64,
        slot_bytes: u64,
        slots: u32,
    },
}

/// The compiled pipelines of the three steps. The workgroup variants of step 1 are compiled on
/// first use, one per level and triangle shape.
pub struct LoopKernel {
    scheme: PatchScheme,
    patch: wgpu::ComputePipeline,
    faces: wgpu::ComputePipeline,
    colours: wgpu::ComputePipeline,
    workgroup: std::sync::Mutex<std::collections::HashMap<WgShape, wgpu::ComputePipeline>>,
}

/// An object's tables on the GPU, validated: every index the kernel reads was checked by
/// [`LoopKernel::upload`].
pub struct LoopObject {
    vertex_count: u32,
    edge_count: u32,
    pub(crate) triangle_count: u32,
    /// Corner copies and split edges of the split at sharp edges (SPEC.md F.5).
    split_copies: u32,
    split_edges: u32,
    /// Largest valence (ring length) of the control mesh: the ring capacity of a scratch slot.
    pub(super) max_valence: u32,
    /// Largest sum of the valences of a triangle's three corners, rounded up to a multiple of 8
    /// (fewer kernel variants): the ring capacity of a workgroup patch.
    ring_points: u32,
    pub(super) coarse_positions: wgpu::Buffer,
    pub(super) topo: wgpu::Buffer,
    offsets: [u32; SECTIONS],
    /// The baked lighting and how vertex colours are reconstructed from it.
    pub(super) lighting: LightingBuffers,
}

/// Output buffers of a Loop refinement: [`RefinedOutput`] with normals, in the numbering of
/// [`hce_geometry::subdivide`].
///
/// [`hce_geometry::subdivide`]: mod@hce_geometry::subdivide
pub type LoopOutput = RefinedOutput;

/// Floats of one scratch square at `level` and of one slot (two squares, two ring sets).
pub(super) fn slot_floats(level: u32, max_valence: u32) -> (u64, u64) {
    let w = (1u64 << level) + 3;
    let square = 3 * w * w;
    (square, 2 * square + 2 * 9 * u64::from(max_valence))
}

impl LoopKernel {
    /// The kernel with [`PatchScheme::Auto`].
    pub fn new(ctx: &GpuContext) -> Self {
        Self::with_scheme(ctx, PatchScheme::Auto)
    }

    pub fn with_scheme(ctx: &GpuContext, scheme: PatchScheme) -> Self {
        let module = shader_module(ctx, "hce loop", loop_source());
        Self {
            scheme,
            patch: compute_pipeline(ctx, &module, "patch_main"),
            faces: compute_pipeline(ctx, &module, "faces_main"),
            colours: compute_pipeline(ctx, &module, "colours_main"),
            workgroup: Default::default(),
        }
    }

    /// The pipelines of the batched kernel's three steps (`loop_batch.wgsl`), compiled when a
    /// scene has objects to batch ([`Pool`](super::batch::Pool)).
    pub(super) fn batch_pipelines(&self, ctx: &GpuContext) -> [wgpu::ComputePipeline; 3] {
        let module = shader_module(ctx, "hce loop batch", loop_batch_source());
        ["patch_batch_main", "faces_batch_main", "colours_batch_main"]
            .map(|entry| compute_pipeline(ctx, &module, entry))
    }

    /// The scheme step 1 uses for `object` at `level` on this device ([`PatchScheme::Workgroup`]
    /// or [`PatchScheme::Scratch`]); an error where a forced scheme cannot run.
    pub fn scheme_for(
        &self,
        ctx: &GpuContext,
        object: &LoopObject,
        level: u32,
    ) -> Result<PatchScheme, GpuError> {
        Ok(match self.plan(ctx, object, level)? {
            PatchPlan::Workgroup(_) => PatchScheme::Workgroup,
            PatchPlan::Scratch { .. } => PatchScheme::Scratch,
        })
    }

    fn plan(
        &self,
        ctx: &GpuContext,
        object: &LoopObject,
        level: u32,
    ) -> Result<PatchPlan, GpuError> {
        let limit = ctx.device.limits().max_compute_workgroup_storage_size;
        // Software adapters run the scratch kernel by default: llvmpipe (lavapipe) executes a
        // shader with barriers as coroutines, and the workgroup kernel runs 2 to 5 times slower
        // there than the scratch kernel (BENCHMARKS.md, "GPU kernels on lavapipe").
        let software = ctx.description.kind == AdapterKind::Software;
        let try_workgroup = match self.scheme {
            PatchScheme::Auto => !software,
            PatchScheme::Workgroup => true,
            PatchScheme::Scratch => false,
        };
        if try_workgroup {
            match WgShape::new(level, object.ring_points, limit) {
                Ok(shape) => return Ok(PatchPlan::Workgroup(shape)),
                Err(needed) if self.scheme == PatchScheme::Workgroup => {
                    return Err(GpuError::TooLarge {
                        what: "one triangle's workgroup patch (PatchScheme::Auto falls back to scratch)",
                        needed,
                        limit: u64::from(limit),
                    })
                }
                Err(_) => {}
            }
        }
        let (square_floats, slot_bytes, slots) = scratch_shape(ctx, object, level)?;
        Ok(PatchPlan::Scratch {
            square_floats,
            slot_bytes,
            slots,
        })
    }

    /// The workgroup variant of `shape`, compiled on first use.
    fn workgroup_pipeline(&self, ctx: &GpuContext, shape: WgShape) -> wgpu::ComputePipeline {
        // A poisoned lock only means another thread panicked while compiling; the map itself
        // is still consistent (insertions are whole).
        let mut cache = self
            .workgroup
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        cache
            .entry(shape)
            .or_insert_with(|| {
                let module = shader_module(
                    ctx,
                    "hce loop workgroup",
                    loop_workgroup_source(&shape.header()),
                );
                compute_pipeline_with(
                    ctx,
                    &module,
                    "patch_wg_main",
                    wgpu::PipelineCompilationOptions {
                        // Every point the kernel reads was written before a barrier in the same
                        // workgroup (band points only on edges with a neighbour, which are the
                        // only ones read), so zeroing 10 KiB per workgroup first would be pure
                        // cost.
                        zero_initialize_workgroup_memory: false,
                        ..Default::default()
                    },
                )
            })
            .clone()
    }

    /// Validates `object` (adjacency tables as [`hce_geometry::subdivide`] reads them, edge and
    /// vertex incidence, HCE records, trees, normals and colours) and uploads it. A malformed
    /// table is an error here, never an out-of-bounds read on the GPU.
    ///
    /// [`hce_geometry::subdivide`]: mod@hce_geometry::subdivide
    ///
    /// Its colours are reconstructed by `reconstruction`.
    pub fn upload(
        &self,
        ctx: &GpuContext,
        object: &Object,
        reconstruction: Reconstruction,
    ) -> Result<LoopObject, GpuError> {
        let invalid = |reason: String| GpuError::InvalidObject {
            object: object.name.clone(),
            reason,
        };
        validate_tables(object)?;
        let mesh = &object.mesh;
        let LoopKernelTables {
            tri_flags,
            crease,
            weights,
            max_valence,
            ring_points,
        } = LoopKernelTables::new(mesh).map_err(|e| invalid(e.to_string()))?;
        let topology = FlatTopology::new(&object.name, mesh)?;
        // The split at sharp edges (SPEC.md F.5): its slot lists replace the topology's vertex
        // and edge incidence, so that each region of a split vertex gathers its own side only.
        let split = SplitTables::from_topology(mesh, &topology, ObjectKind::Multiresolution);
        // Edge slots, corner slots, the copies and slot_split, in SplitTables::tables' order.
        let s = split.tables();
        let (packed, offsets) = pack_sections(
            ctx,
            [
                &mesh.triangles,
                &mesh.ring_offsets,
                &mesh.ring,
                &mesh.spoke_flags,
                &mesh.vertex_flags,
                &mesh.corner_spokes,
                &mesh.edges,
                &tri_flags,
                &crease,
                &weights,
                s[0],
                s[1],
                s[2],
                s[3],
                s[4],
                s[5],
                s[6],
            ],
        )?;
        check_size(ctx, "coarse positions", mesh.positions.len() as u64 * 4)?;
        let lighting = LightingBuffers::upload(ctx, object, reconstruction)?;
        Ok(LoopObject {
            vertex_count: topology.vertex_count,
            edge_count: topology.edge_count,
            triangle_count: topology.triangle_count,
            split_copies: split.copies,
            split_edges: split.split_edges,
            max_valence,
            ring_points,
            coarse_positions: storage_init(ctx, "coarse positions", &mesh.positions),
            topo: storage_init(ctx, "loop topology", &packed),
            offsets,
            lighting,
        })
    }

    /// The scratch buffer of `slots` slots of `slot_bytes`.
    fn scratch_buffer(
        &self,
        ctx: &GpuContext,
        slot_bytes: u64,
        slots: u32,
    ) -> Result<wgpu::Buffer, GpuError> {
        let bytes = check_size(ctx, "subdivision scratch", slot_bytes * u64::from(slots))?;
        Ok(storage_output(
            ctx,
            "loop scratch",
            bytes,
            wgpu::BufferUsages::empty(),
        ))
    }

    /// Refines `object` to `level` (0..=6) into `out`, reallocating only when `out` is too
    /// small (or absent), in one submission. With `measure`, returns the GPU time of the three
    /// dispatches when the adapter has timestamp queries (this waits for the GPU).
    pub fn refine_into(
        &self,
        ctx: &GpuContext,
        object: &LoopObject,
        level: u32,
        out: &mut Option<LoopOutput>,
        measure: bool,
    ) -> Result<KernelTiming, GpuError> {
        let job = self.begin(ctx, object, level, out)?;
        // Two timestamps per step (one compute pass each), so the time of each step is known.
        let mut timing = KernelTiming::default();
        if let Some((total, steps)) = job.submit_whole(ctx, "hce loop timing", measure)? {
            timing.gpu_seconds = Some(total);
            if let [a, b, c] = steps[..] {
                timing.step_seconds = Some([a, b, c]);
            }
        }
        Ok(timing)
    }

    /// Prepares the refinement of `object` to `level` into `out` (reallocated only when too
    /// small or absent) without recording anything: the returned job records its three steps
    /// in pieces ([`RefineJob::encode`]), over one submission or many. `out` holds the refined
    /// mesh once every piece has been submitted; until then it must not be drawn.
    pub fn begin(
        &self,
        ctx: &GpuContext,
        object: &LoopObject,
        level: u32,
        out: &mut Option<LoopOutput>,
    ) -> Result<RefineJob, GpuError> {
        let shape = shape(object, level)?;
        let plan = self.plan(ctx, object, level)?;
        let o = RefinedOutput::prepare(ctx, out, level, shape)?;
        let (v, f) = (shape.vertices, shape.triangles);
        let normals = o.normals.clone().expect("a Loop output has normals");
        // The scratch kernel needs room for at least one slot; the workgroup kernel keeps its
        // patches in workgroup memory. A reused buffer may hold fewer slots than a fresh one
        // would.
        let (square_floats, slots) = match plan {
            PatchPlan::Workgroup(_) => (0, 0),
            PatchPlan::Scratch {
                square_floats,
                slot_bytes,
                slots,
            } => {
                let scratch = match o.scratch.take() {
                    Some(s) if s.size() >= slot_bytes => s,
                    _ => self.scratch_buffer(ctx, slot_bytes, slots)?,
                };
                let slots = slots.min((scratch.size() / slot_bytes) as u32).max(1);
                o.scratch = Some(scratch);
                (square_floats, slots)
            }
        };

        let m = 1u32 << level;
        let params = Params {
            level,
            m,
            coarse_vertices: object.vertex_count,
            edge_count: object.edge_count,
            triangle_count: object.triangle_count,
            per_edge: m - 1,
            per_tri: (m - 1) * m.saturating_sub(2) / 2,
            vertex_total: v,
            fine_total: f,
            slots,
            square_floats: square_floats as u32,
            ring_cap: object.max_valence,
            offsets: object.offsets,
            exact: 1,
            smooth_light: object.lighting.smooth_flag(),
            split_base: v - split_appended(object, level) as u32,
            split_copies: object.split_copies,
            range_first: 0,
            range_end: u32::MAX,
        };
        let triangles = u64::from(object.triangle_count);
        // Step 1: the workgroup kernel (no scratch binding), a workgroup per `tris` triangles,
        // or the scratch kernel, an invocation per slot.
        // The bindings (hce_bindings.wgsl) each step reads or writes.
        let mut patch_bindings = vec![
            (COARSE_POSITIONS, object.coarse_positions.clone()),
            (TOPO, object.topo.clone()),
            (OUT_POSITIONS, o.positions.clone()),
            (OUT_NORMALS, normals),
        ];
        let patch = match plan {
            PatchPlan::Workgroup(shape) => Step {
                pipeline: self.workgroup_pipeline(ctx, shape),
                bindings: patch_bindings,
                items: triangles,
                lanes: Lanes::Groups(shape.tris),
            },
            PatchPlan::Scratch { .. } => Step {
                pipeline: self.patch.clone(),
                bindings: {
                    let scratch = o.scratch.clone().expect("placed above");
                    patch_bindings.push((SCRATCH, scratch));
                    patch_bindings
                },
                items: triangles,
                lanes: Lanes::Slots(slots),
            },
        };
        let faces = Step::faces(&self.faces, &object.topo, o, &object.lighting);
        let colours = Step::colours(&self.colours, &object.topo, o, &object.lighting);
        RefineJob::new(
            ctx,
            "hce loop",
            &params,
            std::mem::offset_of!(Params, range_first) / 4,
            u64::from(f),
            vec![patch, faces, colours],
        )
    }
}

/// Floats per square, bytes per slot and the number of slots (coarse triangles refined at once)
/// at `level`, within [`SCRATCH_BUDGET`] and the device's storage-binding limit.
fn scratch_shape(
    ctx: &GpuContext,
    object: &LoopObject,
    level: u32,
) -> Result<(u64, u64, u32), GpuError> {
    let (square, slot) = slot_floats(level, object.max_valence);
    let slot_bytes = slot * 4;
    let limits = ctx.device.limits();
    let budget = SCRATCH_BUDGET
        .min(limits.max_storage_buffer_binding_size)
        .min(limits.max_buffer_size);
    if slot_bytes > budget {
        return Err(GpuError::TooLarge {
            what: "one triangle's subdivision scratch",
            needed: slot_bytes,
            limit: budget,
        });
    }
    let slots = (budget / slot_bytes)
        .min(u64::from(object.triangle_count))
        .max(1);
    // Whole workgroups where the budget allows, so no lane of the last group idles needlessly.
    let slots = if slots > u64::from(WORKGROUP) {
        slots / u64::from(WORKGROUP) * u64::from(WORKGROUP)
    } else {
        slots
    };
    Ok((square, slot_bytes, slots as u32))
}

/// Vertices the split at sharp edges appends at `level` (SPEC.md F.5): `X + S (2^level − 1)`.
fn split_appended(object: &LoopObject, level: u32) -> u64 {
    u64::from(object.split_copies) + u64::from(object.split_edges) * ((1u64 << level) - 1)
}

/// What a refinement of `object` to `level` writes, checked to fit 32-bit indices as
/// [`hce_geometry::subdivide`] checks them.
///
/// [`hce_geometry::subdivide`]: mod@hce_geometry::subdivide
fn shape(object: &LoopObject, level: u32) -> Result<OutputShape, GpuError> {
    if level > MAX_LOOP_LEVEL {
        return Err(GpuError::LevelTooHigh {
            level,
            max: MAX_LOOP_LEVEL,
        });
    }
    let m = 1u64 << level;
    let per_tri = (m - 1) * m.saturating_sub(2) / 2;
    let v = u64::from(object.vertex_count)
        + u64::from(object.edge_count) * (m - 1)
        + u64::from(object.triangle_count) * per_tri
        + split_appended(object, level);
    OutputShape::new(v, u64::from(object.triangle_count) << (2 * level), true)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn workgroup_shapes_fit_the_webgpu_limit() {
        let limit = 16384;
        // Level 5: one triangle, squares of 36 · 37 / 2 and 20 · 21 / 2 points, two ring sets.
        let s = WgShape::new(5, 24, limit).unwrap();
        assert_eq!((s.tris, s.square_a, s.square_b, s.ring), (1, 1998, 630, 72));
        assert_eq!(s.bytes(), 4 * (1998 + 630 + 2 * 72) + 96);
        // The largest rings that still fit at level 5, and the first that do not.
        assert_eq!(WgShape::new(5, 240, limit).unwrap().bytes(), 16368);
        assert_eq!(WgShape::new(5, 248, limit), Err(16560));
        // Low levels share a workgroup between triangles, fewer when the rings are large.
        assert_eq!(WgShape::new(1, 24, limit).unwrap().tris, 8);
        assert_eq!(WgShape::new(1, 200, limit).unwrap().tris, 2);
        assert_eq!(WgShape::new(0, 24, limit).unwrap().square_b, 0);
        // Level 6 never runs in workgroup memory.
        assert!(WgShape::new(6, 24, limit).is_err());
    }
}
