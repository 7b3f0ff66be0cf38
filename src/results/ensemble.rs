//! Per-cell statistics of an ensemble of N runs on one grid, from each run's peak flow
//! thickness pft = max_t h and peak flow velocity pfv = max_t |u|:
//!
//! - P(pft > h*) = #{runs with pft > h*} / N, the probability (the fraction of the
//!   ensemble) that the flow reaches the cell thicker than the threshold h*;
//! - the means (1/N) Σ pft, (1/N) Σ pfv and the maxima max pft, max pfv over the runs.
//!
//! With every run weighted equally the probability is a count: an ensemble of
//! identical runs gives 0 or 1 only, and two runs give 0, ½ or 1. Sums are taken in
//! run order, so the maps do not depend on how the runs were scheduled.

/// The running statistics of an ensemble (one slot per cell).
#[derive(Debug, Clone)]
pub struct Ensemble {
    threshold: f64,
    runs: usize,
    exceed: Vec<u32>,
    pft_sum: Vec<f64>,
    pft_max: Vec<f64>,
    pfv_sum: Vec<f64>,
    pfv_max: Vec<f64>,
}

impl Ensemble {
    /// An empty ensemble on `cells` cells with the threshold h* = `threshold`.
    pub fn new(cells: usize, threshold: f64) -> Ensemble {
        Ensemble {
            threshold,
            runs: 0,
            exceed: vec![0; cells],
            pft_sum: vec![0.0; cells],
            pft_max: vec![0.0; cells],
            pfv_sum: vec![0.0; cells],
            pfv_max: vec![0.0; cells],
        }
    }

    /// Adds one run's pft and pfv (one value per cell each).
    ///
    /// # Panics
    /// When the lengths differ from the ensemble's cells.
    pub fn add(&mut self, pft: &[f64], pfv: &[f64]) {
        assert!(pft.len() == self.exceed.len() && pfv.len() == self.exceed.len());
        for k in 0..pft.len() {
            if pft[k] > self.threshold {
                self.exceed[k] += 1;
            }
            self.pft_sum[k] += pft[k];
            self.pft_max[k] = self.pft_max[k].max(pft[k]);
            self.pfv_sum[k] += pfv[k];
            self.pfv_max[k] = self.pfv_max[k].max(pfv[k]);
        }
        self.runs += 1;
    }

    /// Runs added.
    pub fn runs(&self) -> usize {
        self.runs
    }

    /// The threshold h* (m).
    pub fn threshold(&self) -> f64 {
        self.threshold
    }

    /// P(pft > h*) per cell.
    pub fn probability(&self) -> Vec<f64> {
        let n = self.runs.max(1) as f64;
        self.exceed.iter().map(|&c| f64::from(c) / n).collect()
    }

    /// The named maps: `pft_probability`, `pft_mean`, `pft_max`, `pfv_mean`,
    /// `pfv_max`.
    pub fn maps(&self) -> Vec<(&'static str, Vec<f64>)> {
        let n = self.runs.max(1) as f64;
        let mean = |s: &[f64]| s.iter().map(|v| v / n).collect::<Vec<_>>();
        vec![
            ("pft_probability", self.probability()),
            ("pft_mean", mean(&self.pft_sum)),
            ("pft_max", self.pft_max.clone()),
            ("pfv_mean", mean(&self.pfv_sum)),
            ("pfv_max", self.pfv_max.clone()),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_runs_give_probabilities_zero_or_one() {
        let pft = [0.0, 0.05, 0.1, 0.1000001, 2.0];
        let pfv = [0.0, 1.0, 2.0, 3.0, 4.0];
        let mut e = Ensemble::new(5, 0.1);
        for _ in 0..7 {
            e.add(&pft, &pfv);
        }
        assert_eq!(e.probability(), [0.0, 0.0, 0.0, 1.0, 1.0]);
        let maps = e.maps();
        assert_eq!(maps[2].1, pft);
        assert_eq!(maps[4].1, pfv);
        for (m, x) in maps[1].1.iter().zip(pft) {
            assert!((m - x).abs() <= 1e-15 * x, "{m} {x}");
        }
    }

    #[test]
    fn two_members_give_one_half_where_exactly_one_reaches() {
        let mut e = Ensemble::new(4, 0.1);
        e.add(&[0.0, 0.2, 0.3, 0.0], &[0.0, 1.0, 1.0, 0.0]);
        e.add(&[0.0, 0.0, 0.4, 0.2], &[0.0, 0.0, 3.0, 2.0]);
        assert_eq!(e.probability(), [0.0, 0.5, 1.0, 0.5]);
        let maps = e.maps();
        assert_eq!(maps[1].1, [0.0, 0.1, 0.35, 0.1]);
        assert_eq!(maps[4].1, [0.0, 1.0, 3.0, 2.0]);
    }
}
