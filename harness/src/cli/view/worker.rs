//! The render thread: runs the panes' iterations off the UI thread, so that the window never
//! freezes during a move; takes the window's commands between iterations (moves that queue
//! up while another runs are merged into one); plays the script; and hands every new image to
//! the window.

use crate::cli::render::{OutputPaths, write_render};
use crate::driver::{MoveReport, Renderer};
use backend_wgpu::WgpuBackend;
use ppm_core::image::Image;
use ppm_core::layout::HitPoint;
use ppm_core::params::{MoveMode, MoveParams, RenderParams};
use ppm_core::passes::{Backend, BackendError};
use ppm_core::scene::path::After;
use ppm_core::scene::{Camera, Move, Scene};
use ppm_core::{camera_move, device_time};
use scenes::file::path::{Script, ScriptEvent};
use std::sync::mpsc::{Receiver, TryRecvError};
use std::sync::{Mutex, MutexGuard};
use std::time::{Duration, Instant};

/// What the window asks of the render thread.
pub enum Command {
    /// Rigid moves of the current pose, in order; `at` is when the user made them.
    Move { moves: Vec<Move>, at: Instant },
    /// Back to an earlier pose (undo).
    Pose { scene: Box<Scene>, at: Instant },
    /// A new camera: every pane starts over.
    Camera(Camera),
    /// The mode of the next moves (a single pane's; a comparison keeps its two).
    Mode(MoveMode),
    /// Photons per iteration and alpha of the later iterations.
    Tune { photons_per_pass: u32, alpha: f32 },
    /// Compute the heat map of each move's resets (it costs a read-back of the slots).
    Heat(bool),
    /// Write every pane's image and report now.
    Save,
    /// Write every pane's image and report, and stop.
    Quit,
}

/// What the render thread tells the window (through the event loop).
#[derive(Debug)]
pub enum UiEvent {
    /// New images are ready.
    Frame,
    /// Draw, read back and write screenshot `n` (counted from 0 in the script's order), then
    /// answer on the acknowledgement channel.
    Screenshot(usize),
    /// The render thread has written its files and stopped.
    Finished,
}

/// Milliseconds of the last iteration, per pass.
#[derive(Clone, Copy, Debug, Default)]
pub struct IterationTimes {
    pub eye: f64,
    pub direct: f64,
    pub photon: f64,
    pub gather: f64,
    /// Resolving the image and handing it to the window.
    pub resolve: f64,
    pub total: f64,
}

/// What the panel shows of a pane.
#[derive(Clone, Debug, Default)]
pub struct PaneStats {
    pub iterations: u32,
    /// Seconds of rendering (iterations and moves) since the window opened.
    pub seconds: f64,
    pub photons_per_second: f64,
    pub last_iteration: IterationTimes,
    /// Milliseconds the device spent per pass since the last figures (the last iteration and
    /// any move before it), where it measures them.
    pub device_ms: Option<Vec<(String, f64)>>,
    pub last_move: Option<MoveReport>,
    /// Milliseconds from a move's request to its first image on screen.
    pub last_latency_ms: Option<f64>,
    /// Why the pane stopped, if a pass failed.
    pub error: Option<String>,
    /// What the last command did that the user should know (a restart).
    pub note: Option<String>,
}

/// What a pane shares with the window.
pub struct PaneView {
    pub mode: MoveMode,
    pub backend: String,
    pub stats: PaneStats,
    /// A CPU pane's newest image, not yet uploaded.
    pub image: Option<Image>,
    /// The newest heat map, not yet uploaded.
    pub resets: Option<Vec<f32>>,
    /// When the move now on this pane's newest image was requested.
    pub moved_at: Option<Instant>,
}

impl PaneView {
    /// A pane rendering in `mode` on the backend named `backend`, nothing shown yet.
    pub fn new(mode: MoveMode, backend: &str) -> Self {
        Self {
            mode,
            backend: backend.to_owned(),
            stats: PaneStats::default(),
            image: None,
            resets: None,
            moved_at: None,
        }
    }
}

/// State shared by the render thread and the window.
pub struct Shared {
    pub panes: Vec<Mutex<PaneView>>,
    /// The pose the render thread stands in (picking starts from it).
    pub pose: Mutex<Scene>,
}

