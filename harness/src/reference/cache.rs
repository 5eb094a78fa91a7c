//! Path-traced references cached on disk, keyed by everything that changes the image.
//!
//! A reference of a 256x256 scene takes minutes to hours, and every report needs one, so it is
//! rendered once and found again by its key: a hash of the posed scene's geometry, materials
//! and camera, the image size, the sample count, the seed and the path tracer's version. The
//! file name holds only the hash: a scene's name never becomes part of a path.

use super::{ReferenceBudget, ReferenceImage, Truth, render_reference, variance_path};
use crate::shard::Shard;
use ppm_core::compile::compile_scene;
use ppm_core::scene::{MaterialKind, Scene};
use scenes::file::image::ImageError;
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Changes whenever the path tracer's output for the same inputs changes, so that stale
/// cached references are not reused.
pub const PATH_TRACER_VERSION: u32 = 4;

/// Why a cached reference could not be had.
#[derive(Debug, Error)]
pub enum ReferenceError {
    /// Reading or writing an image failed.
    #[error(transparent)]
    Image(#[from] ImageError),
    /// The cache folder could not be made.
    #[error("{path}: cannot create the reference cache: {reason}")]
    Cache {
        /// The folder.
        path: String,
        /// What the operating system said.
        reason: String,
    },
    /// The path tracer stopped on a non-finite sample.
    #[error("reference path tracer: {0}")]
    Render(String),
    /// The render was stopped (Ctrl-C) before its samples were taken; nothing was cached.
    #[error(
        "the reference was interrupted after {spp} of {wanted} samples per pixel; nothing was cached"
    )]
    Interrupted {
        /// Samples per pixel taken.
        spp: u32,
        /// Samples per pixel asked for.
        wanted: u32,
    },
}

/// What a cached reference renders.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReferenceRequest {
    /// Frame (0 before the scene's moves, 1 after).
    pub frame: u32,
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    /// Samples per pixel.
    pub spp: u32,
    /// Seed.
    pub seed: u32,
}

/// The cache key of `request` on `scene`: FNV-1a over the posed scene and the request.
pub fn reference_key(scene: &Scene, request: &ReferenceRequest) -> u64 {
    let posed = scene.at_frame(request.frame);
    let mut h = Fnv::new();
    h.u32(PATH_TRACER_VERSION);
    for v in [request.width, request.height, request.spp, request.seed] {
        h.u32(v);
    }
    let c = &posed.camera;
    h.floats(&[c.eye, c.look_at, c.up].map(|v| v.to_array()).concat());
    h.floats(&[c.fov_deg]);
    for m in &posed.materials {
        match m.kind {
            MaterialKind::Diffuse { albedo } => {
                h.u32(0);
                h.floats(&albedo.to_array());
            }
            MaterialKind::Mirror { reflectance } => {
                h.u32(1);
                h.floats(&reflectance.to_array());
            }
            MaterialKind::Glass {
                ior,
                alpha,
                alpha_v,
            } => {
                h.u32(2);
                h.floats(&[ior, alpha]);
                h.anisotropy(alpha, alpha_v);
            }
            MaterialKind::Conductor {
                eta,
                k,
                reflectance,
                alpha,
                alpha_v,
            } => {
                h.u32(4);
                h.floats(&[eta.to_array(), k.to_array(), reflectance.to_array()].concat());
                h.floats(&[alpha]);
                h.anisotropy(alpha, alpha_v);
            }
            MaterialKind::Coated {
                albedo,
                ior,
                alpha,
                nonlinear,
            } => {
                h.u32(5);
                h.floats(&albedo.to_array());
                h.floats(&[ior, alpha]);
                h.u32(u32::from(nonlinear));
            }
            MaterialKind::Light { radiance, albedo } => {
                h.u32(3);
                h.floats(&radiance.to_array());
                h.floats(&albedo.to_array());
            }
        }
    }
    for o in &posed.objects {
        h.u32(o.material as u32);
        h.u32(o.triangles.len() as u32);
        for t in &o.triangles {
            h.floats(&t.map(|v| v.to_array()).concat());
        }
    }
    h.0
}

