//! Time a device spent in each kernel of each pass, measured by the device itself (timestamp
//! queries), beside the wall times the driver measures around each pass.
//!
//! A backend that can measure them returns them from
//! [`Backend::device_times`](crate::passes::Backend::device_times); one that cannot returns
//! `None`, never zeros. The lists are small (one entry per kernel a pass ran, a few dozen in
//! all), so they are plain vectors, in the order the kernels first ran.

use serde::{Deserialize, Serialize};

/// Seconds the device spent in one kernel of one pass, over some number of dispatches.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DeviceTime {
    /// The pass the kernel ran in, as the backend names its submissions ("eye", "photon map",
    /// "local resets").
    pub pass: String,
    /// The kernel (a WGSL entry point, "grid_count_main").
    pub kernel: String,
    /// Seconds from the start of its first workgroup to the end of its last, summed over
    /// `dispatches`.
    pub seconds: f64,
    /// Dispatches measured.
    pub dispatches: u64,
}

/// Adds `more` into `total`, entry by entry (same pass and kernel); entries new to `total`
/// go at its end, in their order.
pub fn add(total: &mut Vec<DeviceTime>, more: &[DeviceTime]) {
    for m in more {
        match total
            .iter_mut()
            .find(|t| t.pass == m.pass && t.kernel == m.kernel)
        {
            Some(t) => {
                t.seconds += m.seconds;
                t.dispatches += m.dispatches;
            }
            None => total.push(m.clone()),
        }
    }
}

/// `now` less `before` (an earlier total of the same render): what ran in between, entries
/// that did not run left out. An entry with fewer dispatches than before belongs to a render
/// that started over: it counts whole.
pub fn since(now: &[DeviceTime], before: &[DeviceTime]) -> Vec<DeviceTime> {
    now.iter()
        .filter_map(|n| {
            let b = before
                .iter()
                .find(|b| b.pass == n.pass && b.kernel == n.kernel)
                .filter(|b| b.dispatches <= n.dispatches);
            let dispatches = n.dispatches - b.map_or(0, |b| b.dispatches);
            (dispatches > 0).then(|| DeviceTime {
                seconds: n.seconds - b.map_or(0.0, |b| b.seconds),
                dispatches,
                ..n.clone()
            })
        })
        .collect()
}

/// Seconds per pass, its kernels summed, in the order the passes first appear.
pub fn per_pass(times: &[DeviceTime]) -> Vec<(String, f64)> {
    let mut out: Vec<(String, f64)> = Vec::new();
    for t in times {
        match out.iter_mut().find(|(pass, _)| *pass == t.pass) {
            Some((_, s)) => *s += t.seconds,
            None => out.push((t.pass.clone(), t.seconds)),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn time(pass: &str, kernel: &str, seconds: f64, dispatches: u64) -> DeviceTime {
        DeviceTime {
            pass: pass.into(),
            kernel: kernel.into(),
            seconds,
            dispatches,
        }
    }

    #[test]
    fn adding_merges_the_same_kernel_of_the_same_pass_and_appends_the_others() {
        let mut total = vec![time("gather", "gather_apply_main", 1.0, 1)];
        add(
            &mut total,
            &[
                time("gather", "gather_apply_main", 0.5, 1),
                time("eye", "eye_main", 2.0, 1),
                time("gather", "check_main", 0.25, 1),
            ],
        );
        assert_eq!(
            total,
            vec![
                time("gather", "gather_apply_main", 1.5, 2),
                time("eye", "eye_main", 2.0, 1),
                time("gather", "check_main", 0.25, 1),
            ]
        );
    }

    #[test]
    fn since_keeps_only_what_ran_in_between() {
        let before = vec![time("eye", "eye_main", 2.0, 1)];
        let mut now = before.clone();
        add(&mut now, &[time("gather", "gather_apply_main", 0.5, 1)]);
        assert_eq!(
            since(&now, &before),
            vec![time("gather", "gather_apply_main", 0.5, 1)]
        );
    }

    #[test]
    fn per_pass_sums_a_pass_s_kernels() {
        let times = [
            time("photon map", "grid_count_main", 1.0, 1),
            time("photon map", "scan_blocks_main", 0.5, 2),
            time("photon trace", "photon_main", 3.0, 1),
        ];
        assert_eq!(
            per_pass(&times),
            vec![("photon map".into(), 1.5), ("photon trace".into(), 3.0)]
        );
    }
}
