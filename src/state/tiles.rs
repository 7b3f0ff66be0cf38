//! The active tiles of a raster state: which tiles of cells a step must visit.
//!
//! The raster's cells are grouped in tiles of [`BAND_ROWS`] rows × [`TILE_COLS`]
//! columns (the tiles of the last row and column of tiles may be smaller), numbered
//! row-major over the tile grid. A cell is **live** when it holds flow or momentum:
//! h > H_DRY (or h is NaN) or a discharge whose bits are not those of +0. A cell that
//! is not live and whose four neighbours are not live is left exactly unchanged by the
//! step's stages: every face between two cells of h ≤ H_DRY carries nothing, the new
//! thickness is h − 0 = h and the discharges stay +0 (`numerics/hydrostatic_2d.rs`,
//! `numerics/friction_2d.rs`). So a step visits only the **stepped** tiles: the tiles
//! with a live cell, and the tiles next to one (across an edge) whose cells along that
//! edge include a live cell. The others are skipped by every pass, and their cells keep
//! the same bits a full sweep would give them.
//!
//! A tile is **non-empty** while any of its cells has a value whose bits are not +0
//! (films thinner than H_DRY stay where the flow left them and still count in the
//! mass): the diagnostics visit the non-empty and the stepped tiles, in row-major
//! order within each band of rows, so that their sums are formed in the order of a
//! full sweep, the empty cells left out adding nothing.
//!
//! Bookkeeping per step is over the tiles (one flag each), never over the cells of the
//! raster: a stage that writes cells of the stepped tiles marks the set pending
//! (`mark_pending`), and the next step's hyperbolic stage re-classifies those tiles
//! alone (`refresh`) before it builds the new stepped set. The stage that writes the
//! stepped tiles last in a step may instead classify each tile in the same task that
//! writes it (`write_classified`: the order-1 hyperbolic step with its friction), so
//! that the next refresh only rebuilds the stepped set from the flags, with no pass
//! over the cells. Until then (the diagnostics, the maps, the copy of the state) the
//! stepped set is the set of tiles the last step may have changed. A state whose
//! fields were written outside the stages has unknown tiles (`touch`): they are
//! classified from every cell at the next step.

use super::disjoint::Disjoint;
use crate::grid::raster::BAND_ROWS;
use crate::physics::shallow::H_DRY;
use std::ops::Range;

/// Runs `f(thread, t)` for every tile t of a list (module documentation of
/// [`Tiles::refresh_on`]).
pub type TileRunner<'r> = &'r dyn Fn(&[u32], &(dyn Fn(usize, usize) + Sync));

/// Columns per tile (the rows are a band's, [`BAND_ROWS`]): a tile's face work is one
/// column of x-faces more than its own (1/32 extra) and its bookkeeping one flag.
pub const TILE_COLS: usize = 32;

/// A live cell in the tile.
const LIVE: u8 = 1;
/// A live cell in the tile's first (west) column.
const WEST: u8 = 2;
/// A live cell in its last (east) column.
const EAST: u8 = 4;
/// A live cell in its first (south) row.
const SOUTH: u8 = 8;
/// A live cell in its last (north) row.
const NORTH: u8 = 16;
/// A cell whose bits are not all +0.
const NONEMPTY: u8 = 32;

/// Whether a cell with thickness `h` and discharges `qx`, `qy` is live (module doc).
#[inline(always)]
pub fn is_live(h: f64, qx: f64, qy: f64) -> bool {
    h > H_DRY || h.is_nan() || qx.to_bits() != 0 || qy.to_bits() != 0
}

