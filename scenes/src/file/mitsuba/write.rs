//! Writes a [`Scene`] as a Mitsuba 3 XML scene with PLY meshes beside it.

use crate::file::bands::Colours;
use crate::file::interop::{
    Export, ExportOptions, Format, clip_range, common_notes, list3, mesh_names, texture_files,
};
use glam::Vec3;
use ppm_core::params::MAX_DEPTH;
use ppm_core::scene::{Material, MaterialKind, Scene, Texture, TextureFilter};
use std::fmt::Write;

/// The scene in Mitsuba 3's XML format (`scene version="3.0.0"`), meshes as PLY files.
///
/// Diffuse, mirror and conductor surfaces are wrapped in `twosided` (Mitsuba's `diffuse` and
/// `conductor` are black from behind, ours reflect on both sides); a mirror is a `conductor`
/// with `material = "none"` (Fresnel factor 1) scaled by our reflectance, which is exact; a
/// conductor is a `conductor`, or a `roughconductor` with the GGX distribution, of the same
/// `eta`, `k` and reflectance factor (exact but for Mitsuba's masking term, listed in the
/// notes); a coated surface is a `twosided` `plastic`, or a `roughplastic` with the GGX
/// distribution, of `int_ior` our index and `ext_ior` 1, with our `nonlinear` (its diffuse
/// reflectance a `bitmap` where textured; a rough one's masking term listed as a
/// conductor's); glass is a `dielectric`, or a `roughdielectric` with the GGX distribution,
/// of `int_ior` our index and `ext_ior` 1 (a rough one's masking term listed as a
/// conductor's); a light is a `twosided` diffuse surface carrying an `area` emitter, which
/// emits on the side of the face normal as ours does (`face_normals` keeps Mitsuba from
/// smoothing the normals). Colours are RGB, exact in Mitsuba's RGB variants, unless
/// `options.colours` asks for band spectra ([`bands`](crate::file::bands)) for its spectral variants.
pub fn export_mitsuba(scene: &Scene, options: &ExportOptions) -> Export {
    let names = mesh_names(scene);
    let mut notes = common_notes(scene, options, Format::Mitsuba);
    notes.push(format!(
        "Mitsuba's path tracer runs to unbounded depth with Russian roulette; ours stops \
             eye paths and photons after {MAX_DEPTH} bounces"
    ));
    // Mitsuba masks and shadows every rough BSDF with the separable Smith term: its plugin,
    // which of our kinds it writes, and what that changes.
    type RoughPlugin = (&'static str, fn(&MaterialKind) -> bool, &'static str);
    let rough: [RoughPlugin; 3] = [
        (
            "roughconductor",
            |k| matches!(k, MaterialKind::Conductor { alpha, .. } if *alpha > 0.0),
            "a rough conductor comes out a little darker there (0.4-0.6% for GGX alpha 0.3, \
             docs/materials.md)",
        ),
        (
            "roughplastic",
            |k| matches!(k, MaterialKind::Coated { alpha, .. } if *alpha > 0.0),
            "a rough coat's reflection comes out a little darker there, and so does the \
             light through it (1-2% on cornell-coated's rough block, docs/materials.md, \
             \"Coated diffuse\")",
        ),
        (
            "roughdielectric",
            |k| matches!(k, MaterialKind::Glass { alpha, .. } if *alpha > 0.0),
            "rough glass comes out a little darker there",
        ),
    ];
    for (plugin, used, what) in rough {
        if scene.materials.iter().any(|m| used(&m.kind)) {
            notes.push(format!(
                "Mitsuba's {plugin} masks and shadows with the separable Smith term G1(wo) \
                 G1(wi), ours (as pbrt-v4's) with the height-correlated one, which is larger: \
                 {what}"
            ));
        }
    }
    let colours = options.colours.unwrap_or(Colours::Rgb);
    notes.push(match colours {
        Colours::Rgb => "colours are RGB, exact for Mitsuba's RGB variants (scalar_rgb); a \
             spectral variant turns them into smooth spectra, whose products are not products \
             of RGB colours (export with band colours for those)"
            .into(),
        Colours::Bands => "colours are written for Mitsuba's spectral variants \
             (scalar_spectral): spectra constant in three bands of wavelengths, lights shaped \
             so that each band lights one sRGB channel (scenes/src/file/bands.rs), so that \
             products of colours come out as ours; an RGB variant would turn them into other \
             colours"
            .into(),
    });
    notes.extend(colours.texture_note(scene, "a spectral variant"));
    let c = &scene.camera;
    let (near, far) = clip_range(scene);
    let mut x = String::new();
    let w = &mut x;
    let _ = writeln!(w, "<?xml version=\"1.0\" encoding=\"utf-8\"?>");
    let _ = writeln!(
        w,
        "<!-- Written by ppm export: scene \"{}\", frame {}.",
        xml_comment(&scene.name),
        options.frame
    );
    let _ = writeln!(w, "     Not expressed exactly:");
    for n in &notes {
        let _ = writeln!(w, "     - {}", xml_comment(n));
    }
    let _ = writeln!(w, "-->");
    let _ = writeln!(w, "<scene version=\"3.0.0\">");
    let _ = writeln!(w, "    <integrator type=\"path\">");
    let _ = writeln!(w, "        <integer name=\"max_depth\" value=\"-1\"/>");
    let _ = writeln!(w, "    </integrator>");
    let _ = writeln!(w, "    <sensor type=\"perspective\">");
    let _ = writeln!(w, "        <string name=\"fov_axis\" value=\"y\"/>");
    let _ = writeln!(w, "        <float name=\"fov\" value=\"{}\"/>", c.fov_deg);
    let _ = writeln!(w, "        <float name=\"near_clip\" value=\"{near}\"/>");
    let _ = writeln!(w, "        <float name=\"far_clip\" value=\"{far}\"/>");
    let _ = writeln!(w, "        <transform name=\"to_world\">");
    let _ = writeln!(
        w,
        "            <lookat origin=\"{}\" target=\"{}\" up=\"{}\"/>",
        list3(c.eye, ", "),
        list3(c.look_at, ", "),
        list3(c.up, ", ")
    );
    let _ = writeln!(w, "        </transform>");
    let _ = writeln!(w, "        <sampler type=\"independent\">");
    let _ = writeln!(
        w,
        "            <integer name=\"sample_count\" value=\"{}\"/>",
        options.samples_per_pixel
    );
    let _ = writeln!(w, "        </sampler>");
    let _ = writeln!(w, "        <film type=\"hdrfilm\">");
    let _ = writeln!(
        w,
        "            <integer name=\"width\" value=\"{}\"/>",
        c.width
    );
    let _ = writeln!(
        w,
        "            <integer name=\"height\" value=\"{}\"/>",
        c.height
    );
    let _ = writeln!(
        w,
        "            <string name=\"pixel_format\" value=\"rgb\"/>"
    );
    let _ = writeln!(w, "            <rfilter type=\"box\"/>");
    let _ = writeln!(w, "        </film>");
    let _ = writeln!(w, "    </sensor>");
    for (m, file) in scene
        .materials
        .iter()
        .zip(texture_files(scene, Format::Mitsuba))
    {
        let id = xml_attr(&material_id(&m.name));
        match &m.kind {
            MaterialKind::Diffuse { albedo } | MaterialKind::Light { albedo, .. } => {
                let _ = writeln!(w, "    <bsdf type=\"twosided\" id=\"{id}\">");
                let _ = writeln!(w, "        <bsdf type=\"diffuse\">");
                match (&m.texture, file) {
                    (Some(t), Some(file)) => write_bitmap(w, t, &file, "reflectance"),
                    _ => {
                        let _ = writeln!(
                            w,
                            "            {}",
                            colour_element("reflectance", *albedo, colours)
                        );
                    }
                }
                let _ = writeln!(w, "        </bsdf>");
                let _ = writeln!(w, "    </bsdf>");
            }
            MaterialKind::Mirror { reflectance } => {
                let _ = writeln!(w, "    <bsdf type=\"twosided\" id=\"{id}\">");
                let _ = writeln!(w, "        <bsdf type=\"conductor\">");
                let _ = writeln!(w, "            <string name=\"material\" value=\"none\"/>");
                write_specular_reflectance(w, (m, file.as_deref()), *reflectance, colours);
                let _ = writeln!(w, "        </bsdf>");
                let _ = writeln!(w, "    </bsdf>");
            }
            MaterialKind::Conductor {
                eta,
                k,
                reflectance,
                alpha,
                alpha_v,
            } => {
                let _ = writeln!(w, "    <bsdf type=\"twosided\" id=\"{id}\">");
                if alpha.max(*alpha_v) > 0.0 {
                    let _ = writeln!(w, "        <bsdf type=\"roughconductor\">");
                    let _ = writeln!(
                        w,
                        "            <string name=\"distribution\" value=\"ggx\"/>"
                    );
                    write_alphas(w, *alpha, *alpha_v, "            ");
                } else {
                    let _ = writeln!(w, "        <bsdf type=\"conductor\">");
                }
                for (name, value) in [("eta", eta), ("k", k)] {
                    let _ = writeln!(w, "            {}", colour_element(name, *value, colours));
                }
                write_specular_reflectance(w, (m, file.as_deref()), *reflectance, colours);
                let _ = writeln!(w, "        </bsdf>");
                let _ = writeln!(w, "    </bsdf>");
            }
            MaterialKind::Coated {
                albedo,
                ior,
                alpha,
                nonlinear,
            } => {
                let _ = writeln!(w, "    <bsdf type=\"twosided\" id=\"{id}\">");
                if *alpha > 0.0 {
                    let _ = writeln!(w, "        <bsdf type=\"roughplastic\">");
                    let _ = writeln!(
                        w,
                        "            <string name=\"distribution\" value=\"ggx\"/>"
                    );
                    let _ = writeln!(w, "            <float name=\"alpha\" value=\"{alpha}\"/>");
                } else {
                    let _ = writeln!(w, "        <bsdf type=\"plastic\">");
                }
                let _ = writeln!(w, "            <float name=\"int_ior\" value=\"{ior}\"/>");
                let _ = writeln!(w, "            <float name=\"ext_ior\" value=\"1\"/>");
                let _ = writeln!(
                    w,
                    "            <boolean name=\"nonlinear\" value=\"{nonlinear}\"/>"
                );
                match (&m.texture, file) {
                    (Some(t), Some(file)) => write_bitmap(w, t, &file, "diffuse_reflectance"),
                    _ => {
                        let _ = writeln!(
                            w,
                            "            {}",
                            colour_element("diffuse_reflectance", *albedo, colours)
                        );
                    }
                }
                let _ = writeln!(w, "        </bsdf>");
                let _ = writeln!(w, "    </bsdf>");
            }
            MaterialKind::Glass {
                ior,
                alpha,
                alpha_v,
            } => {
                if alpha.max(*alpha_v) > 0.0 {
                    let _ = writeln!(w, "    <bsdf type=\"roughdielectric\" id=\"{id}\">");
                    let _ = writeln!(w, "        <string name=\"distribution\" value=\"ggx\"/>");
                    write_alphas(w, *alpha, *alpha_v, "        ");
                } else {
                    let _ = writeln!(w, "    <bsdf type=\"dielectric\" id=\"{id}\">");
                }
                let _ = writeln!(w, "        <float name=\"int_ior\" value=\"{ior}\"/>");
                let _ = writeln!(w, "        <float name=\"ext_ior\" value=\"1\"/>");
                let _ = writeln!(w, "    </bsdf>");
            }
        }
    }
    for (object, file) in scene.objects.iter().zip(&names) {
        let material = &scene.materials[object.material];
        let id = file.trim_end_matches(".ply");
        let _ = writeln!(w, "    <shape type=\"ply\" id=\"{}\">", xml_attr(id));
        let _ = writeln!(
            w,
            "        <string name=\"filename\" value=\"{}\"/>",
            xml_attr(file)
        );
        let _ = writeln!(w, "        <boolean name=\"face_normals\" value=\"true\"/>");
        let _ = writeln!(
            w,
            "        <ref id=\"{}\"/>",
            xml_attr(&material_id(&material.name))
        );
        if let MaterialKind::Light { radiance, .. } = material.kind {
            let _ = writeln!(w, "        <emitter type=\"area\">");
            let _ = writeln!(w, "            {}", radiance_element(radiance, colours));
            let _ = writeln!(w, "        </emitter>");
        }
        let _ = writeln!(w, "    </shape>");
    }
    let _ = writeln!(w, "</scene>");
    Export::of(scene, Format::Mitsuba, x, names, notes)
}

