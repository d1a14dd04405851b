//! Batched refinement: the small objects of a scene that change level in a frame refined
//! together, one dispatch per step of their kernel for all of them (the batched entry points of
//! `flat.wgsl` and `loop_batch.wgsl`, `hce_batch.wgsl`), instead of three dispatches per object. A
//! scene has a [`Pool`] per kernel: one for its flat objects, one for its multiresolution ones.
//!
//! A scene of many small objects (architecture, props) spends a frame's refinement on the fixed
//! cost of its dispatches, not on their work: on lavapipe, 1.3-1.5 ms an object of a few
//! hundred fine triangles (BENCHMARKS.md). So a [`Pool`] copies the tables of every small
//! object of its kind, once, into pooled buffers (each object's tables whole, one after
//! another), and a batch writes its objects' outputs into pooled outputs (each object's range,
//! one after another), copied out to each object's own buffers in the same submission: the
//! objects keep their buffers, drawn and read back as before. Per batch, a table in the pooled
//! `topo` gives each object's first output vertex, fine triangle and coarse triangle (the search
//! keys of the invocations), where its tables start in the pools and its kernel parameters.
//!
//! The outputs are the bytes the object's own dispatches write (the same functions on the same
//! values, `tests/gpu_scene_batch.rs` checks it), so whether an object was refined in a batch
//! or alone is invisible to the caller. A batched Loop refinement builds its patches with the
//! scratch kernel (`patch_main`'s function, one slot per invocation striding over the batch's
//! coarse triangles), which the workgroup kernel matches bit for bit. The pooled inputs
//! duplicate the small objects' tables on the GPU, and the pooled outputs stay allocated at the
//! size of the largest batch ([`BATCH_MAX_FINE`] fine triangles at most, and for Loop objects
//! a scratch of at most the Loop kernel's budget).

use super::flat::{self, FlatKernel, FlatObject};
use super::loop_kernel::{self, slot_floats, LoopKernel, LoopObject, SCRATCH_BUDGET};
use super::outputs::RefinedOutput;
use super::util::{check_size, dispatch_size, LightingBuffers, PassTimer};
use super::{GpuContext, GpuError};

/// Objects refined to at most this many fine triangles are batched; larger ones keep their own
/// dispatches, whose fixed cost is small beside their work. Objects of more coarse triangles
/// than this are not pooled at all.
pub(super) const OBJECT_MAX_FINE: u64 = 1 << 14;
/// The most fine triangles of one batch by default ([`SceneOptions::batch_fine`]): the pooled
/// outputs never grow past it, and a frame that refines more refines them in several batches.
///
/// [`SceneOptions::batch_fine`]: super::SceneOptions::batch_fine
pub const BATCH_MAX_FINE: u64 = 1 << 20;

/// Words of a table entry before the object's `Params` (`BATCH_ENTRY_BASES` of
/// `hce_constants.wgsl`, generated from it), and in all for each kernel (`FLAT_ENTRY_WORDS`,
/// `LOOP_ENTRY_WORDS`).
pub(super) const ENTRY_BASES: usize = 6;
pub(super) const FLAT_ENTRY_WORDS: usize = ENTRY_BASES + std::mem::size_of::<flat::Params>() / 4;
pub(super) const LOOP_ENTRY_WORDS: usize =
    ENTRY_BASES + std::mem::size_of::<loop_kernel::Params>() / 4;

/// Bytes of the batched entry points' `Batch` uniform (`hce_batch.wgsl`): nine words, in a
/// buffer of whole 16-byte rows.
const BATCH_UNIFORM_BYTES: u64 = 48;

/// The kernel whose objects a pool holds.
pub(super) enum PoolKernel<'a> {
    Flat(&'a FlatKernel),
    Loop(&'a LoopKernel),
}

/// One scene object as a pool sees it: its tables on the GPU, `None` for objects of the other
/// kernel.
#[derive(Clone, Copy)]
pub(super) struct PoolInput<'a> {
    coarse_positions: &'a wgpu::Buffer,
    topo: &'a wgpu::Buffer,
    lighting: &'a LightingBuffers,
    triangles: u32,
}

