// How many records the scene's light and mover tables hold: backend-wgpu's
// layout::SceneCounts, bound as the uniform `counts` by the passes that read those tables.

struct SceneCounts {
    lights: u32,
    movers: u32,
    _pad0: u32,
    _pad1: u32,
}
