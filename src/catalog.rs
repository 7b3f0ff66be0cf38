//! The scenarios bundled in the binary (`granflow scenarios`, `granflow init`).
//!
//! An installed `granflow` (`cargo install --path .`) has no `scenarios/` directory next
//! to it, so the paper cases and the CSV tables some of them read are compiled in with
//! `include_str!`. `granflow init NAME --from CASE` writes a case back to disk, with its
//! tables under `data/` next to it, exactly where the scenario's `{ table = "data/…" }`
//! keys look for them (tables resolve against the scenario file's directory).
//! A test (`tests/newcomer.rs`) checks that this list matches `scenarios/*.toml`.

use std::fmt;
use std::path::{Path, PathBuf};

/// One bundled scenario: its name (the file stem), its text and the data files it reads.
#[derive(Debug, Clone, Copy)]
pub struct Bundled {
    pub name: &'static str,
    pub toml: &'static str,
    /// `(path relative to the scenario's directory, contents)`.
    pub data: &'static [(&'static str, &'static str)],
}

macro_rules! bundled {
    ($name:literal) => {
        Bundled {
            name: $name,
            toml: include_str!(concat!("../scenarios/", $name, ".toml")),
            data: &[],
        }
    };
    ($name:literal, [$($data:literal),+]) => {
        Bundled {
            name: $name,
            toml: include_str!(concat!("../scenarios/", $name, ".toml")),
            data: &[$(($data, include_str!(concat!("../scenarios/", $data)))),+],
        }
    };
}

/// Every scenario of `scenarios/`, in alphabetical order.
pub const BUNDLED: &[Bundled] = &[
    bundled!("at_rest_random_bed"),
    bundled!("at_rest_random_bed_multilayer"),
    bundled!("bagnold"),
    bundled!("collapse"),
    bundled!("collapse_nh"),
    bundled!("collapse_nh_gate"),
    bundled!("dam_break_dry"),
    bundled!("dam_break_wet"),
    bundled!(
        "dem_release",
        [
            "data/synthetic_dem.asc",
            "data/synthetic_dem.prj",
            "data/synthetic_release.geojson"
        ]
    ),
    bundled!("dilatancy_dense"),
    bundled!("dilatancy_dense_walls"),
    bundled!("dilatancy_loose"),
    bundled!("erodible_bed"),
    bundled!("helix_channel", ["data/avaframe_helix_release.geojson"]),
    bundled!("hockey_channel", ["data/avaframe_hockey_release.geojson"]),
    bundled!("lake_at_rest"),
    bundled!("lake_landslide"),
    bundled!("nh_complex_topography"),
    bundled!(
        "nh_complex_topography_local",
        [
            "data/complex_topography_local_b.csv",
            "data/complex_topography_local_h.csv"
        ]
    ),
    bundled!("nh_complex_topography_multilayer"),
    bundled!("nh_coordinates_wedge"),
    bundled!("nh_coordinates_wedge_cartesian"),
    bundled!("nh_multilayer_at_rest"),
    bundled!("nh_multilayer_collapse"),
    bundled!("nh_multilayer_convergence"),
    bundled!("radial_collapse"),
    bundled!("radial_collapse_layers"),
    bundled!("sidewall_channel"),
    bundled!("submarine_landslide"),
    bundled!("transient_channel"),
    bundled!("tsunami_30km"),
];

/// The commented starter scenario of `granflow init NAME` (no `--from`); `THIS_FILE`
/// stands for the scenario's file stem.
pub const STARTER: &str = include_str!("starter.toml");

/// Finds a bundled scenario by name (`collapse` or `collapse.toml`).
pub fn find(name: &str) -> Option<&'static Bundled> {
    let stem = name.strip_suffix(".toml").unwrap_or(name);
    BUNDLED.iter().find(|b| b.name == stem)
}

impl Bundled {
    /// The header's first sentence: the comment lines before the first key, joined, cut
    /// at the first `: ` or `. ` outside parentheses.
    pub fn description(&self) -> String {
        first_sentence(&header(self.toml))
    }
}

/// The leading `#` comment lines of a TOML text, joined by spaces.
fn header(toml: &str) -> String {
    toml.lines()
        .map_while(|l| l.strip_prefix('#'))
        .map(str::trim)
        .collect::<Vec<_>>()
        .join(" ")
}

fn first_sentence(text: &str) -> String {
    let mut depth = 0i32;
    let chars: Vec<char> = text.chars().collect();
    for (i, c) in chars.iter().enumerate() {
        match c {
            '(' => depth += 1,
            ')' => depth -= 1,
            ':' | '.' if depth == 0 && chars.get(i + 1).is_none_or(|n| *n == ' ') => {
                return chars[..i].iter().collect();
            }
            _ => {}
        }
    }
    text.trim_end_matches('.').to_owned()
}

/// The bundled text with its `file = "<case>.h5"` output key renamed after the new
/// scenario, so that `init my_run --from collapse` writes `my_run.h5`, not `collapse.h5`.
fn renamed_output(b: &Bundled, scenario: &Path) -> String {
    let stem = scenario.file_stem().unwrap_or_default().to_string_lossy();
    b.toml.replace(
        &format!("file = \"{}.h5\"", b.name),
        &format!("file = \"{stem}.h5\""),
    )
}