/// A colour parameter: `<rgb>`, or with band colours a band `<spectrum>`. A grey stays
/// `<rgb>`, a flat spectrum in every variant (Mitsuba refuses a spectrum that is zero
/// everywhere).
fn colour_element(name: &str, colour: Vec3, colours: Colours) -> String {
    match colours.reflectance(colour) {
        Some(spectrum) => spectrum_element(name, &spectrum),
        None => format!("<rgb name=\"{name}\" value=\"{}\"/>", list3(colour, ", ")),
    }
}

/// An emitter's radiance: `<rgb>`, or with band colours a band `<spectrum>`, which a
/// spectral variant takes as it is.
fn radiance_element(radiance: Vec3, colours: Colours) -> String {
    match colours.illuminant(radiance) {
        Some(spectrum) => spectrum_element("radiance", &spectrum),
        None => format!(
            "<rgb name=\"radiance\" value=\"{}\"/>",
            list3(radiance, ", ")
        ),
    }
}

/// A `<spectrum>` of (wavelength, value) pairs, which Mitsuba interpolates linearly.
fn spectrum_element(name: &str, points: &[(f32, f32)]) -> String {
    let values: Vec<String> = points.iter().map(|(l, v)| format!("{l}:{v}")).collect();
    format!(
        "<spectrum name=\"{name}\" value=\"{}\"/>",
        values.join(", ")
    )
}

