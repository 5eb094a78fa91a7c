//! Finding the photons within a visible point's gather disc in the per-pass grid
//! ([`crate::photon_grid`]).
//!
//! A gather searches neighbouring slots together, a run of [`RUN`] consecutive pixels of a
//! row: at the radii in use their discs span nearly the same cells (at 768x768 a pixel covers
//! under a unit of cornell-box, a disc several), so the run looks each cell up once and tests
//! each of its photons against all its discs at once, in a loop the compiler vectorises (with
//! AVX2 where the CPU has it, checked at run time). One slot at a time would look up some
//! twenty cells per slot, most of them empty, and those lookups, not the photons, would be
//! most of the gather's time. A run whose discs lie far apart (an edge between a near and a
//! far surface) spans more cells than its slots do one by one; its halves are searched apart,
//! down to single slots. Region passes, whose photons carry path weights, and discs that scan
//! every photon are searched one slot at a time: both are rare, and the lanes stay free of a
//! weight lookup per photon. A local move's corrections, which also sum squared powers, run in
//! lanes too (a lane set compiled with the squares, one without).
//!
//! A slot sums its photons cell by cell in z, y, x order and in bucket order within a cell,
//! the order of [`for_photons_in_disc`], whatever the threads or the run; a run adds zero for
//! the photons outside a slot's disc, which leaves the sum bit for bit what adding only those
//! found gives (a sum that starts at +0 never becomes -0). The one difference: a run also
//! visits cells its slot's own range leaves out, so it also finds a photon that lies inside the
//! disc by less than the rounding of the slot's cell range.

use crate::photon_grid::{CellPhoton, PhotonGrid};
use glam::Vec3;
use ppm_core::grid::{cell_key, cell_range, cells_in, scan_instead};
use ppm_core::layout::HitPoint;
use ppm_core::update::gather::search_r2;
use ppm_core::update::luminance;
use ppm_core::update::pairing::{cross_term, variance_term};

/// Slots searched together: consecutive pixels of a row.
pub const RUN: usize = 8;

/// The current photon map: its grid, and (region passes) each deposit's weight.
pub struct PhotonMap<'a> {
    /// The deposits in bucket order.
    pub grid: &'a PhotonGrid,
    /// Path weights per deposit, when the pass kept them.
    pub weights: Option<&'a [f32]>,
    /// The pass's [`gather_r2_floor`](ppm_core::layout::PhotonPassParams::gather_r2_floor).
    pub r2_floor: f32,
}

/// What a slot found in its disc: photon count, summed path weight and summed power.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Found {
    /// Photons in the disc.
    pub count: u32,
    /// Their summed path weights (their count when the pass kept none).
    pub weight: f32,
    /// Their summed power.
    pub flux: Vec3,
    /// Their summed squared power luminance, a deposit's cross term with its pose-A partner
    /// added where both lie in the disc ([`ppm_core::update::pairing`]), where the search was
    /// asked for it (the variance of a local move's correction); zero otherwise.
    pub power_sq: f32,
}

/// What each slot of a run of at most [`RUN`] neighbouring slots found in its disc; zero for
/// the slots `searched` leaves out. `squares` asks for [`Found::power_sq`] too.
pub fn photons_in_discs(
    slots: &[HitPoint],
    searched: impl Fn(&HitPoint) -> bool,
    map: &PhotonMap,
    squares: bool,
) -> [Found; RUN] {
    let mut found = [Found::default(); RUN];
    let discs: [Option<Disc>; RUN] = std::array::from_fn(|lane| {
        slots
            .get(lane)
            .filter(|hp| searched(hp))
            .map(|hp| Disc::new(hp, map))
    });
    let count = map.grid.params.photon_count;
    let one_by_one = map.weights.is_some();
    if one_by_one || discs.iter().flatten().any(|d| scan_instead(d.range, count)) {
        for (lane, hp) in slots.iter().enumerate() {
            if discs[lane].is_some() {
                let f = photons_in_disc(hp, map);
                found[lane] = if squares {
                    f
                } else {
                    Found { power_sq: 0.0, ..f }
                };
            }
        }
    } else {
        search_group(&discs, 0..RUN, map, squares, &mut found);
    }
    found
}

