//! The summary table: `summary.csv` and the table printed at the end of a sweep.
//!
//! One row per run in sweep order. Columns: `index`, `run` (the file stem), one column
//! per axis (named by its dotted key, canonical values), then `runout`, `stop_time`,
//! `h_max_final`, `t_end`, `steps`, `wall_time_s`, `status`, `outflowed_fraction` (of
//! the initial mass, through outflow boundaries), and `max_wave_amplitude` when a run
//! has one (submarine sweeps; empty for runs without). Floats are written in their
//! shortest exact form (`nan` when not at rest); a run without a result has empty
//! numbers and a status that says why (`pending`, `missing`, `stale: …`). Fields are
//! quoted as in RFC 4180 when they hold a comma, a quote or a line break.

use std::fmt::Write;

use super::naming::{format_float, short_names};
use super::record::RunRecord;
use crate::output::Spread;

pub const SUMMARY_FILE: &str = "summary.csv";

/// One line of the summary.
#[derive(Debug, Clone)]
pub struct Row {
    pub index: usize,
    pub name: String,
    /// Value per axis.
    pub values: Vec<String>,
    /// The run's result, when there is one.
    pub record: Option<RunRecord>,
    /// Status shown when there is no result.
    pub note: String,
}

impl Row {
    pub fn status(&self) -> &str {
        self.record
            .as_ref()
            .map_or(&self.note, |r| &r.summary.status)
    }

    /// Completed or stopped at rest.
    pub fn is_ok(&self) -> bool {
        self.record.as_ref().is_some_and(RunRecord::is_ok)
    }
}

pub fn csv_field(text: &str) -> String {
    if text.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_owned()
    }
}

/// Name of the file a (possibly partial) sweep writes its summary to.
pub fn summary_file_name(shard: super::Shard) -> String {
    if shard.is_partial() {
        format!("summary.shard-{}-of-{}.csv", shard.k, shard.n)
    } else {
        SUMMARY_FILE.to_owned()
    }
}

pub const METRICS: [&str; 8] = [
    "runout",
    "stop_time",
    "settled_time",
    "h_max_final",
    "t_end",
    "steps",
    "wall_time_s",
    "status",
];

/// The run's runout along the flow, travel angle and area reached, if it is a
/// raster run.
fn spread(row: &Row) -> Option<Spread> {
    row.record.as_ref()?.summary.spread
}

/// The run's runout along its path (`output.path`): length and angle.
fn path(row: &Row) -> Option<(f64, f64)> {
    let s = spread(row)?;
    Some((
        s.path_runout_length?,
        s.path_runout_angle_deg.unwrap_or(f64::NAN),
    ))
}

/// The largest pft, pfv and ppr along the run's path (`output.path`).
fn path_max(row: &Row) -> Option<[f64; 3]> {
    spread(row)?.path_max
}

/// The run's wave amplitude, if it has one.
fn wave(row: &Row) -> Option<f64> {
    row.record.as_ref()?.summary.max_wave_amplitude
}