impl Shared {
    pub fn pane(&self, i: usize) -> MutexGuard<'_, PaneView> {
        self.panes[i].lock().unwrap_or_else(|p| p.into_inner())
    }

    pub fn pose(&self) -> Scene {
        self.pose.lock().unwrap_or_else(|p| p.into_inner()).clone()
    }

    /// The current camera (without copying the scene).
    pub fn camera(&self) -> Camera {
        self.pose
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .camera
            .clone()
    }
}

/// What to render and where to write it: the command line's part of [`Setup`].
pub struct Plan {
    /// One pane per mode.
    pub modes: Vec<MoveMode>,
    pub scene: Scene,
    pub params: RenderParams,
    pub moves: MoveParams,
    pub script: Option<Script>,
    pub exit_after: bool,
    pub outputs: Vec<OutputPaths>,
    pub exposure: f32,
    /// Compute the heat map of each move's resets from the start.
    pub heat_map: bool,
}

/// Everything the render thread needs: the plan, and per pane a backend (started on the
/// window's device for wgpu) and the device buffer a wgpu pane resolves into (`None`: the
/// CPU image is handed over).
pub struct Setup {
    pub plan: Plan,
    pub backends: Vec<Box<dyn Backend + Send>>,
    pub targets: Vec<Option<wgpu::Buffer>>,
}

/// The channels the render thread listens on.
pub struct Inbox {
    pub commands: Receiver<Command>,
    /// One message per screenshot written.
    pub screenshots: Receiver<()>,
}

/// A wgpu pane keeps a host copy of its image this often, so that a lost device loses no
/// more than this much of the render.
const HOST_COPY_EVERY: Duration = Duration::from_secs(2);

struct Pane<'a> {
    renderer: Renderer<'a>,
    mode: MoveMode,
    target: Option<wgpu::Buffer>,
    /// Seconds rendered: a comparison gives the next iteration to the pane with fewer.
    spent: f64,
    iterations_since_event: u32,
    last_image: Option<Image>,
    last_copy: Instant,
    /// The pass error that stopped the pane, if one did.
    error: Option<String>,
    /// Whether a move ran (the report's `left_out` then keeps the compensation passes).
    moved: bool,
    /// Whether the renderer was told that local moves will follow
    /// ([`Renderer::expect_local_moves`]): once the pane has shown its first images in local
    /// mode.
    expecting: bool,
    previous_times: crate::report::PassTimes,
    previous_device_times: Vec<ppm_core::device_time::DeviceTime>,
}

