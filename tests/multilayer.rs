//! The hydrostatic multilayer μ(I) model (seed 001 eq. 27–28, seed 003 §4 with p_nh = 0).

mod common;
use common::{run, tan_deg, Case};
use granflow::scenario::{BoundaryKind, FrictionLaw};

/// FNV-1a over the bits of every value (−0 counted as +0).
fn fnv(hash: &mut u64, v: f64) {
    for b in (v + 0.0).to_bits().to_le_bytes() {
        *hash ^= b as u64;
        *hash = hash.wrapping_mul(0x100_0000_01b3);
    }
}

fn state_hash(sim: &granflow::simulation::Simulation) -> u64 {
    let mut hash = 0xcbf2_9ce4_8422_2325u64;
    for &v in sim.state.h.iter().chain(&sim.state.hu) {
        fnv(&mut hash, v);
    }
    hash
}

/// The monolayer runs whose final states were hashed with the code of issue 2, before
/// the hyperbolic step was generalised to N layers.
fn monolayer_reference_runs() -> Vec<(&'static str, granflow::simulation::Simulation)> {
    let mut case = Case::new(-0.2, 3.0, 320);
    case.slope_deg = 22.0;
    case.right = BoundaryKind::Outflow;
    case.law = FrictionLaw::MuI {
        mu_s: tan_deg(25.5),
        mu_2: tan_deg(36.0),
        i0: 0.279,
    };
    case.t_end = 1.0;
    case.every = 0.25;
    let collapse = case.build(
        |_| 0.0,
        |x, _| if x <= 0.0 { 0.14 + 1.82e-3 } else { 1.82e-3 },
        |_| 0.0,
    );
    let mut case = Case::new(-2.0, 2.5, 200);
    case.law = FrictionLaw::Coulomb { mu: 0.3 };
    case.slope_deg = 10.0;
    case.t_end = 0.3;
    let dam_break = case.build(
        |x| 0.05 * (3.0 * x).sin(),
        |x, _| if x < 0.0 { 1.0 } else { 0.1 },
        |_| 0.0,
    );
    vec![("collapse", collapse), ("dam_break", dam_break)]
}

/// (steps, hash of the final h and hu) of [`monolayer_reference_runs`], recorded with
/// the monolayer code of issue 2 (commit d38cc89).
const MONOLAYER_REFERENCE: [(u64, u64); 2] =
    [(317, 0x6781_a624_5fbe_7ad9), (138, 0xa573_7a76_90b7_6d18)];

#[test]
fn monolayer_numbers_are_frozen() {
    for ((name, mut sim), (steps, hash)) in monolayer_reference_runs()
        .into_iter()
        .zip(MONOLAYER_REFERENCE)
    {
        let (_, s) = run(&mut sim);
        assert_eq!(s.steps, steps, "{name}");
        assert_eq!(
            state_hash(&sim),
            hash,
            "{name}: the monolayer numbers changed"
        );
    }
}