/// The tiles of a raster state: their classification and the stepped set.
#[derive(Debug, Default)]
pub struct Tiles {
    /// Cells per row and rows of the raster; 0 while the tiles are unknown.
    nx: usize,
    ny: usize,
    /// Tiles per row of tiles and rows of tiles.
    cols: usize,
    rows: usize,
    /// Per tile: the [`LIVE`], edge and [`NONEMPTY`] bits.
    flags: Vec<u8>,
    /// Per tile: whether it is in `stepped`.
    stepped_flag: Vec<bool>,
    /// The stepped tiles, in increasing order.
    stepped: Vec<u32>,
    /// The same tiles with the live ones first (each part in increasing order): the
    /// order in which the threads take them (`numerics::workers::Workers::tiles`).
    by_load: Vec<u32>,
    /// The stepped tiles were changed by a stage: the stepped set is to be rebuilt.
    pending: bool,
    /// The flags of the pending tiles are those of their cells as the last stage left
    /// them ([`Tiles::write_classified`]): the rebuild needs no pass over the cells.
    classified: bool,
    /// Every tile is stepped (the full sweep, for comparison).
    every: bool,
    /// Cell updates of the accepted steps (the cells of their stepped tiles).
    updates: u64,
}

// `Clone` by hand: the run loop copies the state into its backup every step, and the
// derived `clone_from` would allocate.
impl Clone for Tiles {
    fn clone(&self) -> Self {
        let mut t = Tiles::default();
        t.clone_from(self);
        t
    }

    fn clone_from(&mut self, source: &Self) {
        (self.nx, self.ny, self.cols, self.rows) = (source.nx, source.ny, source.cols, source.rows);
        self.flags.clone_from(&source.flags);
        self.stepped_flag.clone_from(&source.stepped_flag);
        self.stepped.clone_from(&source.stepped);
        self.by_load.clone_from(&source.by_load);
        (self.pending, self.classified) = (source.pending, source.classified);
        self.every = source.every;
        self.updates = source.updates;
    }
}

impl Tiles {
    /// Unknown tiles (classified at the first step).
    pub fn unknown() -> Tiles {
        Tiles::default()
    }

    /// Whether the tiles are classified.
    pub fn is_known(&self) -> bool {
        self.nx > 0
    }

    /// Whether the tiles are classified, for the same raster as `other`'s.
    pub fn known_as(&self, other: &Tiles) -> bool {
        self.is_known() && (self.nx, self.ny) == (other.nx, other.ny)
    }

