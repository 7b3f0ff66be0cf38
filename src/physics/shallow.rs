//! Shallow-layer pointwise quantities (Garres-Díaz et al. 2021, eq. 15a–b with q = 0).
//!
//! Below [`H_DRY`] a cell is dry: its velocity is taken as zero. This threshold only
//! desingularises u = hu/h; mass is never removed, so conservation stays exact.

/// Thickness (m) below which a cell is treated as dry.
pub const H_DRY: f64 = 1e-10;

/// Depth-averaged velocity u = hu / h, zero in dry cells.
#[inline(always)]
pub fn velocity(h: f64, hu: f64) -> f64 {
    if h > H_DRY {
        hu / h
    } else {
        0.0
    }
}

/// Gravity wave speed c = √(g_n h), g_n the gravity normal to the reference plane.
#[inline(always)]
pub fn celerity(g_n: f64, h: f64) -> f64 {
    (g_n * h.max(0.0)).sqrt()
}

/// Gravity wave speed of a sheared column, √(g_n h + s) with s = 3 Σ l_α (u_α − ū)²:
/// an estimate of the outer eigenvalues ū ± c of the multilayer system (Escalante et al. 2023, §4;
/// √(g_n h) for N = 1 or a uniform profile, s = 0).
#[inline(always)]
pub fn sheared_celerity(g_n: f64, h: f64, shear: f64) -> f64 {
    if shear == 0.0 {
        celerity(g_n, h)
    } else {
        (g_n * h.max(0.0) + shear).sqrt()
    }
}