/// The cache file of `request` on `scene` in `cache`.
pub fn reference_path(cache: &Path, scene: &Scene, request: &ReferenceRequest) -> PathBuf {
    cache.join(format!(
        "reference-{:016x}.exr",
        reference_key(scene, request)
    ))
}

/// The path-traced reference of `request`, from `cache` when it holds it, else rendered (with
/// `on_round(spp, seconds)` after each round) and stored there.
pub fn cached_reference(
    cache: &Path,
    scene: &Scene,
    request: &ReferenceRequest,
    on_round: &mut dyn FnMut(u32, f64) -> ControlFlow<()>,
) -> Result<Truth, ReferenceError> {
    let path = reference_path(cache, scene, request);
    let source = format!(
        "{} ({} spp path-traced reference of {} frame {})",
        path.display(),
        request.spp,
        scene.name,
        request.frame
    );
    if path.is_file() && variance_path(&path).is_file() {
        let mut truth = Truth::from_exr(&path, request.width, request.height)?;
        truth.source = source;
        return Ok(truth);
    }
    let reference = render(scene, request, on_round)?;
    std::fs::create_dir_all(cache).map_err(|e| ReferenceError::Cache {
        path: cache.display().to_string(),
        reason: e.to_string(),
    })?;
    let summary = reference.summary(&scene.name, request.frame, request.seed, Shard::WHOLE);
    reference.write(&path, &summary)?;
    Ok(Truth::from((&reference, source)))
}

/// Renders the reference `request` asks for; a stop on a non-finite sample or by `on_round`
/// is an error.
pub fn render(
    scene: &Scene,
    request: &ReferenceRequest,
    on_round: &mut dyn FnMut(u32, f64) -> ControlFlow<()>,
) -> Result<ReferenceImage, ReferenceError> {
    let compiled = compile_scene(
        &scene.at_frame(request.frame),
        request.width,
        request.height,
    );
    let budget = ReferenceBudget {
        spp: Some(request.spp),
        seconds: None,
    };
    let reference = render_reference(&compiled, request.seed, budget, on_round);
    if let Some(e) = reference.error {
        return Err(ReferenceError::Render(e));
    }
    if reference.interrupted {
        return Err(ReferenceError::Interrupted {
            spp: reference.spp,
            wanted: request.spp,
        });
    }
    Ok(reference)
}

/// 64-bit FNV-1a: stable across Rust versions and platforms (the standard hasher is not).
struct Fnv(u64);