/// Why `init` wrote nothing.
#[derive(Debug, thiserror::Error)]
pub enum InitError {
    #[error("no bundled scenario named '{0}' (see `granflow scenarios`)")]
    Unknown(String),
    #[error("'{0}' already exists (use --force to overwrite it)")]
    Exists(PathBuf),
    #[error("cannot write '{path}': {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
}

/// What `init` wrote.
#[derive(Debug)]
pub struct Written {
    pub scenario: PathBuf,
    /// Data files written (tables of the scenario), relative paths resolved.
    pub data: Vec<PathBuf>,
    /// Data files that were already there with the same contents.
    pub unchanged: Vec<PathBuf>,
}

impl fmt::Display for Written {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "wrote {}", self.scenario.display())?;
        for d in &self.data {
            write!(f, ", {}", d.display())?;
        }
        if !self.unchanged.is_empty() {
            let kept: Vec<String> = self
                .unchanged
                .iter()
                .map(|d| d.display().to_string())
                .collect();
            write!(f, "; kept {} (same contents)", kept.join(", "))?;
        }
        Ok(())
    }
}

/// The scenario file `init NAME` writes: `NAME` itself if it ends in `.toml`, else
/// `NAME.toml`.
pub fn scenario_path(name: &Path) -> PathBuf {
    if name.extension().is_some_and(|e| e == "toml") {
        name.to_path_buf()
    } else {
        let mut s = name.as_os_str().to_owned();
        s.push(".toml");
        PathBuf::from(s)
    }
}

/// Writes the starter (`from = None`) or a bundled scenario to `NAME.toml`, with the
/// scenario's tables under the same relative paths next to it. Nothing is written if
/// any target exists with other contents, unless `force`; a table already there with
/// the same contents is left alone (two scenarios made from one case share it).
pub fn init(name: &Path, from: Option<&str>, force: bool) -> Result<Written, InitError> {
    let scenario = scenario_path(name);
    let (toml, data) = match from {
        None => {
            let stem = scenario.file_stem().unwrap_or_default().to_string_lossy();
            (STARTER.replace("THIS_FILE", &stem), &[][..])
        }
        Some(case) => {
            let b = find(case).ok_or_else(|| InitError::Unknown(case.to_owned()))?;
            (renamed_output(b, &scenario), b.data)
        }
    };
    // Tables resolve against the scenario's directory (the current one for a bare name).
    let dir = scenario.parent().unwrap_or(Path::new(""));
    let mut plan = vec![(scenario.clone(), toml.as_str(), false)];
    for (rel, text) in data {
        plan.push((dir.join(rel), text, true));
    }
    // Check everything before writing anything.
    let mut todo = Vec::new();
    let mut unchanged = Vec::new();
    for (path, text, is_data) in plan {
        match std::fs::read_to_string(&path) {
            Ok(old) if is_data && old == text => unchanged.push(path),
            Ok(_) if !force => return Err(InitError::Exists(path)),
            Err(_) if path.exists() && !force => return Err(InitError::Exists(path)),
            _ => todo.push((path, text)),
        }
    }
    let mut written = Written {
        scenario: scenario.clone(),
        data: Vec::new(),
        unchanged,
    };
    for (path, text) in todo {
        if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
            std::fs::create_dir_all(parent).map_err(|source| InitError::Io {
                path: parent.to_path_buf(),
                source,
            })?;
        }
        std::fs::write(&path, text).map_err(|source| InitError::Io {
            path: path.clone(),
            source,
        })?;
        if path != scenario {
            written.data.push(path);
        }
    }
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn descriptions_stop_at_the_first_colon_outside_parentheses() {
        let c = find("collapse").unwrap();
        assert_eq!(
            c.description(),
            "Granular column collapse on an inclined plane (Garres-Díaz et al. 2021, §4.3, lab experiments \
             of Mangeney et al. 2010)"
        );
        assert_eq!(
            find("dam_break_dry.toml").unwrap().description(),
            "Frictionless dam break on a dry horizontal bed"
        );
    }

    #[test]
    fn every_description_is_one_short_line() {
        for b in BUNDLED {
            let d = b.description();
            assert!(!d.is_empty() && d.len() < 140, "{}: {d}", b.name);
            assert!(!d.contains('\n'));
        }
    }

    #[test]
    fn first_sentence_without_a_stop_is_the_whole_text() {
        assert_eq!(first_sentence("A plain line."), "A plain line");
        assert_eq!(
            first_sentence("Runs (e.g. this: one)"),
            "Runs (e.g. this: one)"
        );
    }

    #[test]
    fn scenario_path_adds_toml_once() {
        assert_eq!(scenario_path(Path::new("a/b")), PathBuf::from("a/b.toml"));
        assert_eq!(scenario_path(Path::new("c.toml")), PathBuf::from("c.toml"));
    }
}
