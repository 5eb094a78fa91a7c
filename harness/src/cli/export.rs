//! `ppm export`: a scene for Mitsuba 3 or pbrt-v4, to check us against another renderer.

use crate::cli::options::check_frame;
use anyhow::{Result, bail};
use clap::ValueEnum;
use scenes::file::ExportOptions;
use scenes::file::bands::Colours;
use std::path::PathBuf;

#[derive(Clone, Copy, ValueEnum)]
pub enum ExportFormat {
    /// Mitsuba 3 XML.
    Mitsuba,
    /// pbrt-v4.
    Pbrt,
}

/// How colours are written (`--colours`).
#[derive(Clone, Copy, ValueEnum)]
pub enum ColourForm {
    /// RGB triples: exact for an RGB renderer (Mitsuba 3's scalar_rgb); the default for
    /// Mitsuba.
    Rgb,
    /// Spectra constant in three bands of wavelengths, which a spectral renderer multiplies
    /// as we multiply RGB (pbrt-v4, Mitsuba 3's scalar_spectral); the default for pbrt.
    Bands,
}

#[derive(clap::Args)]
pub struct ExportArgs {
    /// Built-in scene name or path to a scene file (.toml, .xml, .pbrt).
    scene: String,
    /// Frame: 0 before the scene's move, 1 after it.
    #[arg(long, default_value_t = 0)]
    frame: u32,
    /// Scene format to write.
    #[arg(long, value_enum)]
    format: ExportFormat,
    /// Samples per pixel the other renderer takes.
    #[arg(long, default_value_t = 1024)]
    spp: u32,
    /// Image width (default: the scene's).
    #[arg(long)]
    width: Option<u32>,
    /// Image height (default: the scene's).
    #[arg(long)]
    height: Option<u32>,
    /// How colours are written (default: bands for pbrt, rgb for Mitsuba).
    #[arg(long, value_enum)]
    colours: Option<ColourForm>,
    /// Folder to write the scene file and its meshes into.
    #[arg(short, long)]
    output: PathBuf,
}

pub fn export(args: ExportArgs) -> Result<()> {
    check_frame(args.frame)?;
    if args.spp == 0 {
        bail!("--spp = 0: must be at least 1");
    }
    let mut scene = crate::load_scene(&args.scene)?.at_frame(args.frame);
    for (option, value, size) in [
        ("--width", args.width, &mut scene.camera.width),
        ("--height", args.height, &mut scene.camera.height),
    ] {
        match value {
            Some(0) => bail!("{option} = 0: must be at least 1"),
            Some(v) => *size = v,
            None => {}
        }
    }
    let options = ExportOptions {
        samples_per_pixel: args.spp,
        frame: args.frame,
        colours: args.colours.map(|c| match c {
            ColourForm::Rgb => Colours::Rgb,
            ColourForm::Bands => Colours::Bands,
        }),
    };
    let export = match args.format {
        ExportFormat::Mitsuba => scenes::file::mitsuba::export_mitsuba(&scene, &options),
        ExportFormat::Pbrt => scenes::file::pbrt::export_pbrt(&scene, &options),
    };
    let path = export.write(&args.output)?;
    println!(
        "{}: frame {}, {} meshes, {} triangles -> {}",
        scene.name,
        args.frame,
        export.meshes.len(),
        scene.triangle_count(),
        path.display()
    );
    println!("not expressed exactly (also listed in the file):");
    for note in &export.notes {
        println!("- {note}");
    }
    Ok(())
}
