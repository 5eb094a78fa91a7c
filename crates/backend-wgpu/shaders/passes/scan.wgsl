// #import layout
// Exclusive prefix sum of u32s in place, in blocks of 256: each block is scanned in workgroup
// memory and its total goes to `block_sums`; the host scans `block_sums` the same way, then
// `scan_add_main` adds each block's offset back. Integer sums: exact, order-free.

struct ScanParams {
    count: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(0) @binding(0) var<uniform> params: ScanParams;
@group(0) @binding(1) var<storage, read_write> data: array<u32>;
@group(0) @binding(2) var<storage, read_write> block_sums: array<u32>;

const BLOCK: u32 = 256u;

var<workgroup> partial: array<u32, 256>;

@compute @workgroup_size(256)
fn scan_blocks_main(@builtin(local_invocation_id) lid: vec3<u32>, @builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let block = wid.y * groups.x + wid.x;
    let i = block * BLOCK + lid.x;
    let value = select(0u, data[min(i, params.count - 1u)], i < params.count);
    partial[lid.x] = value;
    workgroupBarrier();
    // Hillis-Steele inclusive scan over the block.
    for (var offset = 1u; offset < BLOCK; offset *= 2u) {
        var add = 0u;
        if lid.x >= offset {
            add = partial[lid.x - offset];
        }
        workgroupBarrier();
        partial[lid.x] += add;
        workgroupBarrier();
    }
    if i < params.count {
        data[i] = partial[lid.x] - value;
    }
    if lid.x == BLOCK - 1u {
        block_sums[block] = partial[lid.x];
    }
}

@compute @workgroup_size(256)
fn scan_add_main(@builtin(local_invocation_id) lid: vec3<u32>, @builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let block = wid.y * groups.x + wid.x;
    let i = block * BLOCK + lid.x;
    if i < params.count {
        data[i] += block_sums[block];
    }
}
