//! Turns a [`Scene`] into the flat buffers every backend consumes, with the BVH built by obvhs.

use crate::bsdf;
use crate::layout::{
    BvhNode, GpuBounds, GpuCamera, GpuLight, GpuMaterial, GpuTriangle, NO_MATERIAL, material_kind,
};
use crate::scene::{Camera, MaterialKind, Scene};
use crate::scene_tree::{ObjectSpan, SceneTree, build_scene_tree};
use crate::textures::{SurfaceTextures, compile_textures};
use glam::{Vec3, Vec3A};
use obvhs::bvh2::{Bvh2, node::Bvh2Node};
use obvhs::{BvhBuildParams, triangle::Triangle};
use std::ops::Range;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// What a scene contains, so that passes and code paths it does not need are left out.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct SceneFeatures {
    /// Some surface is a mirror.
    pub mirror: bool,
    /// Some surface is glass.
    pub glass: bool,
    /// Some surface is a conductor (smooth or rough).
    #[serde(default)]
    pub conductor: bool,
    /// Some surface is coated diffuse: eye paths and photons may reflect off its coat.
    #[serde(default)]
    pub coated: bool,
    /// Some surface is glossy where eye paths continue (a rough conductor, a rough coat's
    /// reflection, rough glass): the eye pass samples the lights there
    /// ([`crate::bsdf::chain_samples_lights`]).
    #[serde(default)]
    pub glossy: bool,
    /// Some material's colour comes from an image texture.
    #[serde(default)]
    pub textured: bool,
    /// Some rough conductor or glass is anisotropic: its lobe follows the surface's texture
    /// coordinates ([`crate::bsdf::is_anisotropic`]).
    #[serde(default)]
    pub anisotropic: bool,
    /// Some object moves between frames.
    pub moving_objects: bool,
}

impl SceneFeatures {
    /// Mirror, glass, conductor or a coat: photons can form caustics and eye paths can
    /// bounce.
    pub fn specular(&self) -> bool {
        self.mirror || self.glass || self.conductor || self.coated
    }
}

/// obvhs's medium build with leaves of at most two triangles, collapsed only where a node costs
/// as much as a triangle test: the default leaves of up to eight cost the CPU backend's ray
/// passes about an eighth of their time on cornell-box, and two measure faster than one or
/// four.
const BVH_PARAMS: BvhBuildParams = BvhBuildParams {
    max_prims_per_leaf: 2,
    collapse_traversal_cost: 1.0,
    ..BvhBuildParams::medium_build()
};

/// A scene flattened into GPU-layout buffers, plus the obvhs BVH for CPU traversal.
///
/// The triangles, nodes and tree are shared (`Arc`): a backend's or the driver's copy of a
/// pose takes them without copying, and a move's refit writes new ones only for the pose it
/// makes, so a small move in a large scene does not copy the scene for each reader. A clone
/// shares them too (a refit reuses a spare pose's buffers only where nothing else holds them).
#[derive(Clone)]
pub struct CompiledScene {
    /// Camera at the requested resolution.
    pub camera: GpuCamera,
    /// Triangles in BVH leaf order.
    pub triangles: Arc<Vec<GpuTriangle>>,
    /// Flattened BVH nodes; node 0 is the root.
    pub nodes: Arc<Vec<BvhNode>>,
    /// The BVH as obvhs built it; its primitive ids index `triangles` directly.
    pub bvh: Arc<Bvh2>,
    /// Index in `triangles` of each emitting triangle (a refit, which moves no light and
    /// keeps the leaf order, keeps them).
    pub emitters: Arc<Vec<u32>>,
    /// Materials.
    pub materials: Vec<GpuMaterial>,
    /// Emitting triangles with their selection distribution.
    pub lights: Vec<GpuLight>,
    /// What the scene contains.
    pub features: SceneFeatures,
    /// Length of the scene's bounding-box diagonal: the scale for epsilons.
    pub extent: f32,
    /// Total emitted power `sum(pi * A * Le)`.
    pub light_power: Vec3,
    /// Time obvhs spent building the BVH (or [`recompile_moved`](crate::refit::recompile_moved)
    /// refitting it).
    pub bvh_build_time: Duration,
    /// [`tree_cost`] of the BVH when obvhs last built it from scratch: the bar a refitted tree
    /// is held to.
    pub bvh_built_cost: f32,
    /// [`tree_cost`] of the BVH as it is: a refit updates it from the nodes it changes.
    pub bvh_cost: f32,
    /// Levels of the deepest leaf (the root is level 1): bounds a traversal stack.
    pub bvh_depth: usize,
    /// The boxes of the objects a local move moves, in both poses: its photon passes store
    /// and trace only what follows a crossing of one ([`photon_flags`](crate::layout::photon_flags)).
    /// Empty (nothing tests them) until a move sets them ([`mover_boxes`]).
    pub movers: Vec<GpuBounds>,
    /// Texture coordinates and images, empty for an untextured scene.
    pub textures: SurfaceTextures,
    /// Each object's box as its vertices here are posed (`[min, max]`, empty for an object
    /// without triangles): its subtree's root's, so a refit has it without reading the
    /// vertices again, and `extent` is the box around them all.
    pub object_bounds: Vec<[Vec3; 2]>,
    /// Where each object's triangles and subtree lie ([`crate::scene_tree`]).
    pub spans: Vec<ObjectSpan>,
    /// This pose's number, unique in the process. It names the pose's geometry, materials
    /// and lights: a backend holding a pose of the same number rewrites only the movers'
    /// boxes (and checks the camera), so whoever changes anything else compiles anew.
    pub pose: u64,
    /// Where this pose differs from the one it was refitted from, if it was
    /// ([`recompile_moved`](crate::refit::recompile_moved)): that pose's buffers become this
    /// one's by copying these entries alone.
    pub refit_from: Option<RefitWrites>,
}

