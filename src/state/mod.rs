//! The states: each model's conserved variables (cell averages with one ghost cell on
//! each side, index 0 and nx + 1) and their ghost fill, one module per family. Below
//! `numerics/` and `model/` (stages act on a state, a model diagnoses and writes it);
//! a state knows the grid it lives on and physics' pointwise formulas, nothing above.
//!
//! - [`LayeredState`] ([`layered`]): the granular family, N layers of fixed fractions,
//!   with tracers and the non-hydrostatic pressure;
//! - [`TwoLayerState`] ([`two_layer`]): water over grains (seed 004);
//! - [`DilatantState`] ([`dilatant`]): the compressible μ(I)–φ model (seed 002).

pub mod dilatant;
pub mod layered;
pub mod two_layer;

pub use dilatant::DilatantState;
pub use layered::LayeredState;
pub use two_layer::TwoLayerState;
