//! Headless rendering: draw an indexed mesh with per-vertex linear colours into an offscreen
//! floating-point texture with a depth buffer, read it back, and tone-map it for PNG.
//!
//! Tone mapping ([`tone_map_aces`]): exposure `2^ev`, then Krzysztof Narkowicz's fit of the ACES
//! filmic curve ("ACES Filmic Tone Mapping Curve", 2016),
//! `f(x) = x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14)` per channel, clamped to `[0, 1]`, then
//! the sRGB transfer function (IEC 61966-2-1) and rounding to 8 bits. EXR output skips all of
//! this and stores the linear values.
//!
//! Anti-aliasing: multisampling ([`RenderParams::samples`], default 4). The colour target stays
//! 32-bit float, which WebGPU does not promise to multisample or resolve, so the count is the
//! largest the adapter supports for it (with `TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES`, which
//! [`GpuContext::new`] asks for) and `render_resolve.wgsl` averages the samples itself. The
//! fragment stage runs once per pixel and triangle, at the pixel centre where the triangle covers
//! every sample, else inside the covered samples (centroid interpolation: colours are never
//! extrapolated beyond a triangle's edge); coverage is tested at
//! the standard sample positions of Vulkan, Direct3D and WebGPU ([`sample_positions`]), which is
//! where `hce reference --msaa` traces its rays, so the two images still line up pixel for pixel.

use glam::{Mat4, Vec3, Vec4};

use super::draw::{
    colour_pass, float_texture_entry, read_texture, render_pipeline, storage_entry, target_texture,
    uniform_entry, PipelineSpec,
};
use super::framing::auto_camera;
use super::lod::Camera;
use super::util::{bind_buffers, uniform_init};
use super::{GpuContext, GpuError};

/// How the camera is placed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Framing {
    /// Look at the bounds' centre from the front-right-above, far enough that the bounding
    /// sphere fills the view with a small margin; 40° vertical field of view.
    Auto,
    /// An explicit camera.
    Camera(Camera),
}

/// Parameters of a render.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderParams {
    pub width: u32,
    pub height: u32,
    pub framing: Framing,
    /// Linear background colour. Default black.
    pub background: [f32; 3],
    /// Multisamples per pixel (1, 2, 4, 8 or 16). Default 4. The image is drawn with the
    /// largest count the adapter supports up to this ([`RenderedImage::samples`] says which).
    pub samples: u32,
}

impl Default for RenderParams {
    fn default() -> Self {
        Self {
            width: 800,
            height: 600,
            framing: Framing::Auto,
            background: [0.0; 3],
            samples: 4,
        }
    }
}

/// The standard sample positions of `count`-sample multisampling (Vulkan
/// `standardSampleLocations`, Direct3D and WebGPU share them), in pixel units from the pixel's
/// top-left corner, rows downwards; `None` for a count without a standard pattern. One sample
/// is the pixel centre.
pub fn sample_positions(count: u32) -> Option<&'static [[f32; 2]]> {
    const ONE: [[f32; 2]; 1] = [[0.5, 0.5]];
    const TWO: [[f32; 2]; 2] = [[0.75, 0.75], [0.25, 0.25]];
    const FOUR: [[f32; 2]; 4] = [
        [0.375, 0.125],
        [0.875, 0.375],
        [0.125, 0.625],
        [0.625, 0.875],
    ];
    const EIGHT: [[f32; 2]; 8] = [
        [0.5625, 0.3125],
        [0.4375, 0.6875],
        [0.8125, 0.5625],
        [0.3125, 0.1875],
        [0.1875, 0.8125],
        [0.0625, 0.4375],
        [0.6875, 0.9375],
        [0.9375, 0.0625],
    ];
    const SIXTEEN: [[f32; 2]; 16] = [
        [0.5625, 0.5625],
        [0.4375, 0.3125],
        [0.3125, 0.625],
        [0.75, 0.4375],
        [0.1875, 0.375],
        [0.625, 0.8125],
        [0.8125, 0.6875],
        [0.6875, 0.1875],
        [0.375, 0.875],
        [0.5, 0.0625],
        [0.25, 0.125],
        [0.125, 0.75],
        [0.0, 0.5],
        [0.9375, 0.25],
        [0.875, 0.9375],
        [0.0625, 0.0],
    ];
    match count {
        1 => Some(&ONE),
        2 => Some(&TWO),
        4 => Some(&FOUR),
        8 => Some(&EIGHT),
        16 => Some(&SIXTEEN),
        _ => None,
    }
}

