// #import layout
// Exclusive prefix sum of u32s in place, in blocks of 2048: each of a workgroup's 256
// invocations sums 8 consecutive elements on its own, the 256 sums are scanned in workgroup
// memory, and the invocations write their elements' prefixes; each block's total goes to
// `block_sums`, which the host scans the same way before `scan_add_main` adds each block's
// offset back. Eight elements an invocation keep the barriers (costly on software adapters)
// per element low. Integer sums: exact, order-free.

struct ScanParams {
    count: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(0) @binding(0) var<uniform> params: ScanParams;
@group(0) @binding(1) var<storage, read_write> data: array<u32>;
@group(0) @binding(2) var<storage, read_write> block_sums: array<u32>;

const PER_INVOCATION: u32 = 8u;
const BLOCK: u32 = 2048u;

var<workgroup> partial: array<u32, 256>;

@compute @workgroup_size(256)
fn scan_blocks_main(@builtin(local_invocation_id) lid: vec3<u32>, @builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let block = wid.y * groups.x + wid.x;
    let base = block * BLOCK + lid.x * PER_INVOCATION;
    var values: array<u32, 8>;
    var total = 0u;
    for (var j = 0u; j < PER_INVOCATION; j++) {
        let i = base + j;
        values[j] = select(0u, data[min(i, params.count - 1u)], i < params.count);
        total += values[j];
    }
    partial[lid.x] = total;
    workgroupBarrier();
    // Hillis-Steele inclusive scan over the invocations' totals.
    for (var offset = 1u; offset < 256u; offset *= 2u) {
        var add = 0u;
        if lid.x >= offset {
            add = partial[lid.x - offset];
        }
        workgroupBarrier();
        partial[lid.x] += add;
        workgroupBarrier();
    }
    var running = partial[lid.x] - total;
    for (var j = 0u; j < PER_INVOCATION; j++) {
        let i = base + j;
        if i < params.count {
            data[i] = running;
        }
        running += values[j];
    }
    if lid.x == 255u {
        block_sums[block] = partial[lid.x];
    }
}

@compute @workgroup_size(256)
fn scan_add_main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let i = gid.y * groups.x * 256u + gid.x;
    if i < params.count {
        data[i] += block_sums[i / BLOCK];
    }
}