impl Fnv {
    fn new() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }

    fn u32(&mut self, v: u32) {
        for b in v.to_le_bytes() {
            self.0 = (self.0 ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3);
        }
    }

    fn floats(&mut self, v: &[f32]) {
        v.iter().for_each(|f| self.u32(f.to_bits()));
    }

    /// A roughness across the tangent, only where it differs from the one along it: the
    /// keys of isotropic scenes stay those cached before anisotropy existed.
    fn anisotropy(&mut self, alpha: f32, alpha_v: f32) {
        if alpha_v != alpha {
            self.floats(&[alpha_v]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn cornell() -> Scene {
        scenes::builtin("cornell-box").unwrap().load().unwrap()
    }

    fn request() -> ReferenceRequest {
        ReferenceRequest {
            frame: 0,
            width: 64,
            height: 48,
            spp: 256,
            seed: 0,
        }
    }

    /// Every setting that changes the image changes the key; the scene's name does not.
    #[test]
    fn the_key_changes_with_every_setting_that_changes_the_image() {
        let scene = cornell();
        let base = reference_key(&scene, &request());
        assert_eq!(base, reference_key(&scene, &request()), "stable");
        let mut renamed = scene.clone();
        renamed.name = "x/../../../etc/passwd".into();
        assert_eq!(base, reference_key(&renamed, &request()));
        let requests = [
            ReferenceRequest {
                frame: 1,
                ..request()
            },
            ReferenceRequest {
                width: 65,
                ..request()
            },
            ReferenceRequest {
                height: 49,
                ..request()
            },
            ReferenceRequest {
                spp: 257,
                ..request()
            },
            ReferenceRequest {
                seed: 1,
                ..request()
            },
        ];
        let mut scenes = Vec::new();
        let mut s = scene.clone();
        s.camera.fov_deg += 0.01;
        scenes.push(s);
        let mut s = scene.clone();
        s.camera.eye.x += 0.01;
        scenes.push(s);
        let mut s = scene.clone();
        s.materials[0].kind = MaterialKind::Diffuse {
            albedo: Vec3::splat(0.5),
        };
        scenes.push(s);
        let mut s = scene.clone();
        s.objects[0].triangles[0][1].y += 1e-3;
        scenes.push(s);
        let mut s = scene.clone();
        s.objects[1].material = 0;
        scenes.push(s);
        let mut keys: Vec<u64> = requests.iter().map(|r| reference_key(&scene, r)).collect();
        keys.extend(scenes.iter().map(|s| reference_key(s, &request())));
        for (i, k) in keys.iter().enumerate() {
            assert_ne!(*k, base, "change {i} kept the key");
        }
        let distinct: std::collections::HashSet<_> = keys.iter().collect();
        assert_eq!(distinct.len(), keys.len(), "two changes share a key");
    }

    /// A scene with no moves has one image: frame 1 is frame 0, and so is its key.
    #[test]
    fn frames_of_a_still_scene_share_a_key() {
        let scene = scenes::builtin("furnace").unwrap().load().unwrap();
        let one = ReferenceRequest {
            frame: 1,
            ..request()
        };
        assert_eq!(
            reference_key(&scene, &request()),
            reference_key(&scene, &one)
        );
    }

    /// A scene named like a path: the reference is rendered and cached, and every file it
    /// wrote is in the cache folder, named by the key.
    #[test]
    fn a_scene_named_like_a_path_writes_only_into_the_cache() {
        let root = std::env::temp_dir().join(format!("ppm-cache-escape-{}", std::process::id()));
        let cache = root.join("a/b/c/cache");
        let mut scene = cornell();
        scene.name = "x/../../../../tmp/y".into();
        let small = ReferenceRequest {
            width: 4,
            height: 4,
            spp: 8,
            ..request()
        };
        cached_reference(
            &cache,
            &scene,
            &small,
            &mut |_, _| ControlFlow::Continue(()),
        )
        .unwrap();
        let mut written = Vec::new();
        let mut folders = vec![root.clone()];
        while let Some(dir) = folders.pop() {
            for entry in std::fs::read_dir(&dir).unwrap() {
                let path = entry.unwrap().path();
                if path.is_dir() {
                    folders.push(path);
                } else {
                    written.push(path);
                }
            }
        }
        std::fs::remove_dir_all(&root).ok();
        assert_eq!(written.len(), 4, "{written:?}");
        for path in &written {
            let name = path.file_name().unwrap().to_str().unwrap();
            assert!(
                path.parent() == Some(cache.as_path()) && name.starts_with("reference-"),
                "{}",
                path.display()
            );
        }
        assert!(!Path::new("/tmp/y.exr").exists() && !Path::new("/tmp/y.json").exists());
    }

    #[test]
    fn the_cache_file_name_is_the_key_alone() {
        let mut scene = cornell();
        scene.name = "../../escape".into();
        let path = reference_path(Path::new("cache"), &scene, &request());
        assert_eq!(path.parent(), Some(Path::new("cache")));
        let name = path.file_name().unwrap().to_str().unwrap();
        assert!(
            name.starts_with("reference-") && !name.contains(".."),
            "{name}"
        );
    }
}
