//! What the benchmarks share: their settings from the environment, and the wgpu backend
//! when they are asked for its rows.

use backend_wgpu::WgpuBackend;

/// The environment variable `name` parsed, or `default` when unset or unparsable.
pub fn setting<T: std::str::FromStr>(name: &str, default: T) -> T {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// The backends `PPM_BENCH_BACKENDS` names (default `cpu,wgpu`).
pub fn backends() -> String {
    std::env::var("PPM_BENCH_BACKENDS").unwrap_or_else(|_| "cpu,wgpu".into())
}

/// The wgpu backend where `backends` names it and an adapter starts; says why not otherwise.
pub fn wgpu_if_wanted(backends: &str) -> Option<WgpuBackend> {
    if !backends.contains("wgpu") {
        return None;
    }
    WgpuBackend::new()
        .map_err(|e| println!("no wgpu rows: {e}"))
        .ok()
}
