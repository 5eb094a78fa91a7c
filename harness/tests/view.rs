//! `ppm view` in a real window, on a virtual X server (Xvfb) and lavapipe: a screenshot
//! matches `ppm render`, a scripted drag shows the new pose and not the old one, a comparison
//! shows both modes, a close writes the render, and a missing display is a clear error.
//!
//! Without Xvfb or a wgpu adapter these tests show as ignored, unless `PPM_REQUIRE_WGPU=1` (as CI
//! sets it, with Xvfb installed by `.ci/run`) turns that into a failure.

mod common;

use backend_cpu::CpuBackend;
use glam::Vec3;
use harness::driver::{Budget, Schedule, run};
use ppm_core::image::Image;
use ppm_core::metrics::block_relative_rmse;
use ppm_core::params::{MoveParams, RenderParams};
use ppm_core::scene::{Move, Scene};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::process::{Child, Command, Output, Stdio};
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::{Duration, Instant};
use test_support::{Need, Suite, figure};

/// Image size of every test: small, so that lavapipe and two cores render it in seconds.
const SIZE: u32 = 64;

/// A virtual X server of this test's own, stopped when dropped.
struct VirtualDisplay {
    server: Child,
    display: String,
}

impl VirtualDisplay {
    /// Starts Xvfb on a free display number (the suite has checked that it is installed).
    fn start() -> Self {
        static NEXT: AtomicU32 = AtomicU32::new(0);
        for _ in 0..50 {
            let n = 140 + (std::process::id() % 400) + NEXT.fetch_add(1, Ordering::SeqCst);
            if Path::new(&format!("/tmp/.X{n}-lock")).exists() {
                continue;
            }
            let mut server = Command::new("Xvfb")
                .args([
                    &format!(":{n}"),
                    "-screen",
                    "0",
                    "1024x768x24",
                    "-nolisten",
                    "tcp",
                ])
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .spawn()
                .expect("Xvfb starts");
            let socket = PathBuf::from(format!("/tmp/.X11-unix/X{n}"));
            let start = Instant::now();
            while start.elapsed() < Duration::from_secs(10) {
                if socket.exists() {
                    return Self {
                        server,
                        display: format!(":{n}"),
                    };
                }
                if let Ok(Some(_)) = server.try_wait() {
                    break;
                }
                std::thread::sleep(Duration::from_millis(50));
            }
            let _ = server.kill();
            let _ = server.wait();
        }
        panic!("no free display for Xvfb");
    }

    fn ppm(&self, args: &[&str]) -> Command {
        let mut c = Command::new(env!("CARGO_BIN_EXE_ppm"));
        c.args(args)
            .env("DISPLAY", &self.display)
            .env_remove("WAYLAND_DISPLAY");
        c
    }
}

impl Drop for VirtualDisplay {
    fn drop(&mut self) {
        let _ = self.server.kill();
        let _ = self.server.wait();
    }
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("ppm-view-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn checked(out: Output, what: &str) -> Output {
    assert!(
        out.status.success(),
        "{what} failed: {}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// Runs `ppm view` on cornell-box at [`SIZE`] with `script`, screenshots in `dir/shots`.
fn view(display: &VirtualDisplay, dir: &Path, backend: &str, script: &str, extra: &[&str]) {
    let path = dir.join("script.toml");
    std::fs::write(&path, script).unwrap();
    let size = SIZE.to_string();
    let mut args = vec![
        "view",
        "cornell-box",
        "--backend",
        backend,
        "--width",
        &size,
        "--height",
        &size,
        "--exit-after",
    ];
    let (script, shots, out) = (
        path.display().to_string(),
        dir.join("shots").display().to_string(),
        dir.join("view.exr").display().to_string(),
    );
    args.extend(["--script", &script, "--screenshot-dir", &shots, "-o", &out]);
    args.extend(extra);
    checked(display.ppm(&args).output().unwrap(), "ppm view");
}

/// An 8-bit sRGB PNG as linear RGB, with its size.
fn read_png(path: &Path) -> (Vec<[f32; 3]>, u32, u32) {
    let decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())),
    ));
    let mut reader = decoder.read_info().unwrap();
    let mut bytes = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut bytes).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb, "{}", path.display());
    let linear = |b: u8| {
        let v = f32::from(b) / 255.0;
        if v <= 0.04045 {
            v / 12.92
        } else {
            ((v + 0.055) / 1.055).powf(2.4)
        }
    };
    let pixels = bytes[..(info.width * info.height * 3) as usize]
        .chunks_exact(3)
        .map(|p| [linear(p[0]), linear(p[1]), linear(p[2])])
        .collect();
    (pixels, info.width, info.height)
}

