// #import layout sampling update
// Runs update.wgsl's gather rule on given cases, so a test pins it to
// ppm_core::update::gather::test_cases, kind for kind.

// One input: ppm_core::update::gather::GatherCase.
struct GatherCase {
    slot: SlotState,
    found: Found,
    reflectance: vec3<f32>,
    r2_initial: f32,
    params: GatherParams,
}

@group(0) @binding(0) var<storage, read> cases: array<GatherCase>;
@group(0) @binding(1) var<storage, read_write> results: array<SlotState>;

@compute @workgroup_size(64)
fn gather_vectors_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = item_index(gid, groups);
    if i >= arrayLength(&results) {
        return;
    }
    let c = cases[i];
    results[i] = gather_rule(c.params, c.r2_initial, c.reflectance, c.slot, c.found);
}
