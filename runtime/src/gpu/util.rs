//! Small wgpu helpers shared by the kernels: buffers from slices, checked sizes, 2-D dispatch
//! for large grids, and blocking read-back.

use wgpu::util::DeviceExt;

use super::{GpuContext, GpuError};

/// Threads per workgroup of every 1-D kernel (`@workgroup_size(64)` in the WGSL files).
pub const WORKGROUP: u32 = 64;

/// A read-only storage buffer holding `data`. Empty slices get one zero word, because wgpu
/// rejects zero-sized bindings and a kernel never reads past the counts it is given.
pub fn storage_init<T: bytemuck::Pod>(ctx: &GpuContext, label: &str, data: &[T]) -> wgpu::Buffer {
    let bytes: &[u8] = bytemuck::cast_slice(data);
    let pad = [0u8; 4];
    ctx.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: if bytes.is_empty() { &pad } else { bytes },
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        })
}

pub fn uniform_init<T: bytemuck::Pod>(ctx: &GpuContext, label: &str, data: &T) -> wgpu::Buffer {
    uniform_words(ctx, label, bytemuck::cast_slice(bytemuck::bytes_of(data)))
}

/// A uniform buffer holding `words`.
pub fn uniform_words(ctx: &GpuContext, label: &str, words: &[u32]) -> wgpu::Buffer {
    ctx.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: bytemuck::cast_slice(words),
            usage: wgpu::BufferUsages::UNIFORM,
        })
}

/// Checks that a buffer of `bytes` fits the device's limits before allocating it.
pub fn check_size(ctx: &GpuContext, what: &'static str, bytes: u64) -> Result<u64, GpuError> {
    let limits = ctx.device.limits();
    let limit = limits
        .max_buffer_size
        .min(limits.max_storage_buffer_binding_size);
    if bytes > limit {
        return Err(GpuError::TooLarge {
            what,
            needed: bytes,
            limit,
        });
    }
    // wgpu buffers must be non-empty and 4-byte aligned for copies.
    Ok(bytes.max(4).next_multiple_of(4))
}

/// An output storage buffer of `bytes` (already checked) that can be copied out and drawn from.
pub fn storage_output(
    ctx: &GpuContext,
    label: &str,
    bytes: u64,
    extra: wgpu::BufferUsages,
) -> wgpu::Buffer {
    ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: bytes,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | extra,
        mapped_at_creation: false,
    })
}

/// A module of WGSL `source` (an assembled kernel of `wgsl.rs`).
pub fn shader_module(ctx: &GpuContext, label: &str, source: String) -> wgpu::ShaderModule {
    ctx.device
        .create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(label),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        })
}

/// The pipeline of compute entry point `entry` of `module`, with the layout of the bindings it
/// uses (`layout: None`): that keeps every step of the kernels within WebGPU's default limit of
/// 8 storage buffers per stage (the flat kernel's steps bind 3, 8 and 4 of its module's 11, the
/// batched ones one more uniform), as the browser's `layout: 'auto'` does.
pub fn compute_pipeline(
    ctx: &GpuContext,
    module: &wgpu::ShaderModule,
    entry: &str,
) -> wgpu::ComputePipeline {
    compute_pipeline_with(ctx, module, entry, Default::default())
}

/// [`compute_pipeline`] with the compilation options chosen.
pub fn compute_pipeline_with(
    ctx: &GpuContext,
    module: &wgpu::ShaderModule,
    entry: &str,
    options: wgpu::PipelineCompilationOptions<'_>,
) -> wgpu::ComputePipeline {
    ctx.device
        .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(entry),
            layout: None,
            module,
            entry_point: Some(entry),
            compilation_options: options,
            cache: None,
        })
}

/// Workgroup counts covering `threads` invocations: a 2-D grid when one dimension is not
/// enough (kernels rebuild the linear index from `num_workgroups.x`).
pub fn dispatch_size(ctx: &GpuContext, threads: u64) -> Result<(u32, u32), GpuError> {
    let groups = threads.div_ceil(u64::from(WORKGROUP)).max(1);
    let max = u64::from(ctx.device.limits().max_compute_workgroups_per_dimension);
    let x = groups.min(max);
    let y = groups.div_ceil(x);
    if y > max {
        return Err(GpuError::TooLarge {
            what: "dispatch",
            needed: threads,
            limit: max * max * u64::from(WORKGROUP),
        });
    }
    Ok((x as u32, y as u32))
}