/// The multisample count [`RenderParams::samples`] `requested` gets on this device: the largest
/// of 16, 8, 4, 2 not above it that the 32-bit float colour target and the depth buffer both
/// support, else 1.
pub fn supported_samples(ctx: &GpuContext, requested: u32) -> u32 {
    if !ctx
        .device
        .features()
        .contains(wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES)
    {
        return 1;
    }
    let colour = ctx.adapter.get_texture_format_features(COLOUR_FORMAT).flags;
    let depth = ctx
        .adapter
        .get_texture_format_features(MeshPipeline::DEPTH_FORMAT)
        .flags;
    [16, 8, 4, 2]
        .into_iter()
        .find(|&n| {
            n <= requested && colour.sample_count_supported(n) && depth.sample_count_supported(n)
        })
        .unwrap_or(1)
}

const COLOUR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

/// A rendered image: linear RGBA f32, rows top to bottom.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderedImage {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<f32>,
    /// The camera actually used (useful after auto-framing).
    pub camera: Camera,
    /// Multisamples per pixel the image was drawn with ([`supported_samples`]).
    pub samples: u32,
}

impl RenderedImage {
    /// 8-bit sRGB RGBA after [`tone_map_aces`] with exposure `ev` stops.
    pub fn to_srgb8(&self, ev: f32) -> Vec<u8> {
        let mut out = Vec::with_capacity(self.pixels.len());
        for p in self.pixels.chunks_exact(4) {
            out.extend(tone_map_aces([p[0], p[1], p[2]], ev));
            out.push(255);
        }
        out
    }
}

/// Exposure, ACES fitted curve and sRGB encoding of one linear colour (see module docs).
pub fn tone_map_aces(rgb: [f32; 3], ev: f32) -> [u8; 3] {
    let exposure = 2f32.powf(ev);
    rgb.map(|x| {
        let x = if x.is_finite() {
            x.max(0.0) * exposure
        } else {
            0.0
        };
        let y = ((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0);
        let s = if y <= 0.003_130_8 {
            12.92 * y
        } else {
            1.055 * y.powf(1.0 / 2.4) - 0.055
        };
        (s * 255.0 + 0.5).floor().clamp(0.0, 255.0) as u8
    })
}

/// Bounds of `x, y, z` triples (a mesh's positions, as [`render_mesh`] takes them); `None` when
/// empty or not finite.
pub fn mesh_bounds(positions: &[f32]) -> Option<([f32; 3], [f32; 3])> {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for p in positions.chunks_exact(3) {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (lo.iter().chain(&hi).all(|x| x.is_finite())).then_some((lo, hi))
}

/// View-projection matrix (wgpu clip space, depth 0..1) of `camera`, with near and far planes
/// around the bounds.
pub fn view_projection(camera: &Camera, lo: [f32; 3], hi: [f32; 3], aspect: f32) -> Mat4 {
    let eye = Vec3::from(camera.eye);
    let target = Vec3::from(camera.target);
    let forward = (target - eye).normalize_or(Vec3::NEG_Z);
    let up = if forward.cross(Vec3::Y).length() < 1e-4 {
        Vec3::Z
    } else {
        Vec3::Y
    };
    let centre = (Vec3::from(lo) + Vec3::from(hi)) * 0.5;
    let radius = ((Vec3::from(hi) - Vec3::from(lo)).length() * 0.5).max(1e-6);
    let d = (centre - eye).length();
    let near = ((d - radius) * 0.5).max(radius * 1e-4);
    let far = (d + radius) * 1.5 + near;
    // Right-handed, looking down −z, depth mapped to wgpu's 0..1.
    let f = 1.0 / (camera.fov_y_degrees.clamp(1.0, 179.0).to_radians() * 0.5).tan();
    let proj = Mat4::from_cols(
        Vec4::new(f / aspect, 0.0, 0.0, 0.0),
        Vec4::new(0.0, f, 0.0, 0.0),
        Vec4::new(0.0, 0.0, far / (near - far), -1.0),
        Vec4::new(0.0, 0.0, near * far / (near - far), 0.0),
    );
    let s = forward.cross(up).normalize();
    let u = s.cross(forward);
    let view = Mat4::from_cols(
        Vec4::new(s.x, u.x, -forward.x, 0.0),
        Vec4::new(s.y, u.y, -forward.y, 0.0),
        Vec4::new(s.z, u.z, -forward.z, 0.0),
        Vec4::new(-s.dot(eye), -u.dot(eye), forward.dot(eye), 1.0),
    );
    proj * view
}

/// A mesh already on the GPU: `positions` (f32 ×3), `colours` (f32 ×4 linear), `indices` (u32).
pub struct GpuMesh<'a> {
    pub positions: &'a wgpu::Buffer,
    pub colours: &'a wgpu::Buffer,
    pub indices: &'a wgpu::Buffer,
    pub index_count: u32,
    pub bounds: ([f32; 3], [f32; 3]),
}

/// Uploads and draws a CPU mesh (`positions` ×3, linear `colours` ×4, `indices`).
pub fn render_mesh(
    ctx: &GpuContext,
    positions: &[f32],
    colours: &[f32],
    indices: &[u32],
    params: &RenderParams,
) -> Result<RenderedImage, GpuError> {
    let v = positions.len() / 3;
    if positions.len() % 3 != 0 || colours.len() != 4 * v || indices.len() % 3 != 0 {
        return Err(GpuError::InvalidParams(format!(
            "{} position floats, {} colour floats, {} indices: need 3 and 4 floats per vertex \
             and 3 indices per triangle",
            positions.len(),
            colours.len(),
            indices.len()
        )));
    }
    if let Some(&bad) = indices.iter().find(|&&i| i as usize >= v) {
        return Err(GpuError::InvalidParams(format!(
            "index {bad} >= vertex count {v}"
        )));
    }
    let bounds = mesh_bounds(positions)
        .ok_or_else(|| GpuError::InvalidParams("mesh has no finite positions".into()))?;
    let make = |label, data: &[u8], usage| {
        use wgpu::util::DeviceExt;
        ctx.device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: if data.is_empty() { &[0; 4] } else { data },
                usage,
            })
    };
    let p = make(
        "positions",
        bytemuck::cast_slice(positions),
        wgpu::BufferUsages::VERTEX,
    );
    let c = make(
        "colours",
        bytemuck::cast_slice(colours),
        wgpu::BufferUsages::VERTEX,
    );
    let i = make(
        "indices",
        bytemuck::cast_slice(indices),
        wgpu::BufferUsages::INDEX,
    );
    render_gpu_mesh(
        ctx,
        &GpuMesh {
            positions: &p,
            colours: &c,
            indices: &i,
            index_count: indices.len() as u32,
            bounds,
        },
        params,
    )
}