/// The entries a refit wrote over the pose it started from.
#[derive(Clone)]
pub struct RefitWrites {
    /// The pose refitted ([`CompiledScene::pose`]).
    pub pose: u64,
    /// Blocks of triangles rewritten.
    pub triangles: Vec<Range<u32>>,
    /// Blocks of nodes rewritten (in both `nodes` and `bvh`).
    pub nodes: Vec<Range<u32>>,
}

/// A number no other pose of this process holds.
pub(crate) fn next_pose() -> u64 {
    static POSES: AtomicU64 = AtomicU64::new(0);
    POSES.fetch_add(1, Ordering::Relaxed)
}

/// Margin of the movers' boxes, relative to the scene's extent: ten times the ray offset,
/// so a path ending on a moving object's surface always crosses its box despite rounding.
pub const MOVER_MARGIN_RELATIVE: f32 = 1e-4;

/// Flattens `scene` for an image of `width` x `height`.
pub fn compile_scene(scene: &Scene, width: u32, height: u32) -> CompiledScene {
    let mut materials: Vec<GpuMaterial> = scene
        .materials
        .iter()
        .map(|m| gpu_material(&m.kind))
        .collect();
    let mut tris = Vec::new();
    for (object_index, object) in scene.objects.iter().enumerate() {
        for t in &object.triangles {
            tris.push((t, object.material as u32, object_index as u32));
        }
    }
    let per_object: Vec<Vec<Triangle>> = scene
        .objects
        .iter()
        .map(|o| {
            o.triangles
                .iter()
                .map(|t| Triangle {
                    v0: Vec3A::from(t[0]),
                    v1: Vec3A::from(t[1]),
                    v2: Vec3A::from(t[2]),
                })
                .collect()
        })
        .collect();
    let start = Instant::now();
    let SceneTree {
        bvh,
        spans,
        depth: bvh_depth,
    } = build_scene_tree(&per_object, BVH_PARAMS);
    let bvh_build_time = start.elapsed();

    // Lights in the scene's order, not the BVH's: a move rebuilds the BVH, and the paired
    // passes of a move (difference photons, the direct-light correction) trace both poses
    // with the same random numbers, which must pick the same light point in both.
    let mut lights = Vec::new();
    let mut light_of = vec![NO_MATERIAL; tris.len()];
    for (i, &(t, material, object)) in tris.iter().enumerate() {
        if let MaterialKind::Light { .. } = scene.materials[material as usize].kind {
            let gpu = gpu_triangle(t, material, object);
            let area = light_area(Vec3::from(gpu.e1), Vec3::from(gpu.e2));
            if area > 0.0 {
                light_of[i] = lights.len() as u32;
                lights.push(GpuLight {
                    v0: gpu.v0,
                    area,
                    e1: gpu.e1,
                    e2: gpu.e2,
                    normal: gpu.normal,
                    material,
                    ..Default::default()
                });
            }
        }
    }
    let triangles: Vec<GpuTriangle> = bvh
        .primitive_indices
        .iter()
        .map(|&p| {
            let (t, material, object) = tris[p as usize];
            GpuTriangle {
                light: light_of[p as usize],
                ..gpu_triangle(t, material, object)
            }
        })
        .collect();
    let emitters = (0..triangles.len() as u32)
        .filter(|&i| triangles[i as usize].light != NO_MATERIAL)
        .collect();
    let textures = compile_textures(scene, &bvh.primitive_indices, &mut materials);
    let light_power = assign_light_distribution(&mut lights, &materials);
    let nodes = flat_nodes(&bvh);
    let bvh_built_cost = tree_cost(&bvh);
    let object_bounds: Vec<[Vec3; 2]> = spans.iter().map(|s| s.bounds(&bvh)).collect();
    let extent = extent_of(&object_bounds);
    let glossy = materials.iter().any(crate::bsdf::chain_samples_lights);
    let anisotropic = materials.iter().any(crate::bsdf::is_anisotropic);
    CompiledScene {
        camera: gpu_camera(&scene.camera, width, height),
        triangles: Arc::new(triangles),
        nodes: Arc::new(nodes),
        bvh: Arc::new(bvh),
        emitters: Arc::new(emitters),
        materials,
        lights,
        features: SceneFeatures {
            mirror: scene
                .materials
                .iter()
                .any(|m| matches!(m.kind, MaterialKind::Mirror { .. })),
            glass: scene
                .materials
                .iter()
                .any(|m| matches!(m.kind, MaterialKind::Glass { .. })),
            conductor: scene
                .materials
                .iter()
                .any(|m| matches!(m.kind, MaterialKind::Conductor { .. })),
            coated: scene
                .materials
                .iter()
                .any(|m| matches!(m.kind, MaterialKind::Coated { .. })),
            glossy,
            textured: !textures.is_empty(),
            anisotropic,
            moving_objects: !scene.moves.is_empty(),
        },
        extent,
        light_power,
        bvh_build_time,
        bvh_built_cost,
        bvh_cost: bvh_built_cost,
        bvh_depth,
        movers: Vec::new(),
        textures,
        object_bounds,
        spans,
        pose: next_pose(),
        refit_from: None,
    }
}

