//! Joins shards ([`crate::shard`]) into one image, refusing what does not belong together.
//!
//! Reference shards (`ppm reference --shard I/N`) hold disjoint rows of one run: the merge takes
//! each row from the shard that owns it, so mean and variance are that run's, bit for bit. Render
//! shards (`ppm render --shard I/N`) are independent consistent runs: the merge averages them,
//! each weighted by its iterations.

use crate::shard::Shard;
use ppm_core::image::Image;
use ppm_core::metrics::reference_noise;
use scenes::file::image::read_exr;
use serde_json::{Value, json};
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Why shards cannot be merged.
#[derive(Debug, Error)]
pub enum MergeError {
    /// A file cannot be read.
    #[error("{file}: {reason}")]
    Read {
        /// The file.
        file: String,
        /// Why.
        reason: String,
    },
    /// A shard differs from the first in something that must be equal.
    #[error("{file}: {field} = {value}, but {first} has {expected}: shards of one render share it")]
    Mismatch {
        /// The shard.
        file: String,
        /// The field of its JSON.
        field: String,
        /// Its value.
        value: String,
        /// The first shard.
        first: String,
        /// The first shard's value.
        expected: String,
    },
    /// Two files hold the same shard.
    #[error("{file} and {other} are both shard {shard}: a shard merges once")]
    Overlap {
        /// One file.
        file: String,
        /// The other.
        other: String,
        /// The shard both hold.
        shard: Shard,
    },
    /// Shards of a reference are missing (their rows would stay black).
    #[error("shards {missing} of {count} are missing: a reference merges all of its rows")]
    Missing {
        /// Their indices.
        missing: String,
        /// How many there are.
        count: u32,
    },
    /// Something else is wrong with the inputs.
    #[error("{0}")]
    Invalid(String),
}

/// A merged image, its variance for references, and the JSON that describes it.
pub struct Merged {
    /// The image.
    pub image: Image,
    /// The variance of each pixel's mean (references only).
    pub variance: Option<Image>,
    /// What was merged and what the result means.
    pub summary: Value,
}

/// One input: its path, the JSON written beside it, and its shard.
struct Input {
    path: PathBuf,
    json: Value,
    shard: Shard,
}

impl Input {
    fn read(path: &Path) -> Result<Self, MergeError> {
        let file = path.display().to_string();
        let json_path = path.with_extension("json");
        let text = std::fs::read_to_string(&json_path).map_err(|e| MergeError::Read {
            file: json_path.display().to_string(),
            reason: format!("{e} (a shard's JSON report is written beside its EXR)"),
        })?;
        let json: Value = serde_json::from_str(&text).map_err(|e| MergeError::Read {
            file: json_path.display().to_string(),
            reason: e.to_string(),
        })?;
        let shard = match &json["shard"] {
            Value::Null => {
                return Err(MergeError::Invalid(format!(
                    "{file}: not a shard (rendered without --shard I/N)"
                )));
            }
            s => Shard {
                index: s["index"].as_u64().unwrap_or(u64::MAX) as u32,
                count: s["count"].as_u64().unwrap_or(0) as u32,
            },
        };
        if shard.count == 0 || shard.index >= shard.count {
            return Err(MergeError::Invalid(format!(
                "{file}: shard {shard} is not I/N"
            )));
        }
        Ok(Self {
            path: path.to_path_buf(),
            json,
            shard,
        })
    }

    fn name(&self) -> String {
        self.path.display().to_string()
    }

    fn size(&self) -> (u32, u32) {
        let get = |p: &str| self.json.pointer(p).and_then(Value::as_u64).unwrap_or(0) as u32;
        if self.is_reference() {
            (get("/width"), get("/height"))
        } else {
            (get("/params/width"), get("/params/height"))
        }
    }

    fn is_reference(&self) -> bool {
        self.json["renderer"]
            .as_str()
            .is_some_and(|r| r.starts_with("ppm reference"))
    }

    fn image(&self) -> Result<Image, MergeError> {
        let (w, h) = self.size();
        read_exr(&self.path, w, h).map_err(|e| MergeError::Read {
            file: self.name(),
            reason: e.to_string(),
        })
    }
}

/// Merges the shards at `files` (EXRs with their JSON beside them): all reference shards or
/// all render shards, of one scene, pose, size and settings, no shard twice.
pub fn merge(files: &[PathBuf]) -> Result<Merged, MergeError> {
    if files.len() < 2 {
        return Err(MergeError::Invalid(format!(
            "{} file given: a merge takes two shards or more",
            files.len()
        )));
    }
    let inputs = files
        .iter()
        .map(|f| Input::read(f))
        .collect::<Result<Vec<_>, _>>()?;
    let first = &inputs[0];
    for input in &inputs[1..] {
        if input.is_reference() != first.is_reference() {
            return Err(MergeError::Invalid(format!(
                "{} and {}: a reference shard and a render shard do not merge",
                first.name(),
                input.name()
            )));
        }
    }
    for (i, a) in inputs.iter().enumerate() {
        if let Some(b) = inputs[..i].iter().find(|b| b.shard == a.shard) {
            return Err(MergeError::Overlap {
                file: a.name(),
                other: b.name(),
                shard: a.shard,
            });
        }
    }
    if first.is_reference() {
        merge_references(&inputs)
    } else {
        merge_renders(&inputs)
    }
}

