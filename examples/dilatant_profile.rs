//! A fixed number of steps of the Savage–Hutter μ(I) monolayer (`sh`) or of the split
//! dilatant scheme (`split`, no viscosity; `stab`: ξ = (2, 2, 2)) on the 22° collapse of
//! seed 002 §4 (Δx = 5 mm, dense Table 1 column, `layer` m of grains elsewhere), for
//! instruction counts under callgrind (docs/performance.md, "Dilatant model"):
//!
//!   dilatant_profile {sh|split|stab} CELLS LAYER STEPS
//!
//! e.g. `valgrind --tool=callgrind target/release/examples/dilatant_profile split 640 0 2000`.
use granflow::mesh::{Mesh, MeshSpec};
use granflow::model::granular::state::LayeredState as State;
use granflow::numerics::dilatant::split::SplitScheme;
use granflow::numerics::dilatant::state::DilatantState;
use granflow::numerics::dilatant::step::DilatantOptions;
use granflow::numerics::friction::CoulombFrictionStep;
use granflow::numerics::hydrostatic::HydrostaticStep;
use granflow::numerics::Stage;
use granflow::physics::dilatancy::DilatantLaw;
use granflow::physics::rheology::MuI;
use granflow::physics::shallow::velocity;
use granflow::scenario::{BoundaryKind, Coordinates};
fn main() {
    let which: String = std::env::args().nth(1).expect("usage: see the module docs");
    let arg = |k: usize| std::env::args().nth(k).expect("usage: see the module docs");
    let cells: usize = arg(2).parse().unwrap();
    let layer: f64 = arg(3).parse().unwrap();
    let spec = MeshSpec {
        x_min: -0.2,
        x_max: -0.2 + cells as f64 * 0.005,
        cells,
        slope_deg: 22.0,
        coordinates: Coordinates::Local,
        left: BoundaryKind::Wall,
        right: BoundaryKind::Outflow,
    };
    let mesh = Mesh::new(&spec, vec![0.0; cells]);
    let h: Vec<f64> = mesh
        .x
        .iter()
        .map(|&x| if x <= 0.0 { 0.14 } else { layer })
        .collect();
    let zero = vec![0.0; cells];
    let law = MuI {
        mu_s: 0.48,
        mu_2: 0.73,
        i0: 0.279,
        d_s: 7e-4,
        phi: 0.62,
    };
    let n: usize = arg(4).parse().unwrap();
    if which == "sh" {
        let mut st = State::from_profiles(&mesh, &[1.0], &h, &zero);
        let mut hy = HydrostaticStep::new(law, cells);
        let mut fr = CoulombFrictionStep::new(law);
        for _ in 0..n {
            let speed = (1..=cells)
                .map(|j| st.mean_velocity(j).abs() + (mesh.g_n * st.h[j]).sqrt())
                .fold(0.0, f64::max);
            let dt = 0.5 * mesh.dx / speed;
            hy.apply(&mesh, dt, &mut st).unwrap();
            fr.apply(&mesh, dt, &mut st).unwrap();
        }
        println!("{}", st.h.iter().sum::<f64>());
    } else {
        let mut st = DilatantState::from_profiles(&mesh, 2.0, &h, &zero, &vec![0.62; cells]);
        let mut opt = DilatantOptions::default();
        if which != "stab" {
            opt.viscosity.xi = [0.0; 3];
        }
        let mut sc = SplitScheme::new(DilatantLaw::table1(), opt, cells, 0.62);
        for _ in 0..n {
            let speed = (1..=cells)
                .map(|j| velocity(st.h[j], st.hu[j]).abs() + (mesh.g_n * st.h[j]).sqrt())
                .fold(0.0, f64::max);
            let dt = 0.5 * mesh.dx / speed;
            sc.step(&mesh, &mut st, dt).unwrap();
        }
        println!("{}", st.h.iter().sum::<f64>());
    }
}
