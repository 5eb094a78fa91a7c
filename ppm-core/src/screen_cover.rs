//! Which pixels a mesh may cover, seen from the camera: local mode's test for the pose a
//! moving object moves to (docs/algorithm.md 3b), where no eye path has been traced yet.
//!
//! Conservative: a pixel is marked when an eye ray through some point of its square (the
//! eye pass jitters over the whole square) may meet a triangle, at any distance. Marking a
//! pixel no such ray meets costs a needless reset; missing one would keep a pixel the object
//! now covers, so every doubt marks.

use crate::layout::{BvhNode, GpuCamera, GpuTriangle};
use glam::{Mat3, Vec2, Vec3};

/// Widens each pixel's square, in pixels, beyond the rounding of projection and eye rays.
const MARGIN: f32 = 0.05;

/// The camera's projection onto the image, the inverse of
/// [`camera_ray`](crate::compile::camera_ray), its basis inverted once.
pub struct Projection {
    to_camera: Mat3,
    eye: Vec3,
    size: Vec2,
}

impl Projection {
    /// The projection of `camera`.
    pub fn new(camera: &GpuCamera) -> Self {
        let basis = Mat3::from_cols(camera.forward.into(), camera.right.into(), camera.up.into());
        Self {
            to_camera: basis.inverse(),
            eye: camera.eye.into(),
            size: Vec2::new(camera.width as f32, camera.height as f32),
        }
    }

    /// Image coordinates of `p` in pixels: `None` unless `p` lies in front of the eye (a
    /// positive distance along the view direction).
    pub fn project(&self, p: Vec3) -> Option<Vec2> {
        // p - eye = z (forward + sx right + sy up): solve for (z, z sx, z sy).
        let v = self.to_camera * (p - self.eye);
        if v.x.is_nan() || v.x <= 0.0 {
            return None;
        }
        let (sx, sy) = (v.y / v.x, v.z / v.x);
        let image = Vec2::new((sx + 1.0) * 0.5, (1.0 - sy) * 0.5) * self.size;
        image.is_finite().then_some(image)
    }
}

/// One flag per pixel (row-major), set where some eye ray of the pixel may meet one of
/// `triangles`. A triangle reaching behind the eye marks every pixel.
pub fn covered_pixels(camera: &GpuCamera, triangles: &[[Vec3; 3]]) -> Vec<bool> {
    let (width, height) = (camera.width as usize, camera.height as usize);
    let projection = Projection::new(camera);
    let mut covered = vec![false; width * height];
    for t in triangles {
        let [Some(a), Some(b), Some(c)] = t.map(|v| projection.project(v)) else {
            covered.fill(true);
            return covered;
        };
        mark_triangle(&mut covered, width, height, [a, b, c]);
    }
    covered
}

/// [`covered_pixels`] of the triangles under `roots` in a flattened tree (`nodes` over
/// `triangles`): the same flags, without projecting every triangle. A subtree whose box lies
/// wholly in front of the eye projects inside the box of its corners' images, and so do its
/// triangles' marks; where every pixel that box reaches is marked already, or none lies in
/// the image, the subtree is passed over. A moved mesh of tens of thousands of triangles
/// mostly covers itself.
pub fn covered_pixels_in_tree(
    camera: &GpuCamera,
    nodes: &[BvhNode],
    triangles: &[GpuTriangle],
    roots: &[u32],
) -> Vec<bool> {
    let (width, height) = (camera.width as usize, camera.height as usize);
    let projection = Projection::new(camera);
    let mut covered = vec![false; width * height];
    let mut stack = roots.to_vec();
    while let Some(i) = stack.pop() {
        let node = &nodes[i as usize];
        match box_pixels(&projection, node, width, height) {
            Reach::Outside => continue,
            Reach::Pixels(first, last) if all_marked(&covered, width, first, last) => continue,
            Reach::Pixels(..) | Reach::BehindTheEye => {}
        }
        if node.count == 0 {
            stack.extend([node.first, node.first + 1]);
            continue;
        }
        for t in &triangles[node.first as usize..(node.first + node.count) as usize] {
            let v0 = Vec3::from(t.v0);
            let corners = [v0, v0 + Vec3::from(t.e1), v0 + Vec3::from(t.e2)];
            let [Some(a), Some(b), Some(c)] = corners.map(|v| projection.project(v)) else {
                covered.fill(true);
                return covered;
            };
            mark_triangle(&mut covered, width, height, [a, b, c]);
        }
    }
    covered
}

/// Which pixels a tree node's box may reach.
enum Reach {
    /// A corner lies behind the eye (or on its plane): its triangles tell.
    BehindTheEye,
    /// Its image misses the image.
    Outside,
    /// The first and last pixel (column, row) of its image's widened bounding box.
    Pixels([usize; 2], [usize; 2]),
}