/// The CSV text of `rows` for a sweep over `axes`.
pub fn to_csv(axes: &[String], rows: &[Row]) -> String {
    let mut out = String::new();
    let waves = rows.iter().any(|r| wave(r).is_some());
    let spreads = rows.iter().any(|r| spread(r).is_some());
    let paths = rows.iter().any(|r| path(r).is_some());
    let maxima = rows.iter().any(|r| path_max(r).is_some());
    let header: Vec<String> = ["index", "run"]
        .iter()
        .map(|s| s.to_string())
        .chain(axes.iter().map(|a| csv_field(a)))
        .chain(METRICS.iter().map(|s| s.to_string()))
        .chain(["outflowed_fraction".to_string()])
        .chain(waves.then(|| "max_wave_amplitude".to_string()))
        .chain(
            spreads
                .then_some(["runout_length", "travel_angle_deg", "area_reached"])
                .into_iter()
                .flatten()
                .map(str::to_string),
        )
        .chain(
            paths
                .then_some(["path_runout_length", "path_runout_angle_deg"])
                .into_iter()
                .flatten()
                .map(str::to_string),
        )
        .chain(
            maxima
                .then_some(["path_max_pft", "path_max_pfv", "path_max_ppr"])
                .into_iter()
                .flatten()
                .map(str::to_string),
        )
        .collect();
    out.push_str(&header.join(","));
    out.push('\n');
    for row in rows {
        let mut fields = vec![row.index.to_string(), csv_field(&row.name)];
        fields.extend(row.values.iter().map(|v| csv_field(v)));
        match &row.record {
            Some(r) => {
                fields.extend(
                    [
                        r.summary.runout,
                        r.summary.stop_time,
                        r.summary.settled_time,
                        r.summary.h_max_final,
                        r.summary.t_end,
                    ]
                    .iter()
                    .map(|&v| format_float(v)),
                );
                fields.push(r.summary.steps.to_string());
                fields.push(format_float(r.summary.wall_time_s));
            }
            None => fields.extend(std::iter::repeat_n(String::new(), 7)),
        }
        fields.push(csv_field(row.status()));
        fields.push(
            row.record
                .as_ref()
                .map_or_else(String::new, |r| format_float(r.summary.outflowed_fraction)),
        );
        if waves {
            fields.push(wave(row).map_or_else(String::new, format_float));
        }
        if spreads {
            match spread(row) {
                Some(s) => fields.extend(
                    [s.runout_length, s.travel_angle_deg, s.area_reached].map(format_float),
                ),
                None => fields.extend(std::iter::repeat_n(String::new(), 3)),
            }
        }
        if paths {
            match path(row) {
                Some((l, a)) => fields.extend([l, a].map(format_float)),
                None => fields.extend(std::iter::repeat_n(String::new(), 2)),
            }
        }
        if maxima {
            match path_max(row) {
                Some(m) => fields.extend(m.map(format_float)),
                None => fields.extend(std::iter::repeat_n(String::new(), 3)),
            }
        }
        out.push_str(&fields.join(","));
        out.push('\n');
    }
    out
}