/// A diffuse reflectance, the parameter `name`, read from `file` (the texture's image,
/// colour baked in). Mitsuba's `v = 0` is the image's top row, ours the bottom: `to_uv` maps
/// our `(s, t)` to `(s, 1 - t)`.
fn write_bitmap(w: &mut String, t: &Texture, file: &str, name: &str) {
    let filter = match t.filter {
        TextureFilter::Bilinear => "bilinear",
        TextureFilter::Nearest => "nearest",
    };
    let _ = writeln!(w, "            <texture type=\"bitmap\" name=\"{name}\">");
    let _ = writeln!(
        w,
        "                <string name=\"filename\" value=\"{}\"/>",
        xml_attr(file)
    );
    let _ = writeln!(
        w,
        "                <string name=\"filter_type\" value=\"{filter}\"/>"
    );
    let _ = writeln!(w, "                <boolean name=\"raw\" value=\"true\"/>");
    let _ = writeln!(w, "                <transform name=\"to_uv\">");
    let _ = writeln!(
        w,
        "                    <scale x=\"{}\" y=\"{}\"/>",
        t.scale.x, -t.scale.y
    );
    let _ = writeln!(
        w,
        "                    <translate x=\"{}\" y=\"{}\"/>",
        t.offset.x,
        1.0 - t.offset.y
    );
    let _ = writeln!(w, "                </transform>");
    let _ = writeln!(w, "            </texture>");
}

