//! Finiteness checks run after every pass, so NaN and infinity stop the render with a report
//! naming the pass, the field and the slot, instead of spreading into the image.

use crate::layout::HitPoint;
use crate::passes::BackendError;

/// The first non-finite field of a slot, as an error; `Ok` when all are finite. Statistics
/// are checked in every slot (they outlive the visible point), the visible point only where
/// there is one.
pub fn check_hit_points(pass: &'static str, hit_points: &[HitPoint]) -> Result<(), BackendError> {
    if all_finite(hit_points) {
        return Ok(());
    }
    for (index, hp) in hit_points.iter().enumerate() {
        let visible: [(&'static str, &[f32]); 2] =
            [("position", &hp.position), ("throughput", &hp.throughput)];
        let statistics: [(&'static str, &[f32]); 5] = [
            ("direct", &hp.direct),
            ("tau", &hp.tau),
            ("r2", std::slice::from_ref(&hp.r2)),
            ("n", std::slice::from_ref(&hp.n)),
            ("emitted", std::slice::from_ref(&hp.emitted)),
        ];
        let fields = statistics
            .into_iter()
            .chain(visible.into_iter().filter(|_| hp.is_valid()));
        for (field, values) in fields {
            if let Some(v) = values.iter().find(|v| !v.is_finite()) {
                return Err(BackendError::NonFinite {
                    pass,
                    field,
                    index,
                    pixel: hp.pixel,
                    value: v.to_string(),
                });
            }
        }
    }
    Ok(())
}

/// Whether every checked field of every slot is finite, screened without a branch per field
/// or slot (the field-by-field search that names the culprit took a twentieth of a CPU
/// iteration, run after every pass).
fn all_finite(hit_points: &[HitPoint]) -> bool {
    hit_points
        .iter()
        .fold(true, |ok, hp| ok & slot_is_finite(hp))
}

/// Whether every field [`check_hit_points`] checks of `hp` is finite, without a branch: a
/// pass that writes every slot anyway screens each as it goes, and sweeps the slots with
/// [`check_hit_points`] only where one failed, to name it.
pub fn slot_is_finite(hp: &HitPoint) -> bool {
    let finite = |values: &[f32]| values.iter().fold(true, |ok, v| ok & v.is_finite());
    let statistics = finite(&hp.direct) & finite(&hp.tau) & finite(&[hp.r2, hp.n, hp.emitted]);
    let visible = finite(&hp.position) & finite(&hp.throughput);
    statistics & (visible | !hp.is_valid())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layout::hit_flags;

    #[test]
    fn a_nan_in_a_valid_slot_is_reported_with_its_field() {
        let mut hps = vec![HitPoint::default(); 3];
        for hp in &mut hps {
            hp.flags = hit_flags::VALID;
        }
        assert!(check_hit_points("gather", &hps).is_ok());
        hps[2].tau[1] = f32::NAN;
        hps[2].pixel = 7;
        let err = check_hit_points("gather", &hps).unwrap_err().to_string();
        assert_eq!(
            err,
            "gather pass: tau of hit point 2 (pixel 7) is not finite: NaN"
        );
        hps[2].flags = 0;
        assert!(
            check_hit_points("gather", &hps).is_err(),
            "statistics outlive the visible point and are checked without one"
        );
        hps[2].tau[1] = 0.0;
        hps[2].position[0] = f32::INFINITY;
        assert!(
            check_hit_points("gather", &hps).is_ok(),
            "a slot without a visible point has no position to check"
        );
        hps[2].flags = hit_flags::VALID;
        let err = check_hit_points("gather", &hps).unwrap_err().to_string();
        assert!(err.contains("position of hit point 2"), "{err}");
        hps[2].position[0] = 0.0;
        hps[0].r2 = f32::NEG_INFINITY;
        let err = check_hit_points("eye", &hps).unwrap_err().to_string();
        assert!(err.contains("r2 of hit point 0"), "{err}");
    }
}
