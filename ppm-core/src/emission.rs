//! Where photons leave the lights: the ordinary distribution (docs/algorithm.md 1.3), region
//! photons through the emitting rectangle, and guided photons around recorded paths
//! (docs/algorithm.md 2 and 3). Shared by every backend and by the host, which rebuilds the
//! emissions of testing photons from their path index.

use crate::geometry::to_world;
use crate::layout::{
    EmissionRegion, Emitter, GpuLight, GpuMaterial, GuidedEmission, RecordedPath, emission_kind,
    region_mode,
};
use crate::rng::{PassKind, StreamKey};
use crate::sampling::{cosine_hemisphere, sample_cdf, uniform_cone, uniform_triangle};
use glam::Vec3;
use std::f32::consts::PI;

/// Random dimensions an emission may use; bounces start after them.
pub const EMISSION_DIMS: u32 = 8;

/// A photon leaving a light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Emission {
    /// Start point on the light.
    pub origin: Vec3,
    /// Unit direction.
    pub direction: Vec3,
    /// Power carried, weight included.
    pub power: Vec3,
    /// Light index.
    pub light: u32,
    /// The light's normal.
    pub normal: Vec3,
    /// Weight relative to an ordinary photon (1 for ordinary photons, 0 for a wasted one).
    pub weight: f32,
}

/// Where a photon pass's photons start: the one argument besides its parameters that tells
/// the passes of docs/algorithm.md 1.3, 2.2, 2.5 and 2.6 apart. A backend traces every source
/// with the same path code, keyed by [`PhotonSource::pass_kind`] and started by
/// [`PhotonSource::emit`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PhotonSource<'a> {
    /// Ordinary photons ([`ordinary_emission`]): every iteration's, testing and difference
    /// photons.
    Lights,
    /// Compensation (power scale -1) and region photons through the emitting region
    /// ([`region_emission`]); each deposit keeps its path's weight for `M`.
    Region(EmissionRegion),
    /// Guided photons around recorded paths ([`guided_emission`]).
    Guided {
        /// Cone, mixture and weighting; its `paths` field is ignored for `paths.len()`.
        guide: GuidedEmission,
        /// The recorded emissions to draw around.
        paths: &'a [RecordedPath],
    },
}

impl PhotonSource<'_> {
    /// The source's name in errors and reports.
    pub fn name(&self) -> &'static str {
        match self {
            PhotonSource::Lights => "ordinary",
            PhotonSource::Region(_) => "region",
            PhotonSource::Guided { .. } => "guided",
        }
    }

    /// The random streams its paths draw from ([`crate::rng`] module docs).
    pub fn pass_kind(&self) -> PassKind {
        match self {
            PhotonSource::Lights => PassKind::Photon,
            PhotonSource::Region(_) => PassKind::Region,
            PhotonSource::Guided { .. } => PassKind::Guided,
        }
    }

    /// Whether deposits keep their path's weight: region photons count in `M` as the ordinary
    /// photons their weights stand for; every other source's weights are 1.
    pub fn keeps_weights(&self) -> bool {
        matches!(self, PhotonSource::Region(_))
    }

    /// The photon that path `key` emits.
    pub fn emit(
        &self,
        lights: &[GpuLight],
        materials: &[GpuMaterial],
        key: &StreamKey,
    ) -> Emission {
        match self {
            PhotonSource::Lights => ordinary_emission(lights, materials, key),
            PhotonSource::Region(region) => region_emission(lights, materials, region, key),
            PhotonSource::Guided { guide, paths } => {
                guided_emission(lights, materials, guide, paths, key)
            }
        }
    }

    /// The uniform a GPU backend uploads (with the recorded paths in a buffer of their own).
    pub fn emitter(&self) -> Emitter {
        match *self {
            PhotonSource::Lights => Emitter::default(),
            PhotonSource::Region(region) => Emitter {
                kind: emission_kind::REGION,
                region,
                ..Default::default()
            },
            PhotonSource::Guided { guide, paths } => Emitter {
                kind: emission_kind::GUIDED,
                guide: GuidedEmission {
                    paths: paths.len() as u32,
                    ..guide
                },
                ..Default::default()
            },
        }
    }

    /// The recorded paths a guided source draws around (none for the others).
    pub fn paths(&self) -> &[RecordedPath] {
        match self {
            PhotonSource::Guided { paths, .. } => paths,
            _ => &[],
        }
    }
}

/// The light chosen by `u` (by power) and the power an ordinary photon from it carries:
/// the whole light's power `pi * A * Le` over its selection probability.
fn chosen_light<'a>(
    lights: &'a [GpuLight],
    materials: &[GpuMaterial],
    u: f32,
) -> (u32, &'a GpuLight, Vec3) {
    let i = sample_cdf(|k| lights[k].cdf, lights.len(), u);
    let light = &lights[i];
    let le = Vec3::from(materials[light.material as usize].emission);
    (i as u32, light, le * (PI * light.area / light.pdf))
}