    /// The column ranges of the tiles of band `band` (row of tiles) for which
    /// `pick(self, t)` holds, west to east.
    pub fn band_columns<'a>(
        &'a self,
        band: usize,
        pick: impl Fn(&Tiles, usize) -> bool + 'a,
    ) -> impl Iterator<Item = Range<usize>> + 'a {
        (band * self.cols..(band + 1) * self.cols)
            .filter(move |&t| pick(self, t))
            .map(move |t| self.cells(t).1)
    }

    /// The tiles of band `band` (row of tiles), west to east.
    pub fn band_tiles(&self, band: usize) -> Range<usize> {
        band * self.cols..(band + 1) * self.cols
    }

    /// Whether the tiles are classified for a raster of `nx` × `ny` cells.
    pub fn known_for(&self, nx: usize, ny: usize) -> bool {
        self.nx == nx && self.ny == ny && nx > 0
    }

    /// Forgets the classification: the next step classifies every tile (after the
    /// state's fields were written outside the stages).
    pub fn touch(&mut self) {
        self.nx = 0;
        self.ny = 0;
    }

    /// Steps every tile from now on (the full sweep; the results are the same bits).
    pub fn step_every_tile(&mut self) {
        self.every = true;
        self.touch();
    }

    /// Cells per row of the raster the tiles are classified for.
    pub fn nx(&self) -> usize {
        self.nx
    }

    /// Tiles per row of tiles.
    pub fn cols(&self) -> usize {
        self.cols
    }

    /// Number of tiles.
    pub fn count(&self) -> usize {
        self.cols * self.rows
    }

    /// The stepped tiles, in increasing order.
    pub fn stepped(&self) -> &[u32] {
        &self.stepped
    }

    /// The stepped tiles, those with a live cell first: the order for a pass's tasks,
    /// the tiles with flow (the costly ones) taken first so that a pass on several
    /// threads ends on dry tiles, cheap to share.
    pub fn stepped_by_load(&self) -> &[u32] {
        &self.by_load
    }

    /// Whether tile `t` is stepped.
    #[inline]
    pub fn is_stepped(&self, t: usize) -> bool {
        self.stepped_flag[t]
    }

    /// Whether the diagnostics visit tile `t`: non-empty or stepped.
    #[inline]
    pub fn is_visited(&self, t: usize) -> bool {
        self.flags[t] & NONEMPTY != 0 || self.stepped_flag[t]
    }

    /// The band of rows (row of tiles) and the columns of tile `t`.
    #[inline]
    pub fn cells(&self, t: usize) -> (Range<usize>, Range<usize>) {
        let (band, col) = (t / self.cols, t % self.cols);
        let rows = band * BAND_ROWS..((band + 1) * BAND_ROWS).min(self.ny);
        let cols = col * TILE_COLS..((col + 1) * TILE_COLS).min(self.nx);
        (rows, cols)
    }

    /// The cells of tile `t`, row by row: one range of row-major cell indices per row.
    #[inline]
    pub fn row_segments(&self, t: usize) -> impl Iterator<Item = Range<usize>> {
        let (rows, cols) = self.cells(t);
        let nx = self.nx;
        rows.map(move |j| j * nx + cols.start..j * nx + cols.end)
    }

    /// The fraction of the raster's cells in stepped tiles.
    pub fn stepped_fraction(&self) -> f64 {
        self.stepped_cells() as f64 / (self.nx * self.ny).max(1) as f64
    }

    /// Counts a step's cell updates: the cells of its stepped tiles.
    pub fn count_updates(&mut self) {
        self.updates += self.stepped_cells() as u64;
    }

    /// The cell updates counted so far ([`Self::count_updates`]).
    pub fn updates(&self) -> u64 {
        self.updates
    }

    /// The number of cells in the stepped tiles.
    pub fn stepped_cells(&self) -> usize {
        self.stepped
            .iter()
            .map(|&t| {
                let (r, c) = self.cells(t as usize);
                r.len() * c.len()
            })
            .sum()
    }

    /// Marks the stepped tiles as changed by a stage (they are re-classified at the
    /// next [`Self::refresh`]).
    pub fn mark_pending(&mut self) {
        self.pending = true;
        self.classified = false;
    }

    /// Runs `write(tiles, t)` for every stepped tile t with `run` (one task per tile, any
    /// order, any threads), each task writing the cells of its own tile and returning
    /// their bits from [`Tiles::bits`] as it left them; the stepped set is then pending
    /// with those flags, so the next [`Self::refresh_on`] only rebuilds the stepped
    /// set. For the stage that writes the stepped tiles last in a step.
    pub fn write_classified(
        &mut self,
        run: TileRunner,
        write: &(dyn Fn(&Tiles, usize) -> u8 + Sync),
    ) {
        // The flags are taken out while the tasks write them (a task reads the rest of
        // the tiles, never the flags).
        let mut flags = std::mem::take(&mut self.flags);
        let out = Disjoint::new(&mut flags[..]);
        let tiles = &*self;
        run(&tiles.by_load, &|_, t| {
            let bits = write(tiles, t);
            // SAFETY: entry t is this task's alone.
            unsafe { out.set(t, bits) };
        });
        self.flags = flags;
        self.pending = true;
        self.classified = true;
    }

    /// Classifies the tiles for the state (`h`, `hu`, `hv`) on `nx` × `ny` cells: every
    /// tile if unknown, else the tiles a stage changed since the last refresh; then
    /// builds the stepped set.
    pub fn refresh(&mut self, dims: (usize, usize), h: &[f64], hu: &[f64], hv: &[f64]) {
        self.refresh_on(dims, (h, hu, hv), &|tiles, f| {
            tiles.iter().for_each(|&t| f(0, t as usize))
        });
    }

    /// [`Self::refresh`] with the changed tiles classified by `run`, one task per tile:
    /// `run(tiles, f)` calls `f(thread, t)` once for every t of `tiles`, in any order and
    /// on any threads (the stages pass their `numerics::workers::Workers::tiles`). Each
    /// task writes its own flags: the same flags on any number of threads.
    pub fn refresh_on(
        &mut self,
        (nx, ny): (usize, usize),
        (h, hu, hv): (&[f64], &[f64], &[f64]),
        run: TileRunner,
    ) {
        if !self.known_for(nx, ny) {
            self.nx = nx;
            self.ny = ny;
            self.cols = nx.div_ceil(TILE_COLS);
            self.rows = ny.div_ceil(BAND_ROWS);
            self.flags = vec![0; self.count()];
            self.stepped_flag = vec![false; self.count()];
            for t in 0..self.count() {
                self.flags[t] = self.classify(t, h, hu, hv);
            }
        } else if self.pending && self.classified {
            // The flags were set as the tiles were written.
        } else if self.pending {
            self.write_classified(run, &|tiles, t| tiles.classify(t, h, hu, hv));
        } else {
            return;
        }
        self.pending = false;
        self.build_stepped();
    }

    /// The bits of tile `t` from its cells.
    fn classify(&self, t: usize, h: &[f64], hu: &[f64], hv: &[f64]) -> u8 {
        self.bits(t, |k| (h[k], hu[k], hv[k]))
    }

    /// The flags of tile `t` from its cells, `cell(k)` being the (h, hu, hv) of cell k
    /// (for [`Self::write_classified`]'s tasks).
    #[inline]
    pub fn bits(&self, t: usize, cell: impl Fn(usize) -> (f64, f64, f64)) -> u8 {
        let (rows, cols) = self.cells(t);
        let (first_row, last_row) = (rows.start, rows.end - 1);
        let (first_col, last_col) = (cols.start, cols.end - 1);
        let mut bits = 0;
        for j in rows {
            let row = j * self.nx;
            for i in cols.clone() {
                let (h, hu, hv) = cell(row + i);
                if h.to_bits() | hu.to_bits() | hv.to_bits() != 0 {
                    bits |= NONEMPTY;
                }
                if is_live(h, hu, hv) {
                    bits |= LIVE;
                    if i == first_col {
                        bits |= WEST;
                    }
                    if i == last_col {
                        bits |= EAST;
                    }
                    if j == first_row {
                        bits |= SOUTH;
                    }
                    if j == last_row {
                        bits |= NORTH;
                    }
                }
            }
        }
        bits
    }

    /// The stepped set from the flags: live tiles and their neighbours across an edge
    /// with a live cell.
    fn build_stepped(&mut self) {
        self.stepped.clear();
        let (cols, rows) = (self.cols, self.rows);
        for t in 0..self.count() {
            let (band, col) = (t / cols, t % cols);
            let f = |t: usize| self.flags[t];
            let stepped = self.every
                || f(t) & LIVE != 0
                || (col > 0 && f(t - 1) & EAST != 0)
                || (col + 1 < cols && f(t + 1) & WEST != 0)
                || (band > 0 && f(t - cols) & NORTH != 0)
                || (band + 1 < rows && f(t + cols) & SOUTH != 0);
            self.stepped_flag[t] = stepped;
            if stepped {
                self.stepped.push(t as u32);
            }
        }
        self.by_load.clear();
        let live = |&&t: &&u32| self.flags[t as usize] & LIVE != 0;
        self.by_load.extend(self.stepped.iter().filter(live));
        self.by_load
            .extend(self.stepped.iter().filter(|t| !live(t)));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 70 × 40 raster (3 × 3 tiles, the last ones partial) with one live cell at
    /// (i, j).
    fn one_cell(i: usize, j: usize) -> Tiles {
        let (nx, ny) = (70, 40);
        let mut h = vec![0.0; nx * ny];
        h[j * nx + i] = 1.0;
        let z = vec![0.0; nx * ny];
        let mut t = Tiles::unknown();
        t.refresh((nx, ny), &h, &z, &z);
        t
    }

    #[test]
    fn a_live_cell_steps_its_tile_and_the_neighbours_across_the_edges_it_touches() {
        // Inside tile 4 (band 1, column 1), away from its edges: that tile alone.
        assert_eq!(one_cell(40, 20).stepped(), &[4]);
        // On its west column: and the west neighbour.
        assert_eq!(one_cell(32, 20).stepped(), &[3, 4]);
        // On its north-east corner: and the east and north neighbours, not the diagonal.
        assert_eq!(one_cell(63, 31).stepped(), &[4, 5, 7]);
        // A partial tile's last column is its east edge, with no neighbour there.
        assert_eq!(one_cell(69, 39).stepped(), &[8]);
    }

    #[test]
    fn the_tiles_by_load_are_the_stepped_ones_the_live_first() {
        assert_eq!(one_cell(32, 20).stepped_by_load(), &[4, 3]);
        assert_eq!(one_cell(63, 31).stepped_by_load(), &[4, 5, 7]);
        let mut t = one_cell(63, 31);
        t.step_every_tile();
        let (h, z) = (vec![0.0; 70 * 40], vec![0.0; 70 * 40]);
        t.refresh((70, 40), &h, &z, &z);
        assert_eq!(t.stepped_by_load(), t.stepped());
        assert_eq!(t.stepped().len(), 9);
    }

    #[test]
    fn films_below_the_dry_threshold_are_not_live_but_non_empty() {
        let (nx, ny) = (70, 40);
        let mut h = vec![0.0; nx * ny];
        h[5] = 0.5 * H_DRY;
        let mut hu = vec![0.0; nx * ny];
        hu[nx * 39 + 69] = -0.0;
        let z = vec![0.0; nx * ny];
        let mut t = Tiles::unknown();
        t.refresh((nx, ny), &h, &hu, &z);
        // −0 is a momentum that a step turns into +0: live.
        assert_eq!(t.stepped(), &[8]);
        assert!(t.is_visited(0) && !t.is_stepped(0));
        assert!(!t.is_visited(1));
        assert!(is_live(f64::NAN, 0.0, 0.0));
    }

    #[test]
    fn a_refresh_reclassifies_only_the_pending_tiles() {
        let (nx, ny) = (70, 40);
        let mut h = vec![0.0; nx * ny];
        h[20 * nx + 40] = 1.0;
        let z = vec![0.0; nx * ny];
        let mut t = Tiles::unknown();
        t.refresh((nx, ny), &h, &z, &z);
        assert_eq!(t.stepped(), &[4]);
        // The mass moves to the tile's west column: after the stage marks the set
        // pending, the refresh sees it.
        h[20 * nx + 40] = 0.0;
        h[20 * nx + 32] = 1.0;
        t.mark_pending();
        t.refresh((nx, ny), &h, &z, &z);
        assert_eq!(t.stepped(), &[3, 4]);
        // Not pending: nothing is read (a change outside the stages needs `touch`).
        h[20 * nx + 32] = 0.0;
        t.refresh((nx, ny), &h, &z, &z);
        assert_eq!(t.stepped(), &[3, 4]);
        t.touch();
        t.refresh((nx, ny), &h, &z, &z);
        assert!(t.stepped().is_empty());
        t.step_every_tile();
        t.refresh((nx, ny), &h, &z, &z);
        assert_eq!(t.stepped().len(), 9);
        assert_eq!(t.stepped_fraction(), 1.0);
    }
}
