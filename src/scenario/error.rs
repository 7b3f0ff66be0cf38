//! The one error type of scenario loading.
//!
//! An error names, when it can, the dotted key it is about (`domain.cells`) and the
//! 1-based line of that key in the scenario file. Validation code only fills in the key;
//! the loader then looks the key up in the parsed document to add the line, or marks the
//! error as coming from a `--set` override when the key was given on the command line.

use std::fmt;

/// Why a scenario could not be loaded.
///
/// Displayed as `scenario error at line 4, key 'domain.cells': must be at least 1`;
/// parts that are unknown are left out.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{}", Render(self))]
pub struct ScenarioError {
    key: Option<String>,
    line: Option<usize>,
    from_set: bool,
    message: String,
}

impl ScenarioError {
    /// An error about no particular key (unreadable file, …).
    pub(crate) fn new(message: impl Into<String>) -> Self {
        Self {
            key: None,
            line: None,
            from_set: false,
            message: message.into(),
        }
    }

    /// An error about the dotted key `key`; the line is filled in later.
    pub(crate) fn at(key: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            key: Some(key.into()),
            ..Self::new(message)
        }
    }

    pub(crate) fn with_line(mut self, line: Option<usize>) -> Self {
        self.line = line;
        self
    }

    pub(crate) fn with_key(mut self, key: impl Into<String>) -> Self {
        self.key = Some(key.into());
        self
    }

    pub(crate) fn mark_from_set(mut self) -> Self {
        self.from_set = true;
        self.line = None;
        self
    }

    /// The dotted key the error is about (`domain.cells`), when known.
    pub fn key(&self) -> Option<&str> {
        self.key.as_deref()
    }

    /// The 1-based line in the scenario file, when known.
    pub fn line(&self) -> Option<usize> {
        self.line
    }

    /// True when the offending value came from a `--set` override, not from the file.
    pub fn is_from_set(&self) -> bool {
        self.from_set
    }

    /// The description alone, without key and line.
    pub fn message(&self) -> &str {
        &self.message
    }
}

struct Render<'a>(&'a ScenarioError);

impl fmt::Display for Render<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let e = self.0;
        f.write_str("scenario error")?;
        if let Some(line) = e.line {
            write!(f, " at line {line}")?;
        }
        if let Some(key) = &e.key {
            write!(f, ", key '{key}'")?;
        }
        if e.from_set {
            f.write_str(" (from --set)")?;
        }
        write!(f, ": {}", e.message)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn display_with_line_and_key() {
        let e = ScenarioError::at("domain.cells", "must be at least 1").with_line(Some(4));
        assert_eq!(
            e.to_string(),
            "scenario error at line 4, key 'domain.cells': must be at least 1"
        );
        assert_eq!(e.key(), Some("domain.cells"));
        assert_eq!(e.line(), Some(4));
    }

    #[test]
    fn display_from_set_has_no_line() {
        let e = ScenarioError::at("domain.slope_deg", "must be finite")
            .with_line(Some(3))
            .mark_from_set();
        assert_eq!(
            e.to_string(),
            "scenario error, key 'domain.slope_deg' (from --set): must be finite"
        );
        assert_eq!(e.line(), None);
        assert!(e.is_from_set());
    }

    #[test]
    fn display_without_key() {
        let e = ScenarioError::new("cannot read scenario file 'a.toml': gone");
        assert_eq!(
            e.to_string(),
            "scenario error: cannot read scenario file 'a.toml': gone"
        );
        assert_eq!(e.key(), None);
        let e = e.with_line(Some(2));
        assert_eq!(
            e.to_string(),
            "scenario error at line 2: cannot read scenario file 'a.toml': gone"
        );
    }
}
