//! What a path asks of a pose: the nearest surface along a ray, whether a segment is blocked,
//! and the records of what it meets. [`PoseQueries`] is the one interface every per-item
//! function of ppm-core traces through ([`crate::eye_path`], [`crate::direct_light`],
//! [`crate::local_move`]); [`FlatPose`] answers it over the compiled pose's own buffers by
//! walking the flattened BVH ([`BvhNode`]) exactly as backend-wgpu's `bvh.wgsl` does, its
//! twin. A backend may answer with a faster traversal of its own (backend-cpu walks obvhs's
//! tree) as long as it finds the same surfaces: the nearest, and among equally near ones the
//! lowest index ([`nearer`]), whatever order it visits them in.

use crate::compile::CompiledScene;
use crate::geometry::{Frame, intersect_triangle};
use crate::layout::{BvhNode, GpuLight, GpuMaterial, GpuTriangle};
use crate::textures::SurfaceTextures;
use glam::Vec3;

/// The nearest surface a ray meets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the (unit) direction.
    pub t: f32,
    /// Index of the triangle, in leaf order.
    pub triangle: u32,
}

/// Emitting triangles up to which [`PoseQueries::closest_hit_if_emitter`] tests them one by
/// one and casts one shadow ray to the nearest, instead of finding the nearest hit in the
/// tree: most of a direct-light pass's cosine rays meet no emitter and skip the tree, which
/// takes about a tenth off cornell-box's direct light on the CPU.
pub const FEW_EMITTERS: usize = 16;

/// A pose as paths trace it: ray queries, and the triangles, materials, lights and textures
/// they index.
pub trait PoseQueries: Sync {
    /// The nearest hit with `0 < t < tmax`.
    fn closest_hit(&self, origin: Vec3, dir: Vec3, tmax: f32) -> Option<Hit>;
    /// Whether anything lies on the segment from `origin` along `dir` to `tmax`.
    fn occluded(&self, origin: Vec3, dir: Vec3, tmax: f32) -> bool;
    /// Triangles, in leaf order.
    fn triangles(&self) -> &[GpuTriangle];
    /// Materials.
    fn materials(&self) -> &[GpuMaterial];
    /// Emitting triangles with their selection distribution.
    fn lights(&self) -> &[GpuLight];
    /// Index in [`Self::triangles`] of each emitting triangle.
    fn emitters(&self) -> &[u32];
    /// Texture coordinates and images.
    fn textures(&self) -> &SurfaceTextures;

    /// The nearest hit with `0 < t` when it is on an emitting triangle, `None` otherwise.
    /// Where emitters are few ([`FEW_EMITTERS`]) they are tested one by one, then one shadow
    /// ray reaches the nearest; otherwise the tree finds the nearest hit.
    fn closest_hit_if_emitter(&self, origin: Vec3, dir: Vec3) -> Option<Hit> {
        let emitters = self.emitters();
        if emitters.len() > FEW_EMITTERS {
            let hit = self.closest_hit(origin, dir, f32::INFINITY)?;
            let light = self.triangles()[hit.triangle as usize].light;
            return (light != crate::layout::NO_MATERIAL).then_some(hit);
        }
        let triangles = self.triangles();
        let nearest = emitters
            .iter()
            .map(|&i| Hit {
                t: intersect_triangle(origin, dir, &triangles[i as usize], 0.0, f32::INFINITY),
                triangle: i,
            })
            .reduce(|a, b| if b.t < a.t { b } else { a })?;
        (nearest.t < f32::INFINITY && !self.occluded(origin, dir, nearest.t)).then_some(nearest)
    }

    /// The material of triangle `hit.triangle` at `position`, its colour scaled by its
    /// texture there, and that factor (one where it has none).
    fn surface(&self, hit: &Hit, position: Vec3) -> (GpuMaterial, Vec3) {
        let tri = &self.triangles()[hit.triangle as usize];
        let material = &self.materials()[tri.material as usize];
        self.textures()
            .shaded(material, hit.triangle, tri, position)
    }

    /// The frame of `material`'s lobe at `hit`, seen from the side of `facing`
    /// ([`SurfaceTextures::frame`]).
    fn frame(&self, hit: &Hit, material: &GpuMaterial, facing: Vec3) -> Frame {
        let tri = &self.triangles()[hit.triangle as usize];
        self.textures().frame(material, hit.triangle, tri, facing)
    }
}

/// A compiled pose, traced over its flattened tree: the reference the WGSL twin is held to,
/// and what a backend without a tree of its own traces through.
#[derive(Clone, Copy)]
pub struct FlatPose<'a> {
    /// The pose.
    pub pose: &'a CompiledScene,
}

impl<'a> FlatPose<'a> {
    /// `pose`, traced over its flattened tree.
    pub fn new(pose: &'a CompiledScene) -> Self {
        Self { pose }
    }
}

/// Entries of the traversal stack: the deepest tree [`compile_scene`](crate::compile::compile_scene)
/// accepts leaves room for the nearer child at every level (`STACK_SIZE` in bvh.wgsl).
pub const STACK_SIZE: usize = 64;

/// `1 / x`, with `x` no nearer zero than machine epsilon: a box's slabs stay finite for a
/// direction parallel to an axis.
#[inline]
fn safe_inverse(x: f32) -> f32 {
    const EPS: f32 = f32::EPSILON;
    if x.abs() <= EPS {
        return if x >= 0.0 { 1.0 / EPS } else { -1.0 / EPS };
    }
    1.0 / x
}

