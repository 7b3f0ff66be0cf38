//! `domain.crop = [x_min, x_max, y_min, y_max]` and `domain.coarsen = k`: a raster
//! domain that is the grid of its raster bed, cut to a box and coarsened for a quick
//! run. The bed raster is cropped to the cells whose centres lie in the box (nothing
//! is resampled), then each k × k block becomes one cell, the mean of its cells that
//! have data (`gis::Raster::crop`, `gis::Raster::coarsen`); when the cropped grid is
//! not a multiple of k, its last columns (east) and rows (south) are dropped, with a
//! note. Every other raster profile on the bed's original grid (`initial.h`,
//! `initial.u`, `initial.v`) is cut and coarsened in the same way, so the block mean
//! of a thickness raster keeps its volume; rasters on other grids are interpolated at
//! the new centres, as any raster profile.

use super::super::profile::Profile;
use super::super::raw::RawDomain;
use super::check::*;
use crate::gis::{Bbox, Raster};

/// The crop box and the coarsening factor of a scenario.
#[derive(Debug, Clone, Copy)]
pub(super) struct Resample {
    crop: Option<Bbox>,
    factor: usize,
}

/// The grid of the raster bed as read (before crop and coarsening).
#[derive(Debug, Clone, Copy)]
pub(super) struct OriginalGrid {
    nx: usize,
    ny: usize,
    cell_size: f64,
    x_left: f64,
    y_top: f64,
}

/// Largest accepted `domain.coarsen`.
const MAX_FACTOR: i64 = 1000;

/// `domain.crop` and `domain.coarsen`, or `None` when neither is given. Both need the
/// domain to be the raster bed's grid (`from_bed`).
pub(super) fn keys(d: &RawDomain, from_bed: bool) -> Res<Option<Resample>> {
    if d.crop.is_none() && d.coarsen.is_none() {
        return Ok(None);
    }
    if !from_bed {
        let key = if d.crop.is_some() {
            "domain.crop"
        } else {
            "domain.coarsen"
        };
        return err(
            key,
            "applies to a domain that is the grid of a raster bed: give bed.b = { raster = \"dem.asc\" } and none of domain.x_min, x_max, y_min, y_max, cells",
        );
    }
    let crop = match &d.crop {
        None => None,
        Some(v) => {
            const KEY: &str = "domain.crop";
            if v.len() != 4 {
                return err(
                    KEY,
                    format!(
                        "must be [x_min, x_max, y_min, y_max] (four numbers), got {} value{}",
                        v.len(),
                        if v.len() == 1 { "" } else { "s" }
                    ),
                );
            }
            for &c in v {
                finite(KEY, c)?;
            }
            if v[1] <= v[0] || v[3] <= v[2] {
                return err(
                    KEY,
                    format!(
                        "must be [x_min, x_max, y_min, y_max] with x_min < x_max and y_min < y_max, got [{}, {}, {}, {}]",
                        num(v[0]),
                        num(v[1]),
                        num(v[2]),
                        num(v[3])
                    ),
                );
            }
            Some(Bbox {
                x_min: v[0],
                x_max: v[1],
                y_min: v[2],
                y_max: v[3],
            })
        }
    };
    let factor = match d.coarsen {
        None => 1,
        Some(k) => int_in("domain.coarsen", k, 1, MAX_FACTOR)?,
    };
    Ok(Some(Resample { crop, factor }))
}

impl Resample {
    /// `raster` cropped and coarsened; `key` names the profile in errors. The note,
    /// if any, says which columns and rows were dropped to make the grid a multiple
    /// of the factor.
    fn apply(&self, key: &str, raster: &Raster) -> Res<(Raster, Option<String>)> {
        let mut r = match self.crop {
            Some(b) => raster.crop(b).map_err(|e| {
                super::ScenarioError::at(
                    "domain.crop",
                    format!(
                        "{e} (the raster of {key} covers x in [{}, {}], y in [{}, {}])",
                        raster.x_left,
                        raster.x_right(),
                        raster.y_bottom(),
                        raster.y_top
                    ),
                )
            })?,
            None => raster.clone(),
        };
        let k = self.factor;
        let mut note = None;
        if k > 1 {
            if r.nx < k || r.ny < k {
                return err(
                    "domain.coarsen",
                    format!(
                        "a factor of {k} needs at least {k} × {k} cells, the grid of {key} has {} × {}",
                        r.nx, r.ny
                    ),
                );
            }
            let (nx, ny) = (r.nx / k * k, r.ny / k * k);
            if (nx, ny) != (r.nx, r.ny) {
                note = Some(format!(
                    "domain.coarsen = {k}: the grid of {} × {} cells is not a multiple of {k}; its last {} column(s) (east) and {} row(s) (south) are left out",
                    r.nx,
                    r.ny,
                    r.nx - nx,
                    r.ny - ny
                ));
                // By index: a box in metres loses a row to rounding on grids
                // whose cell size is not round.
                r = r
                    .window(0, 0, nx, ny)
                    .expect("the trimmed grid is inside the grid");
            }
            r = r
                .coarsen(k)
                .expect("the grid is a non-empty multiple of the factor");
        }
        Ok((r, note))
    }

    /// The bed cropped and coarsened, with the note of [`Resample::apply`] added to
    /// `notes`; also returns the bed's original grid for [`Resample::profile`].
    pub(super) fn bed(
        &self,
        bed: &Profile,
        notes: &mut Vec<String>,
    ) -> Res<(Profile, OriginalGrid)> {
        let r = bed.raster().expect("the domain is the raster bed's grid");
        let (out, note) = self.apply("bed.b", r)?;
        notes.extend(note);
        let path = bed.raster_path().expect("a raster profile has a path");
        let original = OriginalGrid {
            nx: r.nx,
            ny: r.ny,
            cell_size: r.cell_size,
            x_left: r.x_left,
            y_top: r.y_top,
        };
        Ok((Profile::from_raster(path, out), original))
    }

    /// `p` cropped and coarsened when it is a raster on `original`'s grid; as it is
    /// otherwise.
    pub(super) fn profile(&self, key: &str, p: &mut Profile, original: &OriginalGrid) -> Res<()> {
        let Some(r) = p.raster() else {
            return Ok(());
        };
        let tol = 1e-9 * original.cell_size;
        let same = (r.nx, r.ny) == (original.nx, original.ny)
            && (r.cell_size - original.cell_size).abs() <= tol
            && (r.x_left - original.x_left).abs() <= tol
            && (r.y_top - original.y_top).abs() <= tol;
        if same {
            let (out, _) = self.apply(key, r)?;
            let path = p
                .raster_path()
                .expect("a raster profile has a path")
                .to_owned();
            *p = Profile::from_raster(&path, out);
        }
        Ok(())
    }
}
