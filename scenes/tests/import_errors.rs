//! What a user sees when a Mitsuba or pbrt file holds something we cannot render: one line
//! naming the file, the element or directive, and its line. And never a panic, even on a
//! file cut short anywhere.

use glam::Vec3;
use ppm_core::scene::{MaterialKind, SceneError};
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

/// `PBRT_OK` with the floor's material written as `floor` (any directives before it too),
/// and the lamp given a plain diffuse material of its own (our lights are diffuse and
/// untextured).
fn pbrt_with_floor(floor: &str) -> String {
    PBRT_OK
        .replace(
            "Material \"diffuse\" \"rgb reflectance\" [ 0.8 0.8 0.8 ]",
            floor,
        )
        .replace(
            "AttributeBegin\n",
            "AttributeBegin\n  Material \"diffuse\" \"rgb reflectance\" [ 0.8 0.8 0.8 ]\n",
        )
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
        "<bsdf type=\"principled\"><float name=\"roughness\" value=\"0.1\"/></bsdf>",
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
    let text = PBRT_OK.replace("Material \"diffuse\"", "Material \"coatedconductor\"");
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

/// The first material of a scene read from `text`.
fn first_material(scene: Result<ppm_core::scene::Scene, SceneError>) -> MaterialKind {
    scene.expect("the file loads").materials[0].kind.clone()
}

#[test]
fn mitsuba_rough_conductors_read_with_their_index_and_ggx_roughness() {
    let conductor = |inner: &str| {
        let text = MITSUBA_OK.replace(
            "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.8, 0.8, 0.8\"/></bsdf>",
            inner,
        );
        mitsuba::parse_mitsuba(&text, "scenes/test.xml", Path::new("scenes"), "test")
    };
    let gold = r#"<bsdf type="roughconductor"><string name="distribution" value="ggx"/>
        <float name="alpha" value="0.2"/><rgb name="eta" value="0.1, 0.4, 1.4"/>
        <rgb name="k" value="4, 2.4, 1.6"/><rgb name="specular_reflectance" value="1, 0.9, 0.8"/></bsdf>"#;
    assert_eq!(
        first_material(conductor(gold)),
        MaterialKind::Conductor {
            eta: Vec3::new(0.1, 0.4, 1.4),
            k: Vec3::new(4.0, 2.4, 1.6),
            reflectance: Vec3::new(1.0, 0.9, 0.8),
            alpha: 0.2,
            alpha_v: 0.2,
        }
    );
    // Anisotropic: alpha_u along the surface's dp_du, alpha_v across it, each 0.1 unless
    // given (alpha sets both).
    let brushed = |u: &str, v: &str| {
        format!(
            r#"<bsdf type="roughconductor"><string name="distribution" value="ggx"/>{u}{v}
            <rgb name="eta" value="0.1, 0.4, 1.4"/><rgb name="k" value="4, 2.4, 1.6"/></bsdf>"#
        )
    };
    for (u, v, expected) in [
        (
            r#"<float name="alpha_u" value="0.05"/>"#,
            r#"<float name="alpha_v" value="0.4"/>"#,
            (0.05, 0.4),
        ),
        (r#"<float name="alpha_v" value="0.4"/>"#, "", (0.1, 0.4)),
        (
            r#"<float name="alpha_u" value="0.05"/>"#,
            r#"<float name="alpha" value="0.3"/>"#,
            (0.3, 0.3),
        ),
    ] {
        let MaterialKind::Conductor { alpha, alpha_v, .. } =
            first_material(conductor(&brushed(u, v)))
        else {
            panic!("not a conductor");
        };
        assert_eq!((alpha, alpha_v), expected, "{u} {v}");
    }
    // Mitsuba's material "none" (its default): a lossless metal, Fresnel factor one.
    let none = r#"<bsdf type="roughconductor"><string name="distribution" value="ggx"/>
        <float name="alpha_u" value="0.3"/><float name="alpha_v" value="0.3"/></bsdf>"#;
    assert!(matches!(
        first_material(conductor(none)),
        MaterialKind::Conductor {
            alpha: 0.3,
            k: Vec3::ONE,
            eta: Vec3::ZERO,
            ..
        }
    ));
    let smooth = r#"<bsdf type="conductor"><rgb name="eta" value="0.2, 0.9, 1.1"/><rgb name="k" value="3.9, 2.4, 2.1"/></bsdf>"#;
    assert!(matches!(
        first_material(conductor(smooth)),
        MaterialKind::Conductor { alpha: 0.0, .. }
    ));
    for (inner, says) in [
        (
            r#"<bsdf type="roughconductor"><float name="alpha" value="0.2"/></bsdf>"#,
            "Beckmann",
        ),
        (
            r#"<bsdf type="roughconductor"><string name="distribution" value="ggx"/><float name="alpha" value="1.5"/></bsdf>"#,
            "must be in [0, 1]",
        ),
        (
            r#"<bsdf type="conductor"><rgb name="eta" value="0.2, 0.9, 1.1"/></bsdf>"#,
            "both eta and k",
        ),
    ] {
        let e = conductor(inner).map(|_| ()).unwrap_err().to_string();
        assert!(e.contains(says) && e.contains("scenes/test.xml"), "{e}");
    }
}

#[test]
fn pbrt_conductors_read_with_pbrt_s_roughness_and_reflectance_rules() {
    let conductor = |params: &str| {
        let text = pbrt_with_floor(&format!("Material \"conductor\" {params}"));
        pbrt::parse_pbrt(&text, "scenes/test.pbrt", Path::new("scenes"), "test")
    };
    // remaproughness (on by default) turns roughness 0.04 into alpha sqrt(0.04) = 0.2.
    let gold = "\"rgb eta\" [ 0.1 0.4 1.4 ] \"rgb k\" [ 4 2.4 1.6 ] \"float roughness\" [ 0.04 ]";
    assert_eq!(
        first_material(conductor(gold)),
        MaterialKind::Conductor {
            eta: Vec3::new(0.1, 0.4, 1.4),
            k: Vec3::new(4.0, 2.4, 1.6),
            reflectance: Vec3::ONE,
            alpha: 0.2,
            alpha_v: 0.2,
        }
    );
    // uroughness and vroughness, each roughness where not given, remapped alike.
    for (params, expected) in [
        (
            "\"float uroughness\" [ 0.01 ] \"float vroughness\" [ 0.16 ]",
            (0.1, 0.4),
        ),
        (
            "\"float roughness\" [ 0.04 ] \"float vroughness\" [ 0.16 ]",
            (0.2, 0.4),
        ),
        (
            "\"float uroughness\" [ 0.16 ] \"float roughness\" [ 0.04 ]",
            (0.4, 0.2),
        ),
    ] {
        let MaterialKind::Conductor { alpha, alpha_v, .. } = first_material(conductor(&format!(
            "\"rgb eta\" [ 0.1 0.4 1.4 ] \"rgb k\" [ 4 2.4 1.6 ] {params}"
        ))) else {
            panic!("not a conductor");
        };
        assert!(
            (alpha - expected.0).abs() < 1e-6 && (alpha_v - expected.1).abs() < 1e-6,
            "{params}: {alpha} {alpha_v}"
        );
    }
    let raw = format!("{gold} \"bool remaproughness\" false");
    assert!(matches!(
        first_material(conductor(&raw)),
        MaterialKind::Conductor { alpha: 0.04, .. }
    ));
    // A reflectance with roughness: pbrt's eta = 1 and k = 2 sqrt(r) / sqrt(1 - r), whose
    // normal-incidence Fresnel term is r again.
    let MaterialKind::Conductor { eta, k, .. } = first_material(conductor(
        "\"rgb reflectance\" [ 0.9 0.5 0.2 ] \"float roughness\" [ 0.1 ]",
    )) else {
        panic!("not a conductor");
    };
    for (c, r) in [0.9f32, 0.5, 0.2].into_iter().enumerate() {
        let fresnel =
            ((eta[c] - 1.0).powi(2) + k[c] * k[c]) / ((eta[c] + 1.0).powi(2) + k[c] * k[c]);
        assert!((fresnel - r).abs() < 1e-5, "channel {c}: {fresnel} for {r}");
    }
    // pbrt-v4's named metals, read at our three wavelengths: silver, as Bitterli's scenes
    // name it, takes pbrt's table's values there.
    let silver = "\"spectrum eta\" \"metal-Ag-eta\" \"spectrum k\" [ \"metal-Ag-k\" ]";
    let MaterialKind::Conductor { eta, k, .. } = first_material(conductor(silver)) else {
        panic!("not a conductor");
    };
    assert_eq!(
        (eta, k),
        (
            Vec3::new(0.1394, 0.1248, 0.1517),
            Vec3::new(4.1288, 3.3396, 2.4704)
        )
    );
    for (params, says) in [
        (
            "\"spectrum eta\" \"metal-Pt-eta\" \"spectrum k\" \"metal-Pt-k\"",
            "or a named one other than",
        ),
        (
            "\"spectrum eta\" [ 400 1.2 700 0.4 ] \"spectrum k\" \"metal-Au-k\"",
            "sampled spectrum",
        ),
        ("\"rgb eta\" [ 0.1 0.4 1.4 ]", "together"),
    ] {
        let e = conductor(params).map(|_| ()).unwrap_err().to_string();
        assert!(e.contains(says) && e.contains("scenes/test.pbrt"), "{e}");
    }
}

/// Mitsuba 0.6's `sppm` integrator (Mitsuba 3 reads its files, but ships no photon mapper)
/// sets what means what ours means; a radius of 0 (its heuristic) and -1 passes (until
/// stopped) leave ours; another integrator changes nothing.
#[test]
fn mitsuba_sppm_settings_become_the_render_defaults() {
    let with = |integrator: &str| {
        let text = MITSUBA_OK.replace(
            "<sensor type=\"perspective\">",
            &format!("{integrator}\n    <sensor type=\"perspective\">"),
        );
        mitsuba::parse_mitsuba(&text, "scenes/test.xml", Path::new("scenes"), "test")
            .map(|s| s.render)
    };
    let plain = with("").unwrap();
    let sppm = with(
        r#"<integrator type="sppm"><float name="initialRadius" value="0.01"/>
        <integer name="photonCount" value="40000"/><float name="alpha" value="0.6"/>
        <integer name="maxPasses" value="300"/><integer name="maxDepth" value="12"/></integrator>"#,
    )
    .unwrap();
    assert_eq!(
        (
            sppm.initial_radius,
            sppm.photons_per_pass,
            sppm.alpha,
            sppm.passes
        ),
        (0.01, 40_000, 0.6, 300)
    );
    let defaults = with(
        r#"<integrator type="sppm"><float name="initial_radius" value="0"/>
        <integer name="max_passes" value="-1"/></integrator>"#,
    )
    .unwrap();
    assert_eq!(defaults, plain);
    let path =
        with(r#"<integrator type="path"><integer name="max_depth" value="-1"/></integrator>"#);
    assert_eq!(path.unwrap(), plain);
    for (bad, says) in [
        (
            r#"<integer name="photonCount" value="0"/>"#,
            "positive photon count",
        ),
        (r#"<float name="alpha" value="1.5"/>"#, "must be in (0, 1)"),
        (
            r#"<integer name="maxPasses" value="-3"/>"#,
            "-1 or a positive",
        ),
    ] {
        let e = with(&format!("<integrator type=\"sppm\">{bad}</integrator>")).unwrap_err();
        let e = e.to_string();
        assert!(e.contains(says) && e.contains("scenes/test.xml"), "{e}");
    }
}

/// pbrt textures: a checkerboard on a diffuse reflectance is read; a float texture, an
/// undeclared one, an unknown filter and a missing image are refused with the line.
#[test]
fn pbrt_textures_are_read_or_refused_by_line() {
    let textured = |texture: &str, use_it: &str| {
        pbrt_with_floor(&format!(
            "{texture}\nMaterial \"diffuse\" \"texture reflectance\" \"{use_it}\""
        ))
    };
    let checks = "Texture \"c\" \"spectrum\" \"checkerboard\" \"float uscale\" [ 4 ] \"rgb tex1\" [ 0.5 0.5 0.5 ]";
    let scene = pbrt::parse_pbrt(&textured(checks, "c"), "t.pbrt", Path::new("."), "t").unwrap();
    let floor = &scene.materials[scene.objects[0].material];
    let t = floor.texture.as_ref().expect("the floor is textured");
    assert_eq!((t.width, t.height), (2, 2));
    assert_eq!(
        t.scale,
        glam::Vec2::new(2.0, 0.5),
        "uscale 4 over the 2x2 image"
    );
    let rough = "Texture \"r\" \"float\" \"imagemap\" \"string filename\" \"r.png\"";
    let err = pbrt_error(&textured(rough, "r"));
    assert!(
        err.contains("test.pbrt:6") && err.contains("float texture"),
        "{err}"
    );
    let err = pbrt_error(&textured("", "nowhere"));
    assert!(err.contains("no Texture \"nowhere\""), "{err}");
    // pbrt-v4 turns a conductor's textured reflectance into an index per point.
    let metal = pbrt_with_floor(&format!(
        "{checks}\nMaterial \"conductor\" \"texture reflectance\" \"c\""
    ));
    let err = pbrt_error(&metal);
    assert!(
        err.contains("test.pbrt:6") && err.contains("a textured conductor reflectance"),
        "{err}"
    );
    let odd = "Texture \"i\" \"spectrum\" \"imagemap\" \"string filename\" \"i.png\" \"string filter\" \"cubic\"";
    let err = pbrt_error(&textured(odd, "i"));
    assert!(
        err.contains("test.pbrt:5") && err.contains("filter \"cubic\""),
        "{err}"
    );
    let gone = "Texture \"i\" \"spectrum\" \"imagemap\" \"string filename\" \"gone.tga\"";
    let err = pbrt_error(&textured(gone, "i"));
    assert!(
        err.contains("test.pbrt:5") && err.contains("gone.tga"),
        "{err}"
    );
}

/// Mitsuba's `plastic` and `roughplastic` read as our coated material: index `int_ior /
/// ext_ior` (numbers or named materials), Mitsuba's defaults (diffuse reflectance 0.5,
/// polypropylene in air, alpha 0.1, `nonlinear` false) where a parameter is absent.
#[test]
fn mitsuba_plastics_read_as_coated_with_mitsuba_s_defaults() {
    let plastic = |inner: &str| {
        let text = MITSUBA_OK.replace(
            "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.8, 0.8, 0.8\"/></bsdf>",
            inner,
        );
        mitsuba::parse_mitsuba(&text, "scenes/test.xml", Path::new("scenes"), "test")
    };
    let polypropylene_in_air = 1.49f32 / 1.000277;
    assert_eq!(
        first_material(plastic(r#"<bsdf type="plastic"/>"#)),
        MaterialKind::Coated {
            albedo: Vec3::splat(0.5),
            ior: polypropylene_in_air,
            alpha: 0.0,
            nonlinear: false,
        }
    );
    let red = r#"<bsdf type="plastic"><rgb name="diffuse_reflectance" value="0.7, 0.1, 0.1"/>
        <float name="int_ior" value="1.6"/><float name="ext_ior" value="1"/>
        <boolean name="nonlinear" value="true"/><rgb name="specular_reflectance" value="1, 1, 1"/></bsdf>"#;
    assert_eq!(
        first_material(plastic(red)),
        MaterialKind::Coated {
            albedo: Vec3::new(0.7, 0.1, 0.1),
            ior: 1.6,
            alpha: 0.0,
            nonlinear: true,
        }
    );
    let rough = r#"<bsdf type="roughplastic"><string name="distribution" value="ggx"/>
        <string name="int_ior" value="bk7"/><string name="ext_ior" value="vacuum"/></bsdf>"#;
    assert_eq!(
        first_material(plastic(rough)),
        MaterialKind::Coated {
            albedo: Vec3::splat(0.5),
            ior: 1.5046,
            alpha: 0.1,
            nonlinear: false,
        }
    );
    let equal_uv = r#"<bsdf type="roughplastic"><string name="distribution" value="ggx"/>
        <float name="alpha_u" value="0.3"/><float name="alpha_v" value="0.3"/>
        <boolean name="sample_visible" value="false"/></bsdf>"#;
    assert!(matches!(
        first_material(plastic(equal_uv)),
        MaterialKind::Coated { alpha: 0.3, .. }
    ));
    for (inner, says) in [
        (
            r#"<bsdf type="roughplastic"><float name="alpha" value="0.2"/></bsdf>"#,
            "a roughplastic without distribution=\"ggx\" is Beckmann's",
        ),
        (
            r#"<bsdf type="roughplastic"><string name="distribution" value="beckmann"/></bsdf>"#,
            "test.xml:13: <string name=\"distribution\" value=\"beckmann\">: the beckmann distribution",
        ),
        (
            r#"<bsdf type="roughplastic"><string name="distribution" value="ggx"/><float name="alpha_u" value="0.1"/><float name="alpha_v" value="0.3"/></bsdf>"#,
            "anisotropic",
        ),
        (
            r#"<bsdf type="roughplastic"><string name="distribution" value="ggx"/><float name="alpha" value="1.5"/></bsdf>"#,
            "<float name=\"alpha\" value=\"1.5\">: 1.5: must be in [0, 1]",
        ),
        (
            r#"<bsdf type="plastic"><float name="int_ior" value="1.2"/><float name="ext_ior" value="1.33"/></bsdf>"#,
            "a coat's index must exceed the outside's",
        ),
        (
            r#"<bsdf type="plastic"><float name="int_ior" value="1"/><float name="ext_ior" value="1"/></bsdf>"#,
            "int_ior / ext_ior = 1 / 1 = 1",
        ),
        (
            r#"<bsdf type="plastic"><rgb name="specular_reflectance" value="0.5, 0.5, 0.5"/></bsdf>"#,
            "specular_reflectance other than 1",
        ),
        (
            r#"<bsdf type="plastic"><rgb name="diffuse_reflectance" value="0.5, 1.2, 0.5"/></bsdf>"#,
            "1.2 is above 1",
        ),
        (
            r#"<bsdf type="plastic"><float name="alpha" value="0.1"/></bsdf>"#,
            "unknown parameter of a plastic",
        ),
        (
            r#"<bsdf type="plastic"><texture type="bitmap" name="diffuse_reflectance"><string name="filename" value="paint.png"/></texture><rgb name="diffuse_reflectance" value="0.5"/></bsdf>"#,
            "a second diffuse_reflectance",
        ),
        (
            r#"<bsdf type="roughplastic"><string name="distribution" value="ggx"/><texture type="bitmap" name="diffuse_reflectance"><string name="filename" value="gone.png"/></texture></bsdf>"#,
            "gone.png",
        ),
    ] {
        let e = plastic(inner).map(|_| ()).unwrap_err().to_string();
        assert!(e.contains(says) && e.contains("scenes/test.xml"), "{e}");
    }
}

/// pbrt's `coateddiffuse` reads as our coated material with `nonlinear` on (pbrt's random
/// walk meets the base's colour at every return): its roughness remapped to GGX alpha by
/// the square root unless `remaproughness` is off, its defaults (reflectance 0.5, roughness
/// 0, eta 1.5), and the parameters that tune pbrt's estimate taken and ignored.
#[test]
fn pbrt_coated_diffuse_reads_with_pbrt_s_roughness_rules() {
    let coated = |params: &str| {
        let text = pbrt_with_floor(&format!("Material \"coateddiffuse\" {params}"));
        pbrt::parse_pbrt(&text, "scenes/test.pbrt", Path::new("scenes"), "test")
    };
    assert_eq!(
        first_material(coated("")),
        MaterialKind::Coated {
            albedo: Vec3::splat(0.5),
            ior: 1.5,
            alpha: 0.0,
            nonlinear: true,
        }
    );
    let red = "\"rgb reflectance\" [ 0.7 0.1 0.1 ] \"float roughness\" [ 0.04 ] \"float eta\" [ 1.6 ] \"float thickness\" [ 0.02 ] \"float g\" [ 0.3 ] \"integer maxdepth\" [ 20 ] \"integer nsamples\" [ 4 ] \"rgb albedo\" [ 0 0 0 ]";
    assert_eq!(
        first_material(coated(red)),
        MaterialKind::Coated {
            albedo: Vec3::new(0.7, 0.1, 0.1),
            ior: 1.6,
            alpha: 0.2,
            nonlinear: true,
        }
    );
    let raw = "\"float roughness\" [ 0.04 ] \"bool remaproughness\" false";
    assert!(matches!(
        first_material(coated(raw)),
        MaterialKind::Coated { alpha: 0.04, .. }
    ));
    let equal_uv = "\"float uroughness\" [ 0.09 ] \"float vroughness\" [ 0.09 ]";
    let MaterialKind::Coated { alpha, .. } = first_material(coated(equal_uv)) else {
        panic!("not coated");
    };
    assert!((alpha - 0.3).abs() < 1e-6, "{alpha}");
    // Roughness at or below 0.001 is kept as given (the renderer treats alpha below 1e-3 as
    // smooth).
    assert!(matches!(
        first_material(coated(
            "\"float roughness\" [ 0.0005 ] \"bool remaproughness\" false"
        )),
        MaterialKind::Coated { alpha: 0.0005, .. }
    ));
    for (params, says) in [
        (
            "\"float uroughness\" [ 0.1 ] \"float vroughness\" [ 0.2 ]",
            "anisotropic roughness",
        ),
        (
            "\"rgb albedo\" [ 0.5 0.5 0.5 ]",
            "\"rgb albedo\": a scattering medium in the coat's layer",
        ),
        ("\"float eta\" [ 1 ]", "\"float eta\": 1: must be above 1"),
        ("\"float eta\" [ 0.8 ]", "must be above 1"),
        (
            "\"spectrum eta\" \"glass-BK7\"",
            "\"spectrum eta\": a dispersive (spectral) eta",
        ),
        (
            "\"float roughness\" [ 1.5 ]",
            "\"float roughness\": must be in [0, 1]",
        ),
        ("\"rgb reflectance\" [ 0.5 1.2 0.5 ]", "1.2 is above 1"),
        ("\"float interface.eta\" [ 1.5 ]", "unknown parameter"),
    ] {
        let e = coated(params).map(|_| ()).unwrap_err().to_string();
        assert!(e.contains(says) && e.contains("scenes/test.pbrt:5"), "{e}");
    }
}

/// Mitsuba's `dielectric` and `roughdielectric` read as our glass: index `int_ior /
/// ext_ior` (numbers or named materials), Mitsuba's defaults (BK7 in air, alpha 0.1) where a
/// parameter is absent; a `roughdielectric` needs `distribution="ggx"` and an isotropic
/// roughness, as a `roughconductor` does, and a tinted one is refused.
#[test]
fn mitsuba_rough_dielectrics_read_as_rough_glass_with_mitsuba_s_defaults() {
    let dielectric = |inner: &str| {
        let text = MITSUBA_OK.replace(
            "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.8, 0.8, 0.8\"/></bsdf>",
            inner,
        );
        mitsuba::parse_mitsuba(&text, "scenes/test.xml", Path::new("scenes"), "test")
    };
    let bk7_in_air = 1.5046f32 / 1.000277;
    assert_eq!(
        first_material(dielectric(r#"<bsdf type="dielectric"/>"#)),
        MaterialKind::Glass {
            ior: bk7_in_air,
            alpha: 0.0,
            alpha_v: 0.0,
        }
    );
    assert_eq!(
        first_material(dielectric(
            r#"<bsdf type="roughdielectric"><string name="distribution" value="ggx"/></bsdf>"#
        )),
        MaterialKind::Glass {
            ior: bk7_in_air,
            alpha: 0.1,
            alpha_v: 0.1,
        }
    );
    let water = r#"<bsdf type="roughdielectric"><string name="distribution" value="ggx"/>
        <float name="alpha" value="0.25"/><string name="int_ior" value="water"/>
        <string name="ext_ior" value="vacuum"/><rgb name="specular_reflectance" value="1, 1, 1"/>
        <rgb name="specular_transmittance" value="1, 1, 1"/></bsdf>"#;
    assert_eq!(
        first_material(dielectric(water)),
        MaterialKind::Glass {
            ior: 1.333,
            alpha: 0.25,
            alpha_v: 0.25,
        }
    );
    let equal_uv = r#"<bsdf type="roughdielectric"><string name="distribution" value="ggx"/>
        <float name="alpha_u" value="0.3"/><float name="alpha_v" value="0.3"/>
        <float name="int_ior" value="1.6"/><float name="ext_ior" value="1"/>
        <boolean name="sample_visible" value="false"/></bsdf>"#;
    assert_eq!(
        first_material(dielectric(equal_uv)),
        MaterialKind::Glass {
            ior: 1.6,
            alpha: 0.3,
            alpha_v: 0.3,
        }
    );
    let frosted = r#"<bsdf type="roughdielectric"><string name="distribution" value="ggx"/>
        <float name="alpha_u" value="0.1"/><float name="alpha_v" value="0.3"/></bsdf>"#;
    assert_eq!(
        first_material(dielectric(frosted)),
        MaterialKind::Glass {
            ior: bk7_in_air,
            alpha: 0.1,
            alpha_v: 0.3,
        }
    );
    for (inner, says) in [
        (
            r#"<bsdf type="roughdielectric"><float name="alpha" value="0.2"/></bsdf>"#,
            "test.xml:13: <bsdf type=\"roughdielectric\">: a roughdielectric without distribution=\"ggx\" is Beckmann's",
        ),
        (
            r#"<bsdf type="roughdielectric"><string name="distribution" value="beckmann"/></bsdf>"#,
            "test.xml:13: <string name=\"distribution\" value=\"beckmann\">: the beckmann distribution",
        ),
        (
            r#"<bsdf type="roughdielectric"><string name="distribution" value="ggx"/><float name="alpha" value="1.5"/></bsdf>"#,
            "<float name=\"alpha\" value=\"1.5\">: 1.5: must be in [0, 1]",
        ),
        (
            r#"<bsdf type="roughdielectric"><string name="distribution" value="ggx"/><rgb name="specular_reflectance" value="0.5, 0.5, 0.5"/></bsdf>"#,
            "a specular_reflectance other than 1 (a tinted roughdielectric)",
        ),
        (
            r#"<bsdf type="roughdielectric"><string name="distribution" value="ggx"/><rgb name="specular_transmittance" value="1, 0.9, 1"/></bsdf>"#,
            "a specular_transmittance other than 1 (a tinted roughdielectric)",
        ),
        (
            r#"<bsdf type="dielectric"><rgb name="specular_transmittance" value="0.9, 0.9, 0.9"/></bsdf>"#,
            "a specular_transmittance other than 1 (a tinted dielectric)",
        ),
        (
            r#"<bsdf type="dielectric"><float name="alpha" value="0.1"/></bsdf>"#,
            "unknown parameter of a dielectric",
        ),
        (
            r#"<bsdf type="roughdielectric"><string name="distribution" value="ggx"/><float name="int_ior" value="-1.5"/></bsdf>"#,
            "must be a positive number",
        ),
    ] {
        let e = dielectric(inner).map(|_| ()).unwrap_err().to_string();
        assert!(e.contains(says) && e.contains("scenes/test.xml"), "{e}");
    }
}

/// pbrt's `dielectric` reads as our glass of index `eta` (default 1.5) and pbrt's roughness,
/// remapped to GGX alpha by the square root unless `remaproughness` is off, as a conductor's
/// and a coated diffuse's.
#[test]
fn pbrt_dielectrics_read_with_pbrt_s_roughness_rules() {
    let dielectric = |params: &str| {
        let text = pbrt_with_floor(&format!("Material \"dielectric\" {params}"));
        pbrt::parse_pbrt(&text, "scenes/test.pbrt", Path::new("scenes"), "test")
    };
    assert_eq!(
        first_material(dielectric("")),
        MaterialKind::Glass {
            ior: 1.5,
            alpha: 0.0,
            alpha_v: 0.0,
        }
    );
    // remaproughness (on by default) turns roughness 0.04 into alpha sqrt(0.04) = 0.2.
    assert_eq!(
        first_material(dielectric(
            "\"float eta\" [ 1.33 ] \"float roughness\" [ 0.04 ]"
        )),
        MaterialKind::Glass {
            ior: 1.33,
            alpha: 0.2,
            alpha_v: 0.2,
        }
    );
    assert_eq!(
        first_material(dielectric(
            "\"float roughness\" [ 0.04 ] \"bool remaproughness\" true"
        )),
        MaterialKind::Glass {
            ior: 1.5,
            alpha: 0.2,
            alpha_v: 0.2,
        }
    );
    assert_eq!(
        first_material(dielectric(
            "\"float roughness\" [ 0.04 ] \"bool remaproughness\" false"
        )),
        MaterialKind::Glass {
            ior: 1.5,
            alpha: 0.04,
            alpha_v: 0.04,
        }
    );
    let equal_uv = "\"float uroughness\" [ 0.09 ] \"float vroughness\" [ 0.09 ]";
    let MaterialKind::Glass { alpha, .. } = first_material(dielectric(equal_uv)) else {
        panic!("not glass");
    };
    assert!((alpha - 0.3).abs() < 1e-6, "{alpha}");
    assert!(matches!(
        first_material(dielectric(
            "\"float uroughness\" [ 0.09 ] \"float vroughness\" [ 0.09 ] \"bool remaproughness\" false"
        )),
        MaterialKind::Glass { alpha: 0.09, .. }
    ));
    assert_eq!(
        first_material(dielectric(
            "\"float uroughness\" [ 0.1 ] \"float vroughness\" [ 0.2 ] \"bool remaproughness\" false"
        )),
        MaterialKind::Glass {
            ior: 1.5,
            alpha: 0.1,
            alpha_v: 0.2,
        }
    );
    for (params, says) in [
        (
            "\"float roughness\" [ 1.5 ]",
            "\"float roughness\": must be in [0, 1]",
        ),
        (
            "\"float roughness\" [ -0.1 ]",
            "\"float roughness\": must be in [0, 1]",
        ),
        (
            "\"float eta\" [ -1.5 ]",
            "\"float eta\": must be a positive number",
        ),
        (
            "\"spectrum eta\" \"glass-BK7\"",
            "\"spectrum eta\": a dispersive (spectral) eta",
        ),
        ("\"bool remaproughness\" [ 1 ]", "remaproughness"),
        ("\"rgb tint\" [ 0.5 0.5 0.5 ]", "unknown parameter"),
    ] {
        let e = dielectric(params).map(|_| ()).unwrap_err().to_string();
        assert!(e.contains(says) && e.contains("scenes/test.pbrt:5"), "{e}");
    }
}
