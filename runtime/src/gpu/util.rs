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
    ctx.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: bytemuck::bytes_of(data),
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