/// The `SIZE` x `SIZE` pane `pane` of a screenshot (panes sit side by side from the top-left
/// corner).
fn pane(shot: &Path, pane: u32) -> Image {
    let (pixels, width, height) = read_png(shot);
    assert!(
        width >= SIZE * (pane + 1) && height >= SIZE,
        "{width}x{height}"
    );
    let mut image = Image::new(SIZE, SIZE);
    for y in 0..SIZE {
        for x in 0..SIZE {
            image.pixels[(y * SIZE + x) as usize] = pixels[(y * width + pane * SIZE + x) as usize];
        }
    }
    image
}

/// The PNG of `ppm render` as linear RGB: what the viewer must show.
fn png_image(path: &Path) -> Image {
    let (pixels, width, height) = read_png(path);
    Image {
        width,
        height,
        pixels,
    }
}

/// cornell-box in a pose, rendered for `iterations` on the CPU, as the truth of that pose at
/// this size (quantised as the screenshots are, through the same PNG encoding).
fn rendered(scene: &Scene, iterations: u32, dir: &Path, name: &str) -> Image {
    let mut params = RenderParams::for_scene(scene);
    params.width = SIZE;
    params.height = SIZE;
    let outcome = run(
        &mut CpuBackend::new(),
        scene,
        &params,
        &MoveParams::default(),
        &Schedule::frame(0, Budget::iterations(iterations)),
        &mut (),
    )
    .unwrap();
    let path = dir.join(format!("{name}.png"));
    use scenes::file::image::ImageFiles;
    outcome.image.write_png(&path, 1.0).unwrap();
    png_image(&path)
}

/// The window's screenshot after 6 iterations on `backend` is `ppm render`'s image of the same
/// 6, up to the 8-bit encoding.
fn a_screenshot_matches_ppm_render(backend: &str) {
    let display = VirtualDisplay::start();
    let dir = scratch(&format!("matches-{backend}"));
    view(
        &display,
        &dir,
        backend,
        "[[step]]\nafter_iterations = 6\nscreenshot = true\n",
        &[],
    );
    let render = dir.join("render.exr");
    let size = SIZE.to_string();
    checked(
        display
            .ppm(&[
                "render",
                "cornell-box",
                "--backend",
                backend,
                "--width",
                &size,
                "--height",
                &size,
                "--passes",
                "6",
                "-o",
                &render.display().to_string(),
            ])
            .output()
            .unwrap(),
        "ppm render",
    );
    let shown = pane(&dir.join("shots/screenshot-000.png"), 0);
    let expected = png_image(&render.with_extension("png"));
    let error = block_relative_rmse(&shown, &expected, 8);
    figure!("{backend}: screenshot against ppm render, 8x8 block relative rmse {error:.5}");
    // Same seed, same backend, same iterations: only the 8-bit encoding may differ.
    assert!(error < 0.005, "{backend}: {error}");
    // The render the window wrote on exit is the render's too.
    let json = std::fs::read_to_string(dir.join("view.json")).unwrap();
    assert!(json.contains("\"interrupted\": false"), "{json}");
    assert!(json.contains("\"passes\": 6"), "{json}");
}

