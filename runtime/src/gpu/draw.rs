//! The pieces of a render path written once, for the headless renderer (`render.rs`, `hce
//! render`) and a windowed viewer (`hce view`): a render pipeline of a module's `vs_main` and
//! `fs_main` into one colour target, the 2-D textures it draws into, a render pass over them,
//! the bind-group layout entries of its explicit layouts (the resolve and the tone map), and the
//! read-back of a texture.

use super::{GpuContext, GpuError};

/// The depth buffer's format; a pass clears it to 1.0 (nearer surfaces have smaller depths).
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// A layout entry for a uniform block at `binding`.
pub fn uniform_entry(binding: u32, visibility: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// A layout entry for a read-write storage buffer at `binding`.
pub fn storage_entry(binding: u32, visibility: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only: false },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// A layout entry for a 2-D floating-point texture at `binding`, read with `textureLoad` (not
/// filterable: the linear images are `Rgba32Float`).
pub fn float_texture_entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
    multisampled: bool,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: false },
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled,
        },
        count: None,
    }
}

/// What a render pipeline ([`render_pipeline`]) draws and into what.
#[derive(Clone, Debug)]
pub struct PipelineSpec<'a> {
    pub label: &'a str,
    /// A module with the entry points `vs_main` and `fs_main`.
    pub module: &'a wgpu::ShaderModule,
    /// `None`: the layout of the bindings the entry points use.
    pub layout: Option<&'a wgpu::PipelineLayout>,
    /// The vertex buffers `vs_main` reads; none for a full-screen pass.
    pub buffers: &'a [Option<wgpu::VertexBufferLayout<'a>>],
    /// The colour target's format.
    pub format: wgpu::TextureFormat,
    /// With a [`DEPTH_FORMAT`] depth buffer, the nearest surface kept.
    pub depth: bool,
    /// The targets' sample count.
    pub samples: u32,
}

/// The pipeline of `spec`: triangles, both sides drawn (baked assets may be open surfaces), no
/// blending.
pub fn render_pipeline(ctx: &GpuContext, spec: &PipelineSpec<'_>) -> wgpu::RenderPipeline {
    ctx.device
        .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(spec.label),
            layout: spec.layout,
            vertex: wgpu::VertexState {
                module: spec.module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: spec.buffers,
            },
            primitive: wgpu::PrimitiveState {
                cull_mode: None,
                ..Default::default()
            },
            depth_stencil: spec.depth.then(|| wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: wgpu::MultisampleState {
                count: spec.samples,
                ..Default::default()
            },
            fragment: Some(wgpu::FragmentState {
                module: spec.module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: spec.format,
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        })
}

/// A 2-D texture of `size` (width, height) to draw into or read from.
pub fn target_texture(
    ctx: &GpuContext,
    label: &str,
    size: (u32, u32),
    format: wgpu::TextureFormat,
    samples: u32,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: size.0,
            height: size.1,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: samples,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    })
}

/// A render pass over the colour target `view`, cleared to `clear` first (`None`: drawn over
/// what it holds), with the depth buffer `depth` cleared to 1.0 and discarded after the pass.
pub fn colour_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    label: &str,
    view: &wgpu::TextureView,
    clear: Option<wgpu::Color>,
    depth: Option<&wgpu::TextureView>,
) -> wgpu::RenderPass<'e> {
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: clear.map_or(wgpu::LoadOp::Load, wgpu::LoadOp::Clear),
                store: wgpu::StoreOp::Store,
            },
        })],
        depth_stencil_attachment: depth.map(|view| wgpu::RenderPassDepthStencilAttachment {
            view,
            depth_ops: Some(wgpu::Operations {
                load: wgpu::LoadOp::Clear(1.0),
                store: wgpu::StoreOp::Discard,
            }),
            stencil_ops: None,
        }),
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    })
}

/// Submits `encoder` with a copy of one-sample `texture` (`texel_bytes` a texel, `COPY_SRC`)
/// and returns its rows, top to bottom, without the padding copies require.
pub fn read_texture(
    ctx: &GpuContext,
    mut encoder: wgpu::CommandEncoder,
    texture: &wgpu::Texture,
    texel_bytes: u32,
) -> Result<Vec<u8>, GpuError> {
    let (w, h) = (texture.width(), texture.height());
    let row = u64::from(w) * u64::from(texel_bytes);
    let padded = row.next_multiple_of(u64::from(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT));
    let readback = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("hce image read-back"),
        size: padded * u64::from(h),
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    encoder.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect: wgpu::TextureAspect::All,
        },
        wgpu::TexelCopyBufferInfo {
            buffer: &readback,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded as u32),
                rows_per_image: Some(h),
            },
        },
        texture.size(),
    );
    ctx.queue.submit([encoder.finish()]);
    super::util::map_and_copy(ctx, &readback, readback.size(), |bytes| {
        let mut out = Vec::with_capacity((row * u64::from(h)) as usize);
        for line in bytes.chunks_exact(padded as usize) {
            out.extend_from_slice(&line[..row as usize]);
        }
        out
    })
}
