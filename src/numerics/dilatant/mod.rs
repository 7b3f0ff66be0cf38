//! Numerics of the dilatant μ(I)–φ model (Bouchut et al. 2021). The default time step is
//! [`split`]: the Savage–Hutter μ(I) hyperbolic step with the φ-gradient pressure as a
//! potential on its faces and φ carried by its mass fluxes, then the dilatant friction
//! and the dilatancy step of §3.2
//! (K = 0 with uniform φ is the Savage–Hutter step bit for bit). The scheme of Bouchut et al. 2021,
//! §3 as printed (`dilatancy.scheme = "appendix_b"`, [`step`]) is a two-step splitting
//! of the system (3.1)–(3.3) plus the stabilising viscosity of (3.20),
//!
//! 1. finite volumes (3.5) with the well-balanced, energy-satisfying left/right fluxes
//!    of Appendix B ([`reconstruction`], [`flux`]) and the basal friction as an
//!    apparent topography (3.6)–(3.12);
//! 2. the stabilisation viscosity (3.20)–(3.22) ([`stabilisation`]), sub-cycled so
//!    that it never shortens Δt;
//! 3. the semi-implicit dilatancy step (3.15)–(3.19) ([`source`]), unconditionally
//!    stable: it never shortens Δt, whatever K and d.
//!
//! At `numerics.order = 2` the split scheme runs with the second-order reconstruction
//! inside Heun's method ([`heun`]).
//!
//! [`crate::state::DilatantState`] holds the conservative variables and [`step`] runs one time step,
//! refusing any state with φh < 0 or φ ∉ (0, 1) with the cell and the time.

pub mod flux;
pub mod heun;
pub mod reconstruction;
pub mod source;
pub mod split;
pub mod stabilisation;
pub mod step;
