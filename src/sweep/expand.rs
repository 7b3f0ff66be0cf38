//! From the dimensions of a sweep to its ordered list of runs, and the split into shards.
//!
//! The runs are the product of the dimensions, the first dimension varying slowest
//! (like nested loops written in file order); a zipped group is one dimension whose
//! axes advance together. Run `index` is the position in that order: the sweep order,
//! used for shards and for the rows of the summary.

use std::collections::HashMap;
use std::fmt;
use std::str::FromStr;

use super::naming::{run_name, short_names};
use super::spec::{AxisValue, Dimension, SweepSpec};

/// One run of the sweep, before its scenario is loaded.
#[derive(Debug, Clone, PartialEq)]
pub struct RunPoint {
    /// Position in sweep order.
    pub index: usize,
    /// File stem of the run's outputs.
    pub name: String,
    /// `(dotted key, value)` per axis, in axis order.
    pub params: Vec<(String, AxisValue)>,
}

impl RunPoint {
    /// The run's axis overrides, `key=value` like `--set`.
    pub fn overrides(&self) -> Vec<String> {
        self.params
            .iter()
            .map(|(k, v)| format!("{k}={}", v.toml))
            .collect()
    }
}

/// Index tuples of the product of dimensions of the given lengths, last fastest.
pub fn product_indices(lens: &[usize]) -> Vec<Vec<usize>> {
    let total: usize = lens.iter().product();
    let mut out = Vec::with_capacity(total);
    if total == 0 {
        return out;
    }
    let mut idx = vec![0usize; lens.len()];
    for _ in 0..total {
        out.push(idx.clone());
        for d in (0..lens.len()).rev() {
            idx[d] += 1;
            if idx[d] < lens[d] {
                break;
            }
            idx[d] = 0;
        }
    }
    out
}

/// Every run of `dims`, in sweep order. Fails when two runs get the same file name
/// (values that differ only in characters that are replaced in names).
pub fn expand(dims: &[Dimension]) -> Result<Vec<RunPoint>, String> {
    let keys: Vec<&str> = dims
        .iter()
        .flat_map(|d| d.axes.iter().map(|a| a.key.as_str()))
        .collect();
    let short = short_names(&keys);
    let lens: Vec<usize> = dims.iter().map(Dimension::len).collect();
    let mut runs: Vec<RunPoint> = Vec::new();
    let mut seen: HashMap<String, usize> = HashMap::new();
    for (index, choice) in product_indices(&lens).into_iter().enumerate() {
        let params: Vec<(String, AxisValue)> = dims
            .iter()
            .zip(&choice)
            .flat_map(|(d, &i)| {
                d.axes
                    .iter()
                    .map(move |a| (a.key.clone(), a.values[i].clone()))
            })
            .collect();
        let parts: Vec<(&str, &str)> = short
            .iter()
            .zip(&params)
            .map(|(s, (_, v))| (s.as_str(), v.display.as_str()))
            .collect();
        let name = run_name(&parts);
        if let Some(other) = seen.insert(name.clone(), index) {
            return Err(format!(
                "runs {other} and {index} would both be written to '{name}': make the values differ in letters or digits"
            ));
        }
        runs.push(RunPoint {
            index,
            name,
            params,
        });
    }
    Ok(runs)
}

/// Convenience: the runs of a parsed sweep file.
pub fn expand_spec(spec: &SweepSpec) -> Result<Vec<RunPoint>, String> {
    expand(&spec.dims)
}

/// `--shard K/N`: the runs whose index is K modulo N (0 ≤ K < N).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    pub k: usize,
    pub n: usize,
}

impl Shard {
    /// The whole sweep.
    pub const ALL: Shard = Shard { k: 0, n: 1 };

    pub fn contains(&self, index: usize) -> bool {
        index % self.n == self.k
    }

    /// True for a real split (N > 1).
    pub fn is_partial(&self) -> bool {
        self.n > 1
    }
}

impl FromStr for Shard {
    type Err = String;

