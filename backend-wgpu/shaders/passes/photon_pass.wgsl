// #import layout rng sampling geometry bsdf bvh lights emission movers tables scene materials textures update crossed_mask kept_paths deposits
// Photon pass (docs/algorithm.md 1.3, 2.2, 2.5, 2.6): the twin of backend-cpu's photon_pass.rs.
//
// Each path is traced once and appends its deposits where an atomic counter says, with the
// deposit's rank `(path - first_path) * max_depth + bounce` beside it: the append order
// varies from run to run, but the grid sorts each bucket by rank, which is the CPU's path
// order, so every sum is made in the same order. A deposit past the buffer's end is counted
// and not written: the host sees the count, grows the buffer (or splits the pass into batches
// of paths `first_path + i`, i < photon_count) and traces again. The `EMISSION` override picks
// where photons start: ordinary, through the emitting region, or guided around recorded paths.
//
// Local mode's difference passes keep one bit per path in `crossed`: pose A records whether
// each path crossed a mover's box (atomicOr/atomicAnd, so each path writes only its own bit
// whatever the order), and pose B skips the paths that did not, which would store nothing.
// Pairing their deposits, pose A (PHOTON_RECORD_DEPOSITS) writes each path's first stored
// deposits into `partners` at the path's bit, and pose B (PHOTON_PAIR_DEPOSITS) writes each
// deposit's partner there (position and luminance, four words where region passes write a
// weight; update.wgsl's pairing_partner). Where pose A's deposits are held unfiled for pose
// B's to join (PHOTON_MARK_CANCELLED), a pair that cancels exactly (partner_cancels: its path
// met no moved object up to it) has both deposits' words set to CANCELLED_PARTNER, and the map
// leaves both out: they would add nothing to a gather but rounding, and they are 28% of a
// cornell-box drag step's correction deposits (as backend-cpu's map leaves them out).
//
// An ordinary pass that keeps its paths (PHOTON_KEEP_PATHS, kept_paths.wgsl) writes their
// segments into `words`, for path_replay.wgsl to answer the next correction's pose A.
//
// Pose B does not launch its culled paths at all where it can: photon_list_crossed_main lists
// the paths whose bit is set, and photon_trace_listed_main traces those alone. Culling inside
// photon_trace_main saves little on a device that runs invocations in lockstep, as a group of
// them waits for its one crossed path; the list keeps every invocation busy.

@group(0) @binding(0) var<uniform> params: PhotonPassParams;
@group(0) @binding(1) var scene_table: texture_storage_2d<rgba32uint, read>;
@group(0) @binding(2) var<uniform> scene: SceneIndex;
@group(0) @binding(3) var<storage, read_write> ranks: array<u32>;
@group(0) @binding(4) var<storage, read_write> photons: array<Photon>;
@group(0) @binding(5) var<storage, read_write> counters: array<atomic<u32>, 4>;
@group(0) @binding(6) var<uniform> emitter: Emitter;
@group(0) @binding(7) var<storage, read> recorded: array<RecordedPath>;
// Words a pass writes beside its deposits: a path weight per deposit (region passes), four
// per deposit, its pose-A partner (a pairing pose B), or the kept paths' segments.
@group(0) @binding(8) var<storage, read_write> words: array<f32>;
@group(0) @binding(9) var<storage, read_write> crossed: array<atomic<u32>>;
@group(0) @binding(10) var<storage, read> scene_texels: array<vec2<u32>>;
@group(0) @binding(11) var<storage, read_write> partners: array<PathDeposits>;
// The paths a culling pass traces, listed by photon_list_crossed_main.
@group(0) @binding(12) var<storage, read_write> listed_paths: array<u32>;

// The emission this pipeline traces (EMISSION_*): one pipeline per kind, so ordinary passes
// carry no region or guided code.
override EMISSION: u32 = 0u;

// False for a scene without mirrors, glass or conductors: the bounces through them are
// compiled out.
override SPECULAR: bool = true;

// False for passes that never test the movers' boxes (all but local mode's correction): the
// box tests are compiled out (backend_wgpu::Specialisation).
override MOVERS: bool = true;

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

// What a path did: rays traced, whether it crossed a mover's box (always true when no flag
// asks), and its first stored deposits (pose A of a pairing pass).
struct Traced {
    rays: u32,
    crossed: bool,
    stored: PathDeposits,
}

