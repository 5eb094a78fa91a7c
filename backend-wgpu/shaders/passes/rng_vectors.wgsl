// #import layout rng qmc
// Evaluates the generators on given keys, so tests pin the WGSL twins to ppm_core::rng's and
// ppm_core::qmc's vectors.

@group(0) @binding(0) var<storage, read> keys: array<u32>;
@group(0) @binding(1) var<storage, read_write> bits: array<u32>;

@compute @workgroup_size(64)
fn rng_vectors_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = item_index(gid, groups);
    if i >= arrayLength(&bits) {
        return;
    }
    let k = 5u * i;
    bits[i] = random_bits(keys[k], keys[k + 1u], keys[k + 2u], keys[k + 3u], keys[k + 4u]);
}

// Two words per key: (scramble, index) in, the Sobol pair's bits out.
@compute @workgroup_size(64)
fn qmc_vectors_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = item_index(gid, groups);
    if 2u * i >= arrayLength(&bits) {
        return;
    }
    let b = sobol_pair_bits(keys[2u * i], keys[2u * i + 1u]);
    bits[2u * i] = b.x;
    bits[2u * i + 1u] = b.y;
}