/// A slot's gather disc and the cells it spans.
#[derive(Clone, Copy)]
struct Disc {
    centre: Vec3,
    normal: Vec3,
    r2: f32,
    range: ([i32; 3], [i32; 3]),
}

impl Disc {
    fn new(hp: &HitPoint, map: &PhotonMap) -> Self {
        let (centre, normal, r2) = disc(hp, map);
        let range = cell_range(centre, r2.sqrt(), map.grid.params.cell_size);
        Self {
            centre,
            normal,
            r2,
            range,
        }
    }
}

/// Searches the discs of `lanes` together over the cells they span, or, when those are more
/// than the discs span one by one (discs far apart: an edge between a near and a far surface),
/// each half of them apart, down to single discs.
fn search_group(
    discs: &[Option<Disc>; RUN],
    lanes: std::ops::Range<usize>,
    map: &PhotonMap,
    squares: bool,
    found: &mut [Found; RUN],
) {
    let group = || discs[lanes.clone()].iter().flatten();
    let Some(first) = group().next() else {
        return;
    };
    let union = group().fold(first.range, |(lo, hi), d| {
        (
            std::array::from_fn(|a| lo[a].min(d.range.0[a])),
            std::array::from_fn(|a| hi[a].max(d.range.1[a])),
        )
    });
    let own: f32 = group().map(|d| cells_in(d.range)).sum();
    let count = map.grid.params.photon_count;
    if lanes.len() == 1 || (cells_in(union) <= own && !scan_instead(union, count)) {
        let lanes = Lanes::new(discs, lanes.clone());
        let group_found = if squares {
            lanes.search::<true>(union, map)
        } else {
            lanes.search::<false>(union, map)
        };
        for l in 0..RUN {
            if lanes.r2[l] >= 0.0 {
                found[l] = group_found[l];
            }
        }
    } else {
        let mid = lanes.start + lanes.len() / 2;
        search_group(discs, lanes.start..mid, map, squares, found);
        search_group(discs, mid..lanes.end, map, squares, found);
    }
}

/// The discs of a group, one lane per slot, laid out so that one photon is tested against all
/// of them in a vectorised loop. An unused lane has a negative squared radius: it finds
/// nothing.
struct Lanes {
    x: [f32; RUN],
    y: [f32; RUN],
    z: [f32; RUN],
    nx: [f32; RUN],
    ny: [f32; RUN],
    nz: [f32; RUN],
    r2: [f32; RUN],
}

impl Lanes {
    fn new(discs: &[Option<Disc>; RUN], lanes: std::ops::Range<usize>) -> Self {
        let mut out = Self {
            x: [0.0; RUN],
            y: [0.0; RUN],
            z: [0.0; RUN],
            nx: [0.0; RUN],
            ny: [0.0; RUN],
            nz: [0.0; RUN],
            r2: [-1.0; RUN],
        };
        for l in lanes {
            let Some(d) = discs[l] else { continue };
            [out.x[l], out.y[l], out.z[l]] = d.centre.to_array();
            [out.nx[l], out.ny[l], out.nz[l]] = d.normal.to_array();
            out.r2[l] = d.r2;
        }
        out
    }

