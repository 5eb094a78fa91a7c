//! Writes a [`Scene`] as a pbrt-v4 scene file with PLY meshes beside it.

use crate::file::bands::{self, Colours};
use crate::file::interop::{
    Export, ExportOptions, Format, common_notes, list3, mesh_names, scene_stem, texture_files,
};
use glam::Vec3;
use ppm_core::params::MAX_DEPTH;
use ppm_core::scene::{MaterialKind, Scene, TextureFilter};
use std::fmt::Write;

/// Path depth given to pbrt's path tracer: the bounces our eye and photon paths may take
/// together, and Russian roulette ends paths long before it.
pub const PBRT_MAX_DEPTH: u32 = 2 * MAX_DEPTH;

/// The scene in pbrt-v4's format, meshes as `plymesh` shapes.
///
/// `Scale -1 1 1` before `LookAt` turns pbrt's left-handed camera space into our image
/// orientation; `WorldBegin` resets the transform, so shapes are in world space. Diffuse
/// surfaces are exact, and so is glass: pbrt's `dielectric` of our index and GGX alpha
/// (`remaproughness` off); a mirror is pbrt's `conductor` given `reflectance`, which
/// pbrt treats as the Fresnel reflectance at normal incidence (listed in the notes); a
/// conductor is pbrt's `conductor` of the same `eta`, `k` and GGX alpha (`remaproughness`
/// off), without our reflectance factor, which pbrt lacks (listed when it is not one); a
/// coated surface is pbrt's `coateddiffuse` of our index and GGX alpha (`remaproughness`
/// off) and a layer of thickness zero, where pbrt's walk attenuates nothing (its default,
/// 0.01, would darken the base by a few percent); pbrt always meets the base's colour at
/// every return (our `nonlinear`; listed where ours does not). A
/// textured diffuse surface, or coated one's base, reads an `imagemap` of its image with the
/// colour baked in. Colours are band spectra unless `options.colours` asks for RGB
/// ([`bands`]: pbrt renders spectrally, and products of its smooth spectra for RGB colours
/// are not products of the colours), a light's with its luminance as `scale`, which pbrt
/// divides a light's spectrum by.
pub fn export_pbrt(scene: &Scene, options: &ExportOptions) -> Export {
    let names = mesh_names(scene);
    let mut notes = common_notes(scene, options, Format::Pbrt);
    let colours = options.colours.unwrap_or(Colours::Bands);
    notes.push(match colours {
        Colours::Bands => "pbrt-v4 renders spectrally: colours are written as spectra constant \
             in three bands of wavelengths, lights shaped so that each band lights one sRGB \
             channel (scenes/src/file/bands.rs), so that products of colours come out as ours \
             (within 1e-4 by the CIE 1931 observer)"
            .into(),
        Colours::Rgb => "pbrt-v4 renders spectrally: RGB reflectances and radiances are turned \
             into smooth spectra, whose products are not products of RGB colours (our \
             cornell-box's red wall keeps a sixth of its blue); export with band colours to \
             avoid it"
            .into(),
    });
    notes.extend(colours.texture_note(scene, "pbrt-v4"));
    if scene
        .materials
        .iter()
        .any(|m| matches!(m.kind, MaterialKind::Mirror { .. }))
    {
        notes.push(
            "pbrt-v4 has no constant-reflectance mirror: a mirror is a conductor whose \
             reflectance is ours at normal incidence (clamped to 0.9999) and rises towards 1 at \
             grazing angles"
                .into(),
        );
    }
    for m in &scene.materials {
        if let MaterialKind::Conductor { reflectance, .. } = m.kind
            && reflectance != Vec3::ONE
        {
            notes.push(format!(
                "pbrt-v4's conductor has no reflectance factor: conductor \"{}\" reflects its \
                 Fresnel term there, not times ({})",
                m.name,
                list3(reflectance, ", ")
            ));
        }
    }
    if scene
        .materials
        .iter()
        .any(|m| matches!(m.kind, MaterialKind::Coated { .. }))
    {
        notes.push(
            "pbrt-v4's coateddiffuse estimates the light under its coat by a random walk of at \
             most 10 bounces (maxdepth), through a rough coat by its microfacets' own \
             transmission where we (and Mitsuba 3's roughplastic) take one minus their \
             reflectance; the layer is written 0 thick so that pbrt attenuates nothing in it \
             (exp(-thickness / |cos|), its default thickness 0.01)"
                .into(),
        );
    }
    for m in &scene.materials {
        if let MaterialKind::Coated {
            nonlinear: false, ..
        } = m.kind
        {
            notes.push(format!(
                "pbrt-v4's coateddiffuse meets the base's colour at every return under the coat \
                 (our nonlinear = true): coated material \"{}\", ours with nonlinear = false \
                 (Mitsuba's default), comes out darker and more saturated there",
                m.name
            ));
        }
    }
    notes.push(format!(
        "pbrt's path tracer stops at depth {PBRT_MAX_DEPTH} with Russian roulette; ours stops \
         eye paths and photons after {MAX_DEPTH} bounces"
    ));
    let c = &scene.camera;
    let mut t = String::new();
    let w = &mut t;
    let _ = writeln!(
        w,
        "# Written by ppm export: scene \"{}\", frame {}.",
        scene.name.replace('\n', " "),
        options.frame
    );
    let _ = writeln!(w, "# Not expressed exactly:");
    for n in &notes {
        let _ = writeln!(w, "# - {n}");
    }
    let _ = writeln!(w, "Scale -1 1 1");
    let _ = writeln!(
        w,
        "LookAt {}  {}  {}",
        list3(c.eye, " "),
        list3(c.look_at, " "),
        list3(c.up, " ")
    );
    // pbrt's fov spans the shorter image side; a taller-than-wide image names the vertical
    // extent of the screen window so that fov stays vertical.
    let window = if c.width < c.height {
        format!(
            " \"float screenwindow\" [ {} {} -1 1 ]",
            -(c.width as f32 / c.height as f32),
            c.width as f32 / c.height as f32
        )
    } else {
        String::new()
    };
    let _ = writeln!(
        w,
        "Camera \"perspective\" \"float fov\" [ {} ]{window}",
        c.fov_deg
    );
    let _ = writeln!(
        w,
        "Sampler \"independent\" \"integer pixelsamples\" [ {} ]",
        options.samples_per_pixel
    );
    let _ = writeln!(
        w,
        "Integrator \"path\" \"integer maxdepth\" [ {PBRT_MAX_DEPTH} ]"
    );
    let _ = writeln!(w, "PixelFilter \"box\"");
    let _ = writeln!(
        w,
        "Film \"rgb\" \"integer xresolution\" [ {} ] \"integer yresolution\" [ {} ] \"string filename\" [ \"{}.exr\" ]",
        c.width,
        c.height,
        scene_stem(scene)
    );
    let _ = writeln!(w, "WorldBegin");
    for (m, file) in scene
        .materials
        .iter()
        .zip(texture_files(scene, Format::Pbrt))
    {
        let name = quoted(&m.name);
        // A textured diffuse reflectance (a diffuse surface's or a coated one's base) reads
        // an image that holds the colour (interop::texture_image); pbrt's (s, t) mapping and
        // t flip are ours.
        let mut texture = None;
        if let (Some(t), Some(file)) = (&m.texture, file) {
            let filter = match t.filter {
                TextureFilter::Bilinear => "bilinear",
                TextureFilter::Nearest => "point",
            };
            let texture_name = quoted(&format!("{}-texture", m.name));
            let _ = writeln!(
                w,
                "Texture {texture_name} \"spectrum\" \"imagemap\" \"string filename\" [ {} ] \"string filter\" [ \"{filter}\" ] \"float uscale\" [ {} ] \"float vscale\" [ {} ] \"float udelta\" [ {} ] \"float vdelta\" [ {} ]",
                quoted(&file),
                t.scale.x,
                t.scale.y,
                t.offset.x,
                t.offset.y
            );
            texture = Some(texture_name);
        }
        let reflectance = |colour: Vec3| match &texture {
            Some(texture) => format!("\"texture reflectance\" [ {texture} ]"),
            None => colour_param("reflectance", colour, colours),
        };
        let _ = match &m.kind {
            MaterialKind::Diffuse { albedo } | MaterialKind::Light { albedo, .. } => writeln!(
                w,
                "MakeNamedMaterial {name} \"string type\" [ \"diffuse\" ] {}",
                reflectance(*albedo)
            ),
            MaterialKind::Mirror { reflectance } => writeln!(
                w,
                "MakeNamedMaterial {name} \"string type\" [ \"conductor\" ] {} \"float roughness\" [ 0 ]",
                colour_param("reflectance", *reflectance, colours)
            ),
            MaterialKind::Glass {
                ior,
                alpha,
                alpha_v,
            } => writeln!(
                w,
                "MakeNamedMaterial {name} \"string type\" [ \"dielectric\" ] \"float eta\" [ {ior} ] {} \"bool remaproughness\" false",
                roughness_params(*alpha, *alpha_v)
            ),
            // A layer of thickness zero attenuates nothing; `nonlinear` has no parameter
            // (see the notes).
            MaterialKind::Coated {
                albedo, ior, alpha, ..
            } => writeln!(
                w,
                "MakeNamedMaterial {name} \"string type\" [ \"coateddiffuse\" ] {} \"float roughness\" [ {alpha} ] \"bool remaproughness\" false \"float eta\" [ {ior} ] \"float thickness\" [ 0 ]",
                reflectance(*albedo)
            ),
            MaterialKind::Conductor {
                eta,
                k,
                alpha,
                alpha_v,
                ..
            } => writeln!(
                w,
                "MakeNamedMaterial {name} \"string type\" [ \"conductor\" ] {} {} {} \"bool remaproughness\" false",
                colour_param("eta", *eta, colours),
                colour_param("k", *k, colours),
                roughness_params(*alpha, *alpha_v)
            ),
        };
    }
    for (object, file) in scene.objects.iter().zip(&names) {
        let material = &scene.materials[object.material];
        let _ = writeln!(w, "AttributeBegin");
        let _ = writeln!(w, "  NamedMaterial {}", quoted(&material.name));
        if let MaterialKind::Light { radiance, .. } = material.kind {
            let _ = writeln!(
                w,
                "  AreaLightSource \"diffuse\" {}",
                light_param(radiance, colours)
            );
        }
        let _ = writeln!(
            w,
            "  Shape \"plymesh\" \"string filename\" [ {} ]",
            quoted(file)
        );
        let _ = writeln!(w, "AttributeEnd");
    }
    Export::of(scene, Format::Pbrt, t, names, notes)
}