/// The pixels `node`'s box may reach, widened as [`mark_triangle`] widens a triangle's.
fn box_pixels(projection: &Projection, node: &BvhNode, width: usize, height: usize) -> Reach {
    let (lo, hi) = (Vec3::from(node.min), Vec3::from(node.max));
    let mut image = [Vec2::INFINITY, Vec2::NEG_INFINITY];
    for corner in 0..8 {
        let pick = |axis: usize| {
            if corner >> axis & 1 == 0 {
                lo[axis]
            } else {
                hi[axis]
            }
        };
        let Some(p) = projection.project(Vec3::new(pick(0), pick(1), pick(2))) else {
            return Reach::BehindTheEye;
        };
        image = [image[0].min(p), image[1].max(p)];
    }
    let (lo, hi) = (image[0] - MARGIN, image[1] + MARGIN);
    if hi.x < 0.0 || hi.y < 0.0 || lo.x >= width as f32 || lo.y >= height as f32 {
        return Reach::Outside;
    }
    let first = lo.max(Vec2::ZERO).floor();
    let last = hi
        .min(Vec2::new(width as f32 - 1.0, height as f32 - 1.0))
        .floor();
    Reach::Pixels(
        [first.x as usize, first.y as usize],
        [last.x as usize, last.y as usize],
    )
}

/// Whether every pixel from `first` to `last` (columns and rows, inclusive) is marked.
fn all_marked(covered: &[bool], width: usize, first: [usize; 2], last: [usize; 2]) -> bool {
    (first[1]..=last[1]).all(|y| {
        covered[y * width + first[0]..=y * width + last[0]]
            .iter()
            .all(|&c| c)
    })
}