/// Runs the panes until told to quit (or until the script ends, with `exit_after`), then
/// writes every pane's render. `wake` hands the window an event.
pub fn run(
    setup: Setup,
    shared: &Shared,
    inbox: &Inbox,
    wake: &dyn Fn(UiEvent),
) -> anyhow::Result<()> {
    let Setup {
        plan,
        mut backends,
        targets,
    } = setup;
    let Plan {
        modes,
        scene,
        params,
        moves,
        script,
        exit_after,
        outputs,
        exposure,
        heat_map,
    } = plan;
    let out = Outputs {
        paths: outputs,
        exposure,
    };
    let mut panes = Vec::new();
    for ((backend, target), mode) in backends.iter_mut().zip(targets).zip(modes) {
        let renderer = Renderer::start(backend.as_mut(), scene.at_frame(0), &params, &moves)?;
        panes.push(Pane {
            renderer,
            mode,
            moved: false,
            expecting: false,
            target,
            spent: 0.0,
            iterations_since_event: 0,
            last_image: None,
            last_copy: Instant::now(),
            error: None,
            previous_times: Default::default(),
            previous_device_times: Vec::new(),
        });
    }
    let mut player = script.map(|s| (s.events, 0usize));
    let mut screenshots = 0;
    let mut heat = heat_map;
    // Rendering time since the script's last event (screenshots wait before it restarts).
    let mut event_clock = Instant::now();
    let mut quit = false;
    while !quit {
        // The window's commands, merged: every queued move becomes one move of each pane.
        let mut batch = Batch::default();
        loop {
            match inbox.commands.try_recv() {
                Ok(c) => batch.take(c),
                Err(TryRecvError::Empty) => break,
                Err(TryRecvError::Disconnected) => {
                    batch.quit = true;
                    break;
                }
            }
        }
        quit = batch.quit;
        if let Some(mode) = batch.mode
            && panes.len() == 1
        {
            panes[0].mode = mode;
            shared.pane(0).mode = mode;
        }
        if let Some(on) = batch.heat {
            heat = on;
        }
        if let Some((photons, alpha)) = batch.tune {
            for (i, pane) in panes.iter_mut().enumerate() {
                let note = match pane.renderer.retune(photons, alpha) {
                    Ok(()) => format!("{photons} photons per iteration, alpha {alpha}"),
                    Err(e) => format!("refused: {e}"),
                };
                shared.pane(i).stats.note = Some(note);
            }
        }
        if batch.moved() {
            move_panes(
                &mut panes,
                shared,
                &batch.moves,
                batch.pose.take(),
                heat,
                batch.at,
            );
        }
        if let Some(camera) = batch.camera {
            look_from(&mut panes, shared, camera, heat);
        }
        if batch.save || quit {
            save(&mut panes, &out, quit)?;
        }
        if quit {
            break;
        }
        // The script's next event, once every pane has rendered what it waits for.
        if let Some((events, next)) = &mut player {
            let due = match events[*next].after {
                After::Iterations(n) => panes
                    .iter()
                    .all(|p| p.error.is_some() || p.iterations_since_event >= n),
                After::Seconds(s) => event_clock.elapsed().as_secs_f64() >= s,
            };
            if due {
                let event = events[*next].clone();
                *next += 1;
                play(&mut panes, shared, &event, heat, inbox, wake, screenshots);
                screenshots += usize::from(event.screenshot);
                for pane in &mut panes {
                    pane.iterations_since_event = 0;
                }
                event_clock = Instant::now();
                if *next == events.len() {
                    player = None;
                    if exit_after {
                        save(&mut panes, &out, false)?;
                        break;
                    }
                }
                continue;
            }
        }
        // One iteration of the pane that has rendered least (and still needs iterations
        // before the script's next event).
        let waiting_for = match &player {
            Some((events, next)) => match events[*next].after {
                After::Iterations(n) => Some(n),
                After::Seconds(_) => None,
            },
            None => None,
        };
        let next = panes
            .iter()
            .enumerate()
            .filter(|(_, p)| {
                p.error.is_none() && waiting_for.is_none_or(|n| p.iterations_since_event < n)
            })
            .min_by(|a, b| a.1.spent.total_cmp(&b.1.spent))
            .map(|(i, _)| i);
        let Some(i) = next else {
            // Every pane failed: wait for the window to close.
            std::thread::sleep(Duration::from_millis(20));
            continue;
        };
        let t = Instant::now();
        let result = panes[i].renderer.iteration();
        panes[i].spent += t.elapsed().as_secs_f64();
        let t = Instant::now();
        match result.and_then(|()| present(&mut panes[i], shared, i)) {
            Ok(()) => {
                panes[i].iterations_since_event += 1;
                update_stats(&mut panes[i], shared, i, t.elapsed().as_secs_f64());
            }
            Err(e) => fail(&mut panes[i], shared, i, &e),
        }
        wake(UiEvent::Frame);
        // What a first move needs is prepared once the pane has shown an image and rendered
        // the next (the window draws the first meanwhile), not at the first drag.
        let pane = &mut panes[i];
        let shown = pane.renderer.report().passes >= 2;
        if pane.mode == MoveMode::Local && shown && !pane.expecting && pane.error.is_none() {
            pane.expecting = true;
            if let Err(e) = pane.renderer.expect_local_moves() {
                fail(pane, shared, i, &e);
            }
        }
    }
    wake(UiEvent::Finished);
    Ok(())
}

/// The window's commands since the last iteration, merged.
#[derive(Default)]
struct Batch {
    moves: Vec<Move>,
    pose: Option<Scene>,
    /// When the first merged move was requested.
    at: Option<Instant>,
    camera: Option<Camera>,
    mode: Option<MoveMode>,
    tune: Option<(u32, f32)>,
    heat: Option<bool>,
    save: bool,
    quit: bool,
}

