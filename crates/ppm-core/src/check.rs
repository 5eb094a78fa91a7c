//! Finiteness checks run after every pass, so NaN and infinity stop the render with a report
//! naming the pass, the field and the slot, instead of spreading into the image.

use crate::layout::HitPoint;
use crate::passes::BackendError;

/// The first non-finite field of a valid hit point, as an error; `Ok` when all are finite.
pub fn check_hit_points(pass: &'static str, hit_points: &[HitPoint]) -> Result<(), BackendError> {
    for (index, hp) in hit_points.iter().enumerate().filter(|(_, h)| h.is_valid()) {
        let fields: [(&'static str, &[f32]); 7] = [
            ("position", &hp.position),
            ("direct", &hp.direct),
            ("tau", &hp.tau),
            ("r2", std::slice::from_ref(&hp.r2)),
            ("n", std::slice::from_ref(&hp.n)),
            ("emitted", std::slice::from_ref(&hp.emitted)),
            ("throughput", &hp.throughput),
        ];
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
            check_hit_points("gather", &hps).is_ok(),
            "empty slots are not checked"
        );
    }
}
