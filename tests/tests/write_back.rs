//! Slots written back through the contract ([`ReadBack::write_hit_points`]) are screened as
//! every pass screens what it writes: a slot with a field that is not finite is refused,
//! naming the field, and the slots stay as they were, on every backend.

use harness::driver::Renderer;
use ppm_core::params::{MoveParams, RenderParams};
use ppm_core::passes::{Backend, BackendError};
use std::process::ExitCode;
use tests::{BackendTrials, Suite};

fn a_slot_written_not_finite_is_refused(name: &str, mut backend: Box<dyn Backend + Send>) {
    let scene = scenes::builtin("cornell-box").unwrap().load().unwrap();
    let mut params = RenderParams::for_scene(&scene);
    (params.width, params.height, params.photons_per_pass) = (16, 16, 5_000);
    let mut render =
        Renderer::start(backend.as_mut(), scene, &params, &MoveParams::default()).unwrap();
    render.iteration().unwrap();
    let b = render.backend();
    let held = b.read_hit_points().unwrap();
    let valid = held.iter().position(|hp| hp.is_valid()).unwrap();
    for (field, spoil) in [
        (
            "direct",
            (|hp| hp.direct[2] = f32::NAN) as fn(&mut ppm_core::layout::HitPoint),
        ),
        ("throughput", |hp| hp.throughput[0] = f32::INFINITY),
    ] {
        let mut spoiled = held.clone();
        spoil(&mut spoiled[valid]);
        match b.write_hit_points(&spoiled) {
            Err(BackendError::NonFinite {
                pass,
                field: named,
                index,
                ..
            }) => {
                assert_eq!(
                    (pass, named, index),
                    ("write hit points", field, valid),
                    "{name}"
                )
            }
            other => panic!("{name}: {field}: expected a refusal, got {other:?}"),
        }
        let after = b.read_hit_points().unwrap();
        assert!(
            bytemuck::cast_slice::<_, u8>(&after) == bytemuck::cast_slice::<_, u8>(&held),
            "{name}: a refused write changed the slots"
        );
    }
    b.write_hit_points(&held).unwrap();
}

fn main() -> ExitCode {
    Suite::new()
        .on_every_backend(
            "a_slot_written_not_finite_is_refused",
            a_slot_written_not_finite_is_refused,
        )
        .run()
}
