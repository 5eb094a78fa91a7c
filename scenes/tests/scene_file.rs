//! Scene files load what they describe: OBJ meshes through tobj with their transform, and the
//! rigid moves that make frame 1.

use glam::Vec3;
use scenes::file::load_scene_file;

const SCENE: &str = r#"
name = "obj-probe"

[camera]
eye = [0.0, 1.0, -5.0]
look_at = [0.0, 1.0, 0.0]
fov = 45.0
width = 4
height = 4

[materials]
grey = { type = "diffuse", albedo = [0.5, 0.5, 0.5] }
lamp = { type = "light", radiance = [2.0, 2.0, 2.0] }

[[objects]]
name = "mesh"
material = "grey"
obj = "meshes/tetra.obj"
scale = 2.0
translate = [10.0, 0.0, 0.0]

[[objects]]
name = "lamp"
material = "lamp"
triangles = [[[0.0, 3.0, 0.0], [1.0, 3.0, 0.0], [0.0, 3.0, 1.0]]]

[[moves]]
object = "mesh"
translate = [0.0, 0.0, 4.0]
"#;

const TETRA: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";

#[test]
fn obj_meshes_load_scaled_and_translated_and_moves_apply_in_frame_one() {
    let dir = std::env::temp_dir().join(format!("ppm-scene-file-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("meshes")).unwrap();
    std::fs::write(dir.join("meshes/tetra.obj"), TETRA).unwrap();
    std::fs::write(dir.join("scene.toml"), SCENE).unwrap();
    let scene = load_scene_file(&dir.join("scene.toml")).unwrap();
    std::fs::remove_dir_all(&dir).ok();

    let mesh = &scene.objects[scene.object_index("mesh").unwrap()];
    assert_eq!(mesh.triangles.len(), 4);
    let max = mesh
        .triangles
        .iter()
        .flatten()
        .fold(Vec3::MIN, |a, v| a.max(*v));
    assert_eq!(max, Vec3::new(12.0, 2.0, 2.0));
    let moved = scene.at_frame(1);
    let moved_mesh = &moved.objects[scene.object_index("mesh").unwrap()];
    let moved_max = moved_mesh
        .triangles
        .iter()
        .flatten()
        .fold(Vec3::MIN, |a, v| a.max(*v));
    assert_eq!(moved_max, Vec3::new(12.0, 2.0, 6.0));
    assert_eq!(moved.objects[1], scene.objects[1], "the lamp does not move");
}

#[test]
fn unreadable_scene_file_names_the_file() {
    let err = load_scene_file(std::path::Path::new("no/such/scene.toml")).unwrap_err();
    assert!(
        err.to_string()
            .starts_with("no/such/scene.toml: cannot read"),
        "{err}"
    );
}

/// A textured quad: the image's left column lies at the quad's first corner (u = 0), its
/// bottom row at v = 0; an image that is not there names the field and the file.
#[test]
fn a_textured_quad_reads_its_image_through_the_quad_coordinates() {
    use glam::Vec2;
    use ppm_core::scene::unpack_texel;
    let dir = std::env::temp_dir().join(format!("ppm-textured-quad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // 2x2: top row red, green; bottom row blue, white (8-bit sRGB, 255 decodes to 1).
    let rgb = [255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255];
    scenes::file::image::write_png_rgb(&dir.join("four.png"), &rgb, 2, 2).unwrap();
    let scene = |texture: &str| {
        format!(
            r#"
name = "textured-quad"
[camera]
eye = [0.5, 0.5, -2.0]
look_at = [0.5, 0.5, 0.0]
fov = 45.0
width = 4
height = 4
[materials]
paint = {{ type = "diffuse", texture = "{texture}" }}
lamp = {{ type = "light", radiance = [1.0, 1.0, 1.0] }}
[[objects]]
name = "quad"
material = "paint"
quads = [[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]]]
[[objects]]
name = "lamp"
material = "lamp"
triangles = [[[0.0, 2.0, -1.0], [1.0, 2.0, -1.0], [0.0, 2.0, 0.0]]]
"#
        )
    };
    let loaded = scenes::file::parse_scene(&scene("four.png"), "quad.toml", &dir).unwrap();
    let quad = &loaded.objects[0];
    let texture = loaded.materials[quad.material].texture.as_ref().unwrap();
    assert_eq!(quad.uvs.len(), 2);
    // The corner at (0, 0, 0) has uv (0, 0): near it the bottom-left texel (blue).
    assert_eq!(quad.uvs[0][0], Vec2::ZERO);
    let at = |u: f32, v: f32| texture.lookup(Vec2::new(u, v));
    assert_eq!(at(0.25, 0.25), Vec3::Z);
    assert_eq!(at(0.75, 0.75), Vec3::Y);
    assert_eq!(at(0.25, 0.75), Vec3::X);
    assert_eq!(unpack_texel(texture.texels[3]), Vec3::ONE);
    let err = scenes::file::parse_scene(&scene("gone.png"), "quad.toml", &dir)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("materials.paint.texture") && err.contains("gone.png"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A coated material takes a texture on its base as a diffuse one does, and a mirror or a
/// conductor on its reflectance: the colour is then 1 unless given (a factor on the image),
/// and an image that is not there names the field.
#[test]
fn a_textured_coated_material_reads_its_image_as_a_diffuse_one() {
    use ppm_core::scene::MaterialKind;
    let dir = std::env::temp_dir().join(format!("ppm-textured-coat-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    scenes::file::image::write_png_rgb(&dir.join("grey.png"), &[128; 12], 2, 2).unwrap();
    let scene = |paint: &str| {
        format!(
            r#"
name = "textured-coat"
[camera]
eye = [0.5, 0.5, -2.0]
look_at = [0.5, 0.5, 0.0]
fov = 45.0
width = 4
height = 4
[materials]
paint = {{ type = "coated", {paint} }}
lamp = {{ type = "light", radiance = [1.0, 1.0, 1.0] }}
[[objects]]
name = "quad"
material = "paint"
quads = [[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]]]
[[objects]]
name = "lamp"
material = "lamp"
triangles = [[[0.0, 2.0, -1.0], [1.0, 2.0, -1.0], [0.0, 2.0, 0.0]]]
"#
        )
    };
    let load = |paint: &str| scenes::file::parse_scene(&scene(paint), "coat.toml", &dir);
    let textured = load("texture = \"grey.png\", alpha = 0.2").unwrap();
    let paint = &textured.materials[textured.objects[0].material];
    assert_eq!(paint.texture.as_ref().unwrap().width, 2);
    assert_eq!(
        paint.kind,
        MaterialKind::Coated {
            albedo: Vec3::ONE,
            ior: 1.5,
            alpha: 0.2,
            nonlinear: false,
        }
    );
    let scaled = load("texture = \"grey.png\", albedo = [0.5, 0.5, 0.5]").unwrap();
    assert!(matches!(
        scaled.materials[scaled.objects[0].material].kind,
        MaterialKind::Coated { albedo, .. } if albedo == Vec3::splat(0.5)
    ));
    let err = load("texture = \"gone.png\"").unwrap_err().to_string();
    assert!(
        err.contains("materials.paint.texture") && err.contains("gone.png"),
        "{err}"
    );
    // A texture scales a mirror's or conductor's reflectance too (then 1 unless given).
    let specular = |paint: &str| {
        let text = scene("").replace("paint = { type = \"coated\",  }", paint);
        scenes::file::parse_scene(&text, "metal.toml", &dir)
    };
    let mirror = specular("paint = { type = \"mirror\", texture = \"grey.png\" }").unwrap();
    let m = &mirror.materials[mirror.objects[0].material];
    assert_eq!(
        (m.texture.as_ref().map(|t| t.width), &m.kind),
        (
            Some(2),
            &MaterialKind::Mirror {
                reflectance: Vec3::ONE
            }
        )
    );
    let metal = specular(
        "paint = { type = \"conductor\", eta = [0.2, 0.9, 1.1], k = [3.9, 2.4, 2.1], reflectance = [0.5, 0.5, 0.5], texture = \"grey.png\", alpha = 0.3 }",
    )
    .unwrap();
    let m = &metal.materials[metal.objects[0].material];
    assert!(m.texture.is_some());
    assert!(
        matches!(m.kind, MaterialKind::Conductor { reflectance, .. } if reflectance == Vec3::splat(0.5))
    );
    let err = specular("paint = { type = \"mirror\" }")
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("materials.paint.reflectance = missing: a mirror material needs its reflectance or a texture"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
