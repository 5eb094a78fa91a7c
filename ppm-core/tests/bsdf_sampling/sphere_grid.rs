//! Bins over the sphere of directions about a surface, fine where a lobe concentrates, and a
//! function's integral over each by Gauss-Legendre quadrature in f64, halving a bin's
//! rectangles where their estimates disagree.
//!
//! A bin is a rectangle in `(mu, phi)`, the cosine to the normal and the azimuth in the
//! surface's local frame: the solid angle is `d mu d phi`, so a rectangle's integral needs no
//! Jacobian, and the horizon (`mu = 0`), where a reflection lobe is cut off, is an edge of
//! every bin that meets it. Uniform edges would put a narrow lobe (alpha 0.02) into one or two
//! bins and test nothing of its shape, so each hemisphere's edges are spread by a mixture of a
//! uniform and a Cauchy distribution about where its lobe is expected ([`Focus`]). Any edges
//! make a valid test, since the expected counts are integrals over the same bins; these make
//! a sharp one.

use glam::Vec3;
use ppm_core::geometry::Frame;
use std::f64::consts::PI;

/// Where a hemisphere's lobe is expected and how wide it is: the edges crowd there.
#[derive(Clone, Copy, Debug)]
pub struct Focus {
    /// The lobe's centre's cosine to the normal (its magnitude, on either side).
    pub cos: f64,
    /// The centre's azimuth in the local frame.
    pub azimuth: f64,
    /// The lobe's angular width in radians; infinite for edges uniform in `mu` and `phi`.
    pub width: f64,
    /// Bins along `mu` and along `phi`.
    pub bins: (usize, usize),
    /// A `|mu|` where the density jumps, made an edge so that no bin straddles it: a jump
    /// inside a bin would need more halvings than [`MAX_DEPTH`] allows to integrate.
    pub jump: Option<f64>,
}

impl Focus {
    /// Uniform edges: a lobe that spreads over the hemisphere, or one that should be empty.
    pub fn uniform(bins: (usize, usize)) -> Self {
        Self {
            cos: 1.0,
            azimuth: 0.0,
            width: f64::INFINITY,
            bins,
            jump: None,
        }
    }
}

/// The share of each axis's edges spread uniformly, the rest by the Cauchy distribution:
/// enough to resolve a lobe's tails and whatever else the density holds (a coat's diffuse
/// base under its reflection).
const UNIFORM_SHARE: f64 = 0.3;

/// Gauss-Legendre nodes per axis and rectangle: exact for polynomials of degree 11, which a
/// smooth density over a bin the edges keep narrow next to its lobe is close to; the halving
/// ([`Rect::refine`]) takes over where it is not.
const ORDER: usize = 6;

/// One hemisphere's edges: of `|mu|` over `[0, 1]`, and of the azimuth relative to `azimuth`
/// over `[-pi, pi]`.
struct Hemisphere {
    sign: f64,
    mu: Vec<f64>,
    psi: Vec<f64>,
    azimuth: f64,
}

impl Hemisphere {
    fn new(sign: f64, focus: Focus) -> Self {
        let sin = (1.0 - focus.cos * focus.cos).max(0.0).sqrt();
        let w = focus.width;
        // Near the pole a lobe spans `w^2 / 2` in `mu`; elsewhere `w sin` in `mu` and `w / sin`
        // in azimuth.
        let mu_scale = (w * sin).max(0.5 * w * w);
        let psi_scale = w / sin.max(w);
        let mut mu = warped_edges(0.0, 1.0, focus.cos, mu_scale, focus.bins.0);
        if let Some(jump) = focus.jump.filter(|j| *j > 0.0 && *j < 1.0) {
            // The interior edge nearest the jump moves onto it; its neighbours bracket it.
            let interior = 1..mu.len() - 1;
            if let Some(k) =
                interior.min_by(|&a, &b| (mu[a] - jump).abs().total_cmp(&(mu[b] - jump).abs()))
            {
                mu[k] = jump;
            }
        }
        Self {
            sign,
            mu,
            psi: warped_edges(-PI, PI, 0.0, psi_scale, focus.bins.1),
            azimuth: focus.azimuth,
        }
    }

