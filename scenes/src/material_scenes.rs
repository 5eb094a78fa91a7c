//! A test scene per material beyond the canonical ones: the Cornell box with its blocks in
//! that material, which docs/materials.md measures against Mitsuba 3 rendering our export.

use glam::{Vec2, Vec3};
use ppm_core::scene::{Material, MaterialKind, Scene, SceneError, Texture, TextureFilter};
use std::sync::Arc;

/// Gold's complex index of refraction at the wavelengths of red, green and blue (650, 550
/// and 450 nm; Johnson and Christy 1972).
pub const GOLD: (Vec3, Vec3) = (
    Vec3::new(0.143, 0.374, 1.442),
    Vec3::new(3.983, 2.385, 1.603),
);

/// Copper's, at the same wavelengths and from the same source.
pub const COPPER: (Vec3, Vec3) = (
    Vec3::new(0.200, 0.924, 1.102),
    Vec3::new(3.912, 2.452, 2.142),
);

/// `cornell-metal`: cornell-box with a tall block of rough gold (GGX alpha 0.3) and a short
/// block of nearly polished copper (alpha 0.05); the rest, the light and the move as
/// cornell-box.
pub fn cornell_metal() -> Result<Scene, SceneError> {
    let mut scene = crate::cornell_box_file()?;
    scene.name = "cornell-metal".into();
    for (block, name, (eta, k), alpha) in [
        ("tall-block", "rough-gold", GOLD, 0.3),
        ("short-block", "copper", COPPER, 0.05),
    ] {
        let object = scene
            .object_index(block)
            .expect("cornell-box has both blocks");
        scene.materials.push(Material {
            name: name.into(),
            kind: MaterialKind::Conductor {
                eta,
                k,
                reflectance: Vec3::ONE,
                alpha,
                alpha_v: alpha,
            },
            texture: None,
        });
        scene.objects[object].material = scene.materials.len() - 1;
    }
    Ok(scene)
}

/// `cornell-glass`: cornell-box with blocks of rough glass of index 1.5, the tall one frosted
/// lightly (GGX alpha 0.1), the short one heavily (alpha 0.4), each raised 1 mm off the
/// floor: a glass face lying in the floor's plane would let a path leaving through it start
/// below the floor and escape, whichever of the two the ray query returns first.
pub fn cornell_glass() -> Result<Scene, SceneError> {
    let mut scene = crate::cornell_box_file()?;
    scene.name = "cornell-glass".into();
    for (block, name, alpha) in [
        ("tall-block", "light-frost", 0.1),
        ("short-block", "heavy-frost", 0.4),
    ] {
        let object = scene
            .object_index(block)
            .expect("cornell-box has both blocks");
        scene.materials.push(Material::new(
            name,
            MaterialKind::Glass {
                ior: 1.5,
                alpha,
                alpha_v: alpha,
            },
        ));
        scene.objects[object].material = scene.materials.len() - 1;
        for v in scene.objects[object].triangles.iter_mut().flatten() {
            v.y += 1.0;
        }
    }
    Ok(scene)
}

/// `cornell-coated`: cornell-box with a tall block of red plastic under a rough coat (GGX
/// alpha 0.2, light meeting the base at each return under it) and a short block of blue
/// plastic under a smooth one; both coats of index 1.5.
pub fn cornell_coated() -> Result<Scene, SceneError> {
    let mut scene = crate::cornell_box_file()?;
    scene.name = "cornell-coated".into();
    for (block, name, albedo, alpha, nonlinear) in [
        (
            "tall-block",
            "rough-red-plastic",
            Vec3::new(0.7, 0.12, 0.08),
            0.2,
            true,
        ),
        (
            "short-block",
            "blue-plastic",
            Vec3::new(0.1, 0.25, 0.6),
            0.0,
            false,
        ),
    ] {
        let object = scene
            .object_index(block)
            .expect("cornell-box has both blocks");
        scene.materials.push(Material::new(
            name,
            MaterialKind::Coated {
                albedo,
                ior: 1.5,
                alpha,
                nonlinear,
            },
        ));
        scene.objects[object].material = scene.materials.len() - 1;
    }
    Ok(scene)
}

