//! The peak maps along an avalanche path, as AvaFrame's AIMEC reports them
//! (Fischer 2013's path-following coordinate system; AIMEC's `CrossMax` profiles).
//!
//! Every cell centre p of the band around the line, |l| ≤ w/2 with l the distance to
//! the line ([`PathLine::project`]) and w `output.path.width` (the whole DEM without
//! one), has its s along the line. The stations are s_i = i Δs, Δs the cell size, and
//! a cell belongs to the station of nearest s, i = ⌊s/Δs + ½⌋. At each station
//!
//! ```text
//!   pft_max(s_i) = max { pft(p) : p in the band, station(p) = i }
//! ```
//!
//! and likewise for pfv and ppr: the **maximum across the band's width**, not the value
//! on the line (AIMEC's cross-section maximum). The stations run from s = 0 to the
//! line's length, extended to every station the flow reached (pft > 0) past the ends; a
//! station with no cell of the DEM (all walls or outside it) has NaN. The elevation
//! z(s_i) is that of the station's cell nearest to the line (the thalweg's bed, to a
//! cell; AIMEC interpolates the DEM on the line, which differs by less than the bed's
//! change over one cell).
//!
//! The maxima of a run along its path are the largest values of the profiles, the
//! largest pft, pfv and ppr of the band (AIMEC's `maxpftCrossMax` and so on).

use super::path::PathLine;

/// The profiles along a path: one value per station.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Profile {
    /// Distance along the line (m), the stations' s.
    pub s: Vec<f64>,
    /// The line's point at s (extended past the ends), map coordinates (m).
    pub x: Vec<f64>,
    pub y: Vec<f64>,
    /// Elevation of the station's cell nearest to the line (m).
    pub z: Vec<f64>,
    /// Largest pft, pfv and ppr across the band at the station, in the maps' units.
    pub pft: Vec<f64>,
    pub pfv: Vec<f64>,
    pub ppr: Vec<f64>,
}

/// A cell of the band: its station and its distance to the line.
struct Member {
    cell: usize,
    station: i64,
    dist: f64,
}

/// The profiles along `line` of the maps `pft`, `pfv`, `ppr` (one value per cell),
/// over the cells `k < n` where `cell(k)` is `Some([x, y, z])` (not walls) whose
/// distance to the line is at most `half_width`, stations `ds` apart.
pub fn along(
    line: &PathLine,
    half_width: f64,
    ds: f64,
    n: usize,
    cell: impl Fn(usize) -> Option<[f64; 3]>,
    [pft, pfv, ppr]: [&[f64]; 3],
) -> Profile {
    let members: Vec<Member> = (0..n)
        .filter_map(|k| {
            let c = cell(k)?;
            let (s, dist) = line.project([c[0], c[1]]);
            (dist <= half_width).then(|| Member {
                cell: k,
                station: (s / ds + 0.5).floor() as i64,
                dist,
            })
        })
        .collect();
    // From s = 0 to the line's end, and every station the flow reached beyond.
    let reached = members.iter().filter(|m| pft[m.cell] > 0.0);
    let lo = reached.clone().map(|m| m.station).min().unwrap_or(0).min(0);
    let end = (line.length() / ds + 0.5).floor() as i64;
    let hi = reached.map(|m| m.station).max().unwrap_or(end).max(end);
    let len = (hi - lo + 1) as usize;
    let mut p = Profile {
        s: (lo..=hi).map(|i| i as f64 * ds).collect(),
        z: vec![f64::NAN; len],
        pft: vec![f64::NAN; len],
        pfv: vec![f64::NAN; len],
        ppr: vec![f64::NAN; len],
        ..Profile::default()
    };
    (p.x, p.y) =
        p.s.iter()
            .map(|&s| line.point_at(s))
            .map(|q| (q[0], q[1]))
            .unzip();
    let mut nearest = vec![f64::INFINITY; len];
    for m in members.iter().filter(|m| (lo..=hi).contains(&m.station)) {
        let i = (m.station - lo) as usize;
        for (out, map) in [(&mut p.pft, pft), (&mut p.pfv, pfv), (&mut p.ppr, ppr)] {
            // NaN (no cell yet) gives way to any value.
            if out[i].is_nan() || map[m.cell] > out[i] {
                out[i] = map[m.cell];
            }
        }
        if m.dist < nearest[i] {
            nearest[i] = m.dist;
            p.z[i] = cell(m.cell).map_or(f64::NAN, |c| c[2]);
        }
    }
    p
}

/// The largest value of a profile, NaN when it has none.
pub fn max(values: &[f64]) -> f64 {
    values
        .iter()
        .copied()
        .filter(|v| !v.is_nan())
        .reduce(f64::max)
        .unwrap_or(f64::NAN)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gis::Crs;

    /// A 4 × 3 grid of 1 m cells (centres x = 0..3, y = 0..2), the line along y = 1.
    #[test]
    fn each_station_holds_the_largest_value_across_the_band() {
        let line = PathLine {
            points: vec![[0.0, 1.0], [3.0, 1.0]],
            crs: Crs::default(),
        };
        let cell = |k: usize| Some([(k % 4) as f64, (k / 4) as f64, 10.0 - (k % 4) as f64]);
        let pft: Vec<f64> = (0..12)
            .map(|k| if k % 4 < 3 { k as f64 } else { 0.0 })
            .collect();
        let pfv: Vec<f64> = (0..12).map(|k| (12 - k) as f64).collect();
        let ppr = vec![0.0; 12];
        let p = along(&line, 10.0, 1.0, 12, cell, [&pft, &pfv, &ppr]);
        assert_eq!(p.s, [0.0, 1.0, 2.0, 3.0]);
        // Column i's largest values: pft is row 2's (8 + i, 0 in the last column),
        // pfv row 0's (12 − i).
        assert_eq!(p.pft, [8.0, 9.0, 10.0, 0.0]);
        assert_eq!(p.pfv, [12.0, 11.0, 10.0, 9.0]);
        assert_eq!(p.z, [10.0, 9.0, 8.0, 7.0]);
        assert_eq!((p.x, p.y), (vec![0.0, 1.0, 2.0, 3.0], vec![1.0; 4]));
        assert_eq!(max(&p.pft), 10.0);
        // A band of half a metre: row 1 alone.
        let p = along(&line, 0.5, 1.0, 12, cell, [&pft, &pfv, &ppr]);
        assert_eq!(p.pft, [4.0, 5.0, 6.0, 0.0]);
        // Walls (no cell) leave NaN; reached cells past the end extend the stations.
        let short = PathLine {
            points: vec![[0.0, 1.0], [1.0, 1.0]],
            crs: Crs::default(),
        };
        let p = along(
            &short,
            10.0,
            1.0,
            12,
            |k| (k % 4 != 1).then(|| cell(k).unwrap()),
            [&pft, &pfv, &ppr],
        );
        assert_eq!(p.s, [0.0, 1.0, 2.0]);
        assert!(p.pft[1].is_nan() && p.pft[2] == 10.0);
        assert_eq!(p.x, [0.0, 1.0, 2.0]);
    }
}