/// The short block dragged in five small steps: the screenshot after the drag shows the new
/// pose (it is closer to a long render of the new pose than of the old one, by far).
fn a_scripted_drag_moves_the_object_on_screen(backend: &str) {
    let display = VirtualDisplay::start();
    let step = Vec3::new(-10.0, 0.0, -10.0);
    let mut script = String::from("[[step]]\nafter_iterations = 10\nscreenshot = true\n");
    for _ in 0..5 {
        script += "[[step]]\nafter_iterations = 1\nobject = \"short-block\"\ntranslate = [-10.0, 0.0, -10.0]\n";
    }
    script += "[[step]]\nafter_iterations = 30\nscreenshot = true\n";
    let scene = scenes::builtin("cornell-box").unwrap().load().unwrap();
    let mut moved = scene.clone();
    moved.apply(&Move {
        object: scene.object_index("short-block").unwrap(),
        translation: step * 5.0,
        rotation: glam::Quat::IDENTITY,
    });
    let dir = scratch(&format!("drag-{backend}"));
    let old = rendered(&scene, 120, &dir, "old");
    let new = rendered(&moved, 120, &dir, "new");
    view(&display, &dir, backend, &script, &["--mode", "local"]);
    let before = pane(&dir.join("shots/screenshot-000.png"), 0);
    let after = pane(&dir.join("shots/screenshot-001.png"), 0);
    let (to_new, to_old) = (
        block_relative_rmse(&after, &new, 8),
        block_relative_rmse(&after, &old, 8),
    );
    let before_to_old = block_relative_rmse(&before, &old, 8);
    figure!(
        "{backend}: after the drag {to_new:.4} from the new pose, {to_old:.4} from the old; before it {before_to_old:.4} from the old"
    );
    assert!(
        to_new < 0.5 * to_old,
        "{backend}: {to_new} against {to_old}"
    );
    assert!(
        before_to_old < to_old,
        "{backend}: the first screenshot shows the old pose"
    );
}

/// `--compare restart,local`: both panes show the new pose after a move, each its own render
/// (written as NAME-MODE.exr).
fn a_comparison_shows_both_modes() {
    let display = VirtualDisplay::start();
    let script = "[[step]]\nafter_iterations = 10\nobject = \"short-block\"\ntranslate = [-50.0, 0.0, -50.0]\n\
                  [[step]]\nafter_iterations = 20\nscreenshot = true\n";
    let scene = scenes::builtin("cornell-box").unwrap().load().unwrap();
    let mut moved = scene.clone();
    moved.apply(&Move {
        object: scene.object_index("short-block").unwrap(),
        translation: Vec3::new(-50.0, 0.0, -50.0),
        rotation: glam::Quat::IDENTITY,
    });
    let dir = scratch("compare");
    let old = rendered(&scene, 120, &dir, "old");
    let new = rendered(&moved, 120, &dir, "new");
    view(
        &display,
        &dir,
        "wgpu",
        script,
        &["--compare", "restart,local"],
    );
    let shot = dir.join("shots/screenshot-000.png");
    let (restart, local) = (pane(&shot, 0), pane(&shot, 1));
    for (mode, image) in [("restart", &restart), ("local", &local)] {
        let (to_new, to_old) = (
            block_relative_rmse(image, &new, 8),
            block_relative_rmse(image, &old, 8),
        );
        figure!("{mode}: {to_new:.4} from the new pose, {to_old:.4} from the old");
        assert!(to_new < 0.5 * to_old, "{mode}: {to_new} against {to_old}");
        let json = std::fs::read_to_string(dir.join(format!("view-{mode}.json"))).unwrap();
        assert!(json.contains("\"passes\": 30"), "{mode}: {json}");
    }
    assert!(
        block_relative_rmse(&restart, &local, 8) > 1e-3,
        "the two panes are two renders, not one drawn twice"
    );
}