impl Batch {
    fn take(&mut self, command: Command) {
        match command {
            Command::Move { moves, at } => {
                self.moves.extend(moves);
                self.at.get_or_insert(at);
            }
            Command::Pose { scene, at } => {
                // An earlier pose replaces the moves queued before it.
                self.moves.clear();
                self.pose = Some(*scene);
                self.at.get_or_insert(at);
            }
            Command::Camera(c) => self.camera = Some(c),
            Command::Mode(m) => self.mode = Some(m),
            Command::Tune {
                photons_per_pass,
                alpha,
            } => self.tune = Some((photons_per_pass, alpha)),
            Command::Heat(on) => self.heat = Some(on),
            Command::Save => self.save = true,
            Command::Quit => self.quit = true,
        }
    }

    fn moved(&self) -> bool {
        !self.moves.is_empty() || self.pose.is_some()
    }
}

/// Moves every pane (each in its mode) to `pose` (or the current pose), then by `moves`.
fn move_panes(
    panes: &mut [Pane],
    shared: &Shared,
    moves: &[Move],
    pose: Option<Scene>,
    heat: bool,
    at: Option<Instant>,
) {
    // Without a pose of its own, only the moved objects may differ from the current pose.
    let moved: Vec<usize> = moves.iter().map(|m| m.object).collect();
    let candidates = pose.is_none().then_some(&moved[..]);
    let mut next = pose.unwrap_or_else(|| panes[0].renderer.scene().clone());
    for m in moves {
        // The window only sends moves of objects it picked; one the pose cannot take (a
        // drag far outside the scene) is dropped, not applied half-way.
        if next.check_move(m).is_ok() {
            next.apply(m);
        }
    }
    for (i, pane) in panes.iter_mut().enumerate() {
        if pane.error.is_some() {
            continue;
        }
        let before = heat.then(|| pane.renderer.backend().read_hit_points());
        let t = Instant::now();
        let moved = pane
            .renderer
            .move_among(next.clone(), pane.mode, candidates);
        pane.spent += t.elapsed().as_secs_f64();
        pane.moved = true;
        let moved = moved.and_then(|report| {
            let resets = match before {
                Some(before) => Some(reset_share(
                    &before?,
                    &pane.renderer.backend().read_hit_points()?,
                    pane.renderer.params().width as usize * pane.renderer.params().height as usize,
                )),
                None => None,
            };
            present(pane, shared, i)?;
            Ok((report, resets))
        });
        match moved {
            Ok((report, resets)) => {
                let mut view = shared.pane(i);
                view.stats.note = report
                    .restarted
                    .as_ref()
                    .map(|why| format!("the move restarted: {why}"));
                view.stats.last_move = Some(report);
                view.moved_at = at;
                if resets.is_some() {
                    view.resets = resets;
                }
            }
            Err(e) => fail(pane, shared, i, &e),
        }
    }
    *shared.pose.lock().unwrap_or_else(|p| p.into_inner()) = next;
}

/// Per pixel, the share of its slots the move reset: slots that held statistics (photons
/// or iterations) and hold none after it. A restart (the slots not traced yet) resets all.
fn reset_share(before: &[HitPoint], after: &[HitPoint], pixels: usize) -> Vec<f32> {
    if after.len() != before.len() {
        return vec![1.0; pixels];
    }
    share_per_pixel(before.iter().zip(after), pixels, |(a, b)| {
        let held = a.n > 0.0 || a.iterations > 0;
        (b.pixel, held && b.n == 0.0 && b.iterations == 0)
    })
}

/// Per pixel, the share of its slots for which `test` (giving the slot's pixel and whether
/// it counts) says yes.
fn share_per_pixel<T>(
    slots: impl Iterator<Item = T>,
    pixels: usize,
    test: impl Fn(T) -> (u32, bool),
) -> Vec<f32> {
    let mut yes = vec![0.0f32; pixels];
    let mut all = vec![0.0f32; pixels];
    for slot in slots {
        let (p, counts) = test(slot);
        let p = p as usize;
        if p < pixels {
            all[p] += 1.0;
            yes[p] += f32::from(u8::from(counts));
        }
    }
    for (y, a) in yes.iter_mut().zip(&all) {
        *y /= a.max(1.0);
    }
    yes
}

