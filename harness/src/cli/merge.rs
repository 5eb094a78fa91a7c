//! `ppm merge`: joins the shards of a reference or of a render (crate::merge).

use crate::cli::render::OutputPaths;
use crate::reference::variance_path;
use anyhow::{Context, Result};
use scenes::file::image::ImageFiles;
use scenes::file::output::write_bytes;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct MergeArgs {
    /// The shards' EXR files (each with its JSON beside it).
    #[arg(required = true)]
    inputs: Vec<PathBuf>,
    /// Output EXR; the PNG preview, the JSON summary and, for a reference, the variance
    /// (NAME.var.exr) are written beside it.
    #[arg(short, long)]
    output: PathBuf,
    /// Exposure multiplier of the PNG preview.
    #[arg(long, default_value_t = 1.0)]
    exposure: f32,
}

pub fn merge(args: MergeArgs) -> Result<()> {
    let paths = OutputPaths::new(&args.output)?;
    let merged = crate::merge::merge(&args.inputs)?;
    merged.image.write_exr(&paths.exr)?;
    merged.image.write_png(&paths.png, args.exposure)?;
    if let Some(variance) = &merged.variance {
        variance.write_exr(&variance_path(&paths.exr))?;
    }
    let json = serde_json::to_string_pretty(&merged.summary)?;
    write_bytes(&paths.json, json)
        .with_context(|| format!("{}: cannot write the summary", paths.json.display()))?;
    println!(
        "merged {} shards -> {}, {}",
        args.inputs.len(),
        paths.exr.display(),
        paths.json.display()
    );
    Ok(())
}