/// Copies `src` (which must have `COPY_SRC`) into a mappable buffer and reads it back.
pub fn read_back<T: bytemuck::Pod>(
    ctx: &GpuContext,
    src: &wgpu::Buffer,
    count: usize,
) -> Result<Vec<T>, GpuError> {
    let bytes = (count * std::mem::size_of::<T>()) as u64;
    if bytes == 0 {
        return Ok(Vec::new());
    }
    let size = bytes.next_multiple_of(4);
    let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("hce read-back"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
    encoder.copy_buffer_to_buffer(src, 0, &staging, 0, size);
    ctx.queue.submit([encoder.finish()]);
    map_and_copy(ctx, &staging, bytes, |view| {
        bytemuck::pod_collect_to_vec(view)
    })
}

/// Maps `staging` for reading, waits, and hands the first `bytes` to `f`.
pub fn map_and_copy<R>(
    ctx: &GpuContext,
    staging: &wgpu::Buffer,
    bytes: u64,
    f: impl FnOnce(&[u8]) -> R,
) -> Result<R, GpuError> {
    let (tx, rx) = std::sync::mpsc::channel();
    staging.map_async(wgpu::MapMode::Read, .., move |r| {
        let _ = tx.send(r);
    });
    ctx.wait()?;
    rx.recv()
        .map_err(|e| GpuError::Readback(e.to_string()))?
        .map_err(|e| GpuError::Readback(e.to_string()))?;
    let out = {
        let view = staging
            .get_mapped_range(..)
            .map_err(|e| GpuError::Readback(e.to_string()))?;
        f(&view[..bytes as usize])
    };
    staging.unmap();
    Ok(out)
}

/// GPU timestamps around the compute passes of one submission (two per pass), when timing is
/// asked for and the adapter has timestamp queries: the one timing path of every kernel. It
/// has room for `passes` passes; those timed are the ones given [`PassTimer::writes`] or
/// [`PassTimer::next_pass`], numbered from 0.
pub struct PassTimer {
    query: Option<wgpu::QuerySet>,
    resolve: Option<wgpu::Buffer>,
    passes: u32,
    /// One past the highest pass given timestamp writes.
    used: std::cell::Cell<u32>,
    measure: bool,
}

impl PassTimer {
    pub fn new(ctx: &GpuContext, label: &str, passes: u32, measure: bool) -> Self {
        let passes = passes.max(1);
        let query = (measure && ctx.description.timestamps).then(|| {
            ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some(label),
                ty: wgpu::QueryType::Timestamp,
                count: 2 * passes,
            })
        });
        PassTimer {
            query,
            resolve: None,
            passes,
            used: std::cell::Cell::new(0),
            measure,
        }
    }

    /// The next pass not timed yet, while there is room and timestamps are taken.
    pub fn next_pass(&mut self) -> Option<u32> {
        let next = self.used.get();
        (self.query.is_some() && next < self.passes).then_some(next)
    }

    /// Passes given timestamp writes so far (numbered `0..used`).
    pub fn used(&self) -> u32 {
        self.used.get()
    }

    /// The timestamp writes of pass `pass` (none when not timing or past the timer's room).
    pub fn writes(&self, pass: u32) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        if pass >= self.passes {
            return None;
        }
        let q = self.query.as_ref()?;
        self.used.set(self.used.get().max(pass + 1));
        Some(wgpu::ComputePassTimestampWrites {
            query_set: q,
            beginning_of_pass_write_index: Some(2 * pass),
            end_of_pass_write_index: Some(2 * pass + 1),
        })
    }

    /// Records the copy of the timestamps; call after the passes, before `encoder.finish()`.
    pub fn resolve(&mut self, ctx: &GpuContext, encoder: &mut wgpu::CommandEncoder) {
        let used = self.used.get();
        if let (Some(q), true) = (&self.query, used > 0) {
            let buf = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamps"),
                size: 16 * u64::from(used),
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            encoder.resolve_query_set(q, 0..2 * used, &buf, 0);
            self.resolve = Some(buf);
        }
    }

    /// After the submission: the GPU seconds from the first pass's start to the last pass's end
    /// and of each pass, or `None` without timestamps (having waited for the GPU when timing
    /// was asked for, so that a wall clock around the call measures the work).
    pub fn read(self, ctx: &GpuContext) -> Result<Option<(f64, Vec<f64>)>, GpuError> {
        Ok(self.read_stamps(ctx)?.map(|stamps| {
            let passes = (stamps.len() / 2) as u32;
            let each = (0..passes).map(|k| span(&stamps, k..k + 1)).collect();
            (span(&stamps, 0..passes), each)
        }))
    }

    /// [`PassTimer::read`] as the timestamps themselves: seconds since the first, two per pass
    /// (its start and end); [`span`] measures passes with them.
    pub fn read_stamps(self, ctx: &GpuContext) -> Result<Option<Vec<f64>>, GpuError> {
        let Some(buf) = &self.resolve else {
            if self.measure {
                ctx.wait()?;
            }
            return Ok(None);
        };
        let n = 2 * self.used.get() as usize;
        let ticks: Vec<u64> = read_back(ctx, buf, n)?;
        let period = f64::from(ctx.queue.get_timestamp_period());
        Ok(Some(
            ticks
                .iter()
                .map(|&t| t.saturating_sub(ticks[0]) as f64 * period * 1e-9)
                .collect(),
        ))
    }
}

