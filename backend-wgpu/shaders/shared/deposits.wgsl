// What a photon pass stores, shared by the trace (photon_pass.wgsl) and the replay of kept
// paths (path_replay.wgsl), which must store the same: the deposits, appended where an atomic
// counter says with their ranks, and for a pass that records them, each path's crossed bit and
// its first stored deposits. Needs the bindings `photons`, `ranks`, `counters`, `crossed` and
// `partners` in the importing pass, `params` a PhotonPassParams, and crossed_mask.wgsl and
// update.wgsl imported.

// Appends `photon` with rank `rank`; returns its slot. One past the buffer's end is counted
// and not written: the host sees the count and grows the buffer.
fn append_deposit(photon: Photon, rank: u32) -> u32 {
    let slot = atomicAdd(&counters[COUNTER_ITEMS], 1u);
    if slot < arrayLength(&photons) {
        photons[slot] = photon;
        ranks[slot] = rank;
    }
    return slot;
}

// Notes `photon`, appended at `slot`, as its path's `nth` stored deposit where it is among
// the first PAIRED_DEPOSITS, for a pairing pass to pair with.
fn note_stored(stored: ptr<function, PathDeposits>, nth: u32, photon: Photon, slot: u32) {
    if nth < PAIRED_DEPOSITS {
        (*stored).deposits[nth] = vec4<f32>(photon.position, luminance(photon.power));
        (*stored).normal_oct[nth] = photon.normal_oct;
        (*stored).slots[nth] = slot;
    }
}

// Records, where the pass asks, whether the path of bit `at` crossed a mover's box and its
// first stored deposits.
fn record_path(at: u32, crossed_box: bool, stored: PathDeposits) {
    if (params.flags & PHOTON_RECORD_CROSSED) != 0u {
        set_mask_bit(at, crossed_box);
    }
    if (params.flags & PHOTON_RECORD_DEPOSITS) != 0u && at < arrayLength(&partners) {
        partners[at] = stored;
    }
}
