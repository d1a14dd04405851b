//! `hce view`: a window on the runtime. A baked scene is uploaded once to a
//! [`hce_runtime::gpu::GpuScene`]; every frame the camera (orbit or fly) chooses each object's
//! level ([`hce_runtime::gpu::choose_level`], or a forced one), only the objects whose level
//! changed are refined, and the scene is drawn with `hce render`'s pipeline and tone curve into
//! a winit window, with an egui side panel.
//!
//! Scripted runs (`--frames N`, with `--camera-path`, `--screenshot`, `--stats`) draw N frames
//! and exit, for tests and benchmarks; they run under Xvfb with a software adapter, or with
//! `--offscreen` without a window at all (the same frames drawn into a texture, no panel).
//!
//! Modules: [`camera`] (orbit and fly camera, camera paths), [`content`] (the file and its
//! levels), [`frame`] (drawing and screenshots), [`panel`] (the side panel).

pub mod camera;
pub mod content;
pub mod frame;
pub mod panel;

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use anyhow::{anyhow, bail, Context as _, Result};
use hce_geometry::lighting::Reconstruction;
use hce_geometry::refine::FlatRefinement;
use hce_runtime::gpu::{
    view_projection, AdapterKind, Camera, CameraChoice, ContextOptions, GpuContext,
};
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

use camera::{CameraPath, ViewCamera};
use content::{Content, FileData, Levels, ObjectStats};
use frame::{FrameRenderer, Overlay};

/// What `hce view` was asked to do.
pub struct Options {
    pub file: Option<PathBuf>,
    pub size: (u32, u32),
    pub camera: CameraChoice,
    pub software: bool,
    pub panel: bool,
    /// Scripted run: draw this many frames, then exit.
    pub frames: Option<u32>,
    pub camera_path: Option<CameraPath>,
    /// Scripted run: the last frame's image; interactive: where the screenshot key writes.
    pub screenshot: Option<PathBuf>,
    pub stats: Option<PathBuf>,
    /// Scripted run without a window: frames drawn into a texture, no panel, no display needed.
    pub offscreen: bool,
    pub settings: Settings,
}

/// What the panel changes live.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    pub levels: Levels,
    pub reconstruction: Reconstruction,
    /// How flat objects are refined (`--flat`), fixed for the run.
    pub flat: FlatRefinement,
    pub exposure: f32,
}

/// One frame of a scripted run, as `--stats` writes it.
#[derive(serde::Serialize)]
struct FrameStats {
    frame: u32,
    eye: [f32; 3],
    target: [f32; 3],
    /// Level of every object drawn, in object order.
    levels: Vec<u32>,
    /// Names of the objects whose refinement finished in this frame: their new level is drawn
    /// from this frame on.
    refined: Vec<String>,
    /// Names of the objects refined in part in this frame (a piece of a refinement spread over
    /// frames by the refine budget), still drawn at their old level.
    working: Vec<String>,
    /// Objects whose level should change and is not drawn yet.
    pending: usize,
    triangles: u64,
    /// This frame's refinement work (new output buffers made, one submission), GPU work
    /// waited for.
    refine_ms: f64,
    /// The GPU time of their dispatches, where the adapter has timestamp queries.
    refine_gpu_ms: Option<f64>,
    /// The rest of the frame: panel, drawing, presenting, GPU work waited for.
    draw_ms: f64,
    frame_ms: f64,
}

#[derive(serde::Serialize)]
struct RunStats<'a> {
    file: String,
    adapter: String,
    software: bool,
    width: u32,
    height: u32,
    frames: &'a [FrameStats],
    objects: &'a [ObjectStats],
}

/// The adapter and what frames are drawn into: made when the event loop starts, or at once for
/// an offscreen run.
struct Gpu {
    ctx: GpuContext,
    frame: FrameRenderer,
    egui: egui::Context,
    out: Output,
}

/// Where frames go.
enum Output {
    Window {
        window: Arc<Window>,
        surface: wgpu::Surface<'static>,
        config: wgpu::SurfaceConfiguration,
        egui_state: Box<egui_winit::State>,
    },
    /// A scripted run without a window (`--offscreen`): frames drawn into a texture of the
    /// window's format, no panel.
    Offscreen {
        texture: wgpu::Texture,
        size: (u32, u32),
    },
}