/// Draws a mesh that is already on the GPU (e.g. a kernel's output buffers) and reads the image
/// back.
pub fn render_gpu_mesh(
    ctx: &GpuContext,
    mesh: &GpuMesh<'_>,
    params: &RenderParams,
) -> Result<RenderedImage, GpuError> {
    render_draws(
        ctx,
        &[MeshDraw {
            positions: mesh.positions,
            colours: mesh.colours,
            indices: mesh.indices,
            index_count: mesh.index_count,
            transform: Mat4::IDENTITY,
        }],
        mesh.bounds,
        params,
    )
}

/// One draw of a scene: a mesh on the GPU (`positions` f32 ×3, linear `colours` f32 ×4, `u32`
/// indices) placed in the world by `transform` (object to world).
#[derive(Clone, Copy, Debug)]
pub struct MeshDraw<'a> {
    pub positions: &'a wgpu::Buffer,
    pub colours: &'a wgpu::Buffer,
    pub indices: &'a wgpu::Buffer,
    pub index_count: u32,
    pub transform: Mat4,
}

/// The pipeline that draws placed meshes with their linear colours and no lighting
/// (`render.wgsl`) into a colour target of `format` with a [`MeshPipeline::DEPTH_FORMAT`] depth
/// buffer: the headless renderer's, and a windowed viewer's (`hce view`), which draws into its
/// own pass.
pub struct MeshPipeline {
    pipeline: wgpu::RenderPipeline,
}

impl MeshPipeline {
    /// The depth attachment's format ([`super::draw::DEPTH_FORMAT`]); clear it to 1.0 (nearer
    /// surfaces have smaller depths).
    pub const DEPTH_FORMAT: wgpu::TextureFormat = super::draw::DEPTH_FORMAT;

