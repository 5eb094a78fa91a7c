//! `ppm` with this repository's backends (`cpu`, `wgpu`): everything is in [`harness::cli`].

fn main() -> std::process::ExitCode {
    harness::cli::main(harness::registry::Registry::in_tree())
}
