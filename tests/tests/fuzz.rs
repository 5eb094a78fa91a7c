//! Bad input never panics: mutations of `cornell-box.toml` (numbers replaced by extremes,
//! lines deleted or duplicated, random bytes), of its Mitsuba and pbrt exports, and of OBJ
//! and PLY meshes go through the
//! loaders, validation and compilation, and the scenes that survive render a tiny image. Every
//! error names the file. Cases are drawn from a fixed seed, so a failure reproduces; their
//! counts (3,000 in all) keep the whole file within seconds in release.

use backend_cpu::CpuBackend;
use harness::driver::{Budget, Schedule, run};
use ppm_core::compile::compile_scene;
use ppm_core::params::{MoveParams, RenderParams};
use ppm_core::scene::{Scene, SceneError};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed, TestCaseError, TestRunner};
use scenes::file::mesh::read_ply;
use scenes::file::mitsuba::{export_mitsuba, load_mitsuba_file};
use scenes::file::pbrt::{export_pbrt, load_pbrt_file};
use scenes::file::{Export, ExportOptions, load_scene_file};
use std::path::PathBuf;
use std::sync::atomic::{AtomicU32, Ordering};

const CORNELL: &str = include_str!("../../scenes/data/cornell-box.toml");

/// Numbers at the edges of what TOML, `f32` and `u32` hold, and past them.
const EXTREMES: &[&str] = &[
    "0",
    "-0.0",
    "1e38",
    "-1e38",
    "1e-38",
    "1e-45",
    "3.5e38",
    "1e300",
    "nan",
    "inf",
    "-inf",
    "-1",
    "4294967295",
    "4294967296",
    "18446744073709551616",
    "1e20",
    "1e-30",
];

/// One edit of a text.
#[derive(Clone, Debug)]
enum Mutation {
    /// The `n`-th number (mod their count) becomes `EXTREMES[k]`.
    Number(usize, usize),
    /// Line `n` (mod the line count) removed.
    DeleteLine(usize),
    /// Line `n` written twice.
    DuplicateLine(usize),
    /// Bytes inserted at `at` (mod the length).
    Insert(usize, Vec<u8>),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        4 => (any::<usize>(), 0..EXTREMES.len()).prop_map(|(n, k)| Mutation::Number(n, k)),
        1 => any::<usize>().prop_map(Mutation::DeleteLine),
        1 => any::<usize>().prop_map(Mutation::DuplicateLine),
        1 => (any::<usize>(), prop::collection::vec(any::<u8>(), 1..8))
            .prop_map(|(at, b)| Mutation::Insert(at, b)),
    ]
}

/// Byte ranges of the numbers in `text`.
fn numbers(text: &[u8]) -> Vec<(usize, usize)> {
    let mut spans = Vec::new();
    let mut i = 0;
    while i < text.len() {
        let starts = text[i].is_ascii_digit()
            || (text[i] == b'-' && text.get(i + 1).is_some_and(u8::is_ascii_digit));
        if starts && (i == 0 || !text[i - 1].is_ascii_alphanumeric()) {
            let start = i;
            i += 1;
            while i < text.len() && (text[i].is_ascii_alphanumeric() || b".-+".contains(&text[i])) {
                i += 1;
            }
            spans.push((start, i));
        } else {
            i += 1;
        }
    }
    spans
}

fn apply(text: &[u8], m: &Mutation) -> Vec<u8> {
    let lines =
        |t: &[u8]| -> Vec<Vec<u8>> { t.split(|&b| b == b'\n').map(<[u8]>::to_vec).collect() };
    match m {
        Mutation::Number(n, k) => {
            let spans = numbers(text);
            if spans.is_empty() {
                return text.to_vec();
            }
            let (a, b) = spans[n % spans.len()];
            [&text[..a], EXTREMES[*k].as_bytes(), &text[b..]].concat()
        }
        Mutation::DeleteLine(n) => {
            let mut l = lines(text);
            let at = n % l.len();
            l.remove(at);
            l.join(&b'\n')
        }
        Mutation::DuplicateLine(n) => {
            let mut l = lines(text);
            let at = n % l.len();
            l.insert(at, l[at].clone());
            l.join(&b'\n')
        }
        Mutation::Insert(at, bytes) => {
            let at = at % (text.len() + 1);
            [&text[..at], bytes.as_slice(), &text[at..]].concat()
        }
    }
}

fn config(cases: u32) -> Config {
    Config {
        cases,
        failure_persistence: None,
        rng_seed: RngSeed::Fixed(0x5eed),
        ..Config::default()
    }
}