/// Materials and shapes share Mitsuba's id space, and our scenes reuse names across them
/// (an object and its material both called `light`): materials get a prefix.
fn material_id(name: &str) -> String {
    format!("mat-{name}")
}

fn xml_attr(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('"', "&quot;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// XML comments may not hold `--`.
fn xml_comment(s: &str) -> String {
    s.replace("--", "- -")
}

/// A microfacet BSDF's roughness: `alpha`, or `alpha_u` along the surface's `dp_du` and
/// `alpha_v` across it where they differ (the meshes then carry the coordinates that
/// orient it, `Export::of`).
fn write_alphas(w: &mut String, alpha: f32, alpha_v: f32, indent: &str) {
    if alpha == alpha_v {
        let _ = writeln!(w, "{indent}<float name=\"alpha\" value=\"{alpha}\"/>");
    } else {
        let _ = writeln!(w, "{indent}<float name=\"alpha_u\" value=\"{alpha}\"/>");
        let _ = writeln!(w, "{indent}<float name=\"alpha_v\" value=\"{alpha_v}\"/>");
    }
}

/// A mirror's or conductor's reflectance factor, Mitsuba's `specular_reflectance`: the
/// material's texture where it has one written to `file`, else the colour.
fn write_specular_reflectance(
    w: &mut String,
    (m, file): (&Material, Option<&str>),
    reflectance: Vec3,
    colours: Colours,
) {
    match (&m.texture, file) {
        (Some(t), Some(file)) => write_bitmap(w, t, file, "specular_reflectance"),
        _ => {
            let _ = writeln!(
                w,
                "            {}",
                colour_element("specular_reflectance", reflectance, colours)
            );
        }
    }
}
