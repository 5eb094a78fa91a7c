//! Assembles each pass shader from `shaders/passes/NAME.wgsl` and the shared modules its first
//! line imports (`// #import layout rng ...`, from `shaders/shared/`), so every pass is one
//! WGSL file and the shared math exists once. Writes `OUT_DIR/NAME.wgsl` and `shaders.rs`.

use std::fmt::Write as _;
use std::path::Path;

fn main() {
    // Read at run time: `env!` would bake in the folder this script was first compiled in, and
    // a target folder copied from another checkout would then assemble that checkout's shaders.
    let manifest = std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR");
    let root = Path::new(&manifest).join("shaders");
    println!("cargo:rerun-if-changed={}", root.display());
    let out = std::env::var("OUT_DIR").expect("cargo sets OUT_DIR");
    let mut passes: Vec<_> = std::fs::read_dir(root.join("passes"))
        .expect("shaders/passes exists")
        .map(|e| e.expect("readable entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "wgsl"))
        .collect();
    passes.sort();
    let mut index = String::from(
        "/// Every assembled pass shader: (name, WGSL source).\npub const ALL: &[(&str, &str)] = &[\n",
    );
    let mut consts = String::new();
    for pass in passes {
        let name = pass
            .file_stem()
            .and_then(|s| s.to_str())
            .expect("utf-8 name")
            .to_owned();
        let text = std::fs::read_to_string(&pass).expect("readable shader");
        let imports = text
            .lines()
            .next()
            .and_then(|l| l.strip_prefix("// #import "))
            .unwrap_or_else(|| panic!("{}: first line must be `// #import ...`", pass.display()));
        let mut source = String::new();
        for module in imports.split_whitespace() {
            let path = root.join("shared").join(format!("{module}.wgsl"));
            let shared = std::fs::read_to_string(&path)
                .unwrap_or_else(|e| panic!("{}: import {module}: {e}", pass.display()));
            writeln!(source, "// ---- shared/{module}.wgsl ----\n{shared}").unwrap();
        }
        writeln!(source, "// ---- passes/{name}.wgsl ----\n{text}").unwrap();
        std::fs::write(Path::new(&out).join(format!("{name}.wgsl")), source)
            .expect("writable OUT_DIR");
        let ident = name.to_uppercase();
        writeln!(consts, "/// Assembled `{name}` shader.\npub const {ident}: &str = include_str!(concat!(env!(\"OUT_DIR\"), \"/{name}.wgsl\"));").unwrap();
        writeln!(index, "    (\"{name}\", {ident}),").unwrap();
    }
    index.push_str("];\n");
    std::fs::write(Path::new(&out).join("shaders.rs"), consts + &index).expect("writable OUT_DIR");
}
