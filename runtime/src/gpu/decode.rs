//! Batch HCE colour decoding on the GPU (`decode.wgsl` + `hce_tree.wgsl`): for each query (coarse
//! triangle, level, path, subtriangle normal) the tree node, chosen normal and linear colour.
//!
//! The flat and Loop kernels decode inline; this entry point (feature `testing`, re-exported by
//! [`super::testing`]) lets the decoding be checked against its CPU twin,
//! [`hce_geometry::decode::decode_colour`], in isolation.

use hce_format::Object;

use super::util::{
    bind_buffers_at, check_size, compute_pipeline, dispatch_size, read_back, shader_module,
    storage_init, storage_output, LightingBuffers,
};
use super::wgsl::decode_source;
use super::{GpuContext, GpuError};
use hce_geometry::decode::MAX_PATH_LEVEL;
use hce_geometry::lighting::Reconstruction;
use hce_geometry::tables::validate_tables;

pub use hce_geometry::decode::DecodedColour;

/// One subtriangle to colour. 32 bytes, the layout of `Query` in `decode.wgsl`.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct ColourQuery {
    pub triangle: u32,
    pub level: u32,
    /// `level` child indices, first most significant, two bits each.
    pub path: u32,
    pub _pad: u32,
    /// The subtriangle's normal (`w` ignored); need not be unit length.
    pub normal: [f32; 4],
}

/// Decodes `queries` against `object`'s tables on the GPU. The tables are validated first
/// ([`validate_tables`]) and every query is checked (triangle in range,
/// `level <= MAX_PATH_LEVEL`, `path < 4^level`), so nothing out of bounds reaches the kernel.
pub fn decode_colours(
    ctx: &GpuContext,
    object: &Object,
    queries: &[ColourQuery],
) -> Result<Vec<DecodedColour>, GpuError> {
    validate_tables(object)?;
    for (i, q) in queries.iter().enumerate() {
        let bad = |reason: String| GpuError::InvalidObject {
            object: object.name.clone(),
            reason: format!("query {i}: {reason}"),
        };
        if q.triangle as usize >= object.triangles.len() {
            return Err(bad(format!("triangle {} out of range", q.triangle)));
        }
        if q.level > MAX_PATH_LEVEL {
            return Err(GpuError::LevelTooHigh {
                level: q.level,
                max: MAX_PATH_LEVEL,
            });
        }
        if u64::from(q.path) >= 1u64 << (2 * q.level) {
            return Err(bad(format!(
                "path {} too long for level {}",
                q.path, q.level
            )));
        }
    }
    if queries.is_empty() {
        return Ok(Vec::new());
    }
    let out_bytes = check_size(
        ctx,
        "decoded colours",
        (queries.len() * std::mem::size_of::<DecodedColour>()) as u64,
    )?;
    let module = shader_module(ctx, "hce decode", decode_source());
    let pipeline = compute_pipeline(ctx, &module, "decode_main");
    let queries_buf = storage_init(ctx, "queries", queries);
    let results = storage_output(ctx, "decoded", out_bytes, wgpu::BufferUsages::empty());
    // The paper's rule reads the stored colours, not the lighting table.
    let lighting = LightingBuffers::upload(ctx, object, Reconstruction::NearestNormal)?;
    // The queries and results are the kernel's own bindings; the rest hce_bindings.wgsl's.
    let mut bindings = vec![
        (super::bindings::UNIFORM, queries_buf),
        (super::bindings::KERNEL_OWN, results.clone()),
    ];
    bindings.extend(lighting.tree_bindings());
    let bindings: Vec<(u32, &wgpu::Buffer)> = bindings.iter().map(|(b, buf)| (*b, buf)).collect();
    let bind_group = bind_buffers_at(
        ctx,
        "hce decode",
        &pipeline.get_bind_group_layout(0),
        &bindings,
    );
    let (x, y) = dispatch_size(ctx, queries.len() as u64)?;
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups(x, y, 1);
    }
    ctx.queue.submit([encoder.finish()]);
    read_back(ctx, &results, queries.len())
}
