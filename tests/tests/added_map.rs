//! A photon pass added to the one before it ([`photon_flags::ADD_TO_MAP`]), on every backend:
//! one gather of both passes' photons leaves each slot as two gathers, one per pass, do (local
//! mode's correction gathers its pose-A and pose-B passes at once), and a pass that has
//! nothing to add to is refused.

use glam::Vec3;
use ppm_core::emission::PhotonSource;
use ppm_core::layout::{
    GatherParams, GpuBounds, HitPoint, PhotonPassParams, gather_kind, photon_flags,
};
use ppm_core::passes::{Backend, BackendError};
use std::process::ExitCode;
use tests::{BackendTrials, Suite, figure};

const PHOTONS: u32 = 20_000;
/// A local correction's gather: deferred, flux only.
const KIND: u32 = gather_kind::REGION_POSITIVE | gather_kind::DEFERRED | gather_kind::ADD_FLUX;
const FLOOR: f32 = 0.09;

/// The furnace with a mover's box over part of it, its slots traced and given one ordinary
/// pass of history.
fn load(backend: &mut dyn Backend) {
    let movers = [GpuBounds::new(
        Vec3::new(0.2, -0.9, 0.2),
        Vec3::new(0.9, -0.2, 0.9),
    )];
    tests::load_furnace(backend, &movers);
    let ordinary = PhotonPassParams {
        flags: 0,
        gather_kind: gather_kind::ORDINARY,
        gather_r2_floor: 0.0,
        ..pass(0, 1.0, 0)
    };
    backend
        .photon_pass(&ordinary, &PhotonSource::Lights)
        .unwrap();
    gather(backend, gather_kind::ORDINARY, PHOTONS as f32).unwrap();
}

/// A correction pass keyed by `index` at `power_scale`, with `flags`.
fn pass(index: u32, power_scale: f32, flags: u32) -> PhotonPassParams {
    PhotonPassParams {
        pass_index: index,
        photon_count: PHOTONS,
        max_depth: 8,
        ray_epsilon: 1e-5,
        power_scale,
        flags: photon_flags::CHANGED_ONLY | flags,
        gather_kind: KIND,
        gather_r2_floor: FLOOR,
        ..Default::default()
    }
}

fn gather(backend: &mut dyn Backend, kind: u32, emitted: f32) -> Result<(), BackendError> {
    backend.gather_pass(&GatherParams {
        alpha: 0.7,
        kind,
        emitted_increment: emitted,
        region_photons: 2.0 * PHOTONS as f32,
    })?;
    Ok(())
}

/// The slots after a negative pass and a positive one of other numbers, gathered apart or
/// (`added`) at once, and applied.
fn corrected(backend: &mut dyn Backend, added: bool) -> Vec<HitPoint> {
    load(backend);
    let trace = |backend: &mut dyn Backend, p: &PhotonPassParams| {
        backend.photon_pass(p, &PhotonSource::Lights).unwrap()
    };
    trace(backend, &pass(1, -1.0, 0));
    if !added {
        gather(backend, KIND, 0.0).unwrap();
    }
    let flags = if added { photon_flags::ADD_TO_MAP } else { 0 };
    trace(backend, &pass(2, 1.0, flags));
    gather(backend, KIND, 0.0).unwrap();
    gather(
        backend,
        gather_kind::REGION_APPLY | gather_kind::ADD_FLUX,
        0.0,
    )
    .unwrap();
    backend.read_hit_points().unwrap()
}

fn one_gather_of_an_added_pass_equals_a_gather_of_each(
    name: &str,
    mut backend: Box<dyn Backend + Send>,
) {
    let backend = backend.as_mut();
    let (before, apart, added) = {
        load(backend);
        let before = backend.read_hit_points().unwrap();
        (before, corrected(backend, false), corrected(backend, true))
    };
    let (mut changed, mut worst) = (0, 0.0_f32);
    for ((b, x), y) in before.iter().zip(&apart).zip(&added) {
        changed += usize::from(b.tau != x.tau);
        for c in 0..3 {
            let scale = x.tau[c].abs().max(1e-6);
            worst = worst.max((x.tau[c] - y.tau[c]).abs() / scale);
        }
        assert!((x.emitted - y.emitted).abs() <= 1e-5 * x.emitted.abs().max(1.0));
    }
    figure!("{name}: {changed} slots corrected, largest relative difference {worst:e}");
    assert!(
        changed > 20,
        "{name}: the correction must change slots to test anything"
    );
    assert!(worst < 1e-4, "{name}: {worst}");
}

fn a_pass_with_nothing_to_add_to_is_refused(name: &str, mut backend: Box<dyn Backend + Send>) {
    let backend = backend.as_mut();
    load(backend);
    let add = pass(2, 1.0, photon_flags::ADD_TO_MAP);
    // The last pass was gathered.
    let refused = backend.photon_pass(&add, &PhotonSource::Lights);
    assert!(
        matches!(refused, Err(BackendError::OutOfOrder { .. })),
        "{name}: {refused:?}"
    );
    // The last pass named another floor.
    let other = PhotonPassParams {
        gather_r2_floor: FLOOR * 2.0,
        ..pass(1, -1.0, 0)
    };
    backend.photon_pass(&other, &PhotonSource::Lights).unwrap();
    let refused = backend.photon_pass(&add, &PhotonSource::Lights);
    assert!(
        matches!(refused, Err(BackendError::OutOfOrder { .. })),
        "{name}: {refused:?}"
    );
    backend
        .photon_pass(&pass(1, -1.0, 0), &PhotonSource::Lights)
        .unwrap();
    assert!(
        backend.photon_pass(&add, &PhotonSource::Lights).is_ok(),
        "{name}"
    );
}

fn main() -> ExitCode {
    Suite::new()
        .on_every_backend(
            "one_gather_of_an_added_pass_equals_a_gather_of_each",
            one_gather_of_an_added_pass_equals_a_gather_of_each,
        )
        .on_every_backend(
            "a_pass_with_nothing_to_add_to_is_refused",
            a_pass_with_nothing_to_add_to_is_refused,
        )
        .run()
}