/// GPU seconds from the start of the first of `passes` to the end of the last, from
/// [`PassTimer::read_stamps`]; 0 for no passes. Measure spans of several passes rather than
/// add up passes: on lavapipe the timestamps around one pass were seen to enclose next to none
/// of its work while a span over several passes enclosed most of it.
pub fn span(stamps: &[f64], passes: std::ops::Range<u32>) -> f64 {
    if passes.is_empty() {
        return 0.0;
    }
    let (a, b) = (2 * passes.start as usize, 2 * passes.end as usize - 1);
    (stamps[b] - stamps[a]).max(0.0)
}

/// The `hce_light` buffer of `hce_light.wgsl` ([`hce_geometry::lighting::LightingTable::to_words`]).
/// One unused word for the nearest-normal rule (wgpu rejects empty buffers).
fn lighting_words(
    object: &hce_format::Object,
    reconstruction: hce_geometry::lighting::Reconstruction,
) -> Result<Vec<u32>, GpuError> {
    if reconstruction == hce_geometry::lighting::Reconstruction::NearestNormal {
        return Ok(vec![0]);
    }
    let table =
        hce_geometry::lighting::LightingTable::build_with(object, reconstruction).map_err(|e| {
            GpuError::InvalidObject {
                object: object.name.clone(),
                reason: e.to_string(),
            }
        })?;
    table.to_words().ok_or(GpuError::TooLarge {
        what: "lighting table",
        needed: (table.nodes.len() + table.leaf_points.len() + table.models.len()) as u64 * 4,
        limit: u64::from(u32::MAX) * 4,
    })
}

/// A bind group of whole buffers, each at the binding number it is paired with.
pub fn bind_buffers_at(
    ctx: &GpuContext,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    buffers: &[(u32, &wgpu::Buffer)],
) -> wgpu::BindGroup {
    ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout,
        entries: &buffers
            .iter()
            .map(|&(binding, b)| wgpu::BindGroupEntry {
                binding,
                resource: b.as_entire_binding(),
            })
            .collect::<Vec<_>>(),
    })
}

/// A bind group of whole buffers at bindings 0, 1, 2, ... in order.
pub fn bind_buffers(
    ctx: &GpuContext,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    buffers: &[&wgpu::Buffer],
) -> wgpu::BindGroup {
    let numbered: Vec<(u32, &wgpu::Buffer)> = (0u32..).zip(buffers.iter().copied()).collect();
    bind_buffers_at(ctx, label, layout, &numbered)
}