/// The boxes of `objects` as posed in `before` and in `after`, widened by
/// [`MOVER_MARGIN_RELATIVE`] of `extent`: what a move of them may change lies on paths that
/// cross one of them.
pub fn mover_boxes(
    before: &Scene,
    after: &Scene,
    objects: &[usize],
    extent: f32,
) -> Vec<GpuBounds> {
    let boxes = [before, after]
        .into_iter()
        .flat_map(|scene| objects.iter().map(move |&o| scene.objects[o].bounds()));
    widened_boxes(boxes, extent)
}

/// Boxes (`(min, max)`) widened as [`mover_boxes`] widens them, for a caller that has them.
pub fn widened_boxes(boxes: impl IntoIterator<Item = (Vec3, Vec3)>, extent: f32) -> Vec<GpuBounds> {
    let margin = Vec3::splat(MOVER_MARGIN_RELATIVE * extent);
    boxes
        .into_iter()
        .map(|(lo, hi)| GpuBounds::new(lo - margin, hi + margin))
        .collect()
}

/// obvhs's nodes as the backends read them.
pub(crate) fn flat_nodes(bvh: &Bvh2) -> Vec<BvhNode> {
    bvh.nodes.iter().map(flat_node).collect()
}

/// One obvhs node in the GPU layout.
pub(crate) fn flat_node(n: &Bvh2Node) -> BvhNode {
    BvhNode {
        min: n.aabb.min.into(),
        first: n.first_index,
        max: n.aabb.max.into(),
        count: n.prim_count,
    }
}

/// The summed half surface areas of a BVH's nodes: in proportion to the nodes a ray crossing
/// the scene visits, which is what a refit lets grow.
pub fn tree_cost(bvh: &Bvh2) -> f32 {
    bvh.nodes.iter().map(|n| n.aabb.half_area()).sum()
}

/// Selects lights in proportion to their power, and returns the total power.
fn assign_light_distribution(lights: &mut [GpuLight], materials: &[GpuMaterial]) -> Vec3 {
    let power = |l: &GpuLight| {
        Vec3::from(materials[l.material as usize].emission) * (std::f32::consts::PI * l.area)
    };
    let total = lights.iter().map(power).fold(Vec3::ZERO, |a, b| a + b);
    let weights: Vec<f64> = lights
        .iter()
        .map(|l| f64::from(power(l).element_sum()) + 1e-30)
        .collect();
    let sum: f64 = weights.iter().sum();
    let mut acc = 0.0f64;
    for (l, w) in lights.iter_mut().zip(&weights) {
        acc += w;
        l.pdf = (w / sum) as f32;
        l.cdf = (acc / sum) as f32;
    }
    if let Some(last) = lights.last_mut() {
        last.cdf = 1.0;
    }
    total
}