/// Refuses an input whose JSON differs from the first's at any of `fields` (JSON pointers).
fn same(inputs: &[Input], fields: &[&str]) -> Result<(), MergeError> {
    let first = &inputs[0];
    for input in &inputs[1..] {
        for field in fields {
            let (a, b) = (first.json.pointer(field), input.json.pointer(field));
            if a != b {
                let show = |v: Option<&Value>| v.map_or("nothing".to_owned(), Value::to_string);
                return Err(MergeError::Mismatch {
                    file: input.name(),
                    field: field.trim_start_matches('/').replace('/', "."),
                    value: show(b),
                    first: first.name(),
                    expected: show(a),
                });
            }
        }
    }
    Ok(())
}

fn merge_references(inputs: &[Input]) -> Result<Merged, MergeError> {
    same(
        inputs,
        &[
            "/scene",
            "/frame",
            "/width",
            "/height",
            "/seed",
            "/spp",
            "/max_bounces",
            "/shard/count",
        ],
    )?;
    for input in inputs {
        if let Some(e) = input.json["error"].as_str() {
            return Err(MergeError::Invalid(format!(
                "{}: the shard stopped early: {e}",
                input.name()
            )));
        }
    }
    let count = inputs[0].shard.count;
    let missing: Vec<String> = (0..count)
        .filter(|&i| !inputs.iter().any(|s| s.shard.index == i))
        .map(|i| i.to_string())
        .collect();
    if !missing.is_empty() {
        return Err(MergeError::Missing {
            missing: missing.join(", "),
            count,
        });
    }
    let (width, height) = inputs[0].size();
    let mut image = Image::new(width, height);
    let mut variance = Image::new(width, height);
    let mut seconds = 0.0;
    for input in inputs {
        let var_path = crate::reference::variance_path(&input.path);
        let mean = input.image()?;
        let var = read_exr(&var_path, width, height).map_err(|e| MergeError::Read {
            file: var_path.display().to_string(),
            reason: e.to_string(),
        })?;
        let w = width as usize;
        for y in (0..height).filter(|&y| input.shard.owns_row(y)) {
            let row = y as usize * w..(y as usize + 1) * w;
            image.pixels[row.clone()].copy_from_slice(&mean.pixels[row.clone()]);
            variance.pixels[row.clone()].copy_from_slice(&var.pixels[row]);
        }
        seconds += input.json["seconds"].as_f64().unwrap_or(0.0);
    }
    let mut summary = inputs[0].json.clone();
    let spp = summary["spp"].as_u64().unwrap_or(0);
    let fields = summary.as_object_mut().expect("a summary is an object");
    fields.remove("shard");
    fields.insert("seconds".into(), json!(seconds));
    fields.insert(
        "samples_per_second".into(),
        json!((spp * u64::from(width) * u64::from(height)) as f64 / seconds.max(1e-9)),
    );
    fields.insert(
        "relative_noise".into(),
        json!(reference_noise(&image, &variance)),
    );
    fields.insert(
        "interrupted".into(),
        json!(inputs.iter().any(|i| i.json["interrupted"] == json!(true))),
    );
    fields.insert(
        "merged_from".into(),
        json!(inputs.iter().map(Input::name).collect::<Vec<_>>()),
    );
    Ok(Merged {
        image,
        variance: Some(variance),
        summary,
    })
}

fn merge_renders(inputs: &[Input]) -> Result<Merged, MergeError> {
    same(
        inputs,
        &[
            "/scene",
            "/frame",
            "/shard/count",
            "/params/estimator",
            "/params/width",
            "/params/height",
            "/params/photons_per_pass",
            "/params/alpha",
            "/params/initial_radius",
            "/params/spp",
            "/params/direct",
            "/params/direct_samples",
            "/params/max_eye_depth",
            "/params/max_photon_depth",
        ],
    )?;
    let (width, height) = inputs[0].size();
    let mut sum = vec![[0.0f64; 3]; width as usize * height as usize];
    let mut passes = 0u64;
    let mut shards = Vec::new();
    for input in inputs {
        let n = input.json["passes"].as_u64().unwrap_or(0);
        if n == 0 {
            return Err(MergeError::Invalid(format!(
                "{}: the shard ran no iteration",
                input.name()
            )));
        }
        let image = input.image()?;
        for (s, p) in sum.iter_mut().zip(&image.pixels) {
            for c in 0..3 {
                s[c] += n as f64 * f64::from(p[c]);
            }
        }
        passes += n;
        shards.push(json!({
            "file": input.name(),
            "shard": input.shard,
            "seed": input.json.pointer("/params/seed"),
            "backend": input.json["backend"],
            "passes": n,
            "seconds": input.json.pointer("/times/total"),
            "interrupted": input.json["interrupted"],
        }));
    }
    let image = Image {
        width,
        height,
        pixels: sum
            .iter()
            .map(|s| s.map(|v| (v / passes as f64) as f32))
            .collect(),
    };
    let first = &inputs[0].json;
    // The settings all shards share; seeds and iteration counts are each shard's own.
    let mut params = first["params"].clone();
    if let Some(p) = params.as_object_mut() {
        for own in ["seed", "passes", "time_budget"] {
            p.remove(own);
        }
    }
    let summary = json!({
        "merged": "independent sppm shards, averaged by their iterations",
        "scene": first["scene"],
        "frame": first["frame"],
        "params": params,
        "passes": passes,
        "shards": shards,
        "bias": "each shard is a consistent run of its own length: the average keeps the bias \
                 of a run of each shard's iterations (its radii shrink with them), not of one \
                 run of all of them",
        "noise": "the average of all shards' noise: its variance is about that of one run of \
                  all their iterations at the shards' radii",
    });
    Ok(Merged {
        image,
        variance: None,
        summary,
    })
}
