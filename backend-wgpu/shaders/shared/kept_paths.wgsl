// The paths an ordinary photon pass keeps for a local move's pose-A correction
// (ppm_core::layout::photon_flags::KEEP_PATHS; backend-wgpu's kept_paths.rs): per path, its
// first KEPT_SEGMENTS ray segments and how many it traced. A segment is eight words: where its
// ray started, how far it went (T_MISS where it left the scene), its direction, and one more
// than the index in the photon buffer of the deposit it ended in (0 for none), exact as an f32
// below 2^24 (the host keeps no pass whose buffer holds more). photon_pass.wgsl writes them,
// path_replay.wgsl reads them.

// Segments kept per path: a path that traced more is traced again (path_replay.wgsl lists it).
const KEPT_SEGMENTS: u32 = 6u;
// Words per path: its segments, then how many segments it traced.
const KEPT_STRIDE: u32 = 8u * KEPT_SEGMENTS + 1u;

// The first word of segment `bounce` of the path `local` paths after the pass's first.
fn kept_segment(local: u32, bounce: u32) -> u32 {
    return local * KEPT_STRIDE + 8u * bounce;
}

// The word that holds how many segments path `local` traced.
fn kept_length(local: u32) -> u32 {
    return local * KEPT_STRIDE + 8u * KEPT_SEGMENTS;
}