/// The format offscreen frames are drawn in: the one [`choose_format`] prefers for windows, so
/// that an offscreen screenshot is the window's.
const OFFSCREEN_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

impl Gpu {
    /// The size frames are drawn at.
    fn size(&self) -> (u32, u32) {
        match &self.out {
            Output::Window { config, .. } => (config.width, config.height),
            Output::Offscreen { size, .. } => *size,
        }
    }

    fn window(&self) -> Option<&Arc<Window>> {
        match &self.out {
            Output::Window { window, .. } => Some(window),
            Output::Offscreen { .. } => None,
        }
    }
}

#[derive(Default)]
struct Input {
    keys: HashSet<KeyCode>,
    drag: Option<MouseButton>,
    cursor: Option<(f64, f64)>,
    shift: bool,
    ctrl: bool,
}

struct App {
    options: Options,
    /// The file named on the command line, read before the window opens.
    first: Option<FileData>,
    gpu: Option<Gpu>,
    content: Option<Content>,
    camera: ViewCamera,
    start: Camera,
    camera_source: String,
    settings: Settings,
    panel: bool,
    input: Input,
    last_frame: Option<Instant>,
    frame_ms: f64,
    refine_ms: f64,
    frame_index: u32,
    stats: Vec<FrameStats>,
    message: Option<String>,
    screenshot_requested: bool,
    error: Option<anyhow::Error>,
}

/// Runs the viewer until its window is closed or, in a scripted run, its frames are drawn.
pub fn run(options: Options) -> Result<()> {
    let first = options.file.as_deref().map(FileData::read).transpose()?;
    let offscreen = options.offscreen;
    let mut app = App::new(options, first);
    if offscreen {
        app.init_offscreen()?;
        while !app.redraw()? {}
        return app.finish();
    }
    let event_loop = EventLoop::new().map_err(|e| {
        anyhow!(
            "cannot open a window: {e}; `hce view` needs a display (set DISPLAY, or on a \
             machine without one run it under a virtual X server: `xvfb-run -a hce view FILE`; a \
             scripted run with --frames can draw without a window: --offscreen)"
        )
    })?;
    event_loop.set_control_flow(ControlFlow::Wait);
    event_loop
        .run_app(&mut app)
        .map_err(|e| anyhow!("the window's event loop failed: {e}"))?;
    if let Some(e) = app.error.take() {
        return Err(e);
    }
    if let Some(frames) = app.options.frames {
        if app.frame_index < frames {
            bail!(
                "the window closed after {} of {frames} frames",
                app.frame_index
            );
        }
    }
    app.finish()
}

/// The surface format the window is drawn in: 8-bit UNORM (the tone-map pass encodes sRGB, as
/// the CPU does for PNGs) when the surface offers one, else the first it offers.
fn choose_format(formats: &[wgpu::TextureFormat]) -> Option<wgpu::TextureFormat> {
    use wgpu::TextureFormat::{Bgra8Unorm, Bgra8UnormSrgb, Rgba8Unorm, Rgba8UnormSrgb};
    [Bgra8Unorm, Rgba8Unorm, Bgra8UnormSrgb, Rgba8UnormSrgb]
        .into_iter()
        .find(|f| formats.contains(f))
        .or_else(|| formats.first().copied())
}

impl App {
    fn new(options: Options, first: Option<FileData>) -> Self {
        let placeholder = Camera {
            eye: [0.0, 0.0, 1.0],
            target: [0.0; 3],
            fov_y_degrees: 40.0,
        };
        Self {
            camera: ViewCamera::from_camera(&placeholder),
            start: placeholder,
            camera_source: "none".to_owned(),
            settings: options.settings,
            panel: options.panel && !options.offscreen,
            options,
            first,
            gpu: None,
            content: None,
            input: Input::default(),
            last_frame: None,
            frame_ms: 0.0,
            refine_ms: 0.0,
            frame_index: 0,
            stats: Vec::new(),
            message: None,
            screenshot_requested: false,
            error: None,
        }
    }

    /// After a scripted run: the summary line and the statistics file.
    fn finish(&self) -> Result<()> {
        self.summarise();
        self.write_stats()
    }