    /// `samples`: the colour and depth targets' sample count (1, or one that
    /// [`supported_samples`] gives).
    pub fn new(ctx: &GpuContext, format: wgpu::TextureFormat, samples: u32) -> Self {
        let module = ctx
            .device
            .create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("hce render"),
                source: wgpu::ShaderSource::Wgsl(include_str!("render.wgsl").into()),
            });
        let pipeline = render_pipeline(
            ctx,
            &PipelineSpec {
                label: "hce render",
                module: &module,
                layout: None,
                buffers: &[
                    Some(wgpu::VertexBufferLayout {
                        array_stride: 12,
                        step_mode: wgpu::VertexStepMode::Vertex,
                        attributes: &wgpu::vertex_attr_array![0 => Float32x3],
                    }),
                    Some(wgpu::VertexBufferLayout {
                        array_stride: 16,
                        step_mode: wgpu::VertexStepMode::Vertex,
                        attributes: &wgpu::vertex_attr_array![1 => Float32x4],
                    }),
                ],
                format,
                depth: true,
                samples,
            },
        );
        Self { pipeline }
    }

    /// Records `draws` into `pass` (which must target this pipeline's formats), seen through
    /// `view_proj` ([`view_projection`]).
    pub fn draw(
        &self,
        ctx: &GpuContext,
        pass: &mut wgpu::RenderPass<'_>,
        view_proj: Mat4,
        draws: &[MeshDraw<'_>],
    ) {
        // One uniform per draw: the shader's matrix is view-projection times the draw's
        // transform.
        let layout = self.pipeline.get_bind_group_layout(0);
        pass.set_pipeline(&self.pipeline);
        for d in draws {
            if d.index_count == 0 {
                continue;
            }
            let uniform = uniform_init(
                ctx,
                "view projection",
                &(view_proj * d.transform).to_cols_array(),
            );
            pass.set_bind_group(
                0,
                &bind_buffers(ctx, "hce render", &layout, &[&uniform]),
                &[],
            );
            pass.set_vertex_buffer(0, d.positions.slice(..));
            pass.set_vertex_buffer(1, d.colours.slice(..));
            pass.set_index_buffer(d.indices.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..d.index_count, 0, 0..1);
        }
    }
}

