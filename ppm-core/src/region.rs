//! The emitting region of compensation photons (docs/algorithm.md 2.1, thesis T3.3): the rectangle
//! through which the light sees a moving object in either pose.

use crate::geometry::orthonormal_basis;
use crate::layout::{EmissionRegion, GpuLight, region_mode};
use glam::Vec3;

/// Why no region could be built.
#[derive(Clone, Debug, PartialEq)]
pub enum RegionError {
    /// No vertex or no light.
    Empty,
    /// A vertex lies beside or behind a light point along the view direction, so its
    /// projection onto the plane goes to infinity: the object surrounds the light.
    Unbounded,
}

/// The area-weighted centre of the lights: thesis mode's point light.
pub fn lights_centre(lights: &[GpuLight]) -> Vec3 {
    let (sum, area) = lights.iter().fold((Vec3::ZERO, 0.0f32), |(s, a), l| {
        let c = Vec3::from(l.v0) + (Vec3::from(l.e1) + Vec3::from(l.e2)) / 3.0;
        (s + c * l.area, a + l.area)
    });
    sum / area.max(f32::MIN_POSITIVE)
}

/// The rectangle bounding the projections of `vertices` (the moving object in both poses).
///
/// The plane passes through the vertices' centroid with normal `d`, the direction from the
/// lights' centre to that centroid; its basis is `orthonormal_basis(d)`. Thesis mode projects
/// from the centre only; area mode from every light vertex, so that every light point's view
/// of the object is covered (docs/algorithm.md 3, "Which light point").
pub fn emitting_region(
    lights: &[GpuLight],
    vertices: &[Vec3],
    mode: u32,
) -> Result<EmissionRegion, RegionError> {
    if vertices.is_empty() || lights.is_empty() {
        return Err(RegionError::Empty);
    }
    let centre = lights_centre(lights);
    let centroid = vertices.iter().fold(Vec3::ZERO, |a, v| a + *v) / vertices.len() as f32;
    let d = (centroid - centre).normalize_or(Vec3::Y);
    let (t, b) = orthonormal_basis(d);
    let sources: Vec<Vec3> = if mode == region_mode::POINT {
        vec![centre]
    } else {
        lights
            .iter()
            .flat_map(|l| {
                let v0 = Vec3::from(l.v0);
                [v0, v0 + Vec3::from(l.e1), v0 + Vec3::from(l.e2)]
            })
            .collect()
    };
    let (mut lo, mut hi) = ([f32::INFINITY; 2], [f32::NEG_INFINITY; 2]);
    for s in &sources {
        let depth = (centroid - *s).dot(d);
        for v in vertices {
            let along = (*v - *s).dot(d);
            if along <= 1e-6 * depth.abs().max(1e-30) {
                return Err(RegionError::Unbounded);
            }
            let q = *s + (*v - *s) * (depth / along) - centroid;
            let (x, y) = (q.dot(t), q.dot(b));
            lo = [lo[0].min(x), lo[1].min(y)];
            hi = [hi[0].max(x), hi[1].max(y)];
        }
    }
    let (w, h) = (hi[0] - lo[0], hi[1] - lo[1]);
    Ok(EmissionRegion {
        light_point: centre.into(),
        mode,
        origin: (centroid + t * lo[0] + b * lo[1]).into(),
        _pad1: 0,
        edge_u: (t * w).into(),
        area: w * h,
        edge_v: (b * h).into(),
        _pad0: 0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad_light(half: f32) -> Vec<GpuLight> {
        let l = |v0: Vec3, v1: Vec3, v2: Vec3| GpuLight {
            v0: v0.into(),
            area: 2.0 * half * half,
            e1: (v1 - v0).into(),
            e2: (v2 - v0).into(),
            normal: [0.0, -1.0, 0.0],
            ..Default::default()
        };
        let c = |x: f32, z: f32| Vec3::new(x, 10.0, z);
        vec![
            l(c(-half, -half), c(-half, half), c(half, half)),
            l(c(-half, -half), c(half, half), c(half, -half)),
        ]
    }

    fn cube(centre: Vec3, half: f32) -> Vec<Vec3> {
        let mut v = Vec::new();
        for i in 0..8 {
            let s = |bit: i32| if i & bit != 0 { half } else { -half };
            v.push(centre + Vec3::new(s(1), s(2), s(4)));
        }
        v
    }

    #[test]
    fn a_cube_below_a_point_light_projects_to_its_shadow_square() {
        // Light point at y = 10, cube of half-size 1 centred at y = 5: the plane is y = 5 and
        // the top face (y = 6, distance 4) projects to 2 * 5/4 = 2.5 wide, the widest.
        let region = emitting_region(
            &quad_light(0.5),
            &cube(Vec3::new(0.0, 5.0, 0.0), 1.0),
            region_mode::POINT,
        )
        .unwrap();
        assert!((region.area - 6.25).abs() < 1e-3, "{region:?}");
        let corner = Vec3::from(region.origin)
            + Vec3::from(region.edge_u) * 0.5
            + Vec3::from(region.edge_v) * 0.5;
        assert!(corner.distance(Vec3::new(0.0, 5.0, 0.0)) < 1e-4);
    }

    #[test]
    fn area_mode_covers_more_than_the_point_light_sees() {
        let verts = cube(Vec3::new(1.0, 4.0, -0.5), 0.7);
        let point = emitting_region(&quad_light(1.0), &verts, region_mode::POINT).unwrap();
        let area = emitting_region(&quad_light(1.0), &verts, region_mode::AREA).unwrap();
        assert!(area.area > point.area, "{} <= {}", area.area, point.area);
    }

    #[test]
    fn a_flat_object_edge_on_gives_a_degenerate_rectangle_not_a_failure() {
        // A segment on the light's axis: every projection lands on one point or line.
        let verts = vec![Vec3::new(0.0, 4.0, 0.0), Vec3::new(0.0, 2.0, 0.0)];
        let r = emitting_region(&quad_light(0.5), &verts, region_mode::POINT).unwrap();
        assert!(r.area < 1e-12, "{r:?}");
    }

    #[test]
    fn an_object_around_the_light_is_unbounded() {
        let verts = vec![Vec3::new(0.0, 12.0, 0.0), Vec3::new(0.0, 4.0, 0.0)];
        assert_eq!(
            emitting_region(&quad_light(0.5), &verts, region_mode::AREA),
            Err(RegionError::Unbounded)
        );
    }
}