/// A table for the terminal: parameters by short name, 4 significant decimals.
pub fn to_table(axes: &[String], rows: &[Row]) -> String {
    let keys: Vec<&str> = axes.iter().map(String::as_str).collect();
    let mut header: Vec<String> = short_names(&keys);
    // Raster runs: the runout along the flow and its travel angle and area, not the
    // front's advance in x.
    let spreads = rows.iter().any(|r| spread(r).is_some());
    header.push("runout_m".to_string());
    if spreads {
        header.extend(["travel_deg", "area_m2"].map(str::to_string));
    }
    let paths = rows.iter().any(|r| path(r).is_some());
    if paths {
        header.extend(["path_m", "path_deg", "max_ppr_kPa"].map(str::to_string));
    }
    header.extend(
        [
            "stop_time_s",
            "settled_s",
            "h_max_final_m",
            "steps",
            "wall_s",
            "outflow_%",
            "status",
        ]
        .iter()
        .map(|s| s.to_string()),
    );
    let num = |v: f64| {
        if v.is_nan() {
            "-".to_string()
        } else if v != 0.0 && !(1e-3..1e6).contains(&v.abs()) {
            format!("{v:.4e}")
        } else {
            format!("{v:.4}")
        }
    };
    let mut cells: Vec<Vec<String>> = vec![header];
    for row in rows {
        let mut line = row.values.clone();
        match &row.record {
            Some(r) => line.extend(
                match (spreads, r.summary.spread) {
                    (false, _) => vec![num(r.summary.runout)],
                    (true, Some(s)) => vec![
                        num(s.runout_length),
                        num(s.travel_angle_deg),
                        num(s.area_reached),
                    ],
                    (true, None) => vec![num(r.summary.runout), "-".into(), "-".into()],
                }
                .into_iter()
                .chain(
                    paths
                        .then(|| {
                            let (l, a) = path(row).unwrap_or((f64::NAN, f64::NAN));
                            let ppr = path_max(row).map_or(f64::NAN, |m| m[2] / 1000.0);
                            [num(l), num(a), num(ppr)]
                        })
                        .into_iter()
                        .flatten(),
                )
                .chain([
                    num(r.summary.stop_time),
                    num(r.summary.settled_time),
                    num(r.summary.h_max_final),
                    r.summary.steps.to_string(),
                    format!("{:.2}", r.summary.wall_time_s),
                    num(100.0 * r.summary.outflowed_fraction),
                ]),
            ),
            None => line.extend(std::iter::repeat_n(
                String::new(),
                7 + if spreads { 2 } else { 0 } + if paths { 3 } else { 0 },
            )),
        }
        let status: String = row.status().chars().take(70).collect();
        line.push(status.replace('\n', " "));
        cells.push(line);
    }
    let ncol = cells[0].len();
    let width: Vec<usize> = (0..ncol)
        .map(|c| {
            cells
                .iter()
                .map(|l| l[c].chars().count())
                .max()
                .unwrap_or(0)
        })
        .collect();
    let mut out = String::new();
    for line in &cells {
        let mut text = String::new();
        for (c, cell) in line.iter().enumerate() {
            if c + 1 == ncol {
                text.push_str(cell);
            } else {
                let _ = write!(text, "{cell:>w$}  ", w = width[c]);
            }
        }
        out.push_str(text.trim_end());
        out.push('\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::RunSummary;
    use crate::sweep::record::RECORD_FORMAT;

    fn rows() -> Vec<Row> {
        let record = RunRecord {
            format: RECORD_FORMAT,
            index: 0,
            name: "slope_deg=16".into(),
            scenario_hash: "x".into(),
            summary: RunSummary {
                status: "stopped_at_rest".into(),
                runout: 0.832,
                stop_time: f64::NAN,
                settled_time: 0.8125,
                settle_fraction: 1e-6,
                h_max_final: 0.0417,
                t_end: 1.4258,
                steps: 125,
                wall_time_s: 0.019,
                max_wave_amplitude: None,
                wet: None,
                spread: None,
                outflowed_fraction: 0.25,
                front_at_end_time: f64::NAN,
                max_speed_final: 0.0,
                stage_times: Vec::new(),
            },
            h5: "slope_deg=16.h5".into(),
            parameters: Default::default(),
        };
        let mut failed = record.clone();
        failed.summary.status = "failed: a, \"b\"".into();
        vec![
            Row {
                index: 0,
                name: "slope_deg=16".into(),
                values: vec!["16".into()],
                record: Some(record),
                note: String::new(),
            },
            Row {
                index: 1,
                name: "slope_deg=19".into(),
                values: vec!["19".into()],
                record: None,
                note: "missing".into(),
            },
            Row {
                index: 2,
                name: "slope_deg=22".into(),
                values: vec!["22".into()],
                record: Some(failed),
                note: String::new(),
            },
        ]
    }

    #[test]
    fn csv_layout() {
        let csv = to_csv(&["domain.slope_deg".into()], &rows());
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(
            lines[0],
            "index,run,domain.slope_deg,runout,stop_time,settled_time,h_max_final,t_end,steps,wall_time_s,status,outflowed_fraction"
        );
        assert_eq!(
            lines[1],
            "0,slope_deg=16,16,0.832,nan,0.8125,0.0417,1.4258,125,0.019,stopped_at_rest,0.25"
        );
        assert_eq!(lines[2], "1,slope_deg=19,19,,,,,,,,missing,");
        assert!(
            lines[3].ends_with(",\"failed: a, \"\"b\"\"\",0.25"),
            "{}",
            lines[3]
        );
        assert!(rows()[0].is_ok() && !rows()[1].is_ok() && !rows()[2].is_ok());
    }

    #[test]
    fn wave_amplitude_column_only_when_a_run_has_one() {
        let mut rows = rows();
        let record = rows[0].record.as_mut().unwrap();
        record.summary.max_wave_amplitude = Some(0.03125);
        let csv = to_csv(&["rheology.mu_deg".into()], &rows);
        let lines: Vec<&str> = csv.lines().collect();
        assert!(
            lines[0].ends_with(",status,outflowed_fraction,max_wave_amplitude"),
            "{}",
            lines[0]
        );
        assert!(
            lines[1].ends_with(",stopped_at_rest,0.25,0.03125"),
            "{}",
            lines[1]
        );
        assert_eq!(lines[2], "1,slope_deg=19,19,,,,,,,,missing,,");
    }

    #[test]
    fn table_is_aligned() {
        let t = to_table(&["domain.slope_deg".into()], &rows());
        let lines: Vec<&str> = t.lines().collect();
        assert!(lines[0].starts_with("slope_deg  runout_m"), "{t}");
        assert!(
            lines[1].contains("0.8320") && lines[1].contains(" - "),
            "{t}"
        );
        assert!(lines[2].ends_with("missing"), "{t}");
        let mut big = rows();
        big[0].record.as_mut().unwrap().summary.h_max_final = 1e300;
        let t = to_table(&["domain.slope_deg".into()], &big);
        assert!(t.lines().nth(1).unwrap().contains(" 1.0000e300 "), "{t}");
    }

    #[test]
    fn shard_file_names() {
        use crate::sweep::Shard;
        assert_eq!(summary_file_name(Shard::ALL), "summary.csv");
        assert_eq!(
            summary_file_name(Shard { k: 1, n: 3 }),
            "summary.shard-1-of-3.csv"
        );
    }
}
