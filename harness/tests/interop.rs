//! Round trips through the Mitsuba 3 and pbrt-v4 formats: every built-in scene, in each frame
//! it has, written with `export_*` and read back with `harness::load_scene`, compiles to the
//! same buffers bit for bit (triangles, BVH, materials, lights, camera, textures), but for
//! what pbrt's format cannot say: its `coateddiffuse` is always `nonlinear`.

use ppm_core::compile::compile_scene;
use ppm_core::scene::{MaterialKind, Scene};
use scenes::file::bands::Colours;
use scenes::file::{Export, ExportOptions, mitsuba, pbrt};
use std::path::{Path, PathBuf};

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("ppm-interop-{}-{name}", std::process::id()));
    std::fs::remove_dir_all(&dir).ok();
    dir
}

/// What the round trip must keep, as the backends see it: every compiled buffer's bytes. The
/// formats hold one pose, not the motion, so the scene is compiled as a still one (which
/// triangles move is marked from the motion).
fn compiled_bytes(scene: &Scene) -> Vec<(&'static str, Vec<u8>)> {
    let still = Scene {
        moves: Vec::new(),
        ..scene.clone()
    };
    let c = compile_scene(&still, scene.camera.width, scene.camera.height);
    vec![
        ("camera", bytemuck::bytes_of(&c.camera).to_vec()),
        ("triangles", bytemuck::cast_slice(&c.triangles).to_vec()),
        ("bvh nodes", bytemuck::cast_slice(&c.nodes).to_vec()),
        ("materials", bytemuck::cast_slice(&c.materials).to_vec()),
        ("lights", bytemuck::cast_slice(&c.lights).to_vec()),
        (
            "light power",
            bytemuck::cast_slice(&c.light_power.to_array()).to_vec(),
        ),
        (
            "texture coordinates",
            bytemuck::cast_slice(&c.textures.uvs).to_vec(),
        ),
        (
            "texture headers",
            bytemuck::cast_slice(&c.textures.headers).to_vec(),
        ),
        (
            "texels",
            bytemuck::cast_slice(&c.textures.texels[..]).to_vec(),
        ),
    ]
}

/// The first compiled buffer in which `a` and `b` differ, if any.
fn first_difference(a: &Scene, b: &Scene) -> Option<&'static str> {
    compiled_bytes(a)
        .into_iter()
        .zip(compiled_bytes(b))
        .find(|(x, y)| x.1 != y.1)
        .map(|(x, _)| x.0)
}

/// `scene` as pbrt's format holds it: every coat `nonlinear` (pbrt's `coateddiffuse` meets
/// the base's colour at every return; the export's notes name a coat that is not).
fn as_pbrt_holds_it(scene: &Scene) -> Scene {
    let mut scene = scene.clone();
    for m in &mut scene.materials {
        if let MaterialKind::Coated { nonlinear, .. } = &mut m.kind {
            *nonlinear = true;
        }
    }
    scene
}

