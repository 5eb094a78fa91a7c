//! The window: winit events, the wgpu surface the panes and the panel are drawn to, picking
//! and dragging objects, orbiting the camera, and screenshots read back from the device.

use super::display::Display;
use super::panel::{self, PANEL_WIDTH, Settings};
use super::worker::{self, Command, Inbox, PaneView, Plan, Setup, Shared, UiEvent};
use crate::cli::interrupt;
use crate::cli::options::BackendChoice;
use crate::pick::{DragPlane, Picker, ray};
use anyhow::{Context, Result, anyhow};
use backend_wgpu::{GpuContext, OPTIONAL_FEATURES, WgpuBackend};
use glam::{Quat, Vec3};
use ppm_core::compile::gpu_camera;
use ppm_core::passes::Backend;
use ppm_core::scene::{Camera, Move, Scene};
use scenes::file::image::write_png_rgb;
use std::path::PathBuf;
use std::sync::mpsc::{self, Sender};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};
use winit::application::ApplicationHandler;
use winit::dpi::{PhysicalPosition, PhysicalSize};
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoopProxy};
use winit::keyboard::{Key, ModifiersState, NamedKey};
use winit::window::{Window, WindowId};

/// Everything the window needs before it opens.
pub struct AppSetup {
    /// What the render thread renders.
    pub plan: Plan,
    pub backend: BackendChoice,
    pub screenshot_dir: Option<PathBuf>,
    pub pool: rayon::ThreadPool,
    pub proxy: EventLoopProxy<UiEvent>,
}

/// The viewer: waiting for its window, then running.
pub struct App {
    setup: Option<AppSetup>,
    running: Option<Running>,
    /// The first error, reported when the event loop returns.
    pub error: Option<anyhow::Error>,
}

impl App {
    pub fn new(setup: AppSetup) -> Self {
        Self {
            setup: Some(setup),
            running: None,
            error: None,
        }
    }

    /// Joins the render thread once the event loop has returned: its error, if any.
    pub fn finish(mut self) -> Result<()> {
        if let Some(running) = self.running.take() {
            drop(running.commands);
            let result = running
                .worker
                .join()
                .map_err(|_| anyhow!("the render thread panicked"))?;
            if let Some(e) = self.error {
                return Err(e);
            }
            result?;
        }
        match self.error {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }

    fn fail(&mut self, event_loop: &ActiveEventLoop, e: anyhow::Error) {
        self.error.get_or_insert(e);
        if let Some(r) = &mut self.running {
            r.quit();
        } else {
            event_loop.exit();
        }
    }
}

/// Dragging an object, or orbiting the camera.
enum Gesture {
    Object {
        object: usize,
        plane: DragPlane,
        last: PhysicalPosition<f64>,
    },
    /// Orbiting (right button) or panning (middle button, or right with shift) the camera:
    /// each step goes to the render as it comes, which keeps the light a step did not change
    /// (local mode).
    Camera {
        last: PhysicalPosition<f64>,
        camera: Camera,
        pan: bool,
    },
}

struct Running {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    device: wgpu::Device,
    queue: wgpu::Queue,
    display: Display,
    egui_state: egui_winit::State,
    egui_renderer: egui_wgpu::Renderer,
    shared: Arc<Shared>,
    commands: Sender<Command>,
    screenshots: Sender<()>,
    worker: JoinHandle<Result<()>>,
    settings: Settings,
    scripted: bool,
    screenshot_dir: Option<PathBuf>,
    cursor: PhysicalPosition<f64>,
    modifiers: ModifiersState,
    gesture: Option<Gesture>,
    selected: Option<usize>,
    undo: Vec<Scene>,
    opened: Instant,
    first_image: Option<Duration>,
    latencies: Vec<f64>,
    quitting: bool,
    /// The render thread has stopped.
    finished: bool,
}

impl ApplicationHandler<UiEvent> for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        let Some(setup) = self.setup.take() else {
            return;
        };
        match Running::open(event_loop, setup) {
            Ok(r) => self.running = Some(r),
            Err(e) => self.fail(event_loop, e),
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let Some(r) = &mut self.running else {
            return;
        };
        let response = r.egui_state.on_window_event(&r.window, &event);
        if response.repaint {
            r.window.request_redraw();
        }
        let result = match event {
            WindowEvent::CloseRequested => {
                r.quit();
                Ok(())
            }
            WindowEvent::Resized(size) => {
                r.resize(size);
                Ok(())
            }
            WindowEvent::RedrawRequested => r.draw(None),
            WindowEvent::ModifiersChanged(m) => {
                r.modifiers = m.state();
                Ok(())
            }
            WindowEvent::CursorMoved { position, .. } => {
                r.cursor_moved(position);
                Ok(())
            }
            WindowEvent::MouseInput { state, button, .. } if !response.consumed => {
                r.mouse(state, button);
                Ok(())
            }
            WindowEvent::MouseWheel { delta, .. } if !response.consumed => {
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                r.dolly(steps);
                Ok(())
            }
            WindowEvent::KeyboardInput { event, .. }
                if !response.consumed && event.state == ElementState::Pressed =>
            {
                r.key(&event.logical_key);
                Ok(())
            }
            _ => Ok(()),
        };
        if let Err(e) = result {
            self.fail(event_loop, e);
        }
    }

