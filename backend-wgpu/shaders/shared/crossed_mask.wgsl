// The crossed-path mask (ppm_core::layout::photon_flags::RECORD_CROSSED): a bit per path, set
// where the path crossed a mover's box. Needs the binding `crossed` in the importing pass.

// Bit `bit` of the crossed-path mask; set past its end (and wherever no pass recorded it),
// so a missing bit never culls.
fn mask_bit(bit: u32) -> bool {
    let word = bit / 32u;
    return word >= arrayLength(&crossed) || (atomicLoad(&crossed[word]) & (1u << (bit % 32u))) != 0u;
}

// Sets or clears bit `bit` of the crossed-path mask (atomicOr/atomicAnd, so each path writes
// only its own bit whatever the order; the host sized it for the pass).
fn set_mask_bit(bit: u32, value: bool) {
    let word = bit / 32u;
    let m = 1u << (bit % 32u);
    if word >= arrayLength(&crossed) {
        return;
    }
    if value {
        atomicOr(&crossed[word], m);
    } else {
        atomicAnd(&crossed[word], ~m);
    }
}