// Whether this pass writes its paths' segments (kept_paths.wgsl): an ordinary pass that asks
// (the host clears the flag where it keeps nothing).
fn keeps_paths() -> bool {
    return EMISSION == EMISSION_ORDINARY && (params.flags & PHOTON_KEEP_PATHS) != 0u;
}

// Writes word `at` of the kept segments, where the buffer holds it.
fn keep_word(at: u32, value: f32) {
    if at < arrayLength(&words) {
        words[at] = value;
    }
}

// Writes the four words beside deposit `slot`: its pose-A partner (a pairing pose B).
fn write_words(slot: u32, partner: vec4<f32>) {
    for (var w = 0u; w < 4u; w++) {
        words[4u * slot + w] = partner[w];
    }
}

// Marks pose A's deposit `slot`, held in the buffer before this pass's, as one of a pair that
// cancels (PHOTON_MARK_CANCELLED): its path stored it, so no other invocation writes its words.
fn mark_cancelled(slot: u32) {
    if 4u * slot + 3u < arrayLength(&words) {
        write_words(slot, CANCELLED_PARTNER);
    }
}

// Traces path `path`, of random numbers `key`, from `emission`, appending its deposits.
fn trace_photon(path: u32, key: StreamKey, emission: Emission) -> Traced {
    var stored: PathDeposits;
    if emission.weight <= 0.0 {
        return Traced(0u, false, stored);
    }
    // Pairing is a local correction's, whose passes test the movers' boxes.
    let records = MOVERS && (params.flags & PHOTON_RECORD_DEPOSITS) != 0u;
    let pairs = MOVERS && (params.flags & PHOTON_PAIR_DEPOSITS) != 0u;
    let marks = pairs && (params.flags & PHOTON_MARK_CANCELLED) != 0u;
    // Pose A's deposits of this path (a fresh record pairs nothing), and which of its stored
    // deposits comes next.
    var pose_a: PathDeposits;
    if pairs && params.mask_offset + path < arrayLength(&partners) {
        pose_a = partners[params.mask_offset + path];
    }
    var nth = 0u;
    var dir = emission.direction;
    var origin = emission.origin + emission.normal * params.ray_epsilon;
    var power = emission.power * params.power_scale;
    var rays = 0u;
    let rank_base = (path - params.first_path) * params.max_depth;
    // Whether the path has crossed a mover's box so far; the boxes are tested only when a
    // flag needs the answer (ordinary passes start it true and skip the test).
    let tests_movers = MOVERS && (params.flags & (PHOTON_CHANGED_ONLY | PHOTON_RECORD_CROSSED)) != 0u;
    var crossed_box = !tests_movers;
    let stores_all = (params.flags & PHOTON_CHANGED_ONLY) == 0u;
    let keeps = keeps_paths();
    for (var bounce = 0u; bounce < params.max_depth; bounce++) {
        rays++;
        let hit = closest_hit(origin, dir, T_MISS);
        if MOVERS {
            crossed_box = crossed_box || near_mover(origin, dir, hit.t);
        }
        let kept = kept_segment(path - params.first_path, bounce);
        if keeps && bounce < KEPT_SEGMENTS {
            let segment = array<f32, 8>(origin.x, origin.y, origin.z, hit.t, dir.x, dir.y, dir.z, 0.0);
            for (var w = 0u; w < 8u; w++) {
                keep_word(kept + w, segment[w]);
            }
        }
        if hit.triangle == 0xffffffffu {
            break;
        }
        let tri = scene_triangle(hit.triangle);
        let position = origin + dir * hit.t;
        var material = scene_material(tri.material);
        material.albedo *= texture_factor(material, hit.triangle, tri, position);
        let front = dot(dir, tri.normal) < 0.0;
        let facing = select(-tri.normal, tri.normal, front);
        let d = DIM_BOUNCE + bounce * DIMS_PER_BOUNCE;
        let stores = !SPECULAR || bsdf_holds_visible_points(material);
        if stores && (stores_all || crossed_box) && (bounce > 0u || params.first_hit == FIRST_HIT_DEPOSIT) {
            // What reaches the base of a coated surface (ppm_core::bsdf::arrival).
            let deposit = power * bsdf_arrival(material, -dot(dir, facing));
            let normal_oct = oct_encode(facing);
            let photon = Photon(position, path, deposit, normal_oct);
            let slot = append_deposit(photon, rank_base + bounce);
            if keeps && bounce < KEPT_SEGMENTS {
                keep_word(kept + 7u, f32(slot + 1u));
            }
            if slot < arrayLength(&photons) {
                if EMISSION == EMISSION_REGION {
                    words[slot] = emission.weight;
                }
                if pairs {
                    var partner = pairing_partner(pose_a, nth, normal_oct);
                    if marks && partner_cancels(partner, position, luminance(deposit)) {
                        partner = CANCELLED_PARTNER;
                        mark_cancelled(pose_a.slots[nth]);
                    }
                    write_words(slot, partner);
                }
            }
            if records {
                note_stored(&stored, nth, photon, slot);
            }
            nth++;
        }
        // Dimension d picks the lobe at a delta surface and plays Russian roulette where
        // photons are stored (ppm_core::bsdf::photon_bounce).
        let u = stream_uniform(key, d);
        let u_dir = vec2<f32>(stream_uniform(key, d + 1u), stream_uniform(key, d + 2u));
        var scattered: BsdfSample;
        if !SPECULAR {
            scattered = bsdf_sample_visible(material, facing, u_dir);
            let survive = max(scattered.weight.x, max(scattered.weight.y, scattered.weight.z));
            if u >= survive {
                break;
            }
            power *= scattered.weight / survive;
        } else {
            let frame = surface_frame(material, hit.triangle, tri, facing);
            scattered = bsdf_photon_bounce(material, dir, frame, front, u, u_dir);
            if all(scattered.weight == vec3<f32>(0.0)) {
                break;
            }
            power *= scattered.weight;
        }
        dir = scattered.dir;
        let side = select(facing, -facing, scattered.transmitted);
        origin = position + side * params.ray_epsilon;
    }
    return Traced(rays, crossed_box, stored);
}