    fn user_event(&mut self, event_loop: &ActiveEventLoop, event: UiEvent) {
        let Some(r) = &mut self.running else {
            return;
        };
        let result = match event {
            UiEvent::Frame => {
                r.window.request_redraw();
                Ok(())
            }
            UiEvent::Screenshot(n) => {
                let written = match r.screenshot_dir.clone() {
                    Some(dir) => r.draw(Some(dir.join(format!("screenshot-{n:03}.png")))),
                    None => r.draw(None),
                };
                let _ = r.screenshots.send(());
                written
            }
            UiEvent::Finished if r.finished => Ok(()),
            UiEvent::Finished => {
                r.finished = true;
                let written = match r.screenshot_dir.clone() {
                    Some(dir) => r.draw(Some(dir.join("exit.png"))),
                    None => Ok(()),
                };
                r.report_timing();
                event_loop.exit();
                written
            }
        };
        if let Err(e) = result {
            self.fail(event_loop, e);
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        if let Some(r) = &mut self.running
            && interrupt::requested()
        {
            r.quit();
        }
        event_loop.set_control_flow(ControlFlow::WaitUntil(
            Instant::now() + Duration::from_millis(100),
        ));
    }
}

impl Running {
    /// Opens the window and the device, starts the backends on it, and the render thread.
    fn open(event_loop: &ActiveEventLoop, setup: AppSetup) -> Result<Self> {
        let plan = &setup.plan;
        let (width, height) = (plan.params.width, plan.params.height);
        let panes = plan.modes.len();
        let size = PhysicalSize::new(panes as u32 * width + PANEL_WIDTH, height.max(480));
        let window = Arc::new(
            event_loop
                .create_window(
                    Window::default_attributes()
                        .with_title(format!("ppm view: {}", plan.scene.name))
                        .with_inner_size(size),
                )
                .context("cannot open the window")?,
        );
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let surface = instance
            .create_surface(window.clone())
            .context("cannot draw into the window")?;
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            compatible_surface: Some(&surface),
            ..Default::default()
        }))
        .context("no wgpu adapter can draw into the window (on Linux, install a Vulkan driver such as mesa-vulkan-drivers)")?;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("ppm view"),
            // Timestamps where offered: the panel then shows each pass's device time.
            required_features: adapter.features() & OPTIONAL_FEATURES,
            required_limits: adapter.limits(),
            ..Default::default()
        }))
        .context("cannot open the device")?;
        let caps = surface.get_capabilities(&adapter);
        // A UNORM target: the display pass encodes sRGB exactly as `ppm render`'s PNG, and
        // egui draws its panel in the space it expects.
        let format = caps
            .formats
            .iter()
            .copied()
            .find(|f| {
                matches!(
                    f,
                    wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Rgba8Unorm
                )
            })
            .or(caps.formats.first().copied())
            .context("the window offers no surface format")?;
        let inner = window.inner_size();
        let mut config = surface
            .get_default_config(&adapter, inner.width.max(1), inner.height.max(1))
            .context("the adapter cannot draw into the window")?;
        config.format = format;
        config.present_mode = wgpu::PresentMode::AutoNoVsync;
        surface.configure(&device, &config);
        let display = Display::new(&device, format, panes, width, height);

        let mut backends: Vec<Box<dyn Backend + Send>> = Vec::new();
        let mut targets = Vec::new();
        let context = GpuContext::adopt(device.clone(), queue.clone(), adapter.get_info());
        for i in 0..panes {
            // The window draws the wgpu backend's image on its own device; any other
            // backend uploads its image.
            match setup.backend.name() {
                "wgpu" => {
                    backends.push(Box::new(WgpuBackend::on(context.clone())?));
                    targets.push(Some(display.panes[i].image.clone()));
                }
                _ => {
                    backends.push(setup.backend.start()?);
                    targets.push(None);
                }
            }
        }
        eprintln!(
            "ppm view: {} on {} ({}), {}x{}",
            plan.scene.name,
            backends[0].name(),
            adapter.get_info().name,
            width,
            height
        );
        let shared = Arc::new(Shared {
            panes: plan
                .modes
                .iter()
                .zip(&backends)
                .map(|(m, b)| Mutex::new(PaneView::new(*m, b.name())))
                .collect(),
            pose: Mutex::new(plan.scene.clone()),
        });
        let egui_ctx = egui::Context::default();
        let egui_state = egui_winit::State::new(
            egui_ctx,
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            Some(device.limits().max_texture_dimension_2d as usize),
        );
        let egui_renderer = egui_wgpu::Renderer::new(&device, format, Default::default());

        let settings = Settings {
            exposure: plan.exposure,
            photons_per_pass: plan.params.photons_per_pass,
            alpha: plan.params.alpha,
            mode: plan.modes[0],
            heat: plan.heat_map,
        };
        let (commands, command_inbox) = mpsc::channel();
        let (screenshots, screenshot_inbox) = mpsc::channel();
        let scripted = plan.script.is_some();
        let work = Setup {
            plan: setup.plan,
            backends,
            targets,
        };
        let (pool, proxy, for_worker) = (setup.pool, setup.proxy, shared.clone());
        let worker = std::thread::Builder::new()
            .name("render".to_owned())
            .spawn(move || {
                pool.install(|| {
                    let inbox = Inbox {
                        commands: command_inbox,
                        screenshots: screenshot_inbox,
                    };
                    let wake = |e: UiEvent| {
                        let _ = proxy.send_event(e);
                    };
                    let result = worker::run(work, &for_worker, &inbox, &wake);
                    // However it ended, the window closes.
                    wake(UiEvent::Finished);
                    result
                })
            })
            .context("cannot start the render thread")?;
        Ok(Self {
            window,
            surface,
            config,
            device,
            queue,
            display,
            egui_state,
            egui_renderer,
            shared,
            commands,
            screenshots,
            worker,
            settings,
            scripted,
            screenshot_dir: setup.screenshot_dir,
            cursor: PhysicalPosition::new(0.0, 0.0),
            modifiers: ModifiersState::empty(),
            gesture: None,
            selected: None,
            undo: Vec::new(),
            opened: Instant::now(),
            first_image: None,
            latencies: Vec::new(),
            quitting: false,
            finished: false,
        })
    }

    /// Asks the render thread to write what it has and stop; the window closes when it has.
    fn quit(&mut self) {
        if !self.quitting {
            self.quitting = true;
            let _ = self.commands.send(Command::Quit);
        }
    }

    fn resize(&mut self, size: PhysicalSize<u32>) {
        if size.width > 0 && size.height > 0 {
            self.config.width = size.width;
            self.config.height = size.height;
            self.surface.configure(&self.device, &self.config);
            self.window.request_redraw();
        }
    }

    /// The image point under a window position, if a pane is there.
    fn pane_at(&self, at: PhysicalPosition<f64>) -> Option<(f32, f32)> {
        pane_point(&self.display, self.shared.panes.len(), at)
    }

    fn picker(&self) -> (Picker, Scene) {
        let pose = self.shared.pose();
        let (w, h) = self.display.size();
        (Picker::new(&pose, w, h), pose)
    }

    fn mouse(&mut self, state: ElementState, button: MouseButton) {
        match (state, button) {
            (ElementState::Pressed, MouseButton::Left) => {
                let Some((px, py)) = self.pane_at(self.cursor) else {
                    return;
                };
                let (picker, pose) = self.picker();
                let Some(picked) = picker.pick(px, py) else {
                    return;
                };
                let forward = pose.camera.look_at - pose.camera.eye;
                let plane = if self.modifiers.shift_key() {
                    DragPlane::level(picked.point)
                } else {
                    DragPlane::facing(picked.point, forward)
                };
                self.selected = Some(picked.object);
                self.undo.push(pose);
                self.gesture = Some(Gesture::Object {
                    object: picked.object,
                    plane,
                    last: self.cursor,
                });
            }
            (ElementState::Pressed, MouseButton::Right | MouseButton::Middle)
                if self.pane_at(self.cursor).is_some() =>
            {
                self.gesture = Some(Gesture::Camera {
                    last: self.cursor,
                    camera: self.shared.camera(),
                    pan: button == MouseButton::Middle || self.modifiers.shift_key(),
                });
            }
            (ElementState::Released, _) => {
                self.gesture = None;
            }
            _ => {}
        }
    }

    fn cursor_moved(&mut self, to: PhysicalPosition<f64>) {
        self.cursor = to;
        match &mut self.gesture {
            Some(Gesture::Object {
                object,
                plane,
                last,
            }) => {
                let (Some(a), Some(b)) = (
                    pane_point(&self.display, self.shared.panes.len(), *last),
                    pane_point(&self.display, self.shared.panes.len(), to),
                ) else {
                    return;
                };
                let (w, h) = self.display.size();
                let camera = gpu_camera(&self.shared.camera(), w, h);
                let rays = (ray(&camera, a.0, a.1), ray(&camera, b.0, b.1));
                if let Some(t) = plane.translation(rays.0, rays.1)
                    && t.length_squared() > 0.0
                {
                    plane.point += t;
                    *last = to;
                    let _ = self.commands.send(Command::Move {
                        moves: vec![Move {
                            object: *object,
                            translation: t,
                            rotation: Quat::IDENTITY,
                        }],
                        at: Instant::now(),
                    });
                }
            }
            Some(Gesture::Camera { last, camera, pan }) => {
                let (dx, dy) = ((to.x - last.x) as f32, (to.y - last.y) as f32);
                *camera = if *pan {
                    let (_, h) = self.display.size();
                    pan_by(camera, dx, dy, h)
                } else {
                    orbit(camera, dx, dy)
                };
                *last = to;
                let _ = self.commands.send(Command::Camera(camera.clone()));
            }
            None => {}
        }
    }

    fn dolly(&mut self, steps: f32) {
        let mut camera = self.shared.camera();
        let offset = camera.eye - camera.look_at;
        camera.eye = camera.look_at + offset * 0.9f32.powf(steps);
        let _ = self.commands.send(Command::Camera(camera));
    }

    fn key(&mut self, key: &Key) {
        let ctrl = self.modifiers.control_key();
        match key.as_ref() {
            Key::Character("z") if ctrl => self.undo_move(),
            Key::Character("s") => {
                let _ = self.commands.send(Command::Save);
            }
            Key::Character("h") => {
                self.settings.heat = !self.settings.heat;
                let _ = self.commands.send(Command::Heat(self.settings.heat));
            }
            Key::Character(c @ ("q" | "e")) => {
                let Some(object) = self.selected else {
                    return;
                };
                let degrees: f32 = if c == "q" { -15.0 } else { 15.0 };
                self.undo.push(self.shared.pose());
                let _ = self.commands.send(Command::Move {
                    moves: vec![Move {
                        object,
                        translation: Vec3::ZERO,
                        rotation: Quat::from_rotation_y(degrees.to_radians()),
                    }],
                    at: Instant::now(),
                });
            }
            Key::Named(NamedKey::Escape) => self.quit(),
            _ => {}
        }
    }

    fn undo_move(&mut self) {
        if let Some(scene) = self.undo.pop() {
            let _ = self.commands.send(Command::Pose {
                scene: Box::new(scene),
                at: Instant::now(),
            });
        }
    }

    /// Takes the render thread's newest images, heat maps and move latencies.
    fn take_updates(&mut self) {
        for i in 0..self.shared.panes.len() {
            let mut view = self.shared.pane(i);
            if let Some(image) = view.image.take() {
                self.display.upload(&self.queue, i, &image);
            }
            if let Some(resets) = view.resets.take() {
                self.display.upload_resets(&self.queue, i, &resets);
            }
            if let Some(at) = view.moved_at.take() {
                let ms = at.elapsed().as_secs_f64() * 1e3;
                view.stats.last_latency_ms = Some(ms);
                self.latencies.push(ms);
                if self.scripted {
                    eprintln!("pane {i}: a move's new pose on screen after {ms:.0} ms");
                }
            }
            if self.first_image.is_none() && view.stats.iterations > 0 {
                let t = self.opened.elapsed();
                self.first_image = Some(t);
                eprintln!(
                    "first image on screen {:.0} ms after the window opened",
                    t.as_secs_f64() * 1e3
                );
            }
        }
    }

    /// Draws a frame; with `capture`, also draws it into a texture, reads it back and writes it
    /// there as PNG (the presented frame, panel included).
    fn draw(&mut self, capture: Option<PathBuf>) -> Result<()> {
        self.take_updates();
        let raw = self.egui_state.take_egui_input(&self.window);
        let ctx = self.egui_state.egui_ctx().clone();
        let mut actions = panel::Actions::default();
        let output = ctx.run_ui(raw, |ui| {
            actions = panel::show(ui, &self.shared, &mut self.settings);
        });
        self.apply(actions);
        self.egui_state
            .handle_platform_output(&self.window, output.platform_output);
        let jobs = ctx.tessellate(output.shapes, output.pixels_per_point);
        for (id, deltas) in &output.textures_delta.set {
            for delta in deltas {
                self.egui_renderer
                    .update_texture(&self.device, &self.queue, *id, delta);
            }
        }
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [self.config.width, self.config.height],
            pixels_per_point: output.pixels_per_point,
        };
        let frame = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(f)
            | wgpu::CurrentSurfaceTexture::Suboptimal(f) => Some(f),
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                self.surface.configure(&self.device, &self.config);
                None
            }
            _ => None,
        };
        let mut encoder = self.device.create_command_encoder(&Default::default());
        let mut extra = Vec::new();
        if let Some(frame) = &frame {
            let view = frame.texture.create_view(&Default::default());
            extra.extend(self.encode(&mut encoder, &view, &jobs, &screen));
        }
        let shot = capture.map(|path| {
            let texture = self.device.create_texture(&wgpu::TextureDescriptor {
                label: Some("screenshot"),
                size: wgpu::Extent3d {
                    width: self.config.width,
                    height: self.config.height,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: self.config.format,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            });
            let view = texture.create_view(&Default::default());
            extra.extend(self.encode(&mut encoder, &view, &jobs, &screen));
            let row = (self.config.width * 4).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
            let buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("screenshot read-back"),
                size: u64::from(row) * u64::from(self.config.height),
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            encoder.copy_texture_to_buffer(
                texture.as_image_copy(),
                wgpu::TexelCopyBufferInfo {
                    buffer: &buffer,
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(row),
                        rows_per_image: None,
                    },
                },
                texture.size(),
            );
            (path, buffer, row)
        });
        extra.push(encoder.finish());
        self.queue.submit(extra);
        if let Some(frame) = frame {
            self.window.pre_present_notify();
            self.queue.present(frame);
        }
        for id in &output.textures_delta.free {
            self.egui_renderer.free_texture(id);
        }
        if let Some((path, buffer, row)) = shot {
            self.write_screenshot(&path, &buffer, row)?;
        }
        Ok(())
    }

    /// Records the panes, then the panel over them, into `view`.
    fn encode(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        view: &wgpu::TextureView,
        jobs: &[egui::ClippedPrimitive],
        screen: &egui_wgpu::ScreenDescriptor,
    ) -> Vec<wgpu::CommandBuffer> {
        let uploads =
            self.egui_renderer
                .update_buffers(&self.device, &self.queue, encoder, jobs, screen);
        let attachment = |load| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load,
                    store: wgpu::StoreOp::Store,
                },
            })
        };
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("panes"),
                color_attachments: &[attachment(wgpu::LoadOp::Clear(wgpu::Color {
                    r: 0.02,
                    g: 0.02,
                    b: 0.02,
                    a: 1.0,
                }))],
                ..Default::default()
            });
            self.display.draw(
                &self.queue,
                &mut pass,
                (self.config.width, self.config.height),
                self.settings.exposure,
                self.settings.heat,
            );
        }
        let mut pass = encoder
            .begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("panel"),
                color_attachments: &[attachment(wgpu::LoadOp::Load)],
                ..Default::default()
            })
            .forget_lifetime();
        self.egui_renderer.render(&mut pass, jobs, screen);
        uploads
    }

    fn write_screenshot(
        &self,
        path: &std::path::Path,
        buffer: &wgpu::Buffer,
        row: u32,
    ) -> Result<()> {
        let (tx, rx) = mpsc::channel();
        buffer.map_async(wgpu::MapMode::Read, .., move |r| {
            let _ = tx.send(r);
        });
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| anyhow!("screenshot: {e}"))?;
        rx.recv()
            .map_err(|_| anyhow!("screenshot: the read-back never finished"))?
            .map_err(|e| anyhow!("screenshot: {e}"))?;
        let data = buffer
            .get_mapped_range(..)
            .map_err(|e| anyhow!("screenshot: {e}"))?;
        let (w, h) = (self.config.width, self.config.height);
        let bgra = self.config.format == wgpu::TextureFormat::Bgra8Unorm;
        let mut rgb = Vec::with_capacity((w * h * 3) as usize);
        for y in 0..h as usize {
            let line = &data[y * row as usize..][..w as usize * 4];
            for px in line.chunks_exact(4) {
                match bgra {
                    true => rgb.extend([px[2], px[1], px[0]]),
                    false => rgb.extend([px[0], px[1], px[2]]),
                }
            }
        }
        drop(data);
        buffer.unmap();
        write_png_rgb(path, &rgb, w, h)
            .with_context(|| format!("{}: cannot write the screenshot", path.display()))?;
        eprintln!("screenshot: {}", path.display());
        Ok(())
    }

    /// Sends what the panel changed to the render thread.
    fn apply(&mut self, actions: panel::Actions) {
        if actions.tune {
            let _ = self.commands.send(Command::Tune {
                photons_per_pass: self.settings.photons_per_pass,
                alpha: self.settings.alpha,
            });
        }
        if actions.mode {
            let _ = self.commands.send(Command::Mode(self.settings.mode));
        }
        if actions.heat {
            let _ = self.commands.send(Command::Heat(self.settings.heat));
        }
        if actions.save {
            let _ = self.commands.send(Command::Save);
        }
        if actions.undo {
            self.undo_move();
        }
    }

    /// The figures a session produced: first image, move latencies, iterations per second.
    fn report_timing(&self) {
        if !self.latencies.is_empty() {
            let mean = self.latencies.iter().sum::<f64>() / self.latencies.len() as f64;
            let max = self.latencies.iter().copied().fold(0.0, f64::max);
            eprintln!(
                "moves on screen after {mean:.0} ms on average, {max:.0} ms at most ({} moves)",
                self.latencies.len()
            );
        }
        for i in 0..self.shared.panes.len() {
            let view = self.shared.pane(i);
            let s = &view.stats;
            eprintln!(
                "pane {i} ({}): {} iterations in {:.2}s of rendering, {:.1} iterations/s",
                view.mode.name(),
                s.iterations,
                s.seconds,
                f64::from(s.iterations) / s.seconds.max(1e-9)
            );
        }
    }
}

