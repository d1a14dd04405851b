//! Drawing one frame of the window: the scene with [`MeshPipeline`] (the pipeline of
//! `hce render`) into a linear floating-point image, tone-mapped into the window's format by
//! `tone_map.wgsl` (the GPU twin of [`hce_runtime::gpu::tone_map_aces`]), then the panel on top
//! with egui. A screenshot draws the same passes into a texture of the window's format and reads
//! it back.

use anyhow::Result;
use glam::Mat4;
use hce_runtime::gpu::{
    colour_pass, float_texture_entry, read_texture, render_pipeline, target_texture, uniform_entry,
    GpuContext, MeshDraw, MeshPipeline, PipelineSpec,
};

/// The linear image format the scene is drawn in: `hce render`'s, so that the window shows the
/// values `hce render` writes.
const HDR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

/// The panel's triangles for one frame.
pub struct Overlay<'a> {
    pub primitives: &'a [egui::ClippedPrimitive],
    pub pixels_per_point: f32,
}

struct Targets {
    size: (u32, u32),
    hdr: wgpu::TextureView,
    depth: wgpu::TextureView,
    tone_bind: wgpu::BindGroup,
}

pub struct FrameRenderer {
    /// The window's format.
    pub format: wgpu::TextureFormat,
    scene: MeshPipeline,
    tone: wgpu::RenderPipeline,
    tone_layout: wgpu::BindGroupLayout,
    tone_params: wgpu::Buffer,
    targets: Option<Targets>,
    pub egui: egui_wgpu::Renderer,
}

impl FrameRenderer {
    pub fn new(ctx: &GpuContext, format: wgpu::TextureFormat) -> Self {
        let device = &ctx.device;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("hce view tone map"),
            source: wgpu::ShaderSource::Wgsl(include_str!("tone_map.wgsl").into()),
        });
        let tone_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("hce view tone map"),
            entries: &[
                float_texture_entry(0, wgpu::ShaderStages::FRAGMENT, false),
                uniform_entry(1, wgpu::ShaderStages::FRAGMENT),
            ],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("hce view tone map"),
            bind_group_layouts: &[Some(&tone_layout)],
            immediate_size: 0,
        });
        // A full-screen triangle (no vertex buffers) over the window.
        let tone = render_pipeline(
            ctx,
            &PipelineSpec {
                label: "hce view tone map",
                module: &module,
                layout: Some(&layout),
                buffers: &[],
                format,
                depth: false,
                samples: 1,
            },
        );
        let tone_params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("hce view tone map"),
            size: 16,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let egui = egui_wgpu::Renderer::new(device, format, egui_wgpu::RendererOptions::default());
        Self {
            format,
            scene: MeshPipeline::new(ctx, HDR_FORMAT, 1),
            tone,
            tone_layout,
            tone_params,
            targets: None,
            egui,
        }
    }

    fn ensure_targets(&mut self, ctx: &GpuContext, size: (u32, u32)) {
        if self.targets.as_ref().is_none_or(|t| t.size != size) {
            let texture = |label, format| {
                let usage =
                    wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
                target_texture(ctx, label, size, format, 1, usage).create_view(&Default::default())
            };
            let hdr = texture("hce view scene", HDR_FORMAT);
            let depth = texture("hce view depth", MeshPipeline::DEPTH_FORMAT);
            let tone_bind = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("hce view tone map"),
                layout: &self.tone_layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: wgpu::BindingResource::TextureView(&hdr),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: self.tone_params.as_entire_binding(),
                    },
                ],
            });
            self.targets = Some(Targets {
                size,
                hdr,
                depth,
                tone_bind,
            });
        }
    }

    /// Records the frame into `encoder`: the scene seen through `view_proj` on a black
    /// background, drawn in the columns from `scene_x` to the right edge, tone-mapped with
    /// `exposure` stops into `target` (of [`Self::format`] and `size`), then `overlay` when
    /// given.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::TextureView,
        size: (u32, u32),
        scene_x: u32,
        view_proj: Mat4,
        draws: &[MeshDraw<'_>],
        exposure: f32,
        overlay: Option<&Overlay<'_>>,
    ) {
        let encode = u32::from(!self.format.is_srgb());
        // `Params` of tone_map.wgsl, padded to 16 bytes, in the host's byte order.
        let mut params = [0u8; 16];
        params[..4].copy_from_slice(&2f32.powf(exposure).to_ne_bytes());
        params[4..8].copy_from_slice(&encode.to_ne_bytes());
        ctx.queue.write_buffer(&self.tone_params, 0, &params);
        self.ensure_targets(ctx, size);
        let Self {
            scene,
            tone,
            targets,
            egui,
            ..
        } = self;
        let t = targets.as_ref().expect("ensure_targets made them");
        {
            let mut pass = colour_pass(
                encoder,
                "hce view scene",
                &t.hdr,
                Some(wgpu::Color::BLACK),
                Some(&t.depth),
            );
            let x = scene_x.min(size.0 - 1);
            pass.set_viewport(x as f32, 0.0, (size.0 - x) as f32, size.1 as f32, 0.0, 1.0);
            scene.draw(ctx, &mut pass, view_proj, draws);
        }
        {
            let mut pass = colour_pass(
                encoder,
                "hce view tone map",
                target,
                Some(wgpu::Color::BLACK),
                None,
            );
            pass.set_pipeline(tone);
            pass.set_bind_group(0, &t.tone_bind, &[]);
            pass.draw(0..3, 0..1);
        }
        if let Some(o) = overlay {
            let screen = egui_wgpu::ScreenDescriptor {
                size_in_pixels: [size.0, size.1],
                pixels_per_point: o.pixels_per_point,
            };
            let extra =
                egui.update_buffers(&ctx.device, &ctx.queue, encoder, o.primitives, &screen);
            if !extra.is_empty() {
                ctx.queue.submit(extra);
            }
            let pass = colour_pass(encoder, "hce view panel", target, None, None);
            egui.render(&mut pass.forget_lifetime(), o.primitives, &screen);
        }
    }

    /// Draws the frame as [`Self::record`] does into a texture of the window's format and
    /// returns it as 8-bit RGBA rows, top to bottom: exactly what the window shows.
    #[allow(clippy::too_many_arguments)]
    pub fn screenshot(
        &mut self,
        ctx: &GpuContext,
        size: (u32, u32),
        scene_x: u32,
        view_proj: Mat4,
        draws: &[MeshDraw<'_>],
        exposure: f32,
        overlay: Option<&Overlay<'_>>,
    ) -> Result<Vec<u8>> {
        let texture = target_texture(
            ctx,
            "hce view screenshot",
            size,
            self.format,
            1,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        );
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        let view = texture.create_view(&Default::default());
        self.record(
            ctx,
            &mut encoder,
            &view,
            size,
            scene_x,
            view_proj,
            draws,
            exposure,
            overlay,
        );
        let bytes = read_texture(ctx, encoder, &texture, 4)?;
        let bgra = matches!(
            self.format,
            wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb
        );
        Ok(bytes
            .chunks_exact(4)
            .flat_map(|p| {
                if bgra {
                    [p[2], p[1], p[0], 255]
                } else {
                    [p[0], p[1], p[2], 255]
                }
            })
            .collect())
    }
}