    fn cells(&self) -> usize {
        (self.mu.len() - 1) * (self.psi.len() - 1)
    }
}

/// `n + 1` edges over `[lo, hi]` at equal steps of the mixture's distribution function.
fn warped_edges(lo: f64, hi: f64, centre: f64, scale: f64, n: usize) -> Vec<f64> {
    let cauchy = |x: f64| ((x - centre) / scale).atan();
    let (a, b) = (cauchy(lo), cauchy(hi));
    let uniform = if scale.is_finite() && b - a > 1e-9 {
        UNIFORM_SHARE
    } else {
        1.0
    };
    let cdf = |x: f64| {
        let spread = if uniform < 1.0 {
            (cauchy(x) - a) / (b - a)
        } else {
            0.0
        };
        uniform * (x - lo) / (hi - lo) + (1.0 - uniform) * spread
    };
    let mut edges: Vec<f64> = (1..n)
        .map(|i| {
            let target = i as f64 / n as f64;
            let (mut l, mut h) = (lo, hi);
            for _ in 0..64 {
                let mid = 0.5 * (l + h);
                if cdf(mid) < target { l = mid } else { h = mid }
            }
            0.5 * (l + h)
        })
        .collect();
    edges.insert(0, lo);
    edges.push(hi);
    edges
}

/// The bins of both hemispheres about a [`Frame`]'s normal: the upper one's first.
pub struct SphereGrid {
    frame: Frame,
    hemispheres: [Hemisphere; 2],
}

impl SphereGrid {
    /// Bins about `frame`, crowded at `upper` above the surface and at `lower` below it.
    pub fn new(frame: Frame, upper: Focus, lower: Focus) -> Self {
        Self {
            frame,
            hemispheres: [Hemisphere::new(1.0, upper), Hemisphere::new(-1.0, lower)],
        }
    }

    /// The number of bins.
    pub fn cells(&self) -> usize {
        self.hemispheres.iter().map(Hemisphere::cells).sum()
    }

    /// The bin of the world direction `dir`; the horizon counts as above.
    pub fn cell_of(&self, dir: Vec3) -> usize {
        let local = self.frame.to_local(dir).as_dvec3();
        let side = usize::from(local.z < 0.0);
        let h = &self.hemispheres[side];
        let mu = (local.z.abs() / local.length()).min(1.0);
        let psi = wrap(local.y.atan2(local.x) - h.azimuth);
        let index = |edges: &[f64], x: f64| {
            edges.partition_point(|&e| e <= x).clamp(1, edges.len() - 1) - 1
        };
        let offset = if side == 0 {
            0
        } else {
            self.hemispheres[0].cells()
        };
        offset + index(&h.mu, mu) * (h.psi.len() - 1) + index(&h.psi, psi)
    }

    /// Where the bin `cell` lies: its hemisphere and its ranges of `|mu|` and of the azimuth
    /// (in the local frame), for a failing test's message.
    pub fn describe(&self, cell: usize) -> String {
        let upper = self.hemispheres[0].cells();
        let (side, h, i) = if cell < upper {
            ("above", &self.hemispheres[0], cell)
        } else {
            ("below", &self.hemispheres[1], cell - upper)
        };
        let columns = h.psi.len() - 1;
        let (m, p) = (i / columns, i % columns);
        format!(
            "{side}, |mu| {:.4}..{:.4}, phi {:.4}..{:.4}",
            h.mu[m],
            h.mu[m + 1],
            h.azimuth + h.psi[p],
            h.azimuth + h.psi[p + 1]
        )
    }

