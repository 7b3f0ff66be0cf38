//! Sampled axes (`[sample]` of a sweep file): n runs whose parameters are drawn by a
//! seeded Latin hypercube (McKay et al. 1979) from distributions, as AvaFrame's
//! probAna draws its ensembles.
//!
//! # The Latin hypercube
//!
//! For each axis j an independent random permutation π_j of 0 … n−1 and independent
//! r_ij uniform in (0, 1) give
//!
//! ```text
//!   u_ij = (π_j(i) + r_ij) / n,        x_ij = F_j⁻¹(u_ij),
//! ```
//!
//! so that each of the n equal-probability strata [k/n, (k+1)/n) of every axis holds
//! exactly one run, and the axes are paired at random. F_j is the distribution's
//! cumulative distribution function:
//!
//! - `uniform = [a, b]`: F⁻¹(u) = a + u (b − a);
//! - `normal = [m, σ]`, optionally truncated to [`min`, `max`]: with Φ the standard
//!   normal CDF, α = (min − m)/σ and β = (max − m)/σ (±∞ without them),
//!   F⁻¹(u) = m + σ Φ⁻¹(Φ(α) + u (Φ(β) − Φ(α)));
//! - `ci95 = [v, c]`: uniform on [v − c, v + c], the value and its 95 % confidence
//!   half-width, as probAna's `rangefromci` variation of a release thickness.
//!
//! The generator is SplitMix64 (Steele et al. 2014), written here so that a seed gives
//! the same runs on every machine and with every version of the crates.
//!
//! Φ is ½ erfc(−x/√2), erfc by its Taylor series below 2 and by its continued fraction
//! above (relative error below 1e-12 over the range sampled); Φ⁻¹ by bisection on Φ
//! (monotone, so exact to the last bits), on the lower tail, the upper one by symmetry.

/// A distribution to sample an axis from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Distribution {
    /// Uniform on [lo, hi].
    Uniform { lo: f64, hi: f64 },
    /// Normal of mean `mean` and standard deviation `sd`, truncated to [lo, hi]
    /// (infinite bounds: not truncated).
    Normal {
        mean: f64,
        sd: f64,
        lo: f64,
        hi: f64,
    },
}

impl Distribution {
    /// F⁻¹(u), u in (0, 1).
    pub fn quantile(&self, u: f64) -> f64 {
        match *self {
            Distribution::Uniform { lo, hi } => lo + u * (hi - lo),
            Distribution::Normal { mean, sd, lo, hi } => {
                let (a, b) = ((lo - mean) / sd, (hi - mean) / sd);
                // In the lower tail Φ keeps its relative precision: a window above the
                // mean is sampled as its mirror image.
                let z = if a > 0.0 {
                    -truncated(-b, -a, 1.0 - u)
                } else {
                    truncated(a, b, u)
                };
                mean + sd * z
            }
        }
    }

    /// The probability of the truncation window, > 0 for a usable distribution.
    pub fn mass(&self) -> f64 {
        match *self {
            Distribution::Uniform { .. } => 1.0,
            Distribution::Normal { mean, sd, lo, hi } => {
                let (a, b) = ((lo - mean) / sd, (hi - mean) / sd);
                if a > 0.0 {
                    phi(-a) - phi(-b)
                } else {
                    phi(b) - phi(a)
                }
            }
        }
    }
}

/// Φ⁻¹(Φ(a) + u (Φ(b) − Φ(a))) for a ≤ 0.
fn truncated(a: f64, b: f64, u: f64) -> f64 {
    let (pa, pb) = (phi(a), phi(b));
    phi_inv(pa + u * (pb - pa)).clamp(a, b)
}

/// The standard normal CDF.
pub fn phi(x: f64) -> f64 {
    if x < 0.0 {
        0.5 * erfc(-x / std::f64::consts::SQRT_2)
    } else {
        1.0 - 0.5 * erfc(x / std::f64::consts::SQRT_2)
    }
}

/// erfc(z) for z ≥ 0.
fn erfc(z: f64) -> f64 {
    let sqrt_pi = std::f64::consts::PI.sqrt();
    if z < 2.0 {
        // erf(z) = 2/√π Σ (−1)ⁿ z²ⁿ⁺¹ / (n! (2n + 1))
        let (mut sum, mut term) = (0.0, z);
        for n in 0..200 {
            let t = term / (2 * n + 1) as f64;
            sum += t;
            if t.abs() <= 1e-17 * sum.abs() {
                break;
            }
            term *= -z * z / (n + 1) as f64;
        }
        1.0 - 2.0 / sqrt_pi * sum
    } else {
        // erfc(z) = e^{−z²}/√π · 1/(z + (1/2)/(z + 1/(z + (3/2)/(z + …)))),
        // evaluated from the tail.
        let mut k = 0.0;
        for n in (1..=200).rev() {
            k = (0.5 * n as f64) / (z + k);
        }
        (-z * z).exp() / sqrt_pi / (z + k)
    }
}