impl<'a> From<&'a FlatObject> for PoolInput<'a> {
    fn from(o: &'a FlatObject) -> Self {
        Self {
            coarse_positions: &o.coarse_positions,
            topo: &o.topo,
            lighting: &o.lighting,
            triangles: o.topology.triangle_count,
        }
    }
}

impl<'a> From<&'a LoopObject> for PoolInput<'a> {
    fn from(o: &'a LoopObject) -> Self {
        Self {
            coarse_positions: &o.coarse_positions,
            topo: &o.topo,
            lighting: &o.lighting,
            triangles: o.triangle_count,
        }
    }
}

/// Which kernel a pool batches.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Flat,
    Loop,
}

/// Where one object's tables start in the pools.
#[derive(Clone, Copy, Debug)]
struct Bases {
    /// First coarse vertex, record, bit, colour word, normal and lighting-table word: the
    /// entry's first words ([`ENTRY_BASES`]).
    entry: [u32; ENTRY_BASES],
    /// First word of its `topo` (added to its section offsets).
    topo: u32,
}

/// The pooled outputs of a batch, grown as batches need, with the bind groups of the three
/// steps over them. A Loop pool's also have normals and the patches' scratch.
struct Arena {
    vertices: u64,
    faces: u64,
    scratch_bytes: u64,
    positions: wgpu::Buffer,
    colours: wgpu::Buffer,
    indices: wgpu::Buffer,
    face_colours: wgpu::Buffer,
    normals: Option<wgpu::Buffer>,
    groups: [wgpu::BindGroup; 3],
}

/// The pooled tables of a scene's small objects of one kernel and its batched pipelines. See
/// the module documentation.
pub(super) struct Pool {
    kind: Kind,
    pipelines: [wgpu::ComputePipeline; 3],
    coarse_positions: wgpu::Buffer,
    /// The objects' tables, then room for one batch's table ([`Pool::table_at`]).
    topo: wgpu::Buffer,
    records: wgpu::Buffer,
    bits: wgpu::Buffer,
    normals: wgpu::Buffer,
    colours: wgpu::Buffer,
    light: wgpu::Buffer,
    /// Word of `topo` where a batch's table starts.
    table_at: u32,
    /// The most fine triangles of one batch.
    max_fine: u64,
    /// Per object of the scene, where its tables start (`None`: not pooled).
    bases: Vec<Option<Bases>>,
    /// The batch's `Batch` uniform.
    uniform: wgpu::Buffer,
    arena: Option<Arena>,
}

/// One object of a batch: its index in the scene, its kernel parameters as the kernel's
/// `begin` set them, and the output buffers it was begun into.
pub(super) struct BatchObject<'a> {
    pub(super) object: usize,
    pub(super) params: &'a [u32],
    pub(super) out: &'a RefinedOutput,
}

/// A pool being laid out: its words so far, each region's start.
#[derive(Default)]
struct Layout {
    words: u64,
}

impl Layout {
    /// Places a region of `bytes` aligned to `align` words; its first word.
    fn place(&mut self, bytes: u64, align: u64) -> u64 {
        let at = self.words.next_multiple_of(align);
        self.words = at + bytes.div_ceil(4);
        at
    }
}

fn too_large(what: &'static str, words: u64) -> GpuError {
    GpuError::TooLarge {
        what,
        needed: words * 4,
        limit: u64::from(u32::MAX),
    }
}

fn word(what: &'static str, w: u64) -> Result<u32, GpuError> {
    u32::try_from(w).map_err(|_| too_large(what, w))
}

