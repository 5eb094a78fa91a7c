//! What a user sees when a Mitsuba or pbrt file holds something we cannot render: one line
//! naming the file, the element or directive, and its line. And never a panic, even on a
//! file cut short anywhere.

use ppm_core::scene::SceneError;
use scenes::file::{mitsuba, pbrt};
use std::path::Path;

const MITSUBA_OK: &str = r#"<scene version="3.0.0">
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world">
            <lookat origin="0, 1, -5" target="0, 1, 0" up="0, 1, 0"/>
        </transform>
        <film type="hdrfilm">
            <integer name="width" value="64"/>
            <integer name="height" value="48"/>
        </film>
    </sensor>
    <bsdf type="twosided" id="white">
        <bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.8, 0.8"/></bsdf>
    </bsdf>
    <shape type="cube" id="box">
        <transform name="to_world"><scale value="0.5"/><translate y="0.5"/></transform>
        <ref id="white"/>
    </shape>
    <shape type="rectangle" id="lamp">
        <transform name="to_world"><rotate x="1" angle="90"/><translate y="3"/></transform>
        <emitter type="area"><rgb name="radiance" value="5, 5, 5"/></emitter>
    </shape>
</scene>
"#;

const PBRT_OK: &str = r#"LookAt 0 1 -5  0 1 0  0 1 0
Camera "perspective" "float fov" [ 40 ]
Film "rgb" "integer xresolution" [ 64 ] "integer yresolution" [ 48 ]
WorldBegin
Material "diffuse" "rgb reflectance" [ 0.8 0.8 0.8 ]
Shape "trianglemesh" "point3 P" [ -1 0 -1  1 0 -1  1 0 1  -1 0 1 ] "integer indices" [ 0 2 1 0 3 2 ]
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [ 5 5 5 ]
  Translate 0 3 0
  Shape "trianglemesh" "point3 P" [ -1 0 -1  1 0 -1  1 0 1 ] "integer indices" [ 0 1 2 ]
AttributeEnd
"#;

fn mitsuba_error(text: &str) -> String {
    mitsuba::parse_mitsuba(text, "scenes/test.xml", Path::new("scenes"), "test")
        .map(|_| "no error".to_owned())
        .unwrap_or_else(|e| e.to_string())
}

fn pbrt_error(text: &str) -> String {
    pbrt::parse_pbrt(text, "scenes/test.pbrt", Path::new("scenes"), "test")
        .map(|_| "no error".to_owned())
        .unwrap_or_else(|e| e.to_string())
}

#[test]
fn the_valid_files_load() {
    let scene = mitsuba::parse_mitsuba(MITSUBA_OK, "t.xml", Path::new("."), "t").unwrap();
    assert_eq!(scene.triangle_count(), 12 + 2);
    // The rectangle turned by +90 degrees about x faces -y: down, onto the box.
    let lamp = &scene.objects[1].triangles;
    assert!(
        lamp.iter()
            .all(|t| (t[1] - t[0]).cross(t[2] - t[0]).y < 0.0)
    );
    let scene = pbrt::parse_pbrt(PBRT_OK, "t.pbrt", Path::new("."), "t").unwrap();
    assert_eq!(scene.triangle_count(), 3);
    assert_eq!(scene.camera.width, 64);
}

#[test]
fn mitsuba_unknown_element_names_it_and_its_line() {
    let text = MITSUBA_OK
        .replace("<shape type=\"cube\"", "<shapes type=\"cube\"")
        .replace(
            "<ref id=\"white\"/>\n    </shape>",
            "<ref id=\"white\"/>\n    </shapes>",
        );
    insta::assert_snapshot!(mitsuba_error(&text));
}

#[test]
fn mitsuba_unsupported_material_names_the_bsdf() {
    let text = MITSUBA_OK.replace(
        "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.8, 0.8, 0.8\"/></bsdf>",
        "<bsdf type=\"roughconductor\"><float name=\"alpha\" value=\"0.1\"/></bsdf>",
    );
    insta::assert_snapshot!(mitsuba_error(&text));
}

#[test]
fn mitsuba_bad_number_names_the_value() {
    let text = MITSUBA_OK.replace("value=\"40\"", "value=\"4o\"");
    insta::assert_snapshot!(mitsuba_error(&text));
}

#[test]
fn mitsuba_missing_mesh_file_names_the_file() {
    let text = MITSUBA_OK.replace(
        "<shape type=\"cube\" id=\"box\">",
        "<shape type=\"ply\" id=\"box\"><string name=\"filename\" value=\"missing.ply\"/>",
    );
    insta::assert_snapshot!(mitsuba_error(&text));
}