fn point_on(light: &GpuLight, u1: f32, u2: f32) -> Vec3 {
    let (b1, b2) = uniform_triangle(u1, u2);
    Vec3::from(light.v0) + Vec3::from(light.e1) * b1 + Vec3::from(light.e2) * b2
}

/// An ordinary photon: uniform on the lights' area (by power), cosine-weighted direction.
pub fn ordinary_emission(
    lights: &[GpuLight],
    materials: &[GpuMaterial],
    key: &StreamKey,
) -> Emission {
    let (index, light, power) = chosen_light(lights, materials, key.uniform(0));
    let normal = Vec3::from(light.normal);
    Emission {
        origin: point_on(light, key.uniform(1), key.uniform(2)),
        direction: to_world(cosine_hemisphere(key.uniform(3), key.uniform(4)), normal),
        power,
        light: index,
        normal,
        weight: 1.0,
    }
}

/// A region photon: from the light (area mode: uniform on it; point mode: its centre) towards
/// a point uniform on the rectangle.
///
/// Its weight relative to an ordinary photon is `A_rect cos_l cos_r / (pi d^2)`: the ratio of
/// the ordinary density of the direction (`cos_l / pi` per steradian) to the region's (a point
/// uniform on the rectangle seen from the light: `d^2 / (A_rect cos_r)` per steradian), both
/// taken for the same light point. Zero where the light faces away.
pub fn region_emission(
    lights: &[GpuLight],
    materials: &[GpuMaterial],
    region: &EmissionRegion,
    key: &StreamKey,
) -> Emission {
    let (index, light, light_power) = chosen_light(lights, materials, key.uniform(0));
    let normal = Vec3::from(light.normal);
    let origin = if region.mode == region_mode::POINT {
        Vec3::from(region.light_point)
    } else {
        point_on(light, key.uniform(1), key.uniform(2))
    };
    let (eu, ev) = (Vec3::from(region.edge_u), Vec3::from(region.edge_v));
    let target = Vec3::from(region.origin) + eu * key.uniform(3) + ev * key.uniform(4);
    let to = target - origin;
    let d2 = to.length_squared();
    let direction = to.normalize_or(normal);
    let cos_l = normal.dot(direction);
    let cos_r = eu.cross(ev).normalize_or_zero().dot(direction).abs();
    let weight = if d2 > 0.0 && cos_l > 0.0 && region.area > 0.0 {
        region.area * cos_l * cos_r / (PI * d2)
    } else {
        0.0
    };
    Emission {
        origin,
        direction,
        power: light_power * weight,
        light: index,
        normal,
        weight,
    }
}