/// Draws several placed meshes into one image and reads it back. `bounds` (world space) place
/// the near and far planes and, with [`Framing::Auto`], the camera.
pub(crate) fn render_draws(
    ctx: &GpuContext,
    draws: &[MeshDraw<'_>],
    bounds: ([f32; 3], [f32; 3]),
    params: &RenderParams,
) -> Result<RenderedImage, GpuError> {
    let (w, h) = (params.width, params.height);
    let max_dim = ctx.device.limits().max_texture_dimension_2d;
    if w == 0 || h == 0 || w > max_dim || h > max_dim {
        return Err(GpuError::InvalidParams(format!(
            "image size {w}x{h}: each side must be 1 to {max_dim} pixels"
        )));
    }
    let aspect = w as f32 / h as f32;
    let (lo, hi) = bounds;
    let camera = match params.framing {
        Framing::Auto => auto_camera(lo, hi, aspect),
        Framing::Camera(c) => c,
    };
    if camera.eye == camera.target
        || !camera
            .eye
            .iter()
            .chain(&camera.target)
            .all(|x| x.is_finite())
    {
        return Err(GpuError::InvalidParams(
            "camera eye and target must be finite and distinct".into(),
        ));
    }
    let view_proj = view_projection(&camera, lo, hi, aspect);

    // The resolve writes one storage buffer of the whole image; an image too large for one
    // binding is drawn with one sample.
    let image_bytes = u64::from(w) * u64::from(h) * 16;
    let limits = ctx.device.limits();
    let samples = if image_bytes > limits.max_storage_buffer_binding_size
        || image_bytes > limits.max_buffer_size
    {
        1
    } else {
        supported_samples(ctx, params.samples)
    };
    let target = |label, format, usage| target_texture(ctx, label, (w, h), format, samples, usage);
    let colour_target = target(
        "hce colour target",
        COLOUR_FORMAT,
        wgpu::TextureUsages::RENDER_ATTACHMENT
            | if samples > 1 {
                wgpu::TextureUsages::TEXTURE_BINDING
            } else {
                wgpu::TextureUsages::COPY_SRC
            },
    );
    let depth = target(
        "hce depth",
        MeshPipeline::DEPTH_FORMAT,
        wgpu::TextureUsages::RENDER_ATTACHMENT,
    );
    let pipeline = MeshPipeline::new(ctx, COLOUR_FORMAT, samples);

    let colour_view = colour_target.create_view(&Default::default());
    let depth_view = depth.create_view(&Default::default());
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
    {
        let [r, g, b] = params.background.map(f64::from);
        let mut pass = colour_pass(
            &mut encoder,
            "hce render",
            &colour_view,
            Some(wgpu::Color { r, g, b, a: 1.0 }),
            Some(&depth_view),
        );
        pipeline.draw(ctx, &mut pass, view_proj, draws);
    }
    let pixels = if samples > 1 {
        resolve(ctx, encoder, &colour_view, w, h, samples)?
    } else {
        bytemuck::pod_collect_to_vec(&read_texture(ctx, encoder, &colour_target, 16)?)
    };
    Ok(RenderedImage {
        width: w,
        height: h,
        pixels,
        camera,
        samples,
    })
}

/// The resolve's uniform block (`Params` in `render_resolve.wgsl`).
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
struct ResolveParams {
    width: u32,
    height: u32,
    samples: u32,
    pad: u32,
}

/// Averages the samples of a multisampled colour target into a buffer (`render_resolve.wgsl`)
/// and reads it back.
fn resolve(
    ctx: &GpuContext,
    mut encoder: wgpu::CommandEncoder,
    colour_view: &wgpu::TextureView,
    w: u32,
    h: u32,
    samples: u32,
) -> Result<Vec<f32>, GpuError> {
    let bytes = u64::from(w) * u64::from(h) * 16;
    let device = &ctx.device;
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("hce resolve"),
        entries: &[
            uniform_entry(0, wgpu::ShaderStages::COMPUTE),
            float_texture_entry(1, wgpu::ShaderStages::COMPUTE, true),
            storage_entry(2, wgpu::ShaderStages::COMPUTE),
        ],
    });
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("hce resolve"),
        source: wgpu::ShaderSource::Wgsl(include_str!("render_resolve.wgsl").into()),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("hce resolve"),
        layout: Some(
            &device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("hce resolve"),
                bind_group_layouts: &[Some(&layout)],
                immediate_size: 0,
            }),
        ),
        module: &module,
        entry_point: Some("resolve_main"),
        compilation_options: Default::default(),
        cache: None,
    });
    let uniform = uniform_init(
        ctx,
        "hce resolve",
        &ResolveParams {
            width: w,
            height: h,
            samples,
            pad: 0,
        },
    );
    let resolved = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("hce resolved image"),
        size: bytes,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let readback = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("hce image read-back"),
        size: bytes,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("hce resolve"),
        layout: &layout,
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: uniform.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: wgpu::BindingResource::TextureView(colour_view),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: resolved.as_entire_binding(),
            },
        ],
    });
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("hce resolve"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), 1);
    }
    encoder.copy_buffer_to_buffer(&resolved, 0, &readback, 0, bytes);
    ctx.queue.submit([encoder.finish()]);
    super::util::map_and_copy(ctx, &readback, bytes, |b| {
        bytemuck::cast_slice::<u8, f32>(b).to_vec()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tone_map_is_monotonic_and_saturates() {
        assert_eq!(tone_map_aces([0.0; 3], 0.0), [0, 0, 0]);
        assert_eq!(tone_map_aces([1e6; 3], 0.0), [255, 255, 255]);
        // ACES fit at 0.18 mid-grey: 0.18 (0.4518 + 0.03) / (0.18 (0.4374 + 0.59) + 0.14)
        // = 0.086724 / 0.324932 = 0.26690 → sRGB 0.55346 → 141.1 → 141.
        assert_eq!(tone_map_aces([0.18; 3], 0.0)[0], 141);
        let mut last = 0;
        for i in 0..100 {
            let v = tone_map_aces([i as f32 * 0.05; 3], 0.0)[0];
            assert!(v >= last);
            last = v;
        }
        // One stop of exposure equals doubling the input.
        assert_eq!(tone_map_aces([0.1; 3], 1.0), tone_map_aces([0.2; 3], 0.0));
    }

    #[test]
    fn auto_camera_sees_the_whole_bounding_sphere() {
        let (lo, hi) = ([-1.0, -2.0, -0.5], [3.0, 1.0, 0.5]);
        for aspect in [0.5f32, 1.0, 2.0] {
            let cam = auto_camera(lo, hi, aspect);
            let m = view_projection(&cam, lo, hi, aspect);
            for corner in 0..8 {
                let p = Vec3::new(
                    if corner & 1 == 0 { lo[0] } else { hi[0] },
                    if corner & 2 == 0 { lo[1] } else { hi[1] },
                    if corner & 4 == 0 { lo[2] } else { hi[2] },
                );
                let c = m * p.extend(1.0);
                let ndc = c.truncate() / c.w;
                assert!(ndc.x.abs() < 1.0 && ndc.y.abs() < 1.0, "{aspect}: {ndc}");
                assert!(ndc.z > 0.0 && ndc.z < 1.0, "{aspect}: depth {}", ndc.z);
            }
        }
    }
}