impl Pool {
    /// Pools the tables of `objects` (one per scene object; `None` for those of the other
    /// kernel) whose coarse triangles do not exceed [`OBJECT_MAX_FINE`], with one submission of
    /// copies. `None` when fewer than two objects qualify (nothing to batch).
    pub(super) fn new<'a>(
        ctx: &GpuContext,
        kernel: PoolKernel<'_>,
        objects: &[Option<PoolInput<'a>>],
        max_fine: u64,
    ) -> Result<Option<Self>, GpuError> {
        fn pooled<'a>(o: &Option<PoolInput<'a>>) -> Option<PoolInput<'a>> {
            o.filter(|o| u64::from(o.triangles) <= OBJECT_MAX_FINE)
        }
        let count = objects.iter().filter_map(pooled).count();
        if count < 2 {
            return Ok(None);
        }
        let (kind, entry_words, label) = match kernel {
            PoolKernel::Flat(_) => (Kind::Flat, FLAT_ENTRY_WORDS, "hce flat batch"),
            PoolKernel::Loop(_) => (Kind::Loop, LOOP_ENTRY_WORDS, "hce loop batch"),
        };
        // Regions aligned to their elements: x y z per vertex and normal, 4 words per record.
        let (mut positions, mut topo, mut records) =
            (Layout::default(), Layout::default(), Layout::default());
        let (mut bits, mut normals, mut colours, mut light) = (
            Layout::default(),
            Layout::default(),
            Layout::default(),
            Layout::default(),
        );
        let mut placed = Vec::with_capacity(objects.len());
        for o in objects {
            let Some(o) = pooled(o) else {
                placed.push(None);
                continue;
            };
            let l = o.lighting;
            let at = [
                positions.place(o.coarse_positions.size(), 3),
                topo.place(o.topo.size(), 1),
                records.place(l.records.size(), 4),
                bits.place(l.bits.size(), 1),
                normals.place(l.normals.size(), 3),
                colours.place(l.colours.size(), 1),
                light.place(l.light.size(), 1),
            ];
            placed.push(Some(at));
        }
        // The batch table: three keys and an entry per object at most.
        let table_at = topo.words;
        topo.words += (3 + entry_words as u64) * count as u64;
        let pool = |label: &'static str, l: &Layout| -> Result<wgpu::Buffer, GpuError> {
            let bytes = check_size(ctx, label, l.words.max(1) * 4)?;
            Ok(ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: bytes,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }))
        };
        let buffers = [
            pool("pooled coarse positions", &positions)?,
            pool("pooled topology", &topo)?,
            pool("pooled records", &records)?,
            pool("pooled bits", &bits)?,
            pool("pooled normals", &normals)?,
            pool("pooled colours", &colours)?,
            pool("pooled lighting", &light)?,
        ];
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("hce batch pool"),
            });
        let mut bases = Vec::with_capacity(objects.len());
        for (o, at) in objects.iter().zip(&placed) {
            let (Some(o), Some(at)) = (o, at) else {
                bases.push(None);
                continue;
            };
            let l = o.lighting;
            let sources = [
                o.coarse_positions,
                o.topo,
                &l.records,
                &l.bits,
                &l.normals,
                &l.colours,
                &l.light,
            ];
            for ((src, dst), &w) in sources.iter().zip(&buffers).zip(at) {
                encoder.copy_buffer_to_buffer(src, 0, dst, w * 4, src.size());
            }
            bases.push(Some(Bases {
                entry: [
                    word("pooled coarse positions", at[0] / 3)?,
                    word("pooled records", at[2] / 4)?,
                    word("pooled bits", at[3] * 32)?,
                    word("pooled colours", at[5])?,
                    word("pooled normals", at[4] / 3)?,
                    word("pooled lighting", at[6])?,
                ],
                topo: word("pooled topology", at[1])?,
            }));
        }
        word("pooled topology", topo.words)?;
        ctx.queue.submit([encoder.finish()]);
        let [coarse_positions, topo, records, bits, normals, colours, light] = buffers;
        let pipelines = match kernel {
            PoolKernel::Flat(k) => [
                "positions_batch_main",
                "faces_batch_main",
                "colours_batch_main",
            ]
            .map(|e| k.pipeline(ctx, e)),
            PoolKernel::Loop(k) => k.batch_pipelines(ctx),
        };
        Ok(Some(Self {
            kind,
            pipelines,
            coarse_positions,
            topo,
            records,
            bits,
            normals,
            colours,
            light,
            table_at: word("pooled topology", table_at)?,
            max_fine: max_fine.max(1),
            bases,
            uniform: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: BATCH_UNIFORM_BYTES,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            arena: None,
        }))
    }

    /// Whether scene object `object` is pooled, so that it can be batched.
    pub(super) fn holds(&self, object: usize) -> bool {
        self.bases.get(object).is_some_and(Option::is_some)
    }

    /// Pooled outputs for `vertices` and `faces` (and `scratch_bytes` of patches), grown (to
    /// the next power of two) when too small; a batch holds at most [`Pool::max_fine`] fine
    /// triangles.
    fn arena(
        &mut self,
        ctx: &GpuContext,
        vertices: u64,
        faces: u64,
        scratch_bytes: u64,
    ) -> Result<&Arena, GpuError> {
        let fits = self.arena.as_ref().is_some_and(|a| {
            a.vertices >= vertices && a.faces >= faces && a.scratch_bytes >= scratch_bytes
        });
        if !fits {
            let vertices = vertices.next_power_of_two().max(64);
            let faces = faces.next_power_of_two().max(64);
            let scratch_bytes = match self.kind {
                Kind::Flat => 0,
                Kind::Loop => scratch_bytes.next_power_of_two().max(256),
            };
            let make = |label: &'static str, bytes: u64| -> Result<wgpu::Buffer, GpuError> {
                Ok(ctx.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size: check_size(ctx, label, bytes)?,
                    usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                }))
            };
            let positions = make("pooled refined positions", vertices * 12)?;
            let colours = make("pooled refined colours", vertices * 16)?;
            let indices = make("pooled refined indices", faces * 12)?;
            let face_colours = make("pooled refined faces", faces * 16)?;
            let (normals, scratch) = match self.kind {
                Kind::Flat => (None, None),
                Kind::Loop => (
                    Some(make("pooled refined normals", vertices * 12)?),
                    Some(make("pooled subdivision scratch", scratch_bytes)?),
                ),
            };
            // The bindings (hce_bindings.wgsl, and `batch`: the kernel's own) each batched step
            // reads or writes: those of the kernel's own steps (flat.rs, loop_kernel.rs,
            // job.rs `Step`), over the pools.
            use super::bindings::*;
            let tree = [
                (HCE_RECORDS, &self.records),
                (HCE_BITS, &self.bits),
                (HCE_NORMALS, &self.normals),
                (HCE_COLOURS, &self.colours),
            ];
            let mut first = vec![
                (COARSE_POSITIONS, &self.coarse_positions),
                (TOPO, &self.topo),
                (OUT_POSITIONS, &positions),
                (KERNEL_OWN, &self.uniform),
            ];
            let mut second = vec![
                (TOPO, &self.topo),
                (OUT_POSITIONS, &positions),
                (OUT_INDICES, &indices),
                (OUT_FACES, &face_colours),
                (KERNEL_OWN, &self.uniform),
            ];
            second.extend(tree);
            let mut third = vec![
                (TOPO, &self.topo),
                (OUT_FACES, &face_colours),
                (OUT_COLOURS, &colours),
                (HCE_LIGHT, &self.light),
                (KERNEL_OWN, &self.uniform),
            ];
            if let (Some(normals), Some(scratch)) = (&normals, &scratch) {
                first.extend([(OUT_NORMALS, normals), (SCRATCH, scratch)]);
                third.extend([(OUT_POSITIONS, &positions), (OUT_NORMALS, normals)]);
            }
            let bindings = [first, second, third];
            let groups = std::array::from_fn(|k| {
                super::util::bind_buffers_at(
                    ctx,
                    "hce batch",
                    &self.pipelines[k].get_bind_group_layout(0),
                    &bindings[k],
                )
            });
            self.arena = Some(Arena {
                vertices,
                faces,
                scratch_bytes,
                positions,
                colours,
                indices,
                face_colours,
                normals,
                groups,
            });
        }
        Ok(self.arena.as_ref().expect("allocated above"))
    }

    /// How many of `objects` (in order) one batch takes: while their fine triangles stay
    /// within [`Pool::max_fine`].
    pub(super) fn fitting(&self, outs: impl IntoIterator<Item = u32>) -> usize {
        fitting(outs, self.max_fine)
    }

    /// An object's `Params` with its section offsets counted in the pooled `topo`, and for a
    /// Loop object the scratch square of its level (the object's own refinement may have
    /// planned the workgroup kernel, which has none); with a Loop object's floats per scratch
    /// slot and coarse triangles (0 for a flat one, whose steps do not walk them).
    fn entry_params(&self, params: &[u32], topo: u32) -> (Vec<u32>, u64, u64) {
        match self.kind {
            Kind::Flat => {
                let mut p: flat::Params =
                    bytemuck::pod_read_unaligned(bytemuck::cast_slice(params));
                for off in [
                    &mut p.tri_off,
                    &mut p.edges_off,
                    &mut p.edge_verts_off,
                    &mut p.edge_side_offsets_off,
                    &mut p.edge_sides_off,
                    &mut p.vertex_corners_off,
                    &mut p.vertex_corner_offsets_off,
                    &mut p.corner_copy_off,
                    &mut p.edge_copy_off,
                    &mut p.sources_off,
                    &mut p.faces_off,
                    &mut p.indices_off,
                    &mut p.use_offsets_off,
                    &mut p.uses_off,
                ] {
                    *off += topo;
                }
                (bytemuck::cast_slice(&[p]).to_vec(), 0, 0)
            }
            Kind::Loop => {
                let mut p: loop_kernel::Params =
                    bytemuck::pod_read_unaligned(bytemuck::cast_slice(params));
                for off in &mut p.offsets {
                    *off += topo;
                }
                let (square, slot) = slot_floats(p.level, p.ring_cap);
                p.square_floats = square as u32;
                let triangles = u64::from(p.triangle_count);
                (bytemuck::cast_slice(&[p]).to_vec(), slot, triangles)
            }
        }
    }

    /// Records the refinement of `objects` (pooled, begun, at most [`Pool::max_fine`] fine
    /// triangles together) into `encoder`, which must be submitted before the next batch is
    /// recorded (the table is written once per batch): the batch's table written to the
    /// queue, one compute pass of three dispatches (timestamped by `timer` when it has room),
    /// then the copies of each object's range of the pooled outputs into its own buffers.
    /// Returns the timer pass used, if any.
    pub(super) fn encode(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        objects: &[BatchObject<'_>],
        timer: Option<&mut PassTimer>,
    ) -> Result<Option<u32>, GpuError> {
        let count = objects.len();
        let mut first_vertices = Vec::with_capacity(count);
        let mut first_faces = Vec::with_capacity(count);
        let mut first_triangles = Vec::with_capacity(count);
        let mut entries = Vec::new();
        let (mut vertices, mut faces, mut triangles) = (0u64, 0u64, 0u64);
        let mut slot_floats = 0u64;
        for b in objects {
            let bases = self.bases.get(b.object).copied().flatten().ok_or_else(|| {
                GpuError::InvalidParams(format!("object {} is not pooled", b.object))
            })?;
            let (params, floats, coarse) = self.entry_params(b.params, bases.topo);
            first_vertices.push(word("pooled refined vertices", vertices)?);
            first_faces.push(word("pooled refined faces", faces)?);
            first_triangles.push(word("pooled coarse triangles", triangles)?);
            entries.extend_from_slice(&bases.entry);
            entries.extend_from_slice(&params);
            vertices += u64::from(b.out.vertex_count);
            faces += u64::from(b.out.triangle_count);
            triangles += coarse;
            slot_floats = slot_floats.max(floats);
        }
        if count == 0 {
            return Ok(None);
        }
        if faces > self.max_fine {
            return Err(GpuError::TooLarge {
                what: "refinement batch",
                needed: faces,
                limit: self.max_fine,
            });
        }
        // The Loop kernel's scratch: one slot per coarse triangle, or as many as the budget
        // holds, each striding over the rest.
        let slots = match self.kind {
            Kind::Flat => 0,
            Kind::Loop => {
                let limits = ctx.device.limits();
                let budget = SCRATCH_BUDGET
                    .min(limits.max_storage_buffer_binding_size)
                    .min(limits.max_buffer_size);
                let slot_bytes = 4 * slot_floats.max(1);
                triangles.min(budget / slot_bytes).max(1)
            }
        };
        let keys = self.table_at;
        let mut table = first_vertices;
        table.extend_from_slice(&first_faces);
        table.extend_from_slice(&first_triangles);
        table.extend_from_slice(&entries);
        ctx.queue.write_buffer(
            &self.topo,
            u64::from(keys) * 4,
            bytemuck::cast_slice(&table),
        );
        let n = count as u32;
        let batch = [
            n,
            keys,
            keys + n,
            keys + 3 * n,
            word("pooled refined vertices", vertices)?,
            word("pooled refined faces", faces)?,
            keys + 2 * n,
            word("pooled coarse triangles", triangles)?,
            word("batch slots", slots)?,
            0,
            0,
            0,
        ];
        ctx.queue
            .write_buffer(&self.uniform, 0, bytemuck::cast_slice(&batch));
        let first_items = match self.kind {
            Kind::Flat => vertices,
            Kind::Loop => slots,
        };
        let sizes = [
            dispatch_size(ctx, first_items)?,
            dispatch_size(ctx, faces)?,
            dispatch_size(ctx, vertices)?,
        ];
        let pipelines = self.pipelines.clone();
        let label = match self.kind {
            Kind::Flat => "hce flat batch",
            Kind::Loop => "hce loop batch",
        };
        let arena = self.arena(ctx, vertices, faces, 4 * slot_floats * slots)?;
        let mut timer = timer;
        let pass_index = timer.as_mut().and_then(|t| t.next_pass());
        {
            let writes = match (&timer, pass_index) {
                (Some(t), Some(i)) => t.writes(i),
                _ => None,
            };
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(label),
                timestamp_writes: writes,
            });
            for k in 0..3 {
                pass.set_pipeline(&pipelines[k]);
                pass.set_bind_group(0, &arena.groups[k], &[]);
                pass.dispatch_workgroups(sizes[k].0, sizes[k].1, 1);
            }
        }
        let (mut v, mut f) = (0u64, 0u64);
        for b in objects {
            let (ov, of) = (
                u64::from(b.out.vertex_count),
                u64::from(b.out.triangle_count),
            );
            let mut copies = vec![
                (&arena.positions, &b.out.positions, 12 * v, 12 * ov),
                (&arena.colours, &b.out.colours, 16 * v, 16 * ov),
                (&arena.indices, &b.out.indices, 12 * f, 12 * of),
                (&arena.face_colours, &b.out.faces, 16 * f, 16 * of),
            ];
            if let (Some(src), Some(dst)) = (&arena.normals, &b.out.normals) {
                copies.push((src, dst, 12 * v, 12 * ov));
            }
            for (src, dst, at, len) in copies {
                if len > 0 {
                    encoder.copy_buffer_to_buffer(src, at, dst, 0, len);
                }
            }
            v += ov;
            f += of;
        }
        Ok(pass_index)
    }
}

/// How many of `outs` (fine triangles per object, in order) one batch of at most `max_fine`
/// fine triangles takes.
fn fitting(outs: impl IntoIterator<Item = u32>, max_fine: u64) -> usize {
    let mut faces = 0u64;
    outs.into_iter()
        .take_while(|&f| {
            faces += u64::from(f);
            faces <= max_fine
        })
        .count()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_batch_takes_objects_in_order_while_they_fit() {
        let max = BATCH_MAX_FINE;
        assert_eq!(fitting([], max), 0);
        assert_eq!(fitting([10, 20, 30], max), 3);
        let half = (max / 2) as u32;
        assert_eq!(fitting([half, half, 1, 1], max), 2);
        assert_eq!(fitting([half, half + 1, 1], max), 1);
        assert_eq!(fitting([10, 20, 30], 30), 2);
    }
}
