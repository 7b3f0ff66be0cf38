//! The states: each model's conserved variables (cell averages with one ghost cell on
//! each side, index 0 and nx + 1) and their ghost fill, one module per family. Below
//! `numerics/` and `model/` (stages act on a state, a model diagnoses and writes it);
//! a state knows the grid it lives on and physics' pointwise formulas, nothing above.
//!
//! - [`LayeredState`] ([`layered`]): the granular family, N layers of fixed fractions,
//!   with tracers and the non-hydrostatic pressure;
//! - [`State2d`] ([`layered_2d`]): the 2-D Savage–Hutter model on a raster, h, hu, hv
//!   over the physical cells, with its active tiles ([`tiles`]);
//! - [`TwoLayerState`] ([`two_layer`]): water over grains (Fernández-Nieto et al. 2008),
//!   with the water's layers and non-hydrostatic pressure ([`WaterColumn`],
//!   [`water_column`]) when the water is non-hydrostatic;
//! - [`DilatantState`] ([`dilatant`]): the compressible μ(I)–φ model (Bouchut et al. 2021).

pub mod dilatant;
pub mod disjoint;
pub mod layered;
pub mod layered_2d;
pub mod layered_raster;
pub mod tiles;
pub mod two_layer;
pub mod water_column;

pub use dilatant::DilatantState;
pub use layered::LayeredState;
pub use layered_2d::State2d;
pub use two_layer::TwoLayerState;
pub use water_column::WaterColumn;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{BoundaryKind, Line};

    fn line() -> Line {
        let wall = BoundaryKind::Wall;
        Line::cartesian(0.0, 0.1, &[0.0; 8], wall, wall)
    }

    /// `clone_from` copies into the buffers it has (the run loop's backup is allocated
    /// once), where the derived `Clone` would allocate new ones.
    #[test]
    fn clone_from_copies_into_the_existing_buffers() {
        let line = line();
        let h: Vec<f64> = (0..8).map(|i| 0.1 + 0.01 * i as f64).collect();
        let mut layered = LayeredState::from_profiles(&line, &[0.5, 0.5], &h, &[0.3; 8]);
        layered.add_nonhydrostatic(&[0.01; 8]);
        let mut backup = layered.clone();
        let ptrs = |s: &LayeredState| {
            let nh = s.nh.as_ref().map(|nh| nh.p.as_ptr());
            (s.h.as_ptr(), s.hu.as_ptr(), s.tracers[0].q.as_ptr(), nh)
        };
        let before = ptrs(&backup);
        layered.h[3] = 7.0;
        layered.hw_mut()[5] = -1.0;
        backup.clone_from(&layered);
        assert_eq!(backup, layered);
        assert_eq!(ptrs(&backup), before);

        let mut two = TwoLayerState::zeros(8);
        let mut backup = two.clone();
        let before = (backup.h1.as_ptr(), backup.q2.as_ptr());
        two.h2[4] = 1.5;
        backup.clone_from(&two);
        assert_eq!(backup, two);
        assert_eq!((backup.h1.as_ptr(), backup.q2.as_ptr()), before);

        let mut dil = DilatantState::from_profiles(&line, 2.0, &h, &[0.2; 8], &[0.6; 8]);
        let mut backup = dil.clone();
        let before = (backup.m.as_ptr(), backup.phi.as_ptr(), backup.hu.as_ptr());
        dil.phi[2] = 0.55;
        backup.clone_from(&dil);
        assert_eq!(backup, dil);
        assert_eq!(
            (backup.m.as_ptr(), backup.phi.as_ptr(), backup.hu.as_ptr()),
            before
        );
    }
}