    /// Every lane's photons over the cells of `range`, each cell looked up once, with their
    /// squared power luminances where `SQUARES` (a local move's correction) asks for them.
    fn search<const SQUARES: bool>(
        &self,
        range: ([i32; 3], [i32; 3]),
        map: &PhotonMap,
    ) -> [Found; RUN] {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has AVX2, checked just above.
            return unsafe { self.search_avx2::<SQUARES>(range, map) };
        }
        self.search_portable::<SQUARES>(range, map)
    }

    /// [`Self::search_portable`] compiled for AVX2: eight lanes in one register instead of two,
    /// the same operations in the same order, so the same bits.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn search_avx2<const SQUARES: bool>(
        &self,
        range: ([i32; 3], [i32; 3]),
        map: &PhotonMap,
    ) -> [Found; RUN] {
        self.search_portable::<SQUARES>(range, map)
    }

    /// The search on any CPU. Inlined whole into [`Self::search_avx2`] (cells included): a
    /// call across the change of instruction set cost three times what it saved.
    #[inline(always)]
    fn search_portable<const SQUARES: bool>(
        &self,
        range: ([i32; 3], [i32; 3]),
        map: &PhotonMap,
    ) -> [Found; RUN] {
        let mut count = [0u32; RUN];
        let mut flux = [[0.0f32; RUN]; 3];
        let mut power_sq = [0.0f32; RUN];
        let grid = map.grid;
        for_cells_in(range, grid, |first, photons, key| {
            for (k, p) in photons.iter().enumerate().filter(|(_, p)| p.cell == key) {
                // The deposit's square and, where its pose-A partner lies in the same disc,
                // the cross term (ppm_core's variance_term, lane by lane; the grid holds no
                // pair that cancels).
                let (own_sq, cross, partner) = if SQUARES {
                    let own = luminance(p.power.into());
                    let a = grid.partners.get(first + k).copied().unwrap_or_default();
                    (own * own, cross_term(a[3], own), a)
                } else {
                    (0.0, 0.0, [0.0; 4])
                };
                for l in 0..RUN {
                    let (dx, dy, dz) = (
                        p.position.x - self.x[l],
                        p.position.y - self.y[l],
                        p.position.z - self.z[l],
                    );
                    let d2 = dx * dx + dy * dy + dz * dz;
                    let facing =
                        p.facing.x * self.nx[l] + p.facing.y * self.ny[l] + p.facing.z * self.nz[l];
                    let hit = (d2 < self.r2[l]) & (facing > 0.0);
                    count[l] += u32::from(hit);
                    for (c, power) in p.power.to_array().into_iter().enumerate() {
                        flux[c][l] += if hit { power } else { 0.0 };
                    }
                    if SQUARES {
                        let (ax, ay, az) = (
                            partner[0] - self.x[l],
                            partner[1] - self.y[l],
                            partner[2] - self.z[l],
                        );
                        let both = ax * ax + ay * ay + az * az < self.r2[l];
                        let term = own_sq + if both { cross } else { 0.0 };
                        power_sq[l] += if hit { term } else { 0.0 };
                    }
                }
            }
        });
        std::array::from_fn(|l| Found {
            count: count[l],
            weight: count[l] as f32,
            flux: Vec3::new(flux[0][l], flux[1][l], flux[2][l]),
            power_sq: power_sq[l],
        })
    }
}

/// What one slot finds in its disc.
fn photons_in_disc(hp: &HitPoint, map: &PhotonMap) -> Found {
    let mut found = Found::default();
    let (x, _, r2) = disc(hp, map);
    for_photons_in_disc(hp, map, |i, k, p| {
        found.count += 1;
        found.weight += map.weights.map_or(1.0, |w| w[i]);
        found.flux += p.power;
        let partner = map.grid.partners.get(k).copied().unwrap_or_default();
        let both = (Vec3::from_slice(&partner[..3]) - x).length_squared() < r2;
        let own = luminance(p.power.into());
        // The grid holds no pair that cancels (`MapContents::left_out`).
        found.power_sq += variance_term(own, both.then_some(partner[3]), false);
    });
    found
}

/// Centre, normal and squared radius of the disc a slot gathers the map's photons within
/// ([`search_r2`]).
#[inline]
fn disc(hp: &HitPoint, map: &PhotonMap) -> (Vec3, Vec3, f32) {
    (
        Vec3::from(hp.position),
        Vec3::from(hp.normal),
        search_r2(hp, map.r2_floor),
    )
}

/// Calls `visit(index in the pass, index in the grid, photon)` for each photon within the hit
/// point's gather disc whose surface faces the same way, cell by cell in z, y, x order (or
/// over all photons, when the disc spans more cells than there are photons), in bucket order
/// within a cell.
pub fn for_photons_in_disc(
    hp: &HitPoint,
    map: &PhotonMap,
    mut visit: impl FnMut(usize, usize, &CellPhoton),
) {
    let (x, n, r2) = disc(hp, map);
    let grid = map.grid;
    let inside = |p: &CellPhoton| (p.position - x).length_squared() < r2 && p.facing.dot(n) > 0.0;
    let range = cell_range(x, r2.sqrt(), grid.params.cell_size);
    if scan_instead(range, grid.params.photon_count) {
        for (k, p) in grid.sorted.iter().enumerate() {
            if inside(p) {
                visit(grid.order[k] as usize, k, p);
            }
        }
        return;
    }
    for_cells_in(range, grid, |first, photons, key| {
        for (k, p) in photons.iter().enumerate() {
            if p.cell == key && inside(p) {
                visit(grid.order[first + k] as usize, first + k, p);
            }
        }
    });
}

