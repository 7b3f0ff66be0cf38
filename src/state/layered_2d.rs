//! The state of the 2-D Savage–Hutter model on a raster: cell averages of the
//! thickness h and of the two discharges hu, hv (u along x, v along y), over the
//! physical cells only, row-major (cell = j·nx + i). The boundary rules (a wall
//! mirrors h and reverses the normal discharge, an outflow copies the edge cell) are
//! applied by the stages at the edge faces, so the state needs no ghost ring.
//!
//! The state carries its active tiles ([`Tiles`]): which tiles of cells a step visits.
//! Code that writes h, hu or hv outside the stages calls [`State2d::touch`] so that the
//! next step classifies every tile again.

use super::tiles::Tiles;

/// h, hu, hv per cell (nx·ny each, row-major), and the active tiles.
#[derive(Debug)]
pub struct State2d {
    pub h: Vec<f64>,
    pub hu: Vec<f64>,
    pub hv: Vec<f64>,
    /// The tiles the stages visit (`state::tiles`).
    pub tiles: Tiles,
}

/// Two states are equal when their fields are (the tiles are derived from them).
impl PartialEq for State2d {
    fn eq(&self, other: &Self) -> bool {
        self.h == other.h && self.hu == other.hu && self.hv == other.hv
    }
}

impl State2d {
    /// A state of `cells` dry cells.
    pub fn zeros(cells: usize) -> State2d {
        State2d {
            h: vec![0.0; cells],
            hu: vec![0.0; cells],
            hv: vec![0.0; cells],
            tiles: Tiles::unknown(),
        }
    }

    /// The state with thickness `h` and velocities `u`, `v` per cell (hu = h u,
    /// hv = h v).
    pub fn from_velocities(h: Vec<f64>, u: &[f64], v: &[f64]) -> State2d {
        assert!(h.len() == u.len() && h.len() == v.len());
        let hu = h.iter().zip(u).map(|(h, u)| h * u).collect();
        let hv = h.iter().zip(v).map(|(h, v)| h * v).collect();
        State2d {
            h,
            hu,
            hv,
            tiles: Tiles::unknown(),
        }
    }

    /// Forgets the active tiles after h, hu or hv were written outside the stages: the
    /// next step classifies every tile.
    pub fn touch(&mut self) {
        self.tiles.touch();
    }

    /// Classifies the tiles that changed since the last refresh (every tile if unknown)
    /// on a raster of `nx` × `ny` cells and builds the stepped set (`state::tiles`).
    pub fn refresh_tiles(&mut self, nx: usize, ny: usize) {
        self.tiles.refresh((nx, ny), &self.h, &self.hu, &self.hv);
    }

    /// [`Self::refresh_tiles`] with the changed tiles classified by `run`
    /// ([`super::tiles::Tiles::refresh_on`]).
    pub fn refresh_tiles_on(&mut self, nx: usize, ny: usize, run: super::tiles::TileRunner) {
        let fields = (&self.h[..], &self.hu[..], &self.hv[..]);
        self.tiles.refresh_on((nx, ny), fields, run);
    }

    /// Classifies the tiles if they are unknown (a stage that follows another in the
    /// step keeps the set the step began with).
    pub fn ensure_tiles(&mut self, nx: usize, ny: usize) {
        if !self.tiles.known_for(nx, ny) {
            self.refresh_tiles(nx, ny);
        }
    }

    /// Number of cells.
    pub fn cells(&self) -> usize {
        self.h.len()
    }
}

// `Clone` by hand: the run loop copies the state into its backup every step, and the
// derived `clone_from` would allocate new buffers.
impl Clone for State2d {
    fn clone(&self) -> Self {
        State2d {
            h: self.h.clone(),
            hu: self.hu.clone(),
            hv: self.hv.clone(),
            tiles: self.tiles.clone(),
        }
    }

    fn clone_from(&mut self, source: &Self) {
        self.h.clone_from(&source.h);
        self.hu.clone_from(&source.hu);
        self.hv.clone_from(&source.hv);
        self.tiles.clone_from(&source.tiles);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clone_from_copies_into_the_existing_buffers() {
        let mut s = State2d::from_velocities(vec![1.0, 2.0], &[0.5, 0.0], &[0.0, -1.0]);
        assert_eq!(s.hv, vec![0.0, -2.0]);
        let mut backup = s.clone();
        let before = (backup.h.as_ptr(), backup.hu.as_ptr(), backup.hv.as_ptr());
        s.h[1] = 7.0;
        backup.clone_from(&s);
        assert_eq!(backup, s);
        assert_eq!(
            (backup.h.as_ptr(), backup.hu.as_ptr(), backup.hv.as_ptr()),
            before
        );
    }
}
