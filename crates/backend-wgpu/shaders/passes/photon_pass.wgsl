// #import layout rng sampling geometry bvh lights emission
// Photon pass (ALGORITHM.md 1.3, 2.2, 2.5, 2.6): the twin of backend-cpu's photon_pass.rs.
//
// Deposits land in path order, as on the CPU, without float atomics or an unordered append:
// `photon_count_main` traces every path and stores its deposit count, an exclusive scan turns
// the counts into offsets, and `photon_write_main` traces the same paths again (the generator
// is counter-based, so they are identical) and writes each deposit at its path's offset.
// A launch traces paths `first_path + i` for `i < photon_count`: the host splits a pass whose
// deposits would not fit one binding into such batches. The `EMISSION` override picks where
// photons start: ordinary, through the emitting region, or guided around recorded paths.

struct Emitter {
    kind: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
    region: EmissionRegion,
    guide: GuidedEmission,
}

@group(0) @binding(0) var<uniform> params: PhotonPassParams;
@group(0) @binding(1) var<storage, read> triangles: array<GpuTriangle>;
@group(0) @binding(2) var<storage, read> nodes: array<BvhNode>;
@group(0) @binding(3) var<storage, read> materials: array<GpuMaterial>;
@group(0) @binding(4) var<storage, read> lights: array<GpuLight>;
@group(0) @binding(5) var<storage, read_write> path_offsets: array<u32>;
@group(0) @binding(6) var<storage, read_write> photons: array<Photon>;
@group(0) @binding(7) var<storage, read_write> counters: array<atomic<u32>, 4>;
@group(0) @binding(8) var<uniform> emitter: Emitter;
@group(0) @binding(9) var<storage, read> recorded: array<RecordedPath>;
@group(0) @binding(10) var<storage, read_write> weights: array<f32>;

// The emission this pipeline traces (EMISSION_*): one pipeline per kind, so ordinary passes
// carry no region or guided code.
override EMISSION: u32 = 0u;

// Bounces start after the emission's dimensions (ppm_core::emission::EMISSION_DIMS).
const DIM_BOUNCE: u32 = 8u;
const DIMS_PER_BOUNCE: u32 = 3u;

fn emit(key: StreamKey) -> Emission {
    switch EMISSION {
        case EMISSION_REGION: {
            return region_emission(key);
        }
        case EMISSION_GUIDED: {
            return guided_emission(key);
        }
        default: {
            return ordinary_emission(key);
        }
    }
}

fn pass_kind() -> u32 {
    switch EMISSION {
        case EMISSION_REGION: {
            return PASS_REGION;
        }
        case EMISSION_GUIDED: {
            return PASS_GUIDED;
        }
        default: {
            return PASS_PHOTON;
        }
    }
}

// Traces path `path`; writes its deposits from `photons[base]` on when `write` is set.
// Returns (deposits, rays).
fn trace_photon(path: u32, write: bool, base: u32) -> vec2<u32> {
    let key = StreamKey(params.seed, pass_kind(), params.pass_index, path);
    let emission = emit(key);
    if emission.weight <= 0.0 {
        return vec2<u32>(0u, 0u);
    }
    var dir = emission.direction;
    var origin = emission.origin + emission.normal * params.ray_epsilon;
    var power = emission.power * params.power_scale;
    var deposits = 0u;
    var rays = 0u;
    for (var bounce = 0u; bounce < params.max_depth; bounce++) {
        rays++;
        let hit = closest_hit(origin, dir, T_MISS);
        if hit.triangle == 0xffffffffu {
            break;
        }
        let tri = triangles[hit.triangle];
        let material = materials[tri.material];
        let position = origin + dir * hit.t;
        let front = dot(dir, tri.normal) < 0.0;
        let facing = select(-tri.normal, tri.normal, front);
        let d = DIM_BOUNCE + bounce * DIMS_PER_BOUNCE;
        if material.kind == MATERIAL_DIFFUSE {
            if bounce > 0u || params.first_hit == FIRST_HIT_DEPOSIT {
                if write {
                    photons[base + deposits] = Photon(position, path, power, oct_encode(facing));
                    if EMISSION == EMISSION_REGION {
                        weights[base + deposits] = emission.weight;
                    }
                }
                deposits++;
            }
            let survive = max(material.albedo.x, max(material.albedo.y, material.albedo.z));
            if stream_uniform(key, d) >= survive {
                break;
            }
            power *= material.albedo / survive;
            dir = to_world(cosine_hemisphere(stream_uniform(key, d + 1u), stream_uniform(key, d + 2u)), facing);
            origin = position + facing * params.ray_epsilon;
        } else {
            let sb = specular_bounce(material, dir, facing, front, stream_uniform(key, d));
            power *= sb.weight;
            dir = sb.dir;
            let side = select(facing, -facing, sb.transmitted);
            origin = position + side * params.ray_epsilon;
        }
    }
    return vec2<u32>(deposits, rays);
}

@compute @workgroup_size(64)
fn photon_count_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let local = item_index(gid, groups);
    if local >= params.photon_count {
        return;
    }
    let traced = trace_photon(params.first_path + local, false, 0u);
    path_offsets[local] = traced.x;
    atomicAdd(&counters[COUNTER_ITEMS], traced.x);
    atomicAdd(&counters[COUNTER_RAYS], traced.y);
}

@compute @workgroup_size(64)
fn photon_write_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let local = item_index(gid, groups);
    if local >= params.photon_count {
        return;
    }
    trace_photon(params.first_path + local, true, path_offsets[local]);
}