/// The distance at which the ray enters the box (zero from inside), or infinity.
#[inline]
fn ray_box(origin: Vec3, inv_dir: Vec3, node: &BvhNode) -> f32 {
    let t1 = (Vec3::from(node.min) - origin) * inv_dir;
    let t2 = (Vec3::from(node.max) - origin) * inv_dir;
    let tmin =
        t1.x.min(t2.x)
            .max(t1.y.min(t2.y))
            .max(t1.z.min(t2.z).max(0.0));
    let tmax = t1.x.max(t2.x).min(t1.y.max(t2.y)).min(t1.z.max(t2.z));
    if tmin <= tmax { tmin } else { f32::INFINITY }
}

/// Whether a triangle found at `t` with index `triangle` replaces `hit` as the nearest: it
/// is nearer, or as near with a lower index. Ties (a ray through an edge two triangles
/// share, as a symmetric scene's rays meet them exactly) then resolve the same whatever
/// order a walk visits the triangles in, so every backend's walk finds the same surface.
#[inline]
pub fn nearer(t: f32, triangle: u32, hit: &Hit) -> bool {
    t < hit.t || t == hit.t && triangle < hit.triangle
}

/// The farthest distance at which a triangle may still replace `hit` ([`nearer`]): just
/// past `hit.t` once something was hit, so that a tie is tested, and `tmax` (excluded)
/// before.
#[inline]
pub fn tie_bound(hit: &Hit) -> f32 {
    if hit.triangle == u32::MAX {
        hit.t
    } else {
        hit.t.next_up()
    }
}

/// Relative slack of [`box_reach`]: more than the rounding of a box's entry distance and of
/// a triangle's distance together (a few ulps each).
pub const BOX_SLACK: f32 = 16.0 * f32::EPSILON;

/// The farthest entry distance at which a walk visits a box: a little past the nearest hit,
/// since a box's entry is rounded apart from the distance of a triangle lying in its face
/// (each walk rounds it its own way), and missing that triangle would break a tie
/// differently; `tmax` (excluded) before any hit.
#[inline]
pub fn box_reach(hit: &Hit) -> f32 {
    if hit.triangle == u32::MAX {
        hit.t
    } else {
        hit.t * (1.0 + BOX_SLACK)
    }
}

/// The nearest triangle of `nodes`' leaves with `0 < t < tmax` (the lowest index among
/// equally near ones, [`nearer`]), or with `any_hit` the first found: children nearer first,
/// the nearer straight away, the farther from the stack; a box entered within
/// [`box_reach`] of the nearest hit is visited, as it may hold a tie.
pub fn trace_closest(
    nodes: &[BvhNode],
    triangles: &[GpuTriangle],
    origin: Vec3,
    dir: Vec3,
    tmax: f32,
    any_hit: bool,
) -> Option<Hit> {
    let mut hit = Hit {
        t: tmax,
        triangle: u32::MAX,
    };
    let inv_dir = Vec3::new(
        safe_inverse(dir.x),
        safe_inverse(dir.y),
        safe_inverse(dir.z),
    );
    let mut stack = [0u32; STACK_SIZE];
    let mut sp = 0;
    let mut node = nodes[0];
    let mut enter = ray_box(origin, inv_dir, &node);
    loop {
        if enter < box_reach(&hit) {
            if node.count == 0 {
                let (left, right) = (nodes[node.first as usize], nodes[node.first as usize + 1]);
                let (t_left, t_right) = (
                    ray_box(origin, inv_dir, &left),
                    ray_box(origin, inv_dir, &right),
                );
                let left_first = t_left <= t_right;
                if t_left.max(t_right) < box_reach(&hit) && sp < STACK_SIZE {
                    stack[sp] = if left_first {
                        node.first + 1
                    } else {
                        node.first
                    };
                    sp += 1;
                }
                node = if left_first { left } else { right };
                enter = t_left.min(t_right);
                continue;
            }
            for i in node.first..node.first + node.count {
                let bound = tie_bound(&hit);
                let t = intersect_triangle(origin, dir, &triangles[i as usize], 0.0, bound);
                if t < bound && nearer(t, i, &hit) {
                    hit = Hit { t, triangle: i };
                    if any_hit {
                        return Some(hit);
                    }
                }
            }
        }
        if sp == 0 {
            break;
        }
        sp -= 1;
        node = nodes[stack[sp] as usize];
        enter = ray_box(origin, inv_dir, &node);
    }
    (hit.triangle != u32::MAX).then_some(hit)
}

impl PoseQueries for FlatPose<'_> {
    fn closest_hit(&self, origin: Vec3, dir: Vec3, tmax: f32) -> Option<Hit> {
        trace_closest(
            &self.pose.nodes,
            &self.pose.triangles,
            origin,
            dir,
            tmax,
            false,
        )
    }

    fn occluded(&self, origin: Vec3, dir: Vec3, tmax: f32) -> bool {
        trace_closest(
            &self.pose.nodes,
            &self.pose.triangles,
            origin,
            dir,
            tmax,
            true,
        )
        .is_some()
    }

    fn triangles(&self) -> &[GpuTriangle] {
        &self.pose.triangles
    }

    fn materials(&self) -> &[GpuMaterial] {
        &self.pose.materials
    }

    fn lights(&self) -> &[GpuLight] {
        &self.pose.lights
    }

    fn emitters(&self) -> &[u32] {
        &self.pose.emitters
    }

    fn textures(&self) -> &SurfaceTextures {
        &self.pose.textures
    }
}