/// A guided photon (docs/algorithm.md 3, "Guided photons without bias").
///
/// Weighted (ours): with probability `beta` an ordinary direction, otherwise a direction
/// uniform in the cone around a recorded path's; the start point is drawn as for ordinary
/// photons either way, so the weight is the ratio of direction densities
/// `(cos/pi) / (beta cos/pi + (1-beta)/K sum_k [in cone k] / Omega_cone)`.
/// Unweighted (the thesis): the recorded start point, the jittered direction, weight 1.
/// Without recorded paths, an ordinary photon.
pub fn guided_emission(
    lights: &[GpuLight],
    materials: &[GpuMaterial],
    guide: &GuidedEmission,
    paths: &[RecordedPath],
    key: &StreamKey,
) -> Emission {
    let use_ordinary = paths.is_empty() || (guide.weighted == 1 && key.uniform(7) < guide.beta);
    if use_ordinary && guide.weighted == 0 {
        return ordinary_emission(lights, materials, key);
    }
    let recorded =
        &paths[((key.uniform(5) * paths.len() as f32) as usize).min(paths.len().saturating_sub(1))];
    let cone_direction = |axis: Vec3| {
        to_world(
            uniform_cone(key.uniform(3), key.uniform(4), guide.cos_cone),
            axis,
        )
    };
    if guide.weighted == 0 {
        let light = &lights[recorded.light as usize];
        let le = Vec3::from(materials[light.material as usize].emission);
        return Emission {
            origin: Vec3::from(recorded.origin),
            direction: cone_direction(Vec3::from(recorded.direction)),
            power: le * (PI * light.area / light.pdf),
            light: recorded.light,
            normal: Vec3::from(light.normal),
            weight: 1.0,
        };
    }
    let mut e = ordinary_emission(lights, materials, key);
    if !use_ordinary {
        e.direction = cone_direction(Vec3::from(recorded.direction));
    }
    let cos = e.normal.dot(e.direction);
    let omega = 2.0 * PI * (1.0 - guide.cos_cone);
    let in_cones = paths
        .iter()
        .filter(|p| Vec3::from(p.direction).dot(e.direction) >= guide.cos_cone)
        .count() as f32;
    let mixture =
        guide.beta * cos / PI + (1.0 - guide.beta) * in_cones / (paths.len() as f32 * omega);
    e.weight = if cos > 0.0 && mixture > 0.0 {
        (cos / PI) / mixture
    } else {
        0.0
    };
    e.power *= e.weight;
    e
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::PassKind;

    fn square_light() -> (Vec<GpuLight>, Vec<GpuMaterial>) {
        let tri = |v0: Vec3, v1: Vec3, v2: Vec3, cdf: f32| GpuLight {
            v0: v0.into(),
            area: 0.5,
            e1: (v1 - v0).into(),
            cdf,
            e2: (v2 - v0).into(),
            pdf: 0.5,
            normal: [0.0, -1.0, 0.0],
            material: 0,
        };
        let (a, b, c, d) = (
            Vec3::new(0., 1., 0.),
            Vec3::new(0., 1., 1.),
            Vec3::new(1., 1., 1.),
            Vec3::new(1., 1., 0.),
        );
        let material = GpuMaterial {
            emission: [1.0; 3],
            ..Default::default()
        };
        (vec![tri(a, b, c, 0.5), tri(a, c, d, 1.0)], vec![material])
    }

    fn key(path: u32, kind: PassKind) -> StreamKey {
        StreamKey {
            seed: 1,
            kind,
            pass_index: 0,
            path,
        }
    }

    /// Region photons estimate, in expectation, the power of the ordinary photons that cross
    /// the rectangle: E[w * 1] over region photons equals the fraction of ordinary photons
    /// whose first segment crosses it.
    #[test]
    fn region_weights_reproduce_the_ordinary_flux_through_the_rectangle() {
        let (lights, materials) = square_light();
        let region = EmissionRegion {
            origin: [0.2, 0.0, 0.1],
            edge_u: [0.6, 0.0, 0.0],
            edge_v: [0.0, 0.0, 0.7],
            area: 0.42,
            ..Default::default()
        };
        let n = 400_000;
        let mean_weight: f64 = (0..n)
            .map(|i| {
                f64::from(
                    region_emission(&lights, &materials, &region, &key(i, PassKind::Region)).weight,
                )
            })
            .sum::<f64>()
            / f64::from(n);
        let crossing = (0..n)
            .filter(|&i| {
                let e = ordinary_emission(&lights, &materials, &key(i, PassKind::Photon));
                let t = -e.origin.y / e.direction.y;
                let p = e.origin + e.direction * t;
                (0.2..0.8).contains(&p.x) && (0.1..0.8).contains(&p.z)
            })
            .count() as f64
            / f64::from(n);
        assert!(
            (mean_weight - crossing).abs() < 0.01 * crossing + 1e-3,
            "{mean_weight} vs {crossing}"
        );
    }

    /// The defensive mixture is unbiased: its weights average the ordinary flux through any
    /// set of directions, here the downward cone of half-angle 30 degrees.
    #[test]
    fn weighted_guided_photons_keep_the_ordinary_expectation() {
        let (lights, materials) = square_light();
        let paths = [RecordedPath {
            direction: Vec3::new(0.3, -1.0, 0.1).normalize().into(),
            ..Default::default()
        }];
        let guide = GuidedEmission {
            cos_cone: 10f32.to_radians().cos(),
            beta: 0.3,
            paths: 1,
            weighted: 1,
        };
        let cos30 = 30f32.to_radians().cos();
        let n = 400_000;
        let hits = |e: Emission| {
            if -e.direction.y >= cos30 {
                f64::from(e.weight)
            } else {
                0.0
            }
        };
        let guided: f64 = (0..n)
            .map(|i| {
                hits(guided_emission(
                    &lights,
                    &materials,
                    &guide,
                    &paths,
                    &key(i, PassKind::Guided),
                ))
            })
            .sum::<f64>()
            / f64::from(n);
        let ordinary: f64 = (0..n)
            .map(|i| {
                hits(ordinary_emission(
                    &lights,
                    &materials,
                    &key(i, PassKind::Photon),
                ))
            })
            .sum::<f64>()
            / f64::from(n);
        // Exact: a cosine lobe puts sin^2(30) = 1/4 of its photons within 30 degrees.
        assert!((ordinary - 0.25).abs() < 0.005, "{ordinary}");
        assert!((guided - 0.25).abs() < 0.01, "{guided}");
    }
}