    /// The integrals of `f`'s `K` components over each bin, in [`Self::cell_of`]'s order: `f`
    /// is evaluated at unit world directions, once for all components (a lobe's density and
    /// value come from one call).
    pub fn integrate<const K: usize>(&self, f: impl Fn(Vec3) -> [f64; K]) -> Vec<[f64; K]> {
        let rule = gauss_legendre(ORDER);
        let mut integrals = Vec::with_capacity(self.cells());
        for h in &self.hemispheres {
            let at = |mu: f64, psi: f64| {
                let sin = (1.0 - mu * mu).max(0.0).sqrt();
                let phi = h.azimuth + psi;
                let local = Vec3::new(
                    (sin * phi.cos()) as f32,
                    (sin * phi.sin()) as f32,
                    (h.sign * mu) as f32,
                );
                f(self.frame.to_world(local))
            };
            for mu in h.mu.windows(2) {
                for psi in h.psi.windows(2) {
                    let cell = Rect {
                        mu: (mu[0], mu[1]),
                        psi: (psi[0], psi[1]),
                    };
                    let whole = cell.rule(&rule, &at);
                    integrals.push(cell.refine(&rule, &at, whole, 0));
                }
            }
        }
        integrals
    }
}

/// How often a bin's quadrature may halve its rectangles where the estimates disagree: a
/// kink inside a bin (rough glass's critical angle, where the refraction lobe ends with an
/// infinite slope) converges slowly, and the deepest rectangles are then 1/128 of the bin's
/// sides. A jump converges too slowly for that ([`Focus::jump`]).
const MAX_DEPTH: u32 = 7;

/// When a rectangle's quarters agree with it well enough to stop halving: within 1e-8 of the
/// density's integral (2^18 samples times that is 3e-3 of a count) or 1e-6 of its value.
const ABSOLUTE: f64 = 1e-8;
const RELATIVE: f64 = 1e-6;

/// A rectangle in `(|mu|, psi)`.
#[derive(Clone, Copy)]
struct Rect {
    mu: (f64, f64),
    psi: (f64, f64),
}

impl Rect {
    /// The tensor Gauss-Legendre estimate of `f`'s integrals over the rectangle.
    fn rule<const K: usize>(
        &self,
        (nodes, weights): &(Vec<f64>, Vec<f64>),
        f: &impl Fn(f64, f64) -> [f64; K],
    ) -> [f64; K] {
        let (mu_mid, mu_half) = (0.5 * (self.mu.0 + self.mu.1), 0.5 * (self.mu.1 - self.mu.0));
        let (psi_mid, psi_half) = (
            0.5 * (self.psi.0 + self.psi.1),
            0.5 * (self.psi.1 - self.psi.0),
        );
        let mut sum = [0.0; K];
        for (x, wx) in nodes.iter().zip(weights) {
            for (y, wy) in nodes.iter().zip(weights) {
                let values = f(mu_mid + mu_half * x, psi_mid + psi_half * y);
                for (s, v) in sum.iter_mut().zip(values) {
                    *s += wx * wy * v;
                }
            }
        }
        sum.map(|s| s * mu_half * psi_half)
    }

    /// `whole`, the rule's estimate over the rectangle, improved: the four quarters' estimates
    /// are kept where they agree with it in every component, else each quarter is refined in
    /// turn.
    fn refine<const K: usize>(
        &self,
        rule: &(Vec<f64>, Vec<f64>),
        f: &impl Fn(f64, f64) -> [f64; K],
        whole: [f64; K],
        level: u32,
    ) -> [f64; K] {
        let (mu_mid, psi_mid) = (
            0.5 * (self.mu.0 + self.mu.1),
            0.5 * (self.psi.0 + self.psi.1),
        );
        let quarters = [
            ((self.mu.0, mu_mid), (self.psi.0, psi_mid)),
            ((self.mu.0, mu_mid), (psi_mid, self.psi.1)),
            ((mu_mid, self.mu.1), (self.psi.0, psi_mid)),
            ((mu_mid, self.mu.1), (psi_mid, self.psi.1)),
        ]
        .map(|(mu, psi)| Rect { mu, psi });
        let parts = quarters.map(|q| q.rule(rule, f));
        let sum = add(&parts);
        let agree = sum
            .iter()
            .zip(whole)
            .all(|(s, w)| (s - w).abs() <= ABSOLUTE + RELATIVE * s.abs());
        if level == MAX_DEPTH || agree {
            return sum;
        }
        let refined = quarters
            .iter()
            .zip(parts)
            .map(|(q, part)| q.refine(rule, f, part, level + 1));
        add(&refined.collect::<Vec<_>>())
    }
}

