// #import layout rng qmc sampling geometry bsdf bvh lights tables scene materials textures eye_path
// Eye pass (docs/algorithm.md 1.1): the twin of backend-cpu's eye_pass.rs and
// ppm_core::eye_path::slot_eye_path. Writes each slot's visible point, its eye path traced by
// eye_path.wgsl; the slot starts fresh or keeps its statistics as `params.flags` says. A focus
// pass traces only the slots focus.wgsl listed that are still behind, the others resting.

@group(0) @binding(0) var<uniform> params: EyePassParams;
@group(0) @binding(1) var<uniform> camera: GpuCamera;
@group(0) @binding(2) var scene_table: texture_storage_2d<rgba32uint, read>;
@group(0) @binding(3) var<uniform> scene: SceneIndex;
@group(0) @binding(4) var<storage, read_write> hit_points: array<HitPoint>;
@group(0) @binding(5) var<storage, read_write> counters: array<atomic<u32>, 4>;
@group(0) @binding(6) var<storage, read_write> slot_bounds: array<GpuBounds>;
@group(0) @binding(7) var<storage, read> scene_texels: array<vec2<u32>>;
// One per slot in a scene with glossy surfaces, else one placeholder element.
@group(0) @binding(8) var<storage, read_write> chain_light: array<ChainLight>;
// The slots a focus pass listed (focus.wgsl), walked alone where `list.focus` says so.
@group(0) @binding(9) var<storage, read> listed: array<u32>;
@group(0) @binding(10) var<uniform> list: ListParams;

// False for a scene without mirrors, glass or conductors: every surface is diffuse, and the
// bounces through them are compiled out (backend_wgpu::Specialisation).
override SPECULAR: bool = true;

// The slot before this iteration's eye path: fresh, or its statistics without a visible point.
fn cleared_slot(slot: u32, pixel: u32) -> HitPoint {
    var hp: HitPoint;
    if (params.flags & EYE_KEEP_STATISTICS) != 0u {
        hp = hit_points[slot];
        hp.position = vec3<f32>(0.0);
        hp.normal = vec3<f32>(0.0);
        hp.throughput = vec3<f32>(0.0);
        hp.flags &= HIT_KEPT;
    } else {
        hp.pixel = pixel;
        hp.r2 = params.r2_initial;
    }
    hp.material = NO_MATERIAL;
    return hp;
}

@compute @workgroup_size(64)
fn eye_pass_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    var slot = item_index(gid, groups);
    if list.focus != 0u {
        // A focus pass: the slots behind, each keyed by its own index; the others rest.
        if slot >= list.count {
            return;
        }
        slot = listed[slot];
        // A listed slot that caught up since the list was made (backend_wgpu's focus.rs
        // walks a list again) rests, as focus.wgsl rests it.
        if hit_points[slot].iterations >= params.rest_at {
            hit_points[slot].flags |= HIT_RESTING;
            if (hit_points[slot].flags & HIT_VALID) != 0u {
                atomicAdd(&counters[COUNTER_ITEMS], 1u);
            }
            return;
        }
    } else if slot >= arrayLength(&hit_points) {
        return;
    }
    let pixel = slot / params.spp;
    let key = StreamKey(params.seed, PASS_EYE, params.iteration, slot);
    var jitter = vec2<f32>(0.5);
    if params.spp != 1u || (params.flags & EYE_JITTER) != 0u {
        // Kept slots continue their own sequence, a re-trace repeats the stratum it last used
        // (backend-cpu's eye_pass.rs).
        var start = params.iteration;
        if (params.flags & EYE_KEEP_STATISTICS) != 0u {
            start = hit_points[slot].iterations;
        } else if (params.flags & EYE_RETRACE) != 0u {
            start = max(hit_points[slot].iterations, 1u) - 1u;
        }
        let sample = start * params.spp + slot % params.spp;
        jitter = stratified_pair(params.seed, PASS_EYE, pixel, 0u, sample);
    }
    // What the glossy bounces found (ppm_core::layout::ChainLight) rides beside the slot in
    // a scene with glossy surfaces.
    let chained = arrayLength(&chain_light) == arrayLength(&hit_points);
    let sample_lights = chained && (params.flags & EYE_SAMPLE_LIGHTS) != 0u;
    let settings = EyePathSettings(params.max_depth, params.ray_epsilon, sample_lights);
    let path = trace_eye_path(pixel, jitter, key, settings, 0u);
    var out = cleared_slot(slot, pixel);
    out.eye_met |= path.met;
    if path.chained {
        out.flags |= HIT_EYE_CHAINED;
    }
    if path.visible {
        out.position = path.position;
        out.normal = path.normal;
        out.material = path.material;
        out.throughput = path.throughput;
        out.flags |= eye_path_flags(path);
    }
    hit_points[slot] = out;
    if chained {
        chain_light[slot] = path.chain;
    }
    if (params.flags & EYE_RECORD_BOUNDS) != 0u {
        // Started over where the slot's statistics start (no direct sample yet).
        var bounds = GpuBounds(vec3<f32>(F32_MAX), 0u, vec3<f32>(-F32_MAX), 0u);
        if out.iterations != 0u {
            bounds = slot_bounds[slot];
        }
        slot_bounds[slot] = GpuBounds(min(bounds.min, path.lo), 0u, max(bounds.max, path.hi), 0u);
    }
    atomicAdd(&counters[COUNTER_RAYS], path.rays);
    if (out.flags & HIT_VALID) != 0u {
        atomicAdd(&counters[COUNTER_ITEMS], 1u);
    }
}