    fn scripted(&self) -> bool {
        self.options.frames.is_some()
    }

    fn fail(&mut self, event_loop: &ActiveEventLoop, e: anyhow::Error) {
        self.error.get_or_insert(e);
        event_loop.exit();
    }

    /// An offscreen run: the adapter without a surface, frames drawn into a texture.
    fn init_offscreen(&mut self) -> Result<()> {
        let ctx = GpuContext::new(&ContextOptions {
            force_software: self.options.software,
        })?;
        crate::cmd::render::report_adapter(&ctx.description);
        let size = self.options.size;
        let limit = ctx.device.limits().max_texture_dimension_2d;
        if size.0 > limit || size.1 > limit {
            bail!(
                "--size {}x{}: {} draws at most {limit} pixels a side",
                size.0,
                size.1,
                ctx.description
            );
        }
        let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("hce view offscreen frame"),
            size: wgpu::Extent3d {
                width: size.0,
                height: size.1,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: OFFSCREEN_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        });
        let frame = FrameRenderer::new(&ctx, OFFSCREEN_FORMAT);
        self.gpu = Some(Gpu {
            ctx,
            frame,
            egui: egui::Context::default(),
            out: Output::Offscreen { texture, size },
        });
        self.open_first()
    }

    fn open_first(&mut self) -> Result<()> {
        if let (Some(file), Some(data)) = (self.options.file.clone(), self.first.take()) {
            self.open(&file, data, self.options.camera)?;
        }
        Ok(())
    }

    fn init(&mut self, event_loop: &ActiveEventLoop) -> Result<()> {
        let (w, h) = self.options.size;
        let title = match &self.options.file {
            Some(f) => format!("hce view: {}", f.display()),
            None => "hce view".to_owned(),
        };
        let attributes = Window::default_attributes()
            .with_title(title)
            .with_inner_size(winit::dpi::PhysicalSize::new(w, h))
            // A scripted run keeps the size it was given, as `hce render --size` does.
            .with_resizable(!self.scripted());
        let window = Arc::new(
            event_loop
                .create_window(attributes)
                .context("cannot create the window")?,
        );
        let instance = GpuContext::instance();
        let options = ContextOptions {
            force_software: self.options.software,
        };
        let surface = match instance.create_surface(window.clone()) {
            Ok(s) => s,
            Err(e) => {
                // Without any Vulkan driver there is no surface either: say what to install.
                GpuContext::on_instance(&instance, &options, None)?;
                return Err(e).context("cannot draw into the window with Vulkan");
            }
        };
        let ctx = GpuContext::on_instance(&instance, &options, Some(&surface))?;
        crate::cmd::render::report_adapter(&ctx.description);
        let caps = surface.get_capabilities(&ctx.adapter);
        let format = choose_format(&caps.formats)
            .with_context(|| format!("{} cannot present to this window", ctx.description))?;
        let size = window.inner_size();
        let mut config = surface
            .get_default_config(&ctx.adapter, size.width.max(1), size.height.max(1))
            .with_context(|| format!("{} cannot present to this window", ctx.description))?;
        config.format = format;
        // Scripted runs measure frames, so they do not wait for a vertical blank.
        config.present_mode = if self.scripted() {
            wgpu::PresentMode::AutoNoVsync
        } else {
            wgpu::PresentMode::AutoVsync
        };
        surface.configure(&ctx.device, &config);
        let egui = egui::Context::default();
        let egui_state = egui_winit::State::new(
            egui.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            Some(ctx.device.limits().max_texture_dimension_2d as usize),
        );
        let frame = FrameRenderer::new(&ctx, format);
        self.gpu = Some(Gpu {
            ctx,
            frame,
            egui,
            out: Output::Window {
                window,
                surface,
                config,
                egui_state: Box::new(egui_state),
            },
        });
        self.open_first()
    }

    /// Opens `path`, replacing what is shown, and places the camera.
    fn open(&mut self, path: &Path, data: FileData, choice: CameraChoice) -> Result<()> {
        let gpu = self.gpu.as_ref().context("no window yet")?;
        let content = Content::upload(
            &gpu.ctx,
            path,
            data,
            self.settings.reconstruction,
            self.settings.flat,
        )?;
        let (width, height) = gpu.size();
        let aspect = width.max(1) as f32 / height.max(1) as f32;
        let (camera, source) = content.start_camera(choice, aspect)?;
        println!("{}: camera {source}", path.display());
        if let Some(window) = gpu.window() {
            window.set_title(&format!("hce view: {}", path.display()));
        }
        // Orbit about the point straight ahead nearest the scene's centre, not the file's
        // target (a direction only, placed at the scene's radius).
        let mut view = ViewCamera::from_camera(&camera);
        let (lo, hi) = content.bounds;
        let (lo, hi) = (glam::Vec3::from(lo), glam::Vec3::from(hi));
        let radius = (0.5 * lo.distance(hi)).max(1e-3);
        view.distance = ((lo + hi) * 0.5 - view.eye)
            .dot(view.forward())
            .clamp(0.05 * radius, 2.0 * radius);
        self.start = view.camera();
        self.camera = view;
        self.camera_source = source;
        self.content = Some(content);
        self.message = None;
        Ok(())
    }

    /// Opens a file dropped on the window; a bad file leaves the current one and says why.
    fn open_dropped(&mut self, path: &Path) {
        let opened = FileData::read(path)
            .and_then(|data| self.open(path, data, CameraChoice::SceneOrAuto))
            .with_context(|| format!("cannot open {}", path.display()));
        if let Err(e) = opened {
            eprintln!("error: {e:#}");
            self.message = Some(format!("{e:#}"));
        }
    }

    /// Applies held fly keys over `dt` seconds.
    fn fly(&mut self, dt: f32) {
        let Some(content) = &self.content else { return };
        let (lo, hi) = content.bounds;
        let radius = 0.5 * glam::Vec3::from(hi).distance(glam::Vec3::from(lo));
        let mut speed = 0.25 * radius.max(1e-3) * dt;
        if self.input.shift {
            speed *= 4.0;
        }
        if self.input.ctrl {
            speed *= 0.25;
        }
        let k = |c| f32::from(u8::from(self.input.keys.contains(&c)));
        let forward = k(KeyCode::KeyW) - k(KeyCode::KeyS);
        let right = k(KeyCode::KeyD) - k(KeyCode::KeyA);
        let up = k(KeyCode::KeyE) - k(KeyCode::KeyQ);
        self.camera
            .translate(right * speed, up * speed, forward * speed);
    }

    fn flying(&self) -> bool {
        [
            KeyCode::KeyW,
            KeyCode::KeyA,
            KeyCode::KeyS,
            KeyCode::KeyD,
            KeyCode::KeyQ,
            KeyCode::KeyE,
        ]
        .iter()
        .any(|k| self.input.keys.contains(k))
    }

    fn key(&mut self, code: KeyCode) {
        let digit = [
            KeyCode::Digit0,
            KeyCode::Digit1,
            KeyCode::Digit2,
            KeyCode::Digit3,
            KeyCode::Digit4,
            KeyCode::Digit5,
            KeyCode::Digit6,
        ]
        .iter()
        .position(|k| *k == code);
        match code {
            KeyCode::F12 | KeyCode::KeyP => self.screenshot_requested = true,
            KeyCode::Tab => self.panel = !self.panel,
            KeyCode::KeyR => self.camera = ViewCamera::from_camera(&self.start),
            KeyCode::KeyL => self.settings.levels.forced = None,
            KeyCode::KeyN => {
                self.settings.reconstruction = match self.settings.reconstruction {
                    Reconstruction::Smooth => Reconstruction::NearestNormal,
                    Reconstruction::NearestNormal => Reconstruction::Gouraud,
                    Reconstruction::Gouraud => Reconstruction::Smooth,
                }
            }
            _ => {
                if let Some(level) = digit {
                    self.settings.levels.forced = Some(level as u32);
                }
            }
        }
    }

    fn pointer_moved(&mut self, x: f64, y: f64) {
        let Some((px, py)) = self.input.cursor.replace((x, y)) else {
            return;
        };
        let (dx, dy) = ((x - px) as f32, (y - py) as f32);
        let height = self.gpu.as_ref().map_or(1, |g| g.size().1.max(1)) as f32;
        let pan = self.input.drag == Some(MouseButton::Middle)
            || (self.input.drag == Some(MouseButton::Left) && self.input.shift);
        match self.input.drag {
            _ if pan => {
                // One pixel moves the pivot one pixel's width at the pivot's distance.
                let c = &mut self.camera;
                let s = 2.0 * c.distance * (c.fov_y_degrees.to_radians() * 0.5).tan() / height;
                c.translate(-dx * s, dy * s, 0.0);
            }
            Some(MouseButton::Left) => self.camera.orbit(-dx * 0.005, -dy * 0.005),
            Some(MouseButton::Right) => self.camera.turn(-dx * 0.003, -dy * 0.003),
            _ => {}
        }
    }

    /// Draws one frame: camera, levels, panel, scene; a screenshot when asked. True when it
    /// was the last frame of a scripted run.
    fn redraw(&mut self) -> Result<bool> {
        let scripted = self.scripted();
        let now = Instant::now();
        let dt = self
            .last_frame
            .map_or(0.0, |t| now.duration_since(t).as_secs_f32().min(0.25));
        self.last_frame = Some(now);
        self.fly(dt);
        if let (Some(path), Some(frames)) = (&self.options.camera_path, self.options.frames) {
            self.camera = ViewCamera::from_camera(&path.at(&self.start, self.frame_index, frames));
        }
        let camera = self.camera.camera();

        // The reconstruction is part of the upload: a change uploads the file again.
        let gpu = self.gpu.as_mut().context("no window yet")?;
        if let Some(c) = self.content.take() {
            let c = if c.reconstruction != self.settings.reconstruction {
                c.with_reconstruction(&gpu.ctx, self.settings.reconstruction)?
            } else {
                c
            };
            self.content = Some(c);
        }
        let (width, height) = gpu.size();

        let t0 = Instant::now();
        let refined = match self.content.as_mut() {
            Some(c) => match c.update(&gpu.ctx, camera, height, &self.settings.levels) {
                Ok(r) => r,
                // In the window a level the adapter cannot hold is a message, not the end:
                // back to levels from the view, which stay within its buffers.
                Err(e) if !scripted => {
                    eprintln!("error: {e:#}");
                    self.message = Some(format!("{e:#}"));
                    self.settings.levels.forced = None;
                    Default::default()
                }
                Err(e) => return Err(e),
            },
            None => Default::default(),
        };
        let refine_ms = refined.ms;
        if !refined.objects.is_empty() || !refined.working.is_empty() {
            self.refine_ms = refine_ms;
        }
        for n in &refined.notes {
            if scripted {
                eprintln!("note: {n}");
            }
        }

        // The panel.
        let empty = Vec::new();
        let objects = self.content.as_ref().map_or(&empty, |c| &c.objects);
        let triangles = self.content.as_ref().map_or(0, |c| c.drawn_triangles());
        let file = self.content.as_ref().map(|c| c.path.display().to_string());
        let facts = panel::Facts {
            file: file.as_deref(),
            adapter: &gpu.ctx.description.name,
            software: gpu.ctx.description.kind == AdapterKind::Software,
            camera: crate::cmd::render::camera_text(&camera),
            camera_source: &self.camera_source,
            objects,
            triangles,
            frame_ms: self.frame_ms,
            refine_ms: self.refine_ms,
            pending: refined.pending,
            message: self.message.as_deref(),
        };
        let mut actions = panel::Actions::default();
        let show_panel = self.panel;
        let mut primitives = Vec::new();
        let mut pixels_per_point = 1.0;
        let mut to_free: Vec<egui::TextureId> = Vec::new();
        // The panel is drawn in windows only.
        if let Output::Window {
            window, egui_state, ..
        } = &mut gpu.out
        {
            let raw = egui_state.take_egui_input(window);
            let settings = &mut self.settings;
            let output = gpu.egui.run_ui(raw, |ui| {
                if show_panel {
                    actions = panel::show(ui, &facts, settings);
                }
            });
            egui_state.handle_platform_output(window, output.platform_output);
            // The panel animates (a header opening, a slider dragged): draw again at once.
            if output
                .viewport_output
                .get(&egui::ViewportId::ROOT)
                .is_some_and(|v| v.repaint_delay.is_zero())
            {
                window.request_redraw();
            }
            primitives = gpu.egui.tessellate(output.shapes, output.pixels_per_point);
            pixels_per_point = output.pixels_per_point;
            // Applied now, freed after painting; drained so that nothing is left to drop
            // unapplied.
            let mut textures = output.textures_delta;
            to_free = textures.free.drain().collect();
            for (id, deltas) in textures.set.drain() {
                for delta in &deltas {
                    gpu.frame
                        .egui
                        .update_texture(&gpu.ctx.device, &gpu.ctx.queue, id, delta);
                }
            }
        }
        let overlay = Overlay {
            primitives: &primitives,
            pixels_per_point,
        };
        if actions.reset_camera {
            self.camera = ViewCamera::from_camera(&self.start);
        }

        // The scene.
        let draws = self.content.as_ref().map(|c| c.draws()).unwrap_or_default();
        let (lo, hi) = self
            .content
            .as_ref()
            .map_or(([-1.0; 3], [1.0; 3]), |c| c.bounds);
        // The scene fills the window right of the panel.
        let scene_x = if show_panel {
            ((actions.width * pixels_per_point).round() as u32).min(width.saturating_sub(1))
        } else {
            0
        };
        let aspect = (width - scene_x) as f32 / height.max(1) as f32;
        let view_proj = view_projection(&camera, lo, hi, aspect);
        let mut encoder = gpu
            .ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        let mut record = |frame: &mut FrameRenderer, view: &wgpu::TextureView| {
            frame.record(
                &gpu.ctx,
                &mut encoder,
                view,
                (width, height),
                scene_x,
                view_proj,
                &draws,
                self.settings.exposure,
                show_panel.then_some(&overlay),
            );
        };
        let drawn = match &mut gpu.out {
            Output::Window {
                window,
                surface,
                config,
                ..
            } => {
                let surface_texture = match surface.get_current_texture() {
                    wgpu::CurrentSurfaceTexture::Success(t)
                    | wgpu::CurrentSurfaceTexture::Suboptimal(t) => Some(t),
                    wgpu::CurrentSurfaceTexture::Timeout
                    | wgpu::CurrentSurfaceTexture::Occluded => None,
                    wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                        surface.configure(&gpu.ctx.device, config);
                        None
                    }
                    wgpu::CurrentSurfaceTexture::Validation => {
                        bail!("the window's surface rejected the frame (a wgpu validation error)")
                    }
                };
                match surface_texture {
                    Some(texture) => {
                        record(
                            &mut gpu.frame,
                            &texture.texture.create_view(&Default::default()),
                        );
                        gpu.ctx.queue.submit([encoder.finish()]);
                        window.pre_present_notify();
                        gpu.ctx.queue.present(texture);
                        true
                    }
                    None => false,
                }
            }
            Output::Offscreen { texture, .. } => {
                record(&mut gpu.frame, &texture.create_view(&Default::default()));
                gpu.ctx.queue.submit([encoder.finish()]);
                true
            }
        };
        // Waiting makes the frame time the GPU's too, not only the time to record it.
        gpu.ctx.wait()?;
        let frame_ms = t0.elapsed().as_secs_f64() * 1e3;
        self.frame_ms = frame_ms;

        let last = self
            .options
            .frames
            .is_some_and(|n| self.frame_index + 1 >= n);
        let screenshot = (self.screenshot_requested || actions.screenshot)
            || (last && self.options.screenshot.is_some());
        if screenshot {
            self.screenshot_requested = false;
            let pixels = gpu.frame.screenshot(
                &gpu.ctx,
                (width, height),
                scene_x,
                view_proj,
                &draws,
                self.settings.exposure,
                show_panel.then_some(&overlay),
            )?;
            let path = match (&self.options.screenshot, scripted) {
                (Some(p), true) => p.clone(),
                (Some(p), false) if p.extension().is_some() => p.clone(),
                (dir, _) => free_name(dir.as_deref().unwrap_or(Path::new(".")))?,
            };
            crate::cmd::render::write_png(&path, width, height, &pixels)?;
            println!("wrote {} ({width}x{height})", path.display());
            self.message = Some(format!("wrote {}", path.display()));
        }
        for id in &to_free {
            gpu.frame.egui.free_texture(id);
        }

        if scripted {
            let names: Vec<String> = refined
                .objects
                .iter()
                .filter_map(|&i| objects.get(i))
                .map(|o| format!("{}@{}", o.name, o.level))
                .collect();
            let levels: Vec<u32> = objects
                .iter()
                .filter(|o| o.instances > 0)
                .map(|o| o.level)
                .collect();
            let working: Vec<String> = refined
                .working
                .iter()
                .filter_map(|&i| objects.get(i))
                .map(|o| o.name.clone())
                .collect();
            println!(
                "frame {}: {} triangles{}, refined [{}]{} in {:.1} ms{}, frame {:.1} ms",
                self.frame_index,
                triangles,
                if drawn { "" } else { " (not presented)" },
                names.join(" "),
                if working.is_empty() {
                    String::new()
                } else {
                    format!(", in part [{}]", working.join(" "))
                },
                refine_ms,
                match refined.pending {
                    0 => String::new(),
                    n => format!(" ({n} left for later frames)"),
                },
                frame_ms
            );
            if !drawn {
                bail!("frame {} could not be presented", self.frame_index);
            }
            self.stats.push(FrameStats {
                frame: self.frame_index,
                eye: camera.eye,
                target: camera.target,
                levels,
                refined: refined
                    .objects
                    .iter()
                    .filter_map(|&i| objects.get(i))
                    .map(|o| o.name.clone())
                    .collect(),
                working,
                pending: refined.pending,
                triangles,
                refine_ms,
                refine_gpu_ms: refined.gpu_ms,
                draw_ms: frame_ms - refine_ms,
                frame_ms,
            });
        }
        if drawn {
            self.frame_index += 1;
        }
        Ok(last && drawn)
    }

    /// After a scripted run: the mean frame, draw and refine times, the first frame (uploads
    /// and pipeline creation) left out.
    fn summarise(&self) {
        let frames = self.stats.get(1..).unwrap_or_default();
        if frames.is_empty() {
            return;
        }
        let n = frames.len() as f64;
        let mean = |f: &dyn Fn(&FrameStats) -> f64| frames.iter().map(f).sum::<f64>() / n;
        let changed: Vec<&FrameStats> = frames
            .iter()
            .filter(|f| !f.refined.is_empty() || !f.working.is_empty())
            .collect();
        let draw = mean(&|f| f.draw_ms);
        let refine = mean(&|f| f.refine_ms);
        let gpu = mean(&|f| f.refine_gpu_ms.unwrap_or(0.0));
        println!(
            "{} frames after the first: frame {:.1} ms, draw {draw:.1} ms, refine {refine:.1} ms \
             ({gpu:.1} ms in GPU timestamps; refine / draw {:.2}); {} frames refined (a level \
             change finished or a piece of one), {:.1} ms each, longest frame {:.1} ms",
            frames.len(),
            mean(&|f| f.frame_ms),
            refine / draw.max(1e-9),
            changed.len(),
            changed.iter().map(|f| f.refine_ms).sum::<f64>() / changed.len().max(1) as f64 + 0.0,
            frames.iter().map(|f| f.frame_ms).fold(0.0, f64::max),
        );
    }

    fn write_stats(&self) -> Result<()> {
        let Some(path) = &self.options.stats else {
            return Ok(());
        };
        let gpu = self.gpu.as_ref().context("no window was opened")?;
        let (width, height) = gpu.size();
        let stats = RunStats {
            file: self
                .content
                .as_ref()
                .map(|c| c.path.display().to_string())
                .unwrap_or_default(),
            adapter: gpu.ctx.description.to_string(),
            software: gpu.ctx.description.kind == AdapterKind::Software,
            width,
            height,
            frames: &self.stats,
            objects: self.content.as_ref().map_or(&[], |c| &c.objects),
        };
        let json = serde_json::to_string_pretty(&stats)?;
        hce_meshio::write_atomic(path, json.as_bytes())
            .with_context(|| format!("writing {}", path.display()))
    }
}

