// Light selection by power: needs the `lights` binding in the importing pass.

fn sample_light(u: f32) -> u32 {
    var lo = 0u;
    var hi = arrayLength(&lights) - 1u;
    while lo < hi {
        let mid = (lo + hi) / 2u;
        if u < lights[mid].cdf {
            hi = mid;
        } else {
            lo = mid + 1u;
        }
    }
    return lo;
}