// What every traced path leaves besides its deposits: whether it crossed a mover's box where
// the pass records it, pose A's first stored deposits where the pass records them, how many
// segments it traced where it keeps them, and its rays.
fn finish_path(path: u32, traced: Traced) {
    // Only correction passes, which test the movers' boxes, record.
    if MOVERS {
        record_path(params.mask_offset + path, traced.crossed, traced.stored);
    }
    if keeps_paths() {
        keep_word(kept_length(path - params.first_path), f32(traced.rays));
    }
    atomicAdd(&counters[COUNTER_RAYS], traced.rays);
}

@compute @workgroup_size(64)
fn photon_trace_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let local = item_index(gid, groups);
    if local >= params.photon_count {
        return;
    }
    let path = params.first_path + local;
    if (params.flags & PHOTON_CULL_UNCROSSED) != 0u && !mask_bit(params.mask_offset + path) {
        atomicAdd(&counters[COUNTER_CULLED], 1u);
        return;
    }
    let key = StreamKey(params.seed, pass_kind(), params.pass_index, path);
    finish_path(path, trace_photon(path, key, emit(key)));
}

// A culling pass's paths whose bit is set, appended to `listed_paths` (in no fixed order: the
// grid orders deposits by rank, which follows the path), counted in COUNTER_ITEMS.
@compute @workgroup_size(64)
fn photon_list_crossed_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let local = item_index(gid, groups);
    if local >= params.photon_count {
        return;
    }
    let path = params.first_path + local;
    if mask_bit(params.mask_offset + path) {
        listed_paths[atomicAdd(&counters[COUNTER_ITEMS], 1u)] = path;
    }
}

// The first `photon_count` listed paths of an ordinary pass (a culling pose B's, or the paths
// too long to keep that a pose A answered from kept paths traces again), as
// photon_trace_main traces them. Ordinary emission only, so the guided paths stay unbound.
@compute @workgroup_size(64)
fn photon_trace_listed_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let local = item_index(gid, groups);
    if local >= params.photon_count {
        return;
    }
    let path = listed_paths[local];
    let key = StreamKey(params.seed, PASS_PHOTON, params.pass_index, path);
    finish_path(path, trace_photon(path, key, ordinary_emission(key)));
}