/// `hce-view-N.png` in `dir` for the first N not taken.
fn free_name(dir: &Path) -> Result<PathBuf> {
    (1..100_000)
        .map(|n| dir.join(format!("hce-view-{n}.png")))
        .find(|p| !p.exists())
        .with_context(|| format!("{}: no free screenshot name", dir.display()))
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.gpu.is_none() {
            if let Err(e) = self.init(event_loop) {
                self.fail(event_loop, e);
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(gpu) = self.gpu.as_mut() else { return };
        let Output::Window {
            window,
            surface,
            config,
            egui_state,
        } = &mut gpu.out
        else {
            return;
        };
        let response = egui_state.on_window_event(window, &event);
        // egui asks for a repaint after a redraw too; following that would redraw forever.
        if response.repaint && !matches!(event, WindowEvent::RedrawRequested) {
            window.request_redraw();
        }
        let window = window.clone();
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) if size.width > 0 && size.height > 0 => {
                config.width = size.width;
                config.height = size.height;
                surface.configure(&gpu.ctx.device, config);
                window.request_redraw();
            }
            WindowEvent::RedrawRequested => match self.redraw() {
                Ok(true) => event_loop.exit(),
                Ok(false) => {}
                Err(e) => self.fail(event_loop, e),
            },
            WindowEvent::DroppedFile(path) => {
                self.open_dropped(&path);
                window.request_redraw();
            }
            WindowEvent::ModifiersChanged(m) => {
                self.input.shift = m.state().shift_key();
                self.input.ctrl = m.state().control_key();
            }
            // The panel takes Tab to move its focus; the window's own keys come first.
            WindowEvent::KeyboardInput { ref event, .. }
                if event.state == ElementState::Pressed
                    && !event.repeat
                    && matches!(
                        event.physical_key,
                        PhysicalKey::Code(KeyCode::Tab | KeyCode::F12)
                    ) =>
            {
                if let PhysicalKey::Code(code) = event.physical_key {
                    self.key(code);
                }
                window.request_redraw();
            }
            _ if response.consumed => {}
            WindowEvent::KeyboardInput { event, .. } => {
                if let PhysicalKey::Code(code) = event.physical_key {
                    match event.state {
                        ElementState::Pressed => {
                            if !event.repeat {
                                self.key(code);
                            }
                            self.input.keys.insert(code);
                        }
                        ElementState::Released => {
                            self.input.keys.remove(&code);
                        }
                    }
                    window.request_redraw();
                }
            }
            WindowEvent::MouseInput { state, button, .. } => {
                self.input.drag = (state == ElementState::Pressed).then_some(button);
            }
            WindowEvent::CursorMoved { position, .. } => {
                self.pointer_moved(position.x, position.y);
                if self.input.drag.is_some() {
                    window.request_redraw();
                }
            }
            WindowEvent::MouseWheel { delta, .. } => {
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                self.camera.dolly(0.85f32.powf(steps));
                window.request_redraw();
            }
            WindowEvent::Focused(false) => self.input.keys.clear(),
            _ => {}
        }
    }

    fn about_to_wait(&mut self, _event_loop: &ActiveEventLoop) {
        if let Some(window) = self.gpu.as_ref().and_then(Gpu::window) {
            if self.scripted() || self.flying() {
                window.request_redraw();
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_window_format_is_8_bit_unorm_when_offered() {
        use wgpu::TextureFormat::*;
        assert_eq!(
            choose_format(&[Bgra8UnormSrgb, Rgba16Float, Bgra8Unorm]),
            Some(Bgra8Unorm)
        );
        assert_eq!(
            choose_format(&[Rgba8UnormSrgb, Rgba8Unorm]),
            Some(Rgba8Unorm)
        );
        assert_eq!(choose_format(&[Bgra8UnormSrgb]), Some(Bgra8UnormSrgb));
        assert_eq!(choose_format(&[Rgb10a2Unorm]), Some(Rgb10a2Unorm));
        assert_eq!(choose_format(&[]), None);
    }

    #[test]
    fn screenshot_names_do_not_overwrite() {
        let dir = tempfile::tempdir().unwrap();
        let first = free_name(dir.path()).unwrap();
        assert_eq!(first, dir.path().join("hce-view-1.png"));
        std::fs::write(&first, b"taken").unwrap();
        assert_eq!(
            free_name(dir.path()).unwrap(),
            dir.path().join("hce-view-2.png")
        );
    }
}