/// A fresh folder: the properties run on parallel threads of one process.
fn scratch(name: &str) -> PathBuf {
    static COUNTER: AtomicU32 = AtomicU32::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("ppm-fuzz-{}-{name}-{n}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// What the cases of one property came to.
#[derive(Debug, Default)]
struct Tally {
    refused: u32,
    loaded: u32,
    rendered: u32,
}

/// Runs `cases` cases of edits to `original` through `check`, which says whether the input
/// loaded and rendered; prints the tally (`--nocapture` shows it).
fn fuzz(
    name: &str,
    original: &str,
    cases: u32,
    check: impl Fn(&[u8]) -> Result<Outcome, TestCaseError>,
) {
    let tally = std::cell::RefCell::new(Tally::default());
    let mut runner = TestRunner::new(config(cases));
    runner
        .run(&prop::collection::vec(mutation(), 1..4), |edits| {
            let text = edits
                .iter()
                .fold(original.as_bytes().to_vec(), |t, m| apply(&t, m));
            let mut t = tally.borrow_mut();
            match check(&text)? {
                Outcome::Refused => t.refused += 1,
                Outcome::Loaded => t.loaded += 1,
                Outcome::Rendered => t.rendered += 1,
            }
            Ok(())
        })
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    eprintln!("{name}: {cases} cases: {:?}", tally.borrow());
}

/// How one input ended.
enum Outcome {
    /// Refused by the loader with an error naming the file.
    Refused,
    /// Loaded (and its settings refused, or nothing to render).
    Loaded,
    /// Loaded, validated, compiled and rendered.
    Rendered,
}

/// A scene that loaded: its settings validate or are refused with the source named, and a
/// valid one compiles and renders a tiny image (8x8, 200 photons) with a finite result.
fn render_tiny(scene: &Scene) -> Result<Outcome, TestCaseError> {
    let mut params = RenderParams::for_scene(scene);
    (
        params.width,
        params.height,
        params.passes,
        params.photons_per_pass,
    ) = (8, 8, 1, 200);
    if let Err(e) = params.validate("fuzz.toml") {
        prop_assert!(e.to_string().starts_with("fuzz.toml: "), "{e}");
        return Ok(Outcome::Loaded);
    }
    let compiled = compile_scene(scene, 8, 8);
    prop_assert!(compiled.extent.is_finite(), "{}", compiled.extent);
    let outcome = run(
        &mut CpuBackend::new(),
        scene,
        &params,
        &MoveParams::default(),
        &Schedule::frame(1, Budget::iterations(1)),
        &mut (),
    )
    .map_err(|e| TestCaseError::fail(format!("the scene does not load: {e}")))?;
    prop_assert!(outcome.image.is_finite());
    Ok(Outcome::Rendered)
}

/// Loads `scene_text` as `fuzz.toml` beside `mesh` (written as `mesh_name`, if any).
fn load(scene_text: &[u8], mesh: Option<(&str, &[u8])>) -> (Result<Scene, SceneError>, String) {
    let dir = scratch("case");
    if let Some((name, bytes)) = mesh {
        std::fs::write(dir.join(name), bytes).unwrap();
    }
    let path = dir.join("fuzz.toml");
    std::fs::write(&path, scene_text).unwrap();
    let loaded = load_scene_file(&path);
    std::fs::remove_dir_all(&dir).ok();
    (loaded, path.display().to_string())
}

/// Mutated scene files: loaded, validated, compiled and rendered, or refused naming the
/// file; never a panic.
#[test]
fn mutated_scene_files_are_refused_or_render() {
    fuzz("scene", CORNELL, 1000, |text| match load(text, None) {
        (Err(e), file) => {
            prop_assert!(e.to_string().starts_with(&file), "{e}");
            Ok(Outcome::Refused)
        }
        (Ok(scene), _) => render_tiny(&scene),
    });
}

/// A tetrahedron beside cornell-box's light, as an OBJ file the fuzz mutates.
const TETRA_OBJ: &str = "# tetrahedron\nv 100 100 100\nv 200 100 100\nv 100 200 100\n\
                         v 100 100 200\nvn 0 0 1\nf 1 3 2\nf 1//1 2//1 4//1\nf 1 4 3\nf 2 3 4\n";

/// The same tetrahedron as an ascii PLY file.
const TETRA_PLY: &str = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\n\
                         property float y\nproperty float z\nelement face 4\n\
                         property list uchar int vertex_indices\nend_header\n\
                         100 100 100\n200 100 100\n100 200 100\n100 100 200\n\
                         3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";

/// cornell-box with the tetrahedron of `mesh.obj` added.
fn scene_with_obj() -> String {
    format!("{CORNELL}\n[[objects]]\nname = \"mesh\"\nmaterial = \"white\"\nobj = \"mesh.obj\"\n")
}

/// Mutated OBJ meshes of a scene: loaded or refused naming the scene file and the mesh.
#[test]
fn mutated_obj_meshes_are_refused_or_render() {
    let scene = scene_with_obj();
    fuzz("obj", TETRA_OBJ, 500, |obj| {
        match load(scene.as_bytes(), Some(("mesh.obj", obj))) {
            (Err(e), file) => {
                let message = e.to_string();
                prop_assert!(
                    message.starts_with(&file) && message.contains("mesh.obj"),
                    "{message}"
                );
                Ok(Outcome::Refused)
            }
            (Ok(scene), _) => render_tiny(&scene),
        }
    });
}

/// Mutated PLY files: read, or refused with the file named; never a panic, and every face
/// refers to a vertex that exists.
#[test]
fn mutated_ply_files_are_refused_or_read() {
    fuzz("ply", TETRA_PLY, 500, |ply| {
        let dir = scratch("ply");
        let path = dir.join("mesh.ply");
        std::fs::write(&path, ply).unwrap();
        let read = read_ply(&path);
        std::fs::remove_dir_all(&dir).ok();
        match read {
            Err(e) => {
                prop_assert!(e.contains(&path.display().to_string()), "{e}");
                Ok(Outcome::Refused)
            }
            Ok(mesh) => {
                let n = mesh.positions.len() as u32;
                prop_assert!(mesh.triangles.iter().flatten().all(|&i| i < n));
                Ok(Outcome::Loaded)
            }
        }
    });
}

/// Mutated Mitsuba and pbrt exports of cornell-box (their PLY meshes left whole): loaded and
/// rendered, or refused naming the file; never a panic.
#[test]
fn mutated_mitsuba_and_pbrt_files_are_refused_or_render() {
    let scene = scenes::builtin("cornell-box").unwrap().load().unwrap();
    let options = ExportOptions {
        samples_per_pixel: 16,
        frame: 0,
        ..ExportOptions::default()
    };
    let dir = scratch("import");
    type Load = fn(&std::path::Path) -> Result<Scene, SceneError>;
    let formats: [(&str, Export, Load); 2] = [
        (
            "mitsuba",
            export_mitsuba(&scene, &options),
            load_mitsuba_file,
        ),
        ("pbrt", export_pbrt(&scene, &options), load_pbrt_file),
    ];
    for (name, export, load) in formats {
        let original = export.write(&dir).unwrap();
        let extension = original.extension().unwrap().to_str().unwrap().to_owned();
        assert!(load(&original).is_ok(), "{name}: the export itself loads");
        let text = std::fs::read_to_string(&original).unwrap();
        let case = AtomicU32::new(0);
        fuzz(name, &text, 500, |mutated| {
            let n = case.fetch_add(1, Ordering::Relaxed);
            let path = dir.join(format!("case-{n}.{extension}"));
            std::fs::write(&path, mutated).unwrap();
            let loaded = load(&path);
            std::fs::remove_file(&path).ok();
            match loaded {
                Err(e) => {
                    let message = e.to_string();
                    prop_assert!(
                        message.starts_with(&path.display().to_string()),
                        "{message}"
                    );
                    Ok(Outcome::Refused)
                }
                Ok(scene) => render_tiny(&scene),
            }
        });
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// The inputs the fuzz mutates are valid: a refusal of a mutant is the mutation's doing.
#[test]
fn the_unmutated_inputs_load_and_render() {
    let (scene, _) = load(
        scene_with_obj().as_bytes(),
        Some(("mesh.obj", TETRA_OBJ.as_bytes())),
    );
    let scene = scene.unwrap();
    assert_eq!(scene.objects.last().unwrap().triangles.len(), 4);
    assert!(matches!(render_tiny(&scene), Ok(Outcome::Rendered)));
    let dir = scratch("plain-ply");
    std::fs::write(dir.join("mesh.ply"), TETRA_PLY).unwrap();
    let ply = read_ply(&dir.join("mesh.ply"));
    std::fs::remove_dir_all(&dir).ok();
    assert_eq!(ply.unwrap().triangles.len(), 4);
}
