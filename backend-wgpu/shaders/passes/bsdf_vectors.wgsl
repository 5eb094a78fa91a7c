// #import layout sampling geometry bsdf
// Runs bsdf.wgsl on given cases, so a test pins it to ppm_core::bsdf::test_cases.

// One input: ppm_core::bsdf::BsdfCase.
struct BsdfCase {
    material: GpuMaterial,
    incoming: vec3<f32>,
    front: u32,
    facing: vec3<f32>,
    u_lobe: f32,
    u_direction: vec3<f32>,
    transport: u32,
    u_dir: vec2<f32>,
    _pad: vec2<u32>,
}

// One output: ppm_core::bsdf::BsdfOutcome.
struct BsdfOutcome {
    dir: vec3<f32>,
    pdf: f32,
    weight: vec3<f32>,
    transmitted: u32,
    f_cos: vec3<f32>,
    pdf_of_dir: f32,
    glossy_f_cos: vec3<f32>,
    glossy_pdf: f32,
}

@group(0) @binding(0) var<storage, read> cases: array<BsdfCase>;
@group(0) @binding(1) var<storage, read_write> results: array<BsdfOutcome>;

@compute @workgroup_size(64)
fn bsdf_vectors_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = item_index(gid, groups);
    if i >= arrayLength(&results) {
        return;
    }
    let c = cases[i];
    let frame = bsdf_frame(c.material, c.facing, c.u_direction);
    let s = bsdf_sample(c.material, c.incoming, frame, c.front != 0u, c.u_lobe, c.u_dir, c.transport);
    let wo = -c.incoming;
    let f_cos = bsdf_eval_cos(c.material, frame, wo, s.dir);
    let glossy = bsdf_glossy_lobe(c.material, frame, c.front != 0u, wo, s.dir);
    results[i] = BsdfOutcome(s.dir, s.pdf, s.weight, select(0u, 1u, s.transmitted), f_cos, bsdf_pdf(c.material, frame, wo, s.dir), glossy.xyz, glossy.w);
}