#[test]
fn pbrt_unknown_directive_names_it_and_its_line() {
    let text = PBRT_OK.replace("AttributeBegin", "AtributeBegin");
    insta::assert_snapshot!(pbrt_error(&text));
}

#[test]
fn pbrt_unsupported_material_names_the_directive() {
    let text = PBRT_OK.replace("Material \"diffuse\"", "Material \"coateddiffuse\"");
    insta::assert_snapshot!(pbrt_error(&text));
}

#[test]
fn pbrt_bad_number_names_the_value() {
    let text = PBRT_OK.replace("[ 40 ]", "[ 4o ]");
    insta::assert_snapshot!(pbrt_error(&text));
}

#[test]
fn pbrt_missing_mesh_file_names_the_file() {
    let text = PBRT_OK.replace(
        "Shape \"trianglemesh\" \"point3 P\" [ -1 0 -1  1 0 -1  1 0 1  -1 0 1 ] \"integer indices\" [ 0 2 1 0 3 2 ]",
        "Shape \"plymesh\" \"string filename\" \"missing.ply\"",
    );
    insta::assert_snapshot!(pbrt_error(&text));
}

#[test]
fn unsupported_shapes_and_lights_are_refused_with_their_line() {
    let sphere = MITSUBA_OK.replace("type=\"cube\"", "type=\"sphere\"");
    assert!(
        mitsuba_error(&sphere)
            .starts_with("scenes/test.xml:15: <shape type=\"sphere\" id=\"box\">")
    );
    let point = PBRT_OK.replace("WorldBegin", "WorldBegin\nLightSource \"point\"");
    assert!(pbrt_error(&point).starts_with("scenes/test.pbrt:5: LightSource \"point\":"));
}

/// Every prefix of a valid file (cut at each line) either loads or is an error: no panic.
#[test]
fn files_cut_short_anywhere_are_errors_not_panics() {
    for text in [MITSUBA_OK, PBRT_OK] {
        let lines: Vec<&str> = text.lines().collect();
        for n in 0..lines.len() {
            let cut = lines[..n].join("\n");
            let _ = mitsuba::parse_mitsuba(&cut, "cut.xml", Path::new("."), "cut");
            let _ = pbrt::parse_pbrt(&cut, "cut.pbrt", Path::new("."), "cut");
        }
    }
    let e = pbrt::parse_pbrt(
        "Camera \"perspective\" \"float fov\" [ 4",
        "c.pbrt",
        Path::new("."),
        "c",
    );
    assert!(matches!(
        e,
        Err(SceneError::At { .. }) | Err(SceneError::Invalid { .. })
    ));
}

/// An `Integrator "sppm"` sets what means the same here: the initial radius, photons per
/// iteration (-1: one per pixel, as pbrt), the iterations. Another integrator's settings
/// leave ours, and a radius or count that cannot be one is refused naming it.
#[test]
fn pbrt_sppm_settings_become_the_render_defaults() {
    let with = |integrator: &str| {
        let text = format!("{integrator}\n{PBRT_OK}");
        pbrt::parse_pbrt(&text, "t.pbrt", Path::new("."), "t").map(|s| s.render)
    };
    let sppm = with(
        r#"Integrator "sppm" "float radius" [ 0.01 ] "integer photonsperiteration" [ 20000 ] "integer iterations" [ 32 ] "integer maxdepth" [ 5 ]"#,
    )
    .unwrap();
    assert_eq!(
        (sppm.initial_radius, sppm.photons_per_pass, sppm.passes),
        (0.01, 20_000, 32)
    );
    let per_pixel = with(r#"Integrator "sppm" "integer photonsperiteration" [ -1 ]"#).unwrap();
    assert_eq!(per_pixel.photons_per_pass, 64 * 48);
    let plain = pbrt::parse_pbrt(PBRT_OK, "t.pbrt", Path::new("."), "t")
        .unwrap()
        .render;
    let path = with(r#"Integrator "volpath" "integer maxdepth" [ 5 ]"#).unwrap();
    assert_eq!(path, plain, "another integrator's settings are not ours");
    for (bad, named) in [
        (r#"Integrator "sppm" "float radius" [ -1 ]"#, "radius"),
        (
            r#"Integrator "sppm" "integer photonsperiteration" [ 0 ]"#,
            "photonsperiteration",
        ),
        (
            r#"Integrator "sppm" "integer iterations" [ 2.5 ]"#,
            "iterations",
        ),
    ] {
        let e = with(bad).unwrap_err().to_string();
        assert!(
            e.starts_with("t.pbrt:1: Integrator") && e.contains(named),
            "{bad}: {e}"
        );
    }
}