/// One object's baked lighting on the GPU, as every kernel that colours refined vertices binds
/// it: the triangle records, the HCE tree bits, the normal sets and the packed colours (the
/// paper's rule and `decode.wgsl` read them), and the lighting table of the smooth
/// reconstruction (`hce_light.wgsl`).
pub struct LightingBuffers {
    /// How vertex colours are reconstructed.
    pub reconstruction: hce_geometry::lighting::Reconstruction,
    /// [`records_words`].
    pub records: wgpu::Buffer,
    pub bits: wgpu::Buffer,
    /// `x, y, z` f32 per normal.
    pub normals: wgpu::Buffer,
    /// RGB9E5 words.
    pub colours: wgpu::Buffer,
    /// [`lighting_words`]: one unused word for the nearest-normal rule.
    pub light: wgpu::Buffer,
}

impl LightingBuffers {
    /// Checks every buffer against the device's limits, then uploads them.
    pub fn upload(
        ctx: &GpuContext,
        object: &hce_format::Object,
        reconstruction: hce_geometry::lighting::Reconstruction,
    ) -> Result<Self, GpuError> {
        let records = records_words(object);
        check_size(ctx, "HCE records", records.len() as u64 * 4)?;
        check_size(ctx, "HCE colours", object.colours.len() as u64 * 4)?;
        check_size(ctx, "HCE bits", object.bits.len() as u64 * 4)?;
        check_size(ctx, "HCE normals", object.normals.len() as u64 * 12)?;
        let light = lighting_words(object, reconstruction)?;
        check_size(ctx, "lighting table", light.len() as u64 * 4)?;
        Ok(LightingBuffers {
            reconstruction,
            records: storage_init(ctx, "records", &records),
            bits: storage_init(ctx, "bits", &object.bits),
            normals: storage_init(ctx, "normals", object.normals.as_flattened()),
            colours: storage_init(ctx, "colours", &object.colours),
            light: storage_init(ctx, "lighting table", &light),
        })
    }

    /// The buffers of the paper's rule (`hce_tree.wgsl`) at their bindings of
    /// `hce_bindings.wgsl`: the records, bits, normals and colours.
    pub fn tree_bindings(&self) -> [(u32, wgpu::Buffer); 4] {
        use super::bindings::{HCE_BITS, HCE_COLOURS, HCE_NORMALS, HCE_RECORDS};
        [
            (HCE_RECORDS, self.records.clone()),
            (HCE_BITS, self.bits.clone()),
            (HCE_NORMALS, self.normals.clone()),
            (HCE_COLOURS, self.colours.clone()),
        ]
    }

    /// The `smooth_light` word of the kernels' parameters: 0 for the nearest-normal rule (the
    /// faces pass colours fine triangles), 1 for the reconstructions that read the table.
    pub fn smooth_flag(&self) -> u32 {
        u32::from(self.reconstruction != hce_geometry::lighting::Reconstruction::NearestNormal)
    }
}

/// Packs a kernel's table sections into one word buffer, checked against the device's limits:
/// the words, and where each section starts (the offsets its WGSL reads from a uniform).
pub fn pack_sections<const N: usize>(
    ctx: &GpuContext,
    sections: [&[u32]; N],
) -> Result<(Vec<u32>, [u32; N]), GpuError> {
    let mut packed = Vec::with_capacity(sections.iter().map(|s| s.len()).sum());
    let mut offsets = [0u32; N];
    for (i, s) in sections.iter().enumerate() {
        offsets[i] = u32::try_from(packed.len()).map_err(|_| GpuError::TooLarge {
            what: "topology tables",
            needed: packed.len() as u64 * 4,
            limit: u64::from(u32::MAX),
        })?;
        packed.extend_from_slice(s);
    }
    check_size(ctx, "topology tables", packed.len() as u64 * 4)?;
    Ok((packed, offsets))
}

/// The triangle records as the `array<TriRecord>` words the kernels read.
fn records_words(object: &hce_format::Object) -> Vec<u32> {
    object
        .triangles
        .iter()
        .flat_map(|r| [r.bits_start, r.colour_start, r.normal_start, r.normal_count])
        .collect()
}
