//! Mass conservation to round-off between walls, and h ≥ 0 everywhere, always,
//! including at dry fronts and wall reflections.

use crate::common::{run, Case};
use granflow::scenario::{FrictionLaw, MonolayerShear};

fn check(mut case: Case, slope_deg: f64) {
    case.mesh.slope_deg = slope_deg;
    case.every = 0.02;
    let mut sim = case.build(|_| 0.0, |x, _| if x <= 0.0 { 0.14 } else { 0.0 }, |_| 0.0);
    let (sink, _) = run(&mut sim);
    let m0 = sink.steps[0].mass;
    for rec in &sink.steps {
        assert!(
            (rec.mass - m0).abs() <= 1e-13 * m0,
            "t = {}: mass {} vs {m0}",
            rec.t,
            rec.mass
        );
    }
    for snap in &sink.snapshots {
        assert!(
            snap.h.iter().all(|&h| h >= 0.0),
            "negative h at t = {}",
            snap.t
        );
    }
}

#[test]
fn granular_collapse_between_walls_conserves_mass() {
    let mut case = Case::new(-0.2, 1.0, 240);
    case.law = FrictionLaw::MuI {
        mu_s: 0.48,
        mu_2: 0.73,
        i0: 0.279,
        shear: MonolayerShear::Bagnold,
    };
    case.t_end = 2.0;
    check(case, 22.0);
}

#[test]
fn frictionless_dam_break_reflecting_on_walls_conserves_mass() {
    let mut case = Case::new(-0.2, 0.6, 160);
    case.t_end = 3.0;
    check(case, 10.0);
}