/// A colour parameter: an `rgb` triple, or with band colours a band spectrum. A grey
/// stays `rgb`: pbrt's RGB model makes it a flat spectrum, exact.
fn colour_param(name: &str, colour: Vec3, colours: Colours) -> String {
    match colours.reflectance(colour) {
        Some(spectrum) => format!("\"spectrum {name}\" [ {} ]", spectrum_values(&spectrum)),
        None => format!("\"rgb {name}\" [ {} ]", list3(colour, " ")),
    }
}

/// An area light's radiance: `rgb`, or with band colours a band spectrum scaled by its
/// luminance, which pbrt divides a light's spectrum by.
fn light_param(radiance: Vec3, colours: Colours) -> String {
    match colours.illuminant(radiance) {
        Some(spectrum) => format!(
            "\"spectrum L\" [ {} ] \"float scale\" [ {} ]",
            spectrum_values(&spectrum),
            bands::luminance(radiance)
        ),
        None => format!("\"rgb L\" [ {} ]", list3(radiance, " ")),
    }
}

/// Interleaved wavelengths and values, as pbrt's `spectrum` parameters take them.
fn spectrum_values(points: &[(f32, f32)]) -> String {
    let values: Vec<String> = points.iter().map(|(l, v)| format!("{l} {v}")).collect();
    values.join(" ")
}

/// A pbrt string literal (pbrt strings cannot hold a double quote or a line break).
fn quoted(s: &str) -> String {
    format!("\"{}\"", s.replace(['"', '\n'], "_"))
}

/// A microfacet lobe's roughness as pbrt-v4 takes it (`remaproughness` false): one value, or
/// `uroughness` along the surface's `dpdu` and `vroughness` across it where they differ
/// (the meshes then carry the coordinates that orient it, `Export::of`).
fn roughness_params(alpha: f32, alpha_v: f32) -> String {
    if alpha == alpha_v {
        format!("\"float roughness\" [ {alpha} ]")
    } else {
        format!("\"float uroughness\" [ {alpha} ] \"float vroughness\" [ {alpha_v} ]")
    }
}