    fn from_str(s: &str) -> Result<Shard, String> {
        let bad = || format!("expected K/N with 0 <= K < N, e.g. 0/4, got '{s}'");
        let (k, n) = s.split_once('/').ok_or_else(bad)?;
        let k: usize = k.trim().parse().map_err(|_| bad())?;
        let n: usize = n.trim().parse().map_err(|_| bad())?;
        if n == 0 || k >= n {
            return Err(bad());
        }
        Ok(Shard { k, n })
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.k, self.n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sweep::spec::parse;
    use proptest::prelude::*;
    use std::path::Path;

    fn runs(text: &str) -> Vec<RunPoint> {
        let spec = parse(Path::new("s.toml"), text).unwrap();
        expand_spec(&spec).unwrap()
    }

    fn names(runs: &[RunPoint]) -> Vec<String> {
        runs.iter().map(|r| r.name.clone()).collect()
    }

    #[test]
    fn product_first_axis_slowest() {
        let r = runs("scenario = \"c\"\n[axes]\ndomain.slope_deg = [16, 22]\ninitial.erodible_bed = [0, 1.4e-3, 2.5e-3]\n");
        assert_eq!(
            names(&r),
            [
                "slope_deg=16__erodible_bed=0",
                "slope_deg=16__erodible_bed=0.0014",
                "slope_deg=16__erodible_bed=0.0025",
                "slope_deg=22__erodible_bed=0",
                "slope_deg=22__erodible_bed=0.0014",
                "slope_deg=22__erodible_bed=0.0025",
            ]
        );
        assert_eq!(r[4].index, 4);
        assert_eq!(
            r[4].overrides(),
            ["domain.slope_deg=22", "initial.erodible_bed=0.0014"]
        );
    }

    #[test]
    fn zip_takes_values_together_and_combines_with_product() {
        let r = runs("scenario = \"c\"\n[axes]\ntime.cfl = [0.4, 0.5]\n[[zip]]\ndomain.slope_deg = [16, 19, 22]\ninitial.erodible_bed = [1.4e-3, 1.5e-3, 1.82e-3]\n");
        assert_eq!(r.len(), 6);
        assert_eq!(r[0].name, "cfl=0.4__slope_deg=16__erodible_bed=0.0014");
        assert_eq!(r[2].name, "cfl=0.4__slope_deg=22__erodible_bed=0.00182");
        assert_eq!(r[5].name, "cfl=0.5__slope_deg=22__erodible_bed=0.00182");
        // Two zip groups multiply.
        let r = runs("scenario = \"c\"\n[[zip]]\na = [1, 2]\nb = [3, 4]\n[[zip]]\nc = [5, 6, 7]\n");
        assert_eq!(r.len(), 6);
        assert_eq!(r[3].name, "a=2__b=4__c=5");
    }

    #[test]
    fn colliding_names_are_refused() {
        let spec = parse(
            Path::new("s.toml"),
            "scenario = \"c\"\n[axes]\nx.f = [\"a b\", \"a_b\"]\n",
        )
        .unwrap();
        let e = expand_spec(&spec).unwrap_err();
        assert!(
            e.contains("runs 0 and 1 would both be written to 'f=a_b'"),
            "{e}"
        );
    }

    #[test]
    fn shard_parsing() {
        assert_eq!("1/4".parse::<Shard>(), Ok(Shard { k: 1, n: 4 }));
        assert_eq!("0/1".parse::<Shard>(), Ok(Shard::ALL));
        for bad in ["4/4", "1/0", "x/2", "1", "-1/2", "1/2/3"] {
            assert!(bad.parse::<Shard>().is_err(), "{bad}");
        }
        assert_eq!(Shard { k: 2, n: 3 }.to_string(), "2/3");
    }

    #[test]
    fn product_indices_counts() {
        assert_eq!(product_indices(&[2, 1, 3]).len(), 6);
        assert_eq!(product_indices(&[2, 0]).len(), 0);
        assert_eq!(product_indices(&[2, 2]), [[0, 0], [0, 1], [1, 0], [1, 1]]);
    }

    proptest! {
        /// Every run lands in exactly one shard, and the shards are balanced to within one run.
        #[test]
        fn shards_partition_the_runs(runs in 0usize..500, n in 1usize..40) {
            let mut owner = vec![Vec::new(); runs];
            let mut sizes = Vec::new();
            for k in 0..n {
                let shard: Shard = format!("{k}/{n}").parse().unwrap();
                let mine: Vec<usize> = (0..runs).filter(|&i| shard.contains(i)).collect();
                sizes.push(mine.len());
                for i in mine {
                    owner[i].push(k);
                }
            }
            for (i, o) in owner.iter().enumerate() {
                prop_assert_eq!(o.len(), 1, "run {} is in shards {:?}", i, o);
            }
            let (min, max) = (sizes.iter().min().unwrap(), sizes.iter().max().unwrap());
            prop_assert!(max - min <= 1);
        }

        /// The product has the product of the lengths, no duplicates, and each axis value
        /// appears equally often.
        #[test]
        fn product_is_complete(lens in proptest::collection::vec(1usize..5, 1..4)) {
            let idx = product_indices(&lens);
            prop_assert_eq!(idx.len(), lens.iter().product::<usize>());
            let mut sorted = idx.clone();
            sorted.sort();
            sorted.dedup();
            prop_assert_eq!(sorted.len(), idx.len());
            prop_assert_eq!(sorted, idx);
        }
    }
}