/// Calls `visit(first, bucket's photons, cell key)` for each cell of `range` in z, y, x order
/// (`first`: the bucket's start in the grid); only the bucket's photons with the cell's key
/// belong to the cell. Inlined always, for [`Lanes::search_avx2`].
#[inline(always)]
fn for_cells_in(
    (lo, hi): ([i32; 3], [i32; 3]),
    grid: &PhotonGrid,
    mut visit: impl FnMut(usize, &[CellPhoton], u32),
) {
    let mask = grid.params.bucket_count - 1;
    for cz in lo[2]..=hi[2] {
        for cy in lo[1]..=hi[1] {
            for cx in lo[0]..=hi[0] {
                let key = cell_key([cx, cy, cz]);
                let b = (key & mask) as usize;
                let (start, end) = (
                    grid.bucket_start[b] as usize,
                    grid.bucket_start[b + 1] as usize,
                );
                visit(start, &grid.sorted[start..end], key);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::photon_grid::{MapContents, build_photon_grid};
    use ppm_core::geometry::{oct_encode, oct_faces};
    use ppm_core::layout::{Photon, hit_flags};
    use ppm_core::rng::{PassKind, StreamKey};

    /// A map of `photons` alone, none paired or left out.
    fn contents(photons: &[Photon]) -> MapContents<'_> {
        MapContents {
            photons,
            partners: None,
            left_out: &[],
        }
    }

    /// Photons on a plane (some on its underside) and a perpendicular wall at `scale`, one far
    /// away; visible points on the plane with radii spread over two orders of magnitude.
    fn case(scale: f32, far: f32) -> (Vec<Photon>, Vec<HitPoint>) {
        let u = |path: u32, d: u32| {
            StreamKey {
                seed: 9,
                kind: PassKind::Photon,
                pass_index: 0,
                path,
            }
            .uniform(d)
        };
        let mut photons: Vec<Photon> = (0..4000)
            .map(|i| {
                let (a, b) = (u(i, 0) * scale, u(i, 1) * scale);
                let (position, normal) = match i % 4 {
                    0 => ([a, b, 0.0], Vec3::Z),
                    1 => ([a, 0.0, b], Vec3::NEG_Y),
                    _ => ([a, 0.0, b], Vec3::Y),
                };
                Photon {
                    position,
                    path: i,
                    power: [1.0; 3],
                    normal_oct: oct_encode(normal),
                }
            })
            .collect();
        photons.push(Photon {
            position: [far, -far, far],
            normal_oct: oct_encode(Vec3::Y),
            ..Photon::default()
        });
        let hit_points = (0..300)
            .map(|i| {
                let r = scale * 0.002 * 100f32.powf(u(10_000 + i, 2));
                HitPoint {
                    position: [u(10_000 + i, 0) * scale, 0.0, u(10_000 + i, 1) * scale],
                    normal: [0.0, 1.0, 0.0],
                    r2: r * r,
                    flags: hit_flags::VALID,
                    ..HitPoint::default()
                }
            })
            .collect();
        (photons, hit_points)
    }

    /// The grid finds exactly the photons a scan of all of them finds, at any scale and with a
    /// deposit far from the rest (which must not starve the others' buckets), within each
    /// slot's radius or a pass's wider floor, or a slot's own wider correction disc, which
    /// only a pass with a floor reads; never one it was told to leave out (with a floor, a
    /// correction's pairs that cancel).
    #[test]
    fn the_grid_finds_what_a_brute_force_scan_finds() {
        let cases = [(1.0, 10.0), (1e-4, 1e-3), (1e4, 1e37), (1.0, 1e8)];
        for ((scale, far), floor) in cases.into_iter().flat_map(|c| [(c, 0.0), (c, 0.01)]) {
            let (photons, mut hit_points) = case(scale, far);
            for hp in hit_points.iter_mut().step_by(3) {
                hp.correction_r2 = 0.04 * scale * scale;
            }
            let r2_floor = floor * scale * scale;
            let left_out: Vec<u32> = match floor > 0.0 {
                true => (0..photons.len() as u32).filter(|i| i % 7 == 3).collect(),
                false => Vec::new(),
            };
            let filed = MapContents {
                left_out: &left_out,
                ..contents(&photons)
            };
            let grid = build_photon_grid(filed, &hit_points, r2_floor);
            let map = PhotonMap {
                grid: &grid,
                weights: None,
                r2_floor,
            };
            for hp in &hit_points {
                let mut found = Vec::new();
                for_photons_in_disc(hp, &map, |i, _, _| found.push(i));
                found.sort_unstable();
                let n = Vec3::from(hp.normal);
                let expected: Vec<usize> = (0..photons.len())
                    .filter(|&i| !left_out.contains(&(i as u32)))
                    .filter(|&i| {
                        let p = &photons[i];
                        let r2 = match floor > 0.0 {
                            true => hp.r2.max(r2_floor).max(hp.correction_r2),
                            false => hp.r2,
                        };
                        (Vec3::from(p.position) - Vec3::from(hp.position)).length_squared() < r2
                            && oct_faces(p.normal_oct, n)
                    })
                    .collect();
                assert_eq!(
                    found, expected,
                    "scale {scale}, far {far}, floor {floor}, {hp:?}"
                );
            }
        }
    }

    /// Slots in rows, neighbours a fraction of a radius apart, along the corner where the floor
    /// meets a wall, with jumps to a far part of the floor and slots left out (the photons on
    /// the floor's underside face away from every slot): what a run finds, together or split, is bit for bit what
    /// each of its slots finds alone, with the vectorised lanes or the portable ones.
    #[test]
    fn runs_find_what_one_slot_at_a_time_finds() {
        let (photons, scattered) = case(1.0, 10.0);
        let mut rows = scattered.clone();
        for (i, hp) in rows.iter_mut().enumerate() {
            let far = (i / 5) % 3 == 0;
            hp.position = [
                0.2 + 0.0007 * i as f32,
                0.0,
                if far { 0.9 } else { 0.0005 * (i % 7) as f32 },
            ];
        }
        for (hit_points, floor) in [(&scattered, 0.0), (&rows, 0.0), (&rows, 1e-4)] {
            let grid = build_photon_grid(contents(&photons), hit_points, floor);
            let map = PhotonMap {
                grid: &grid,
                weights: None,
                r2_floor: floor,
            };
            let searched = |hp: &HitPoint| hp.position[0] * 1e4 % 10.0 > 1.0;
            for slots in hit_points.chunks(RUN) {
                let found = photons_in_discs(slots, searched, &map, false);
                let with_squares = photons_in_discs(slots, searched, &map, true);
                for (lane, hp) in slots.iter().enumerate() {
                    let alone = if searched(hp) {
                        photons_in_disc(hp, &map)
                    } else {
                        Found::default()
                    };
                    let unsquared = Found {
                        power_sq: 0.0,
                        ..alone
                    };
                    assert_eq!(found[lane], unsquared, "floor {floor}, {hp:?}");
                    assert_eq!(with_squares[lane], alone, "floor {floor}, {hp:?}");
                }
                let discs = std::array::from_fn(|l| slots.get(l).map(|hp| Disc::new(hp, &map)));
                let lanes = Lanes::new(&discs, 0..slots.len());
                let union = discs
                    .iter()
                    .flatten()
                    .fold(discs[0].unwrap().range, |r, d| {
                        (
                            std::array::from_fn(|a| r.0[a].min(d.range.0[a])),
                            std::array::from_fn(|a| r.1[a].max(d.range.1[a])),
                        )
                    });
                if !scan_instead(union, grid.params.photon_count) {
                    assert_eq!(
                        lanes.search::<false>(union, &map),
                        lanes.search_portable::<false>(union, &map)
                    );
                    assert_eq!(
                        lanes.search::<true>(union, &map),
                        lanes.search_portable::<true>(union, &map)
                    );
                }
            }
        }
    }
}
