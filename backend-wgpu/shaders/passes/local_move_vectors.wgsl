// #import layout sampling update reach local_move
// Runs local_move.wgsl's per-slot decisions on given cases, so that a test pins them to
// ppm_core::local_move and ppm_core::reach (backend-wgpu's tests/local_move.rs).

// One input of the decisions (backend_wgpu::layout::MoveDecisionCase): a box of a slot's
// paths (also a segment's start box), a segment's end and target boxes, then the move's boxes
// (its objects' in pose A, in pose B, then the lights').
struct MoveDecisionCase {
    boxes: array<GpuBounds, 8>,
    position: vec3<f32>,
    covered: u32,
    eye: vec3<f32>,
    eye_met: u32,
    flags: u32,
    groups: u32,
    r2_floor: f32,
    widest: f32,
    objects: u32,
    lights: u32,
    _pad0: u32,
    _pad1: u32,
}

// One output of the decisions (backend_wgpu::layout::MoveDecisionOutcome).
struct MoveDecisionOutcome {
    meets: u32,
    flags: u32,
    view: u32,
    correction_r2: f32,
}

@group(0) @binding(0) var<storage, read> decision_cases: array<MoveDecisionCase>;
@group(0) @binding(1) var<storage, read_write> decisions: array<MoveDecisionOutcome>;

// The case's boxes, where local_move.wgsl reads a move's.
var<private> move_boxes: array<GpuBounds, 8>;

// The move's boxes from the fourth on.
const FIRST_MOVE_BOX: u32 = 3u;

@compute @workgroup_size(64)
fn move_decision_vectors_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = item_index(gid, groups);
    if i >= arrayLength(&decisions) {
        return;
    }
    let c = decision_cases[i];
    move_boxes = c.boxes;
    let boxes = MoveBoxes(FIRST_MOVE_BOX, c.objects, c.lights);
    let bounds = move_box(0u);
    var hp: HitPoint;
    hp.position = c.position;
    hp.eye_met = c.eye_met;
    hp.flags = c.flags;
    var m: LocalMoveParams;
    m.groups = c.groups;
    m.r2_floor = c.r2_floor;
    m.widest = c.widest;
    m.objects = c.objects;
    m.lights = c.lights;
    let prepared = prepare_slot(hp, bounds, m, boxes);
    let nearest = nearest_after(boxes, c.eye);
    let view = view_test(hp, bounds, c.covered != 0u, c.eye, nearest, c.groups, boxes);
    let meets = segments_may_meet(bounds, move_box(1u), move_box(2u));
    decisions[i] = MoveDecisionOutcome(select(0u, 1u, meets), prepared.flags, view, prepared.correction_r2);
}
