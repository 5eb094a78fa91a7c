//! The side panel: what each pane is doing (iterations, photons per second, milliseconds per
//! iteration by pass, on the device too where it measures them, what the last move cost and
//! kept) and the settings that change live.

use super::worker::{PaneStats, Shared};
use ppm_core::params::MoveMode;

/// Width of the panel in logical pixels; the window is the panes plus this.
pub const PANEL_WIDTH: u32 = 300;

/// The settings the panel changes.
pub struct Settings {
    /// Multiplies the image before display (and the PNGs written).
    pub exposure: f32,
    /// Photons per iteration of the later iterations.
    pub photons_per_pass: u32,
    /// Fraction of new photons kept per gather.
    pub alpha: f32,
    /// Mode of the next moves (a single pane).
    pub mode: MoveMode,
    /// Show (and compute) the heat map of each move's resets.
    pub heat: bool,
}

/// What the user asked for through the panel this frame.
#[derive(Default)]
pub struct Actions {
    pub tune: bool,
    pub mode: bool,
    pub heat: bool,
    pub save: bool,
    pub undo: bool,
}

/// Draws the panel.
pub fn show(ui: &mut egui::Ui, shared: &Shared, settings: &mut Settings) -> Actions {
    let mut actions = Actions::default();
    egui::Panel::right("stats")
        .resizable(false)
        .exact_size(PANEL_WIDTH as f32)
        .show(ui, |ui| {
            egui::ScrollArea::vertical()
                .show(ui, |ui| contents(ui, shared, settings, &mut actions));
        });
    actions
}

fn contents(ui: &mut egui::Ui, shared: &Shared, settings: &mut Settings, actions: &mut Actions) {
    for i in 0..shared.panes.len() {
        let (mode, backend, stats) = {
            let view = shared.pane(i);
            (view.mode, view.backend.clone(), view.stats.clone())
        };
        let mode = mode.name();
        ui.heading(format!("{mode} on {backend}"));
        pane_stats(ui, &stats);
        ui.separator();
    }
    let single = shared.panes.len() == 1;
    if single {
        egui::ComboBox::from_id_salt("mode")
            .selected_text(format!("move mode: {}", settings.mode.name()))
            .show_ui(ui, |ui| {
                for m in MoveMode::ALL {
                    if ui
                        .selectable_value(&mut settings.mode, m, m.name())
                        .changed()
                    {
                        actions.mode = true;
                    }
                }
            });
    }
    ui.add(egui::Slider::new(&mut settings.exposure, 0.05..=20.0).text("exposure"));
    let photons = ui.add(
        egui::DragValue::new(&mut settings.photons_per_pass)
            .range(1000..=10_000_000)
            .speed(1000.0)
            .prefix("photons/iteration "),
    );
    let alpha = ui.add(egui::Slider::new(&mut settings.alpha, 0.05..=0.99).text("alpha"));
    actions.tune = photons.changed() || alpha.changed();
    actions.heat = ui
        .checkbox(&mut settings.heat, "heat map of the last move's resets")
        .changed();
    ui.horizontal(|ui| {
        actions.save = ui.button("save (S)").clicked();
        actions.undo = ui.button("undo (Ctrl+Z)").clicked();
    });
    ui.separator();
    ui.small(
        "left-drag an object: move it facing the camera (Shift: along the floor)\n\
                 Q / E: turn the picked object 15 degrees\n\
                 Ctrl+Z: undo a move; S: save EXR, PNG and JSON; H: heat map\n\
                 right-drag: orbit; middle-drag (Shift+right): pan; wheel: dolly\n\
                 (local mode keeps the light of what is still seen)",
    );
}

fn pane_stats(ui: &mut egui::Ui, s: &PaneStats) {
    let t = &s.last_iteration;
    ui.monospace(format!(
        "iterations {:>8}\nrendered   {:>7.1} s\nphotons/s  {:>8.3e}\n\
         ms/iter    {:>8.1}\n  eye {:.1}  direct {:.1}\n  photon {:.1}  gather {:.1}\n  resolve {:.1}",
        s.iterations,
        s.seconds,
        s.photons_per_second,
        t.total,
        t.eye,
        t.direct,
        t.photon,
        t.gather,
        t.resolve
    ));
    if let Some(device) = &s.device_ms {
        let lines: Vec<String> = device
            .iter()
            .map(|(pass, ms)| format!("  {pass:<13} {ms:>7.2}"))
            .collect();
        ui.monospace(format!("device ms\n{}", lines.join("\n")));
    }
    if let Some(m) = &s.last_move {
        let latency = s
            .last_latency_ms
            .map_or(String::new(), |l| format!(", on screen after {l:.0} ms"));
        ui.monospace(format!(
            "last move  {:.0} ms{latency}\n  slots reset {}\n  kept {}",
            m.seconds * 1e3,
            m.updated,
            m.kept
        ));
    }
    if let Some(note) = &s.note {
        ui.label(note);
    }
    if let Some(e) = &s.error {
        ui.colored_label(egui::Color32::RED, format!("stopped: {e}"));
    }
}
