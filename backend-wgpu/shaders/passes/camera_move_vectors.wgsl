// #import layout camera_move
// Runs camera_move.wgsl's `inherit_slot` on given cases over a given old view, and its
// `on_an_edge` at every slot of a given new view, so that a test pins them to
// ppm_core::camera_move's (backend-wgpu's tests/camera_move.rs).

// One input (backend_wgpu::layout::InheritCase): a fresh slot of the new view, its box, and
// the move.
struct InheritCase {
    slot: HitPoint,
    bounds: GpuBounds,
    request: CameraMoveParams,
}

// One output (backend_wgpu::layout::InheritOutcome): the slot and its box after, and whether
// it inherited (0 or 1).
struct InheritOutcome {
    slot: HitPoint,
    bounds: GpuBounds,
    inherited: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(0) @binding(0) var<storage, read> inherit_cases: array<InheritCase>;
@group(0) @binding(1) var<storage, read> before_slots: array<HitPoint>;
@group(0) @binding(2) var<storage, read> before_bounds: array<GpuBounds>;
@group(0) @binding(3) var<storage, read> case_materials: array<GpuMaterial>;
@group(0) @binding(4) var<storage, read_write> outcomes: array<InheritOutcome>;
// The new view whose edges are asked for, the move it follows, and one answer (0 or 1) a
// slot.
@group(0) @binding(5) var<storage, read> hit_points: array<HitPoint>;
@group(0) @binding(6) var<uniform> edge_request: CameraMoveParams;
@group(0) @binding(7) var<storage, read_write> edges: array<u32>;

// The cases' materials, where a pass reads the scene table's (materials.wgsl).
fn scene_material(i: u32) -> GpuMaterial {
    return case_materials[i];
}

@compute @workgroup_size(64)
fn camera_move_vectors_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = item_index(gid, groups);
    if i < arrayLength(&edges) {
        edges[i] = select(0u, 1u, on_an_edge(i, edge_request));
    }
    if i >= arrayLength(&outcomes) {
        return;
    }
    let c = inherit_cases[i];
    var hp = c.slot;
    var bounds = c.bounds;
    let inherited = inherit_slot(&hp, &bounds, c.request);
    outcomes[i] = InheritOutcome(hp, bounds, select(0u, 1u, inherited), 0u, 0u, 0u);
}