/// Every pane moves its camera to `camera` the way its mode says (local mode keeps the light
/// of what is still seen, docs/algorithm.md 3d), then renders one iteration of the new view,
/// and says what it kept; with `heat`, the heat map shows the slots that started over.
fn look_from(panes: &mut [Pane], shared: &Shared, camera: Camera, heat: bool) {
    for (i, pane) in panes.iter_mut().enumerate() {
        if pane.error.is_some() {
            continue;
        }
        // One iteration at once: the new view replaces the old one on screen now.
        let t = Instant::now();
        let moved = pane.renderer.move_camera(camera.clone(), pane.mode);
        let resets = match (&moved, heat) {
            (Ok(_), true) => Some(pane.renderer.backend().read_hit_points().map(|after| {
                let pixels = pane.renderer.params().width * pane.renderer.params().height;
                started_over(&after, pixels as usize)
            })),
            _ => None,
        };
        let moved = moved.and_then(|report| {
            pane.renderer.iteration()?;
            Ok(report)
        });
        pane.spent += t.elapsed().as_secs_f64();
        pane.moved = true;
        let shown = moved.and_then(|report| {
            present(pane, shared, i)?;
            Ok((report, resets.transpose()?))
        });
        match shown {
            Ok((report, resets)) => {
                pane.iterations_since_event = 0;
                let mut view = shared.pane(i);
                view.stats.note = Some(match &report.restarted {
                    Some(why) => format!("the camera moved: the render started over ({why})"),
                    None => format!(
                        "the camera moved: {} slots kept their light, {} started over",
                        report.kept, report.updated
                    ),
                });
                view.stats.last_move = Some(report);
                if resets.is_some() {
                    view.resets = resets;
                }
            }
            Err(e) => fail(pane, shared, i, &e),
        }
    }
    let mut pose = shared.pose.lock().unwrap_or_else(|p| p.into_inner());
    pose.camera = camera;
}

/// Per pixel, the share of its slots a camera move started over.
fn started_over(after: &[HitPoint], pixels: usize) -> Vec<f32> {
    share_per_pixel(after.iter(), pixels, |hp| {
        (hp.pixel, camera_move::started_over(hp))
    })
}

/// Plays one script event: its moves, its camera, then its screenshot (waiting until the
/// window has written it).
fn play(
    panes: &mut [Pane],
    shared: &Shared,
    event: &ScriptEvent,
    heat: bool,
    inbox: &Inbox,
    wake: &dyn Fn(UiEvent),
    screenshot: usize,
) {
    if !event.moves.is_empty() {
        move_panes(
            panes,
            shared,
            &event.moves,
            None,
            heat,
            Some(Instant::now()),
        );
    }
    if let Some(c) = event.camera {
        let mut camera = panes[0].renderer.scene().camera.clone();
        camera.eye = c.eye;
        camera.look_at = c.look_at;
        look_from(panes, shared, camera, heat);
    }
    if event.screenshot {
        for (i, pane) in panes.iter_mut().enumerate() {
            if pane.error.is_none()
                && let Err(e) = present(pane, shared, i)
            {
                fail(pane, shared, i, &e);
            }
        }
        wake(UiEvent::Screenshot(screenshot));
        // The window answers once the file is written (or drops the channel on exit).
        let _ = inbox.screenshots.recv();
    } else {
        wake(UiEvent::Frame);
    }
}

/// Puts the pane's current image where the window draws it: resolved on the device into its
/// buffer (wgpu), or resolved on the host and handed over (CPU).
fn present(pane: &mut Pane, shared: &Shared, i: usize) -> Result<(), BackendError> {
    if !pane.renderer.has_image() {
        return Ok(());
    }
    let params = pane.renderer.resolve_params();
    let on_device = match &pane.target {
        Some(target) => {
            let backend = pane
                .renderer
                .backend()
                .as_any_mut()
                .and_then(|b| b.downcast_mut::<WgpuBackend>());
            match backend {
                Some(wgpu) => {
                    wgpu.resolve_into(&params, target)?;
                    true
                }
                None => false,
            }
        }
        None => false,
    };
    if on_device {
        if pane.last_copy.elapsed() >= HOST_COPY_EVERY || pane.last_image.is_none() {
            pane.last_image = Some(pane.renderer.resolve()?);
            pane.last_copy = Instant::now();
        }
    } else {
        let image = pane.renderer.resolve()?;
        shared.pane(i).image = Some(image.clone());
        pane.last_image = Some(image);
    }
    Ok(())
}

