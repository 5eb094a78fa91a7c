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
