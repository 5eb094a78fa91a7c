//! `ppm stress`: the stress family on one or both backends.

use crate::cli::options::BackendChoice;
use crate::cli::render::output_folder;
use anyhow::{Context, Result, bail};
use clap::ValueEnum;
use scenes::file::output::write_bytes;
use std::path::{Path, PathBuf};

#[derive(Clone, Copy, ValueEnum)]
pub enum StressBackends {
    /// The CPU backend.
    Cpu,
    /// The wgpu backend.
    Wgpu,
    /// Both, one after the other.
    Both,
}

#[derive(clap::Args)]
pub struct StressArgs {
    /// Backends to run.
    #[arg(long, value_enum, default_value = "cpu")]
    backend: StressBackends,
    /// Run only this case (see the table for names).
    #[arg(long)]
    case: Option<String>,
    /// JSON report.
    #[arg(short, long, default_value = "out/stress.json")]
    output: PathBuf,
}

pub fn run(args: StressArgs) -> Result<()> {
    let cases: Vec<&scenes::stress::StressCase> = match &args.case {
        Some(name) => vec![scenes::stress::stress_case(name).with_context(|| {
            let names: Vec<&str> = scenes::stress::STRESS.iter().map(|c| c.name).collect();
            format!("--case {name}: no such case (cases: {})", names.join(", "))
        })?],
        None => scenes::stress::STRESS.iter().collect(),
    };
    let folder = args.output.parent().unwrap_or(Path::new(""));
    output_folder(folder, &format!("-o {}", args.output.display()))?;
    let names: &[&str] = match args.backend {
        StressBackends::Cpu => &["cpu"],
        StressBackends::Wgpu => &["wgpu"],
        StressBackends::Both => &["cpu", "wgpu"],
    };
    let mut backends = names
        .iter()
        .map(|name| BackendChoice(name.to_string()).start())
        .collect::<Result<Vec<_>>>()?;
    let mut results = Vec::new();
    for case in cases {
        for backend in &mut backends {
            results.push(crate::stress::run_case(backend.as_mut(), case));
        }
    }
    print!("{}", crate::stress::table(&results));
    write_bytes(&args.output, serde_json::to_string_pretty(&results)?)
        .with_context(|| format!("{}: cannot write", args.output.display()))?;
    let failed = results.iter().filter(|r| !r.passed).count();
    if failed > 0 {
        bail!("{failed} of {} stress runs failed", results.len());
    }
    println!(
        "all {} stress runs passed; wrote {}",
        results.len(),
        args.output.display()
    );
    Ok(())
}