/// The panel's figures after an iteration whose image took `present` seconds to hand over.
fn update_stats(pane: &mut Pane, shared: &Shared, i: usize, present: f64) {
    let report = pane.renderer.report();
    let (now, before) = (&report.times, &pane.previous_times);
    let ms = |a: f64, b: f64| (a - b) * 1e3;
    let times = IterationTimes {
        eye: ms(now.eye, before.eye),
        direct: ms(now.direct, before.direct),
        photon: ms(now.photon, before.photon),
        gather: ms(now.gather, before.gather),
        resolve: present * 1e3,
        total: 0.0,
    };
    let total = times.eye + times.direct + times.photon + times.gather + times.resolve;
    let mut view = shared.pane(i);
    view.stats.iterations = report.passes;
    view.stats.seconds = pane.spent;
    view.stats.photons_per_second = report.photons_emitted as f64 / pane.spent.max(1e-9);
    view.stats.last_iteration = IterationTimes { total, ..times };
    pane.previous_times = report.times.clone();
    view.stats.device_ms = report.device_times.as_ref().map(|now| {
        let ran = device_time::since(now, &pane.previous_device_times);
        pane.previous_device_times = now.clone();
        device_time::per_pass(&ran)
            .into_iter()
            .map(|(pass, s)| (pass, s * 1e3))
            .collect()
    });
}

fn fail(pane: &mut Pane, shared: &Shared, i: usize, e: &BackendError) {
    pane.error = Some(e.to_string());
    eprintln!("pane {i}: stopped: {e}");
    shared.pane(i).stats.error = Some(e.to_string());
}

/// Where the panes' renders go.
struct Outputs {
    /// Per pane.
    paths: Vec<OutputPaths>,
    /// Of the PNG previews.
    exposure: f32,
}

/// Writes every pane's image, PNG preview and report as `ppm render` does (`interrupted`
/// when the window closed before the end).
fn save(panes: &mut [Pane], out: &Outputs, interrupted: bool) -> anyhow::Result<()> {
    for (pane, paths) in panes.iter_mut().zip(&out.paths) {
        let image = match pane.error.is_some() {
            true => pane.last_image.clone(),
            false => match pane.renderer.resolve() {
                Ok(image) => Some(image),
                Err(e) => {
                    eprintln!("cannot resolve the image ({e}); writing the last one shown");
                    pane.last_image.clone()
                }
            },
        };
        let Some(image) = image else {
            eprintln!("{}: nothing rendered yet", paths.exr.display());
            continue;
        };
        let mut report = pane.renderer.final_report(pane.moved);
        report.interrupted = interrupted;
        report.times.total = pane.spent;
        report.error = pane.error.clone();
        println!(
            "{} ({}, {}): {} iterations, {:.2}s -> {}",
            report.scene,
            pane.mode.name(),
            report.backend,
            report.passes,
            pane.spent,
            paths.exr.display()
        );
        write_render(image, report, paths, out.exposure)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A pixel's heat is the share of its slots the move reset: those that held photons or
    /// iterations and hold neither after it; a restart resets every pixel.
    #[test]
    fn heat_is_the_share_of_each_pixels_slots_reset() {
        let slot = |pixel: u32, n: f32, iterations: u32| HitPoint {
            n,
            iterations,
            ..HitPoint::empty(pixel)
        };
        let before = [
            slot(0, 5.0, 9),
            slot(0, 5.0, 9),
            slot(1, 0.0, 1),
            slot(2, 0.0, 0),
            slot(3, 5.0, 9),
        ];
        let after = [
            slot(0, 0.0, 0),
            slot(0, 3.0, 9),
            slot(1, 0.0, 0),
            slot(2, 0.0, 0),
            slot(3, 5.0, 0),
        ];
        assert_eq!(reset_share(&before, &after, 4), vec![0.5, 1.0, 0.0, 0.0]);
        assert_eq!(reset_share(&before, &[], 2), vec![1.0, 1.0]);
    }
}
