//! Property tests: for random beds, thicknesses (with dry patches), velocities and
//! friction, a run between walls keeps h ≥ 0, conserves mass to round-off and never
//! produces a non-finite value.

mod common;
use common::Case;
use granflow::output::memory::MemorySink;
use granflow::scenario::FrictionLaw;
use proptest::prelude::*;

fn piecewise(values: Vec<f64>, x_min: f64, width: f64) -> impl Fn(f64) -> f64 {
    move |x: f64| {
        let k = ((x - x_min) / width * values.len() as f64) as usize;
        values[k.min(values.len() - 1)]
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn random_states_stay_positive_conservative_and_finite(
        h in prop::collection::vec(prop_oneof![Just(0.0), 0.0..0.5f64], 8),
        u in prop::collection::vec(-3.0..3.0f64, 8),
        b in prop::collection::vec(0.0..0.4f64, 6),
        slope in 0.0..35.0f64,
        mu in 0.0..1.0f64,
        use_mu_i in any::<bool>(),
    ) {
        let mut case = Case::new(0.0, 1.0, 64);
        case.slope_deg = slope;
        case.t_end = 0.2;
        case.every = 0.05;
        case.law = if use_mu_i {
            FrictionLaw::MuI { mu_s: mu, mu_2: mu + 0.3, i0: 0.279 }
        } else {
            FrictionLaw::Coulomb { mu }
        };
        let (fh, fu, fb) = (piecewise(h, 0.0, 1.0), piecewise(u, 0.0, 1.0), piecewise(b, 0.0, 1.0));
        let mut sim = case.build(fb, move |x, _| fh(x), fu);
        let mut sink = MemorySink::default();
        let summary = sim.run(&mut sink, &mut |_| {});
        prop_assert!(summary.is_ok(), "{:?}", summary.err());
        let m0 = sink.steps[0].mass;
        for rec in &sink.steps {
            prop_assert!((rec.mass - m0).abs() <= 1e-13 * m0.max(1e-300));
            prop_assert!(rec.max_speed.is_finite());
        }
        for snap in &sink.snapshots {
            prop_assert!(snap.h.iter().all(|&h| h >= 0.0 && h.is_finite()));
            prop_assert!(snap.u.iter().all(|u| u.is_finite()));
        }
    }
}
