//! The backends the `ppm` command can run, by name. `Registry::in_tree` holds this
//! repository's (`cpu`, `wgpu`); a crate with a backend of its own builds its own `ppm` with
//! it added, and every command that takes `--backend` or `--backends` (render, animate, the
//! reports, diff) then runs it too:
//!
//! ```no_run
//! use backend_cpu::CpuBackend;
//! use harness::registry::Registry;
//!
//! fn main() -> std::process::ExitCode {
//!     // The CPU backend under a second name stands in for a crate's own backend.
//!     let registry = Registry::in_tree().with("mine", "my backend", || {
//!         Ok(Box::new(CpuBackend::new()))
//!     });
//!     harness::cli::main(registry)
//! }
//! ```
//!
//! `examples/minimal-backend` does exactly this (its `ppm-minimal` binary).

use backend_cpu::CpuBackend;
use backend_wgpu::WgpuBackend;
use ppm_core::passes::{Backend, BackendError};

/// Starts a backend.
pub type Factory = Box<dyn Fn() -> Result<Box<dyn Backend + Send>, BackendError> + Send + Sync>;

/// One registered backend.
pub struct Entry {
    /// The name `--backend` takes.
    pub name: String,
    /// One line for `--help`.
    pub about: String,
    factory: Factory,
}

/// Named backends, in the order registered.
#[derive(Default)]
pub struct Registry {
    entries: Vec<Entry>,
}

impl Registry {
    /// This repository's backends: `cpu` and `wgpu`.
    pub fn in_tree() -> Self {
        Self::default()
            .with("cpu", "rayon on this machine's cores", || {
                Ok(Box::new(CpuBackend::new()))
            })
            .with(
                "wgpu",
                "WGSL compute shaders on the best wgpu adapter (a GPU, or lavapipe on the CPU)",
                || Ok(Box::new(WgpuBackend::new()?)),
            )
    }

    /// The registry with `name` added (or replaced), started by `factory`.
    pub fn with(
        mut self,
        name: &str,
        about: &str,
        factory: impl Fn() -> Result<Box<dyn Backend + Send>, BackendError> + Send + Sync + 'static,
    ) -> Self {
        self.entries.retain(|e| e.name != name);
        self.entries.push(Entry {
            name: name.to_owned(),
            about: about.to_owned(),
            factory: Box::new(factory),
        });
        self
    }

    /// The registered backends.
    pub fn entries(&self) -> &[Entry] {
        &self.entries
    }

    /// Starts the backend called `name`; the error names the registered ones.
    pub fn start(&self, name: &str) -> Result<Box<dyn Backend + Send>, BackendError> {
        match self.entries.iter().find(|e| e.name == name) {
            Some(e) => (e.factory)(),
            None => Err(BackendError::Unsupported(format!(
                "no backend called '{name}' (registered: {})",
                self.names().join(", ")
            ))),
        }
    }

    /// The registered names.
    pub fn names(&self) -> Vec<&str> {
        self.entries.iter().map(|e| e.name.as_str()).collect()
    }
}