/// `cornell-brushed`: cornell-box with anisotropic blocks, their texture coordinate `u`
/// running up each side (and along z on top), so that the lobes are oriented alike on every
/// face and across the basis an isotropic lobe takes about the normal (horizontal there): a
/// tall block of brushed gold (GGX alpha 0.4 along the brushing, 0.05 across) and a short
/// block of anisotropically frosted glass (0.05 and 0.3), raised 1 mm as cornell-glass's
/// are.
pub fn cornell_brushed() -> Result<Scene, SceneError> {
    let mut scene = crate::cornell_box_file()?;
    scene.name = "cornell-brushed".into();
    let (eta, k) = GOLD;
    for (block, name, kind) in [
        (
            "tall-block",
            "brushed-gold",
            MaterialKind::Conductor {
                eta,
                k,
                reflectance: Vec3::ONE,
                alpha: 0.4,
                alpha_v: 0.05,
            },
        ),
        (
            "short-block",
            "brushed-frost",
            MaterialKind::Glass {
                ior: 1.5,
                alpha: 0.05,
                alpha_v: 0.3,
            },
        ),
    ] {
        let index = scene
            .object_index(block)
            .expect("cornell-box has both blocks");
        scene.materials.push(Material::new(name, kind));
        let object = &mut scene.objects[index];
        object.material = scene.materials.len() - 1;
        object.uvs = upward_uvs(&object.triangles);
        if block == "short-block" {
            for v in object.triangles.iter_mut().flatten() {
                v.y += 1.0;
            }
        }
    }
    Ok(scene)
}

/// Texture coordinates whose `u` runs up each triangle's plane (along z where the triangle
/// is horizontal), `v` across it: the brushing direction of [`cornell_brushed`]'s blocks.
fn upward_uvs(triangles: &[[Vec3; 3]]) -> Vec<[Vec2; 3]> {
    triangles
        .iter()
        .map(|t| {
            let n = (t[1] - t[0]).cross(t[2] - t[0]).normalize_or_zero();
            let across = Vec3::Y.cross(n).try_normalize().unwrap_or(Vec3::X);
            let up = n.cross(across);
            t.map(|p| Vec2::new(p.dot(up), p.dot(across)))
        })
        .collect()
}

/// `cornell-textured`: cornell-box with a checkered floor (nearest texel, hard edges) and a
/// back wall painted with soft coloured rings (a 64x64 image, bilinear); textures generated
/// here, so the scene needs no file. The rest, the light and the move as cornell-box.
pub fn cornell_textured() -> Result<Scene, SceneError> {
    let mut scene = crate::cornell_box_file()?;
    scene.name = "cornell-textured".into();
    let invalid = |e| SceneError::invalid("cornell-textured", "textures", "generated", e);
    let floor = Texture::checkerboard(
        Vec3::new(0.8, 0.8, 0.75),
        Vec3::new(0.15, 0.2, 0.35),
        Vec2::splat(8.0),
    )
    .map_err(invalid)?;
    let rings = Texture::from_linear("rings", 64, 64, &rings(64), TextureFilter::Bilinear)
        .map_err(invalid)?;
    for (object, name, texture) in [("floor", "checkers", floor), ("back-wall", "rings", rings)] {
        let index = scene.object_index(object).expect("cornell-box has it");
        // The texture holds the whole colour.
        let material = Material {
            texture: Some(Arc::new(texture)),
            ..Material::new(name.to_owned(), MaterialKind::Diffuse { albedo: Vec3::ONE })
        };
        scene.materials.push(material);
        let object = &mut scene.objects[index];
        object.material = scene.materials.len() - 1;
        object.uvs = planar_uvs(&object.triangles);
    }
    Ok(scene)
}

/// Texture coordinates spanning the unit square over a flat object's bounding box, along
/// its two longest sides.
fn planar_uvs(triangles: &[[Vec3; 3]]) -> Vec<[Vec2; 3]> {
    let lo = triangles
        .iter()
        .flatten()
        .fold(Vec3::INFINITY, |a, &v| a.min(v));
    let hi = triangles
        .iter()
        .flatten()
        .fold(Vec3::NEG_INFINITY, |a, &v| a.max(v));
    let size = hi - lo;
    let mut axes = [0, 1, 2];
    axes.sort_by(|&a, &b| size[b].total_cmp(&size[a]));
    let (u, v) = (axes[0].min(axes[1]), axes[0].max(axes[1]));
    triangles
        .iter()
        .map(|t| t.map(|p| Vec2::new((p[u] - lo[u]) / size[u], (p[v] - lo[v]) / size[v])))
        .collect()
}

/// Concentric rings whose colour turns around the hue circle, on a light grey ground.
fn rings(n: u32) -> Vec<Vec3> {
    (0..n * n)
        .map(|i| {
            let (x, y) = ((i % n) as f32 + 0.5, (i / n) as f32 + 0.5);
            let r = (Vec2::new(x, y) / n as f32 - 0.5).length() * 2.0;
            let phase = r * 9.0;
            let wave = 0.5 + 0.5 * phase.cos();
            let hue = Vec3::new(phase.sin(), (phase + 2.1).sin(), (phase + 4.2).sin()) * 0.35 + 0.5;
            Vec3::splat(0.7).lerp(hue, wave)
        })
        .collect()
}
