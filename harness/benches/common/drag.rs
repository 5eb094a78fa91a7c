//! A drag, as the drag and gpu benches measure it: iterations of warm-up, then many small
//! local moves of one object in a row, each followed by one iteration. Declared with
//! `#[path]` by the benches that drag, so that the others do not carry it unused.

use glam::Quat;
use harness::driver::Renderer;
use ppm_core::params::MoveMode;
use ppm_core::scene::Move;
use std::time::Instant;

/// A thirtieth of `declared` (a scene's `[[moves]]` entry): one step of a drag.
pub fn step_of(declared: Move) -> Move {
    Move {
        translation: declared.translation / 30.0,
        rotation: Quat::IDENTITY.slerp(declared.rotation, 1.0 / 30.0),
        ..declared
    }
}

/// Runs `iterations` iterations; returns the mean milliseconds of the last ten (the first
/// compile pipelines and fill buffers).
pub fn warm_up(r: &mut Renderer, iterations: u32) -> f64 {
    let mut ms = Vec::new();
    for _ in 0..iterations {
        let t = Instant::now();
        r.iteration().expect("an iteration runs");
        ms.push(t.elapsed().as_secs_f64() * 1e3);
    }
    mean(&ms[ms.len().saturating_sub(10)..])
}

/// What a drag of `moves` steps cost, per move.
pub struct Drag {
    /// Milliseconds per iteration between the moves (they keep their photon paths for the
    /// next move and serve the reset slots first).
    pub iteration_ms: f64,
    /// Milliseconds per move: mean, median and largest (the first move's, where it waits for
    /// pipelines still compiling).
    pub move_ms: f64,
    pub median_ms: f64,
    pub largest_ms: f64,
    /// Slots reset and direct-light corrections per move.
    pub reset: u64,
    pub corrected: u64,
    /// Where a move's time goes: each part's median milliseconds, in order.
    parts: Vec<(&'static str, f64)>,
}

impl Drag {
    /// Where a move's time goes: each part and its median milliseconds, in order.
    pub fn parts_line(&self) -> String {
        let parts: Vec<String> = self
            .parts
            .iter()
            .map(|(p, ms)| format!("{p} {ms:.1}"))
            .collect();
        parts.join(", ")
    }
}

/// Moves by `step` `moves` times in local mode, an iteration after each.
pub fn drag(r: &mut Renderer, step: Move, moves: u32) -> Drag {
    let (mut move_ms, mut iteration_ms, mut reset, mut corrected) = (Vec::new(), Vec::new(), 0, 0);
    let mut parts: Vec<(&'static str, Vec<f64>)> = Vec::new();
    for _ in 0..moves {
        let t = Instant::now();
        let m = r
            .move_objects(&[step], MoveMode::Local)
            .expect("a move runs");
        move_ms.push(t.elapsed().as_secs_f64() * 1e3);
        (reset, corrected) = (reset + m.updated, corrected + m.direct_corrected);
        for p in &m.parts {
            match parts.iter_mut().find(|(name, _)| *name == p.part) {
                Some((_, ms)) => ms.push(p.seconds * 1e3),
                None => parts.push((p.part, vec![p.seconds * 1e3])),
            }
        }
        let t = Instant::now();
        r.iteration().expect("an iteration runs");
        iteration_ms.push(t.elapsed().as_secs_f64() * 1e3);
    }
    let n = u64::from(moves.max(1));
    Drag {
        iteration_ms: mean(&iteration_ms),
        move_ms: mean(&move_ms),
        largest_ms: move_ms.iter().copied().fold(0.0, f64::max),
        median_ms: median(move_ms),
        reset: reset / n,
        corrected: corrected / n,
        parts: parts.into_iter().map(|(p, ms)| (p, median(ms))).collect(),
    }
}

fn median(mut ms: Vec<f64>) -> f64 {
    ms.sort_by(f64::total_cmp);
    ms.get(ms.len() / 2).copied().unwrap_or(0.0)
}

fn mean(ms: &[f64]) -> f64 {
    ms.iter().sum::<f64>() / ms.len().max(1) as f64
}