/// The image point under window position `at`, if one of the `panes` is there (every pane
/// shows the same camera).
fn pane_point(display: &Display, panes: usize, at: PhysicalPosition<f64>) -> Option<(f32, f32)> {
    let (w, h) = display.size();
    let (w, h) = (f64::from(w), f64::from(h));
    if at.x < 0.0 || at.y < 0.0 || at.x >= w * panes as f64 || at.y >= h {
        return None;
    }
    Some(((at.x % w) as f32, at.y as f32))
}

/// The camera and its look-at point moved together across the view, so that the scene
/// follows the cursor: `dx`, `dy` pixels of drag in a pane `height` pixels high.
fn pan_by(camera: &Camera, dx: f32, dy: f32, height: u32) -> Camera {
    let forward = camera.look_at - camera.eye;
    let right = forward.cross(camera.up).normalize_or_zero();
    let up = right.cross(forward).normalize_or_zero();
    // The size of a pixel at the look-at point's depth.
    let pixel =
        2.0 * forward.length() * (camera.fov_deg.to_radians() * 0.5).tan() / height.max(1) as f32;
    let shift = (-dx * right + dy * up) * pixel;
    Camera {
        eye: camera.eye + shift,
        look_at: camera.look_at + shift,
        ..camera.clone()
    }
}

/// The camera turned about its look-at point: `dx` about the up axis, `dy` about its right
/// axis (pixels of drag; 0.3 degrees each), never over the pole.
fn orbit(camera: &Camera, dx: f32, dy: f32) -> Camera {
    let up = camera.up.normalize();
    let offset = camera.eye - camera.look_at;
    let right = offset.cross(up).normalize_or_zero();
    let step = 0.3f32.to_radians();
    let turned = Quat::from_axis_angle(up, -dx * step) * offset;
    let tilted = Quat::from_axis_angle(right, dy * step) * turned;
    // Keep at least 5 degrees from the up axis.
    let offset = if tilted.normalize().dot(up).abs() < 5f32.to_radians().cos() {
        tilted
    } else {
        turned
    };
    Camera {
        eye: camera.look_at + offset,
        ..camera.clone()
    }
}
