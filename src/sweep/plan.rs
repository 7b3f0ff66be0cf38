//! `DIR/sweep-plan.toml`: the expanded run list of a sweep, kept in its output directory.
//!
//! `sweep merge DIR` rebuilds the summary from the result files of all shards; it needs
//! to know which runs make up the sweep, in which order, with which parameters, without
//! access to the sweep file or the scenarios. Every invocation writes this plan before
//! running anything. Its content depends only on the sweep (sweep file text, base
//! scenario path, overrides, expanded runs and their scenario hashes), never on the
//! shard, the number of jobs or the time, so every shard of one sweep writes the same
//! bytes; the write is atomic and skipped when the file already holds them.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::record::write_atomic;

pub const PLAN_FILE: &str = "sweep-plan.toml";
pub const PLAN_FORMAT: u32 = 1;

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    pub format: u32,
    pub granflow_version: String,
    /// The sweep file as given on the command line.
    pub sweep_file: String,
    /// The base scenario file.
    pub scenario: String,
    /// Overrides applied to every run: the sweep file's `set`, then `--set`.
    pub base_overrides: Vec<String>,
    /// Axis keys, in column order.
    pub axes: Vec<String>,
    /// A copy of the sweep file.
    pub sweep_toml: String,
    pub runs: Vec<PlanRun>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlanRun {
    pub index: usize,
    pub name: String,
    pub scenario_hash: String,
    /// Value per axis (canonical text, as in the summary).
    pub values: Vec<String>,
    /// The run's axis overrides (`key=value`).
    pub overrides: Vec<String>,
}

impl Plan {
    pub fn to_text(&self) -> Result<String, String> {
        let body = toml::to_string(self).map_err(|e| format!("cannot encode the plan: {e}"))?;
        Ok(format!(
            "# Run list of a granflow sweep, written by `granflow sweep` and read by\n# `granflow sweep merge`. Do not edit.\n{body}"
        ))
    }

    /// Writes the plan into `dir` unless it already holds exactly this plan. Returns
    /// whether a different plan was replaced.
    pub fn write(&self, dir: &Path) -> Result<bool, String> {
        let path = dir.join(PLAN_FILE);
        let text = self.to_text()?;
        let old = std::fs::read_to_string(&path).ok();
        if old.as_deref() == Some(text.as_str()) {
            return Ok(false);
        }
        write_atomic(&path, &text).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
        Ok(old.is_some())
    }

    pub fn read(dir: &Path) -> Result<Plan, String> {
        let path = dir.join(PLAN_FILE);
        let text = std::fs::read_to_string(&path).map_err(|e| {
            format!(
                "cannot read {}: {e} (is '{}' the output directory of a sweep?)",
                path.display(),
                dir.display()
            )
        })?;
        let plan: Plan = toml::from_str(&text)
            .map_err(|e| format!("cannot read {}: {}", path.display(), e.message()))?;
        if plan.format != PLAN_FORMAT {
            return Err(format!(
                "{}: plan format {} is not supported (expected {PLAN_FORMAT})",
                path.display(),
                plan.format
            ));
        }
        Ok(plan)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_idempotent_write() {
        let dir = tempfile::tempdir().unwrap();
        let plan = Plan {
            format: PLAN_FORMAT,
            granflow_version: "0".into(),
            sweep_file: "s.toml".into(),
            scenario: "c.toml".into(),
            base_overrides: vec!["domain.cells=100".into()],
            axes: vec!["domain.slope_deg".into()],
            sweep_toml: "scenario = \"c.toml\"\n[axes]\ndomain.slope_deg = [1, 2]\n".into(),
            runs: vec![PlanRun {
                index: 0,
                name: "slope_deg=1".into(),
                scenario_hash: "00".into(),
                values: vec!["1".into()],
                overrides: vec!["domain.slope_deg=1".into()],
            }],
        };
        assert!(!plan.write(dir.path()).unwrap());
        assert!(!plan.write(dir.path()).unwrap());
        assert_eq!(Plan::read(dir.path()).unwrap(), plan);
        let mut other = plan.clone();
        other.runs[0].scenario_hash = "11".into();
        assert!(other.write(dir.path()).unwrap());
        assert_eq!(Plan::read(dir.path()).unwrap(), other);
        let e = Plan::read(&dir.path().join("nope")).unwrap_err();
        assert!(e.contains("output directory of a sweep"), "{e}");
    }
}