/// Φ⁻¹(p), p in (0, 1).
pub fn phi_inv(p: f64) -> f64 {
    if p > 0.5 {
        return -phi_inv(1.0 - p);
    }
    let (mut lo, mut hi) = (-40.0f64, 0.0f64);
    loop {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            return mid;
        }
        if phi(mid) < p {
            lo = mid;
        } else {
            hi = mid;
        }
    }
}

/// SplitMix64 (Steele et al. 2014): 64 random bits per call.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Rng {
        Rng(seed)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in (0, 1): 53 random bits, offset by half a step (never 0 or 1).
    pub fn open01(&mut self) -> f64 {
        ((self.next_u64() >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }

    /// Uniform in 0 … n−1 (n > 0), without modulo bias.
    fn below(&mut self, n: usize) -> usize {
        let n = n as u64;
        let zone = u64::MAX - u64::MAX % n;
        loop {
            let v = self.next_u64();
            if v < zone {
                return (v % n) as usize;
            }
        }
    }
}

/// The Latin hypercube of `n` points in `dims` dimensions: `u[j][i]`, axis j, run i,
/// each in (0, 1) and in stratum ⌊n u⌋ = π_j(i) (see the module docs).
pub fn latin_hypercube(n: usize, dims: usize, seed: u64) -> Vec<Vec<f64>> {
    let mut rng = Rng::new(seed);
    (0..dims)
        .map(|_| {
            // Fisher–Yates.
            let mut perm: Vec<usize> = (0..n).collect();
            for i in (1..n).rev() {
                perm.swap(i, rng.below(i + 1));
            }
            perm.iter()
                .map(|&k| {
                    let mut u = (k as f64 + rng.open01()) / n as f64;
                    // Rounding may carry u across a stratum's edge: brought back.
                    while (u * n as f64).floor() as usize > k {
                        u = u.next_down();
                    }
                    while ((u * n as f64).floor() as usize) < k {
                        u = u.next_up();
                    }
                    u
                })
                .collect()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_stratum_of_each_axis_holds_exactly_one_run() {
        for (n, dims, seed) in [(1, 1, 0), (7, 3, 1), (40, 2, 12345), (1000, 4, 9)] {
            let u = latin_hypercube(n, dims, seed);
            assert_eq!(u.len(), dims);
            for axis in &u {
                let mut hits = vec![0; n];
                for &v in axis {
                    assert!(v > 0.0 && v < 1.0);
                    hits[(v * n as f64).floor() as usize] += 1;
                }
                assert!(hits.iter().all(|&h| h == 1), "{n} {seed}: {hits:?}");
            }
        }
    }

    #[test]
    fn a_seed_gives_the_same_hypercube_and_another_seed_another() {
        assert_eq!(latin_hypercube(20, 3, 7), latin_hypercube(20, 3, 7));
        assert_ne!(latin_hypercube(20, 3, 7), latin_hypercube(20, 3, 8));
        // The axes are not paired in order.
        let u = latin_hypercube(20, 2, 7);
        let rank = |v: &[f64]| v.iter().map(|x| (x * 20.0) as usize).collect::<Vec<_>>();
        assert_ne!(rank(&u[0]), rank(&u[1]));
    }

    #[test]
    fn the_normal_cdf_and_its_inverse_match_known_values() {
        // Φ(1.96) = 0.975002104851780, Φ(−3) = 1.349898031630095e-3, Φ(−8) =
        // 6.220960574271785e-16 (tables of the normal distribution).
        for (x, p) in [
            (1.96, 0.975002104851780),
            (-3.0, 1.349898031630095e-3),
            (-8.0, 6.220960574271785e-16),
            (0.0, 0.5),
        ] {
            assert!((phi(x) - p).abs() <= 1e-12 * p, "Φ({x}) = {}", phi(x));
            assert!((phi_inv(p) - x).abs() <= 1e-9, "Φ⁻¹({p}) = {}", phi_inv(p));
        }
    }

    #[test]
    fn quantiles_stay_in_their_window_and_split_it_in_equal_probability() {
        let d = Distribution::Normal {
            mean: 2000.0,
            sd: 400.0,
            lo: 1500.0,
            hi: f64::INFINITY,
        };
        // The median of the window: Φ(z) = (Φ(−1.25) + 1)/2.
        let z = phi_inv(0.5 * (phi(-1.25) + 1.0));
        assert!((d.quantile(0.5) - (2000.0 + 400.0 * z)).abs() < 1e-9);
        assert!(d.quantile(1e-12) >= 1500.0);
        // A window far in the upper tail, sampled by symmetry.
        let t = Distribution::Normal {
            mean: 0.0,
            sd: 1.0,
            lo: 6.0,
            hi: 7.0,
        };
        for u in [1e-9, 0.3, 0.999999] {
            let x = t.quantile(u);
            assert!((6.0..=7.0).contains(&x), "{x}");
        }
        assert!(t.quantile(0.3) < t.quantile(0.6));
        let uniform = Distribution::Uniform { lo: 1.0, hi: 3.0 };
        assert_eq!(uniform.quantile(0.25), 1.5);
    }
}
