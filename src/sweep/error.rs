//! Why a sweep could not start (or a merge could not be done).
//!
//! Errors in the sweep file name the file, the 1-based line and the dotted key, like
//! scenario errors do:
//!
//! ```text
//! sweep error in 'slopes.toml' at line 7, key 'axes.domain.slope_deg': needs at least one value
//! ```
//!
//! Errors in one generated scenario name the run, and the axis whose value caused them.
//! Both are bad input (exit code 2). Trouble writing the output directory is exit code 1.

use std::fmt;
use std::path::{Path, PathBuf};

pub use crate::terminal::{EXIT_BAD_INPUT, EXIT_FAILURE};

#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SweepError {
    /// A mistake in the sweep file.
    #[error("{}", RenderFile(self))]
    File {
        path: PathBuf,
        line: Option<usize>,
        key: Option<String>,
        message: String,
    },
    /// A generated scenario is invalid (or cannot be run by this build).
    #[error("{0}")]
    Scenario(String),
    /// Other bad input: options, output directory that is not a sweep's, …
    #[error("{0}")]
    Input(String),
    /// The output directory cannot be written.
    #[error("{0}")]
    Io(String),
}

impl SweepError {
    pub(crate) fn file(
        path: &Path,
        line: Option<usize>,
        key: Option<&str>,
        message: impl Into<String>,
    ) -> Self {
        SweepError::File {
            path: path.to_path_buf(),
            line,
            key: key.map(str::to_owned),
            message: message.into(),
        }
    }

    /// The process exit code this error maps to.
    pub fn exit_code(&self) -> u8 {
        match self {
            SweepError::Io(_) => EXIT_FAILURE,
            _ => EXIT_BAD_INPUT,
        }
    }

    /// The dotted key a sweep-file error is about.
    pub fn key(&self) -> Option<&str> {
        match self {
            SweepError::File { key, .. } => key.as_deref(),
            _ => None,
        }
    }

    /// The 1-based line of a sweep-file error.
    pub fn line(&self) -> Option<usize> {
        match self {
            SweepError::File { line, .. } => *line,
            _ => None,
        }
    }
}

struct RenderFile<'a>(&'a SweepError);

impl fmt::Display for RenderFile<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let SweepError::File {
            path,
            line,
            key,
            message,
        } = self.0
        else {
            unreachable!("only used for File")
        };
        write!(f, "sweep error in '{}'", path.display())?;
        if let Some(line) = line {
            write!(f, " at line {line}")?;
        }
        if let Some(key) = key {
            write!(f, ", key '{key}'")?;
        }
        write!(f, ": {message}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn file_errors_name_file_line_and_key() {
        let e = SweepError::file(Path::new("s.toml"), Some(7), Some("axes.a.b"), "bad");
        assert_eq!(
            e.to_string(),
            "sweep error in 's.toml' at line 7, key 'axes.a.b': bad"
        );
        assert_eq!(e.exit_code(), EXIT_BAD_INPUT);
        assert_eq!(e.key(), Some("axes.a.b"));
        assert_eq!(e.line(), Some(7));
        let e = SweepError::file(Path::new("s.toml"), None, None, "gone");
        assert_eq!(e.to_string(), "sweep error in 's.toml': gone");
        assert_eq!(SweepError::Io("x".into()).exit_code(), EXIT_FAILURE);
    }
}
