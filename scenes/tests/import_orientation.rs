//! Which side an imported surface faces (the side a light emits from, the outside of glass):
//! the winding, each renderer's flags that reverse it, mirroring transforms, and vertex
//! normals, as Mitsuba 3 and pbrt-v4 apply them.

use glam::Vec3;
use ppm_core::scene::Scene;
use scenes::file::{mitsuba, pbrt};
use std::path::Path;

/// The direction the light (the last object) faces, as the sum of its triangle normals.
fn light_normal(scene: &Scene) -> Vec3 {
    let light = scene.objects.last().unwrap();
    light
        .triangles
        .iter()
        .map(|t| (t[1] - t[0]).cross(t[2] - t[0]))
        .sum::<Vec3>()
        .normalize()
}

/// A floor, then a light triangle at y = 2 whose winding faces +y, preceded by `before` and
/// with `params` added to its shape.
fn pbrt_light(before: &str, params: &str) -> Vec3 {
    let text = format!(
        "Scale -1 1 1\nLookAt 0 5 -5  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin\n\
         Shape \"trianglemesh\" \"point3 P\" [ -1 0 -1  1 0 -1  1 0 1 ] \"integer indices\" [ 0 1 2 ]\n\
         AttributeBegin\n{before}\nAreaLightSource \"diffuse\" \"rgb L\" [ 1 1 1 ]\n\
         Shape \"trianglemesh\" \"point3 P\" [ 0 2 0  0 2 1  1 2 0 ] \"integer indices\" [ 0 1 2 ] {params}\n\
         AttributeEnd\n"
    );
    light_normal(&pbrt::parse_pbrt(&text, "t.pbrt", Path::new("."), "t").unwrap())
}

#[test]
fn pbrt_light_faces_its_winding_and_reverse_orientation_turns_it() {
    assert_eq!(pbrt_light("", ""), Vec3::Y);
    assert_eq!(pbrt_light("ReverseOrientation", ""), -Vec3::Y);
}

/// pbrt negates the normal of a mesh under a transform that swaps handedness, so a mirrored
/// light still faces the way its object-space winding says.
#[test]
fn pbrt_mirroring_transform_keeps_the_light_facing_its_way() {
    assert_eq!(pbrt_light("Scale -1 1 1", ""), Vec3::Y);
    assert_eq!(pbrt_light("Scale 1 -1 1", ""), -Vec3::Y);
}

#[test]
fn pbrt_vertex_normals_decide_the_side() {
    let down = "\"normal N\" [ 0 -1 0  0 -1 0  0 -1 0 ]";
    assert_eq!(pbrt_light("", down), -Vec3::Y);
    assert_eq!(pbrt_light("ReverseOrientation", down), Vec3::Y);
}

fn mitsuba_lamp(shape: &str) -> Vec3 {
    let text = format!(
        r#"<scene version="3.0.0">
    <sensor type="perspective"><float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, 0, -5" target="0, 0, 0" up="0, 1, 0"/></transform>
    </sensor>
    <shape type="cube"/>
    <shape type="rectangle">{shape}
        <emitter type="area"><rgb name="radiance" value="1, 1, 1"/></emitter>
    </shape>
</scene>"#
    );
    light_normal(&mitsuba::parse_mitsuba(&text, "t.xml", Path::new("."), "t").unwrap())
}

/// Mitsuba's rectangle faces +z; `flip_normals` turns it; a mirroring `to_world` does not
/// (its normal is transformed as a normal).
#[test]
fn mitsuba_rectangle_faces_plus_z_unless_flipped() {
    assert_eq!(mitsuba_lamp(""), Vec3::Z);
    assert_eq!(
        mitsuba_lamp(r#"<boolean name="flip_normals" value="true"/>"#),
        -Vec3::Z
    );
    let mirrored = r#"<transform name="to_world"><scale x="-1"/></transform>"#;
    assert_eq!(mitsuba_lamp(mirrored), Vec3::Z);
    let turned = r#"<transform name="to_world"><scale z="-1"/></transform>"#;
    assert_eq!(mitsuba_lamp(turned), -Vec3::Z);
}

/// A pbrt sphere light: tessellated, every facet faces outwards (away from its centre), or
/// inwards under ReverseOrientation; pbrt transforms a sphere's normal as a normal, so a
/// mirroring transform then turns it in (ours follows). Two spheres sharing one material
/// with different radiances become two lights.
#[test]
fn pbrt_sphere_lights_face_outwards_unless_reversed() {
    let facing = |before: &str| -> (f32, usize) {
        let text = format!(
            "Scale -1 1 1\nLookAt 0 5 -5  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin\n\
             MakeNamedMaterial \"null\" \"string type\" \"diffuse\" \"rgb reflectance\" [ 0 0 0 ]\n\
             Shape \"trianglemesh\" \"point3 P\" [ -1 0 -1  1 0 -1  1 0 1 ] \"integer indices\" [ 0 1 2 ]\n\
             AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [ 2 2 2 ]\nNamedMaterial \"null\"\n\
             Translate 0 9 0\nShape \"sphere\" \"float radius\" [ 0.5 ]\nAttributeEnd\n\
             AttributeBegin\n{before}\nAreaLightSource \"diffuse\" \"rgb L\" [ 1 1 1 ]\nNamedMaterial \"null\"\n\
             Translate 0 3 0\nShape \"sphere\" \"float radius\" [ 0.5 ]\nAttributeEnd\n"
        );
        let scene = pbrt::parse_pbrt(&text, "t.pbrt", Path::new("."), "t").unwrap();
        let light = scene.objects.last().unwrap();
        let centre = light.bounds_centre();
        let outwards = light
            .triangles
            .iter()
            .filter(|t| (t[1] - t[0]).cross(t[2] - t[0]).dot(t[0] - centre) > 0.0)
            .count();
        let lights = scene
            .materials
            .iter()
            .filter(|m| matches!(m.kind, ppm_core::scene::MaterialKind::Light { .. }))
            .count();
        (outwards as f32 / light.triangles.len() as f32, lights)
    };
    assert_eq!(facing(""), (1.0, 2));
    assert_eq!(facing("ReverseOrientation"), (0.0, 2));
    assert_eq!(facing("Scale -1 1 1"), (0.0, 2));
}