/// A camera step starts the render over from the new view: the screenshot after it shows
/// that view, not the old one.
fn a_camera_step_shows_the_new_view() {
    let display = VirtualDisplay::start();
    let scene = scenes::builtin("cornell-box").unwrap().load().unwrap();
    let mut turned = scene.clone();
    turned.camera.eye += Vec3::new(150.0, 60.0, 0.0);
    let (e, l) = (turned.camera.eye, turned.camera.look_at);
    let script = format!(
        "[[step]]\nafter_iterations = 5\nscreenshot = true\n\
         [[step]]\nafter_iterations = 1\ncamera = {{ eye = [{}, {}, {}], look_at = [{}, {}, {}] }}\n\
         [[step]]\nafter_iterations = 20\nscreenshot = true\n",
        e.x, e.y, e.z, l.x, l.y, l.z
    );
    let dir = scratch("camera");
    let old = rendered(&scene, 120, &dir, "old");
    let new = rendered(&turned, 120, &dir, "new");
    view(&display, &dir, "cpu", &script, &[]);
    let after = pane(&dir.join("shots/screenshot-001.png"), 0);
    let (to_new, to_old) = (
        block_relative_rmse(&after, &new, 8),
        block_relative_rmse(&after, &old, 8),
    );
    figure!("after the camera step: {to_new:.4} from the new view, {to_old:.4} from the old");
    assert!(to_new < 0.5 * to_old, "{to_new} against {to_old}");
}

/// Ctrl-C in the middle of a session writes the render as it stood, marked interrupted, and
/// exits with 130 as `ppm render` does.
fn an_interrupt_writes_the_render() {
    let display = VirtualDisplay::start();
    let dir = scratch("interrupt");
    let script = dir.join("script.toml");
    std::fs::write(
        &script,
        "[[step]]\nafter_iterations = 3\nscreenshot = true\n",
    )
    .unwrap();
    let size = SIZE.to_string();
    let shots = dir.join("shots");
    let out = dir.join("view.exr");
    let command = display.ppm(&[
        "view",
        "cornell-box",
        "--width",
        &size,
        "--height",
        &size,
        "--script",
        &script.display().to_string(),
        "--screenshot-dir",
        &shots.display().to_string(),
        "-o",
        &out.display().to_string(),
    ]);
    let (status, stderr) = common::interrupted(command, "screenshot:");
    assert_eq!(status, Some(130), "{stderr}");
    let json = std::fs::read_to_string(out.with_extension("json")).unwrap();
    assert!(json.contains("\"interrupted\": true"), "{json}");
    assert!(out.exists() && out.with_extension("png").exists());
}

fn without_a_display_the_error_says_what_to_do() {
    let out = Command::new(env!("CARGO_BIN_EXE_ppm"))
        .args(["view", "cornell-box"])
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    for needed in ["DISPLAY", "WAYLAND_DISPLAY", "xvfb-run", "ppm render"] {
        assert!(stderr.contains(needed), "{needed}: {stderr}");
    }
}

fn main() -> ExitCode {
    let (display, adapter) = (
        Need::display(),
        Need::wgpu(|| {
            backend_wgpu::GpuContext::new()
                .map(drop)
                .map_err(|e| e.to_string())
        }),
    );
    // The window draws with wgpu whichever backend renders.
    let window = [&display, &adapter];
    let mut suite = Suite::new();
    for backend in ["cpu", "wgpu"] {
        suite = suite
            .test_needing(
                &window,
                format!("a_screenshot_matches_ppm_render::{backend}"),
                move || a_screenshot_matches_ppm_render(backend),
            )
            .test_needing(
                &window,
                format!("a_scripted_drag_moves_the_object_on_screen::{backend}"),
                move || a_scripted_drag_moves_the_object_on_screen(backend),
            );
    }
    suite
        .test_needing(
            &window,
            "a_comparison_shows_both_modes",
            a_comparison_shows_both_modes,
        )
        .test_needing(
            &window,
            "a_camera_step_shows_the_new_view",
            a_camera_step_shows_the_new_view,
        )
        .test_needing(
            &window,
            "an_interrupt_writes_the_render",
            an_interrupt_writes_the_render,
        )
        .test(
            "without_a_display_the_error_says_what_to_do",
            without_a_display_the_error_says_what_to_do,
        )
        .run()
}
