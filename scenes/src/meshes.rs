//! Procedural closed meshes the project may distribute: the stand-in for the Stanford bunny
//! (a displaced sphere) and the wedding band (a rounded band revolved about +y).

use glam::Vec3;
use std::f32::consts::{PI, TAU};

/// A closed latitude-longitude sphere of `2 * lon * (lat - 1)` triangles, each vertex pushed
/// out to `radius(direction)`, with triangles facing outwards.
pub fn displaced_sphere(lat: u32, lon: u32, radius: impl Fn(Vec3) -> f32) -> Vec<[Vec3; 3]> {
    let point = |i: u32, j: u32| {
        let theta = PI * i as f32 / lat as f32;
        let phi = TAU * (j % lon) as f32 / lon as f32;
        let d = Vec3::new(
            theta.sin() * phi.cos(),
            theta.cos(),
            theta.sin() * phi.sin(),
        );
        d * radius(d)
    };
    let mut tris = Vec::with_capacity((2 * lon * (lat - 1)) as usize);
    for i in 0..lat {
        for j in 0..lon {
            let (a, b, c, d) = (
                point(i, j),
                point(i, j + 1),
                point(i + 1, j),
                point(i + 1, j + 1),
            );
            if i > 0 {
                tris.push([a, b, c]);
            }
            if i + 1 < lat {
                tris.push([b, d, c]);
            }
        }
    }
    tris
}

/// The bunny stand-in: a lumpy body with a head and two ears' worth of bumps, ~70,300
/// triangles, scaled to `height` and set on the floor (`min y = 0`) centred at `(x, z)`.
pub fn blob(height: f32, x: f32, z: f32) -> Vec<[Vec3; 3]> {
    let bump = |d: Vec3, centre: Vec3, width: f32, size: f32| {
        size * (-(1.0 - d.dot(centre.normalize())) / width).exp()
    };
    let tris = displaced_sphere(186, 190, |d| {
        1.0 + 0.06 * (5.0 * d.x).sin() * (4.0 * d.z).cos()
            + bump(d, Vec3::new(0.6, 0.6, 0.0), 0.08, 0.35)
            + bump(d, Vec3::new(0.3, 1.0, 0.25), 0.02, 0.45)
            + bump(d, Vec3::new(0.3, 1.0, -0.25), 0.02, 0.45)
    });
    place(tris, height, Vec3::new(x, 0.0, z))
}

/// A wedding band lying on the floor: the rounded rectangle `r in [inner, outer]`,
/// `y in [0, height]` (corners of radius `round`) revolved about +y in `segments` steps;
/// `profile` points around the rectangle. Closed, facing outwards.
pub fn band(
    inner: f32,
    outer: f32,
    height: f32,
    round: f32,
    profile: u32,
    segments: u32,
) -> Vec<[Vec3; 3]> {
    let outline = rounded_rectangle(inner, outer, height, round, profile);
    let mut tris = Vec::with_capacity((2 * outline.len() as u32 * segments) as usize);
    let at = |(r, y): (f32, f32), s: u32| {
        let a = TAU * (s % segments) as f32 / segments as f32;
        Vec3::new(r * a.cos(), y, r * a.sin())
    };
    for s in 0..segments {
        for k in 0..outline.len() {
            let (p, q) = (outline[k], outline[(k + 1) % outline.len()]);
            let (a, b, c, d) = (at(p, s), at(q, s), at(p, s + 1), at(q, s + 1));
            tris.push([a, c, b]);
            tris.push([b, c, d]);
        }
    }
    tris
}

/// Points around a rounded rectangle in the (r, y) plane, counter-clockwise seen with r to
/// the right and y up, `per_corner` points per quarter circle (`4 * per_corner` in all).
fn rounded_rectangle(r0: f32, r1: f32, h: f32, round: f32, points: u32) -> Vec<(f32, f32)> {
    let per_corner = (points / 4).max(1);
    let corners = [
        ((r1 - round, round), -0.5 * PI),
        ((r1 - round, h - round), 0.0),
        ((r0 + round, h - round), 0.5 * PI),
        ((r0 + round, round), PI),
    ];
    let mut out = Vec::new();
    for ((cr, cy), start) in corners {
        for k in 0..per_corner {
            let a = start + 0.5 * PI * k as f32 / (per_corner - 1).max(1) as f32;
            out.push((cr + round * a.cos(), cy + round * a.sin()));
        }
    }
    out
}

/// Scales `tris` to `height` tall, sets their lowest point on `base.y` and centres them on
/// `base.x`, `base.z`.
fn place(tris: Vec<[Vec3; 3]>, height: f32, base: Vec3) -> Vec<[Vec3; 3]> {
    let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    for v in tris.iter().flatten() {
        lo = lo.min(*v);
        hi = hi.max(*v);
    }
    let scale = height / (hi.y - lo.y);
    let centre = Vec3::new((lo.x + hi.x) * 0.5, lo.y, (lo.z + hi.z) * 0.5);
    tris.into_iter()
        .map(|t| t.map(|v| (v - centre) * scale + base))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    /// Every edge of a closed mesh is shared by exactly two triangles, once in each direction.
    fn assert_closed(tris: &[[Vec3; 3]]) {
        let key = |v: Vec3| (v * 1e4).round().to_array().map(|x| x as i64);
        let mut edges: HashMap<_, i32> = HashMap::new();
        for t in tris {
            for k in 0..3 {
                let (a, b) = (key(t[k]), key(t[(k + 1) % 3]));
                if a == b {
                    continue;
                }
                *edges.entry((a, b)).or_default() += 1;
                *edges.entry((b, a)).or_default() -= 1;
            }
        }
        let open = edges.values().filter(|&&c| c != 0).count();
        assert_eq!(open, 0, "{open} unmatched directed edges");
    }

    #[test]
    fn blob_is_a_closed_mesh_of_sixty_to_eighty_thousand_triangles_on_the_floor() {
        let tris = blob(250.0, 368.0, 351.0);
        assert!((60_000..=80_000).contains(&tris.len()), "{}", tris.len());
        assert_closed(&tris);
        let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
        for v in tris.iter().flatten() {
            lo = lo.min(*v);
            hi = hi.max(*v);
        }
        assert!(
            lo.y.abs() < 1e-3 && (hi.y - 250.0).abs() < 1e-2,
            "{lo} {hi}"
        );
        assert!(
            ((lo.x + hi.x) * 0.5 - 368.0).abs() < 1e-2
                && ((lo.z + hi.z) * 0.5 - 351.0).abs() < 1e-2
        );
    }

    #[test]
    fn band_is_closed_with_the_specified_radii_and_height() {
        let tris = band(9.2, 10.0, 3.0, 0.3, 48, 143);
        assert_eq!(tris.len(), 2 * 48 * 143);
        assert_closed(&tris);
        let radial = |v: &Vec3| (v.x * v.x + v.z * v.z).sqrt();
        let r_min = tris.iter().flatten().map(radial).fold(f32::MAX, f32::min);
        let r_max = tris.iter().flatten().map(radial).fold(0.0, f32::max);
        let y_max = tris.iter().flatten().map(|v| v.y).fold(0.0, f32::max);
        assert!(
            (r_min - 9.2).abs() < 1e-3 && (r_max - 10.0).abs() < 1e-3 && (y_max - 3.0).abs() < 1e-3
        );
    }
}