fn gpu_material(kind: &MaterialKind) -> GpuMaterial {
    match *kind {
        MaterialKind::Diffuse { albedo } => GpuMaterial {
            albedo: albedo.into(),
            kind: material_kind::DIFFUSE,
            ..Default::default()
        },
        MaterialKind::Mirror { reflectance } => GpuMaterial {
            albedo: reflectance.into(),
            kind: material_kind::MIRROR,
            ..Default::default()
        },
        MaterialKind::Glass {
            ior,
            alpha,
            alpha_v,
        } => {
            let (alpha, alpha_v) = bsdf::roughness_pair(alpha, alpha_v);
            GpuMaterial {
                albedo: [1.0; 3],
                kind: material_kind::GLASS,
                ior,
                alpha,
                alpha_v,
                ..Default::default()
            }
        }
        MaterialKind::Conductor {
            eta,
            k,
            reflectance,
            alpha,
            alpha_v,
        } => {
            let (alpha, alpha_v) = bsdf::roughness_pair(alpha, alpha_v);
            GpuMaterial {
                albedo: reflectance.into(),
                kind: material_kind::CONDUCTOR,
                eta: eta.into(),
                alpha,
                alpha_v,
                k: k.into(),
                ..Default::default()
            }
        }
        MaterialKind::Coated {
            albedo,
            ior,
            alpha,
            nonlinear,
        } => bsdf::coated(albedo.into(), ior, alpha, nonlinear),
        MaterialKind::Light { radiance, albedo } => GpuMaterial {
            albedo: albedo.into(),
            kind: material_kind::DIFFUSE,
            emission: radiance.into(),
            ..Default::default()
        },
    }
}

pub(crate) fn gpu_triangle(t: &[Vec3; 3], material: u32, object: u32) -> GpuTriangle {
    let e1 = t[1] - t[0];
    let e2 = t[2] - t[0];
    GpuTriangle {
        v0: t[0].into(),
        material,
        e1: e1.into(),
        object,
        e2: e2.into(),
        light: NO_MATERIAL,
        normal: unit_normal(e1, e2).into(),
        group: object_group(object as usize),
    }
}

/// Groups an object shares with others: the slots record which groups their eye paths met
/// in 32 bits, so objects beyond the 32nd share a bit with an earlier one (`index % 32`). A
/// move of an object then resets the slots that met any object of its group: more than it
/// must, never less.
pub const OBJECT_GROUPS: usize = 32;

/// The bit of object `index`'s group in [`HitPoint::eye_met`](crate::layout::HitPoint::eye_met).
pub fn object_group(index: usize) -> u32 {
    1 << (index % OBJECT_GROUPS)
}

/// The unit normal of edges `e1`, `e2`: in `f32`, or in `f64` where the cross product's
/// squared length overflows `f32` (edges beyond ~1e9, which `MAX_COORDINATE` admits), so that
/// ordinary scenes keep their bits and large ones their normals.
fn unit_normal(e1: Vec3, e2: Vec3) -> Vec3 {
    e1.cross(e2).try_normalize().unwrap_or_else(|| {
        e1.as_dvec3()
            .cross(e2.as_dvec3())
            .normalize_or_zero()
            .as_vec3()
    })
}

/// A light triangle's area, in `f32` or, where that overflows, in `f64` (see [`unit_normal`]).
fn light_area(e1: Vec3, e2: Vec3) -> f32 {
    let area = 0.5 * e1.cross(e2).length();
    if area.is_finite() {
        area
    } else {
        (0.5 * e1.as_dvec3().cross(e2.as_dvec3()).length()) as f32
    }
}

/// The camera of `c` for an image of `width` x `height`, as [`camera_ray`] reads it.
pub fn gpu_camera(c: &Camera, width: u32, height: u32) -> GpuCamera {
    let forward = (c.look_at - c.eye).normalize();
    let right = forward.cross(c.up).normalize();
    let up = right.cross(forward);
    let tan_half = (c.fov_deg.to_radians() * 0.5).tan();
    let aspect = width as f32 / height as f32;
    GpuCamera {
        eye: c.eye.into(),
        width,
        forward: forward.into(),
        height,
        right: (right * (tan_half * aspect)).into(),
        _pad0: 0,
        up: (up * tan_half).into(),
        _pad1: 0,
    }
}

/// A box that contains nothing.
pub(crate) const EMPTY_BOX: [Vec3; 2] = [Vec3::INFINITY, Vec3::NEG_INFINITY];

/// The length of the diagonal of the box around `boxes`.
pub(crate) fn extent_of(boxes: &[[Vec3; 2]]) -> f32 {
    let [lo, hi] = boxes
        .iter()
        .fold(EMPTY_BOX, |[lo, hi], [a, b]| [lo.min(*a), hi.max(*b)]);
    (hi - lo).length()
}

/// Ray direction through the image point `(px, py)` in pixels (`(0, 0)` is the top-left corner).
#[inline]
pub fn camera_ray(camera: &GpuCamera, px: f32, py: f32) -> Vec3 {
    let sx = 2.0 * px / camera.width as f32 - 1.0;
    let sy = 1.0 - 2.0 * py / camera.height as f32;
    (Vec3::from(camera.forward) + Vec3::from(camera.right) * sx + Vec3::from(camera.up) * sy)
        .normalize()
}
