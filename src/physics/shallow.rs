//! Shallow-layer pointwise quantities (seed 000 eq. 15a–b with q = 0).
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