/// Marks the pixels whose widened square the image-space triangle `p` may overlap: those
/// in its bounding box that lie on the inner side of all three edges (the whole box for a
/// triangle seen edge-on).
fn mark_triangle(covered: &mut [bool], width: usize, height: usize, p: [Vec2; 3]) {
    let lo = p[0].min(p[1]).min(p[2]) - MARGIN;
    let hi = p[0].max(p[1]).max(p[2]) + MARGIN;
    if hi.x < 0.0 || hi.y < 0.0 || lo.x >= width as f32 || lo.y >= height as f32 {
        return;
    }
    let first = lo.max(Vec2::ZERO).floor();
    let last = hi
        .min(Vec2::new(width as f32 - 1.0, height as f32 - 1.0))
        .floor();
    let twice_area = (p[1] - p[0]).perp_dot(p[2] - p[0]);
    let edge_on = twice_area.abs() <= f32::EPSILON * (hi - lo).length_squared();
    // Edges oriented so that the inside is on their left; the edge function's largest value
    // over a square is its value at the centre plus the half-size times the gradient's 1-norm.
    let edges = [0, 1, 2].map(|i| (p[i], (p[(i + 1) % 3] - p[i]) * twice_area.signum()));
    let half = 0.5 + MARGIN;
    for y in first.y as usize..=last.y as usize {
        for x in first.x as usize..=last.x as usize {
            let centre = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            let inside = || {
                edges.iter().all(|&(a, edge)| {
                    edge.perp_dot(centre - a) + half * (edge.x.abs() + edge.y.abs()) >= 0.0
                })
            };
            if edge_on || inside() {
                covered[y * width + x] = true;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::compile::{camera_ray, gpu_camera};
    use crate::geometry::intersect_triangle;
    use crate::layout::GpuTriangle;
    use crate::rng::{PassKind, StreamKey};
    use crate::scene::Camera;

    fn camera(width: u32, height: u32) -> GpuCamera {
        let camera = Camera {
            eye: Vec3::new(1.0, 2.0, 9.0),
            look_at: Vec3::new(0.0, 0.5, 0.0),
            up: Vec3::Y,
            fov_deg: 50.0,
            width,
            height,
        };
        gpu_camera(&camera, width, height)
    }

    /// Whether the eye ray through image point `(px, py)` meets triangle `t` at any distance:
    /// the exact question [`covered_pixels`] answers conservatively.
    fn ray_meets(camera: &GpuCamera, px: f32, py: f32, t: &[Vec3; 3]) -> bool {
        let tri = GpuTriangle {
            v0: t[0].into(),
            e1: (t[1] - t[0]).into(),
            e2: (t[2] - t[0]).into(),
            ..Default::default()
        };
        let dir = camera_ray(camera, px, py);
        intersect_triangle(camera.eye.into(), dir, &tri, 0.0, f32::INFINITY).is_finite()
    }

    #[test]
    fn projection_inverts_camera_rays() {
        let cam = camera(64, 48);
        for (px, py) in [(0.0, 0.0), (31.5, 20.25), (63.9, 47.9), (10.0, 40.0)] {
            for distance in [0.5, 3.0, 40.0] {
                let p = Vec3::from(cam.eye) + camera_ray(&cam, px, py) * distance;
                let image = Projection::new(&cam).project(p).unwrap();
                approx::assert_abs_diff_eq!(image.x, px, epsilon = 1e-3);
                approx::assert_abs_diff_eq!(image.y, py, epsilon = 1e-3);
            }
        }
        let behind = Vec3::from(cam.eye) - Vec3::from(cam.forward);
        assert_eq!(Projection::new(&cam).project(behind), None);
    }

    /// Every jittered eye ray that meets a triangle lands in a marked pixel, and the marks
    /// stay close to what the rays meet (a few pixels' rim, not the bounding box).
    #[test]
    fn marks_every_pixel_a_ray_meets() {
        let cam = camera(64, 48);
        let triangles = [
            [
                Vec3::new(-2.0, 0.0, 0.0),
                Vec3::new(2.5, 0.2, -1.0),
                Vec3::new(0.3, 3.0, 0.5),
            ],
            // Small, and seen almost edge-on.
            [
                Vec3::new(2.0, 1.0, 1.0),
                Vec3::new(2.2, 1.0, 1.0),
                Vec3::new(2.1, 1.0, 0.2),
            ],
        ];
        let covered = covered_pixels(&cam, &triangles);
        let mut met = vec![false; covered.len()];
        for pixel in 0..covered.len() as u32 {
            let key = StreamKey {
                seed: 1,
                kind: PassKind::Eye,
                pass_index: 0,
                path: pixel,
            };
            for sample in 0..64 {
                let px = (pixel % cam.width) as f32 + key.uniform(2 * sample);
                let py = (pixel / cam.width) as f32 + key.uniform(2 * sample + 1);
                if triangles.iter().any(|t| ray_meets(&cam, px, py, t)) {
                    met[pixel as usize] = true;
                    assert!(covered[pixel as usize], "pixel {pixel} met but not marked");
                }
            }
        }
        let (marked, hit) = (
            covered.iter().filter(|&&c| c).count(),
            met.iter().filter(|&&m| m).count(),
        );
        assert!(hit > 100, "the test triangles cover {hit} pixels");
        assert!(marked <= hit + hit / 4, "{marked} marked for {hit} met");
    }

    /// A sphere of 3,200 triangles of radius 1 at `centre`.
    fn sphere(centre: Vec3) -> Vec<[Vec3; 3]> {
        let (rings, segments) = (40, 40);
        let at = |i: usize, j: usize| {
            let (theta, phi) = (
                std::f32::consts::PI * i as f32 / rings as f32,
                std::f32::consts::TAU * j as f32 / segments as f32,
            );
            centre
                + Vec3::new(
                    theta.sin() * phi.cos(),
                    theta.cos(),
                    theta.sin() * phi.sin(),
                )
        };
        (0..rings * segments)
            .flat_map(|k| {
                let (i, j) = (k / segments, k % segments);
                [
                    [at(i, j), at(i + 1, j), at(i + 1, j + 1)],
                    [at(i, j), at(i + 1, j + 1), at(i, j + 1)],
                ]
            })
            .collect()
    }

    /// The tree's cover marks exactly the pixels the triangles' does, for a mesh seen whole,
    /// from close by, cut by the image's edge, from inside its box, and from inside itself
    /// (some triangles behind the eye: every pixel).
    #[test]
    fn the_tree_marks_what_the_triangles_mark() {
        use crate::compile::compile_scene;
        use crate::local_move::moved_triangles;
        use crate::scene::testing::{object, room};
        let scene = room(vec![
            object("floor", 0, sphere(Vec3::new(-3.0, 0.0, 0.0))),
            object("ball", 0, sphere(Vec3::new(0.5, 1.0, 0.0))),
        ]);
        let compiled = compile_scene(&scene, 8, 8);
        let root = compiled.spans[1].root;
        let views = [
            (Vec3::new(1.0, 2.0, 9.0), Vec3::new(0.0, 0.5, 0.0)),
            (Vec3::new(0.5, 1.2, 2.5), Vec3::new(0.5, 1.0, 0.0)),
            (Vec3::new(3.0, 1.0, 3.0), Vec3::new(-1.0, 1.0, 0.0)),
            (Vec3::new(1.2, 1.8, 0.7), Vec3::new(0.5, 1.0, 0.0)),
            (Vec3::new(0.5, 1.0, 0.0), Vec3::new(0.5, 1.0, 5.0)),
        ];
        let mut marked = Vec::new();
        for (eye, look_at) in views {
            let view = Camera {
                eye,
                look_at,
                up: Vec3::Y,
                fov_deg: 50.0,
                width: 96,
                height: 64,
            };
            let cam = gpu_camera(&view, 96, 64);
            let expected = covered_pixels(&cam, &moved_triangles(&compiled.triangles, &[1]));
            let tree = covered_pixels_in_tree(&cam, &compiled.nodes, &compiled.triangles, &[root]);
            assert_eq!(tree, expected, "eye {eye}");
            marked.push(expected.iter().filter(|&&c| c).count());
        }
        // The views see the ball whole, close, cut, and from inside.
        assert!(marked[0] > 100 && marked[0] < marked[1], "{marked:?}");
        assert!(marked[2] > 0 && marked[4] == 96 * 64, "{marked:?}");
    }

    #[test]
    fn a_triangle_behind_the_eye_marks_everything() {
        let cam = camera(16, 16);
        let eye = Vec3::from(cam.eye);
        let t = [eye + Vec3::X, eye - Vec3::Z, eye + Vec3::Z];
        assert!(covered_pixels(&cam, &[t]).iter().all(|&c| c));
        assert!(covered_pixels(&cam, &[]).iter().all(|&c| !c));
    }
}