/// The componentwise sum of `parts`.
fn add<const K: usize>(parts: &[[f64; K]]) -> [f64; K] {
    let mut sum = [0.0; K];
    for part in parts {
        for (s, p) in sum.iter_mut().zip(part) {
            *s += p;
        }
    }
    sum
}

/// `x` in `[-pi, pi)`.
fn wrap(x: f64) -> f64 {
    (x + PI).rem_euclid(2.0 * PI) - PI
}

/// The nodes and weights of `n`-point Gauss-Legendre quadrature on `[-1, 1]`: the roots of
/// the Legendre polynomial `P_n` by Newton's method from Chebyshev's guesses.
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let (mut nodes, mut weights) = (Vec::with_capacity(n), Vec::with_capacity(n));
    for i in 0..n {
        let mut x = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut derivative = 0.0;
        for _ in 0..100 {
            // P_n(x) and P_n'(x) by the three-term recurrence.
            let (mut p0, mut p1) = (1.0, x);
            for k in 2..=n {
                let k = k as f64;
                (p0, p1) = (p1, ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k);
            }
            derivative = n as f64 * (x * p1 - p0) / (x * x - 1.0);
            let step = p1 / derivative;
            x -= step;
            if step.abs() < 1e-15 {
                break;
            }
        }
        nodes.push(x);
        weights.push(2.0 / ((1.0 - x * x) * derivative * derivative));
    }
    (nodes, weights)
}

#[test]
fn the_quadrature_integrates_the_sphere_and_the_cosine_lobe() {
    let (nodes, weights) = gauss_legendre(ORDER);
    // x^10 over [-1, 1] is 2 / 11; the rule is exact up to degree 2n - 1 = 11.
    let moment: f64 = nodes
        .iter()
        .zip(&weights)
        .map(|(x, w)| w * x.powi(10))
        .sum();
    assert!((moment - 2.0 / 11.0).abs() < 1e-14, "{moment}");
    let frame = Frame::around(Vec3::new(0.2, 0.9, -0.1).normalize());
    let focus = Focus {
        cos: 0.3,
        azimuth: 2.0,
        width: 0.05,
        bins: (12, 16),
        jump: None,
    };
    let grid = SphereGrid::new(frame, focus, Focus::uniform((4, 8)));
    assert_eq!(grid.cells(), 12 * 16 + 4 * 8);
    let area: f64 = grid.integrate(|_| [1.0]).iter().map(|[a]| a).sum();
    assert!((area - 4.0 * PI).abs() < 1e-9, "{area}");
    let cosine = |d: Vec3| [f64::from(frame.normal.dot(d).max(0.0)) / PI];
    let total: f64 = grid.integrate(cosine).iter().map(|[c]| c).sum();
    // The directions are rounded to f32.
    assert!((total - 1.0).abs() < 1e-6, "{total}");
    // Directions uniform over the sphere land in each bin in proportion to its area.
    let mut rng = super::chi_square::Rng::new(7);
    let n = 200_000;
    let mut counts = vec![0.0f64; grid.cells()];
    for _ in 0..n {
        let z = 2.0 * rng.uniform() - 1.0;
        let phi = 2.0 * std::f32::consts::PI * rng.uniform();
        let r = (1.0 - z * z).max(0.0).sqrt();
        counts[grid.cell_of(frame.to_world(Vec3::new(r * phi.cos(), r * phi.sin(), z)))] += 1.0;
    }
    let areas = grid.integrate(|_| [1.0]);
    for (count, [area]) in counts.iter().zip(&areas) {
        let expected = f64::from(n) * area / (4.0 * PI);
        // Five standard deviations of a binomial count, and one count's rounding.
        assert!(
            (count - expected).abs() <= 5.0 * expected.sqrt() + 1.0,
            "{count} against {expected}"
        );
    }
}