fn round_trip(export: &Export, dir: &Path) -> Scene {
    let path = export.write(dir).unwrap();
    harness::load_scene(path.to_str().unwrap()).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn every_builtin_scene_round_trips_through_mitsuba_and_pbrt_exactly_in_rgb_and_bands() {
    for builtin in scenes::BUILTIN {
        let scene = builtin.load().unwrap();
        let frames: &[u32] = if scene.moves.is_empty() {
            &[0]
        } else {
            &[0, 1]
        };
        for (&frame, colours) in frames
            .iter()
            .flat_map(|f| [(f, Colours::Rgb), (f, Colours::Bands)])
        {
            let posed = scene.at_frame(frame);
            let options = ExportOptions {
                samples_per_pixel: 64,
                frame,
                colours: Some(colours),
            };
            for (format, export, posed) in [
                (
                    "mitsuba",
                    mitsuba::export_mitsuba(&posed, &options),
                    posed.clone(),
                ),
                (
                    "pbrt",
                    pbrt::export_pbrt(&posed, &options),
                    as_pbrt_holds_it(&posed),
                ),
            ] {
                let dir = scratch(&format!("{}-{frame}-{format}-{colours:?}", builtin.name));
                let back = round_trip(&export, &dir);
                std::fs::remove_dir_all(&dir).ok();
                let what = format!("{} frame {frame} via {format}, {colours:?}", builtin.name);
                assert_eq!(back.camera, posed.camera, "{what}");
                let kinds = |s: &Scene| -> Vec<MaterialKind> {
                    s.materials.iter().map(|m| m.kind.clone()).collect()
                };
                assert_eq!(kinds(&back), kinds(&posed), "{what}");
                assert_eq!(back.triangle_count(), posed.triangle_count(), "{what}");
                assert_eq!(first_difference(&back, &posed), None, "{what}");
            }
        }
    }
}

/// The comparison sees a one-ulp change of one vertex, so the round trip test can fail.
#[test]
fn one_ulp_moved_vertex_is_a_different_compiled_scene() {
    let scene = scenes::cornell_box_file().unwrap();
    let mut nudged = scene.clone();
    let v = &mut nudged.objects[0].triangles[0][0];
    v.x = f32::from_bits(v.x.to_bits() + 1);
    assert_eq!(first_difference(&scene, &scene.clone()), None);
    assert!(first_difference(&scene, &nudged).is_some());
}

/// A pbrt file with a plain `LookAt` (no `Scale -1 1 1`) shows pbrt's mirrored view of our
/// world: the green wall on the left. The importer mirrors the world so that we see it too.
#[test]
fn pbrt_camera_without_the_flip_is_read_as_pbrt_shows_it() {
    let scene = scenes::cornell_box_file().unwrap();
    let export = pbrt::export_pbrt(&scene, &ExportOptions::default());
    let mut plain = export.clone();
    plain.text = export.text.replace("Scale -1 1 1\n", "");
    let dir = scratch("plain-lookat");
    let flipped = round_trip(&export, &dir);
    let mirrored = round_trip(&plain, &dir);
    std::fs::remove_dir_all(&dir).ok();
    let mean_x = |s: &Scene, name: &str| {
        let o = &s.objects[s.object_index(name).unwrap()];
        o.triangles.iter().flatten().map(|v| v.x).sum::<f32>() / (3 * o.triangles.len()) as f32
    };
    // Our image's left is +x for a camera looking along +z with +y up.
    assert!(mean_x(&flipped, "left-wall") > mean_x(&flipped, "right-wall"));
    assert!(mean_x(&mirrored, "right-wall") > mean_x(&mirrored, "left-wall"));
    // Mirroring keeps every light facing into the box (down, -y).
    let light = &mirrored.objects[mirrored.object_index("light").unwrap()];
    for t in &light.triangles {
        assert!((t[1] - t[0]).cross(t[2] - t[0]).y < 0.0);
    }
}

/// pbrt's fov spans the shorter image side: a tall image keeps our vertical fov through the
/// screen window, and a wide one needs none; Mitsuba names the axis.
#[test]
fn tall_and_wide_cameras_round_trip_exactly() {
    for (width, height) in [(48, 64), (64, 48)] {
        let mut scene = scenes::cornell_box_file().unwrap();
        (scene.camera.width, scene.camera.height) = (width, height);
        let options = ExportOptions::default();
        for export in [
            mitsuba::export_mitsuba(&scene, &options),
            pbrt::export_pbrt(&scene, &options),
        ] {
            let dir = scratch(&format!("aspect-{width}x{height}"));
            let back = round_trip(&export, &dir);
            std::fs::remove_dir_all(&dir).ok();
            assert_eq!(
                back.camera, scene.camera,
                "{width}x{height} {}",
                export.scene_file
            );
            assert_eq!(first_difference(&back, &scene), None);
        }
    }
}

/// A texture on a mirror's reflectance is written for Mitsuba 3 (its `specular_reflectance`
/// is a factor, as ours); pbrt-v4 has no such factor, and its export says so rather than drop
/// the texture silently.
#[test]
fn a_textured_mirror_goes_to_mitsuba_and_is_named_in_pbrt_s_notes() {
    use ppm_core::scene::{Texture, TextureFilter};
    let mut scene = scenes::builtin("specular-furnace").unwrap().load().unwrap();
    let white = Texture::from_linear("white", 1, 1, &[glam::Vec3::ONE], TextureFilter::Nearest);
    let mirror = scene
        .materials
        .iter_mut()
        .find(|m| matches!(m.kind, MaterialKind::Mirror { .. }))
        .unwrap();
    mirror.texture = Some(std::sync::Arc::new(white.unwrap()));
    let name = mirror.name.clone();
    let options = ExportOptions::default();
    let written = mitsuba::export_mitsuba(&scene, &options);
    assert_eq!(written.textures.len(), 1);
    let export = pbrt::export_pbrt(&scene, &options);
    assert!(export.textures.is_empty());
    let note = format!(
        "'{name}' is textured (white): this format takes a texture only on a diffuse reflectance"
    );
    assert!(
        export.notes.iter().any(|n| n.contains(&note)),
        "{:?}",
        export.notes
    );
}
