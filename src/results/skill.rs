//! A simulated footprint against an observed one, cell by cell over the domain's cells
//! with data (`granflow maps` leaves the wall cells out: nodata of the DEM, NaN in pft):
//! a cell is simulated when the run's pft exceeds the threshold, observed when the footprint
//! covers it (the confusion matrix of a binary classifier, Fawcett 2006, §2). With
//! the cell area A,
//!
//! - TP = A·#(simulated ∧ observed), FP = A·#(simulated ∧ ¬observed),
//!   FN = A·#(¬simulated ∧ observed), TN = A·#(¬simulated ∧ ¬observed);
//! - the ROC point (FPR, TPR) with TPR = TP/(TP + FN), FPR = FP/(FP + TN) (Fawcett
//!   2006, §2–3);
//! - the distance to the perfect point (0, 1), d = √((1 − TPR)² + FPR²), by which
//!   the runs are ranked (smallest first).
//!
//! FPR depends on the domain's extent (TN grows with it), not on its nodata cells:
//! compare runs on one grid.

/// The skill of one run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Skill {
    /// Areas (map units squared).
    pub tp: f64,
    pub fp: f64,
    pub fn_: f64,
    pub tn: f64,
    pub tpr: f64,
    pub fpr: f64,
    /// √((1 − TPR)² + FPR²).
    pub distance: f64,
}

/// The skill of `simulated` against `observed` (one flag per cell each, at least one
/// observed cell), cells of area `cell_area`. A domain observed everywhere has FPR 0.
pub fn skill(simulated: &[bool], observed: &[bool], cell_area: f64) -> Skill {
    assert_eq!(simulated.len(), observed.len());
    let (mut tp, mut fp, mut fn_, mut tn) = (0u64, 0u64, 0u64, 0u64);
    for (&s, &o) in simulated.iter().zip(observed) {
        match (s, o) {
            (true, true) => tp += 1,
            (true, false) => fp += 1,
            (false, true) => fn_ += 1,
            (false, false) => tn += 1,
        }
    }
    let ratio = |a: u64, b: u64| {
        if a + b == 0 {
            0.0
        } else {
            a as f64 / (a + b) as f64
        }
    };
    let tpr = ratio(tp, fn_);
    let fpr = ratio(fp, tn);
    Skill {
        tp: tp as f64 * cell_area,
        fp: fp as f64 * cell_area,
        fn_: fn_ as f64 * cell_area,
        tn: tn as f64 * cell_area,
        tpr,
        fpr,
        distance: (1.0 - tpr).hypot(fpr),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_contingency_table_and_the_roc_point() {
        let sim = [true, true, false, false, true, false];
        let obs = [true, false, true, false, true, false];
        let s = skill(&sim, &obs, 2.0);
        assert_eq!((s.tp, s.fp, s.fn_, s.tn), (4.0, 2.0, 2.0, 4.0));
        assert_eq!((s.tpr, s.fpr), (2.0 / 3.0, 1.0 / 3.0));
        assert!((s.distance - (2.0f64 / 9.0).sqrt()).abs() < 1e-15);
        let perfect = skill(&obs, &obs, 1.0);
        assert_eq!(
            (perfect.tpr, perfect.fpr, perfect.distance),
            (1.0, 0.0, 0.0)
        );
    }
}
