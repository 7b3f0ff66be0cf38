//! Where keys are in the scenario text: dotted path ↔ byte span ↔ line.
//!
//! The file is parsed once with `toml_edit` (which keeps spans) into a [`KeyIndex`].
//! Errors are produced with a dotted key only; [`Locator::locate`] then adds the line of
//! that key in the file as written, or marks the error as coming from `--set` when the
//! key was overridden. Working by path rather than by byte offset keeps lines right even
//! when overrides have inserted text into the document that is finally deserialised.

use std::ops::Range;

use super::error::ScenarioError;

/// 1-based line of byte `offset` in `text`.
pub(crate) fn line_of(text: &str, offset: usize) -> usize {
    let end = offset.min(text.len());
    text.as_bytes()[..end]
        .iter()
        .filter(|&&c| c == b'\n')
        .count()
        + 1
}

#[derive(Debug)]
struct Entry {
    path: String,
    key_span: Option<Range<usize>>,
    item_span: Option<Range<usize>>,
    line: Option<usize>,
}

/// Every key of a parsed document with its spans and line.
#[derive(Debug, Default)]
pub(crate) struct KeyIndex {
    entries: Vec<Entry>,
}

impl KeyIndex {
    /// Indexes a document parsed with spans (`toml_edit::Document::parse`).
    pub(crate) fn build(text: &str, doc: &toml_edit::Document<&str>) -> KeyIndex {
        let mut index = KeyIndex::default();
        index.walk(text, doc.as_table(), "");
        index
    }

    fn walk(&mut self, text: &str, table: &dyn toml_edit::TableLike, prefix: &str) {
        for (name, item) in table.iter() {
            let path = if prefix.is_empty() {
                name.to_owned()
            } else {
                format!("{prefix}.{name}")
            };
            let key_span = table.get_key_value(name).and_then(|(k, _)| k.span());
            let item_span = item.span();
            let line = key_span
                .as_ref()
                .or(item_span.as_ref())
                .map(|s| line_of(text, s.start));
            self.entries.push(Entry {
                path: path.clone(),
                key_span,
                item_span,
                line,
            });
            if let Some(sub) = item.as_table_like() {
                self.walk(text, sub, &path);
            }
        }
    }

    pub(crate) fn contains(&self, path: &str) -> bool {
        self.entries.iter().any(|e| e.path == path)
    }

    /// Line of the key `path`, if it is in the document.
    pub(crate) fn line(&self, path: &str) -> Option<usize> {
        self.entries
            .iter()
            .find(|e| e.path == path)
            .and_then(|e| e.line)
    }

    /// The innermost key whose name or value covers byte `offset`.
    pub(crate) fn path_at(&self, offset: usize) -> Option<&str> {
        let covers = |s: &Option<Range<usize>>| {
            s.as_ref()
                .is_some_and(|s| s.contains(&offset) || (s.is_empty() && s.start == offset))
        };
        self.entries
            .iter()
            .filter(|e| covers(&e.key_span) || covers(&e.item_span))
            .max_by_key(|e| e.path.matches('.').count())
            .map(|e| e.path.as_str())
    }
}

/// Adds lines (or the `--set` mark) to errors that name a key.
#[derive(Debug)]
pub(crate) struct Locator {
    /// Index of the file as written.
    pub(crate) file: KeyIndex,
    /// Dotted keys given with `--set`.
    pub(crate) overridden: Vec<String>,
}

fn is_under(path: &str, ancestor: &str) -> bool {
    path == ancestor
        || (path.len() > ancestor.len()
            && path.starts_with(ancestor)
            && path.as_bytes()[ancestor.len()] == b'.')
}

impl Locator {
    pub(crate) fn locate(&self, err: ScenarioError) -> ScenarioError {
        if err.line().is_some() || err.is_from_set() {
            return err;
        }
        let Some(key) = err.key().map(str::to_owned) else {
            return err;
        };
        // The key, or a table holding it, was set on the command line.
        if self.overridden.iter().any(|o| is_under(&key, o)) {
            return err.mark_from_set();
        }
        // A table changed by an override of one of its keys. When the table only exists
        // because of the override (`--set foo.bar=1`), report the key as typed.
        if let Some(o) = self.overridden.iter().find(|o| is_under(o, &key)) {
            return if self.file.contains(&key) {
                err.mark_from_set()
            } else {
                let o = o.clone();
                err.with_key(o).mark_from_set()
            };
        }
        // The key itself, else the nearest enclosing table (for missing keys).
        let mut path = key.as_str();
        loop {
            if let Some(line) = self.file.line(path) {
                return err.with_line(Some(line));
            }
            match path.rfind('.') {
                Some(i) => path = &path[..i],
                None => return err,
            }
        }
    }
}

/// A TOML syntax error, with the line the parser points at.
pub(crate) fn syntax_error(text: &str, e: &toml_edit::TomlError) -> ScenarioError {
    let line = e.span().map(|s| line_of(text, s.start));
    let mut message = e.message().trim().to_owned();
    // toml_edit says only "duplicate key"; its span covers the repeated key or table
    // header, which names it.
    if message.starts_with("duplicate key") {
        let named = e
            .span()
            .and_then(|s| {
                // A table header names the whole dotted table, not just its last part.
                let start = text.get(..s.start)?.rfind('\n').map_or(0, |i| i + 1);
                let header = text.get(start..)?.lines().next()?.trim();
                let header = header.split('#').next()?.trim();
                if header.starts_with('[') {
                    Some(header)
                } else {
                    text.get(s)
                }
            })
            .map(|k| k.trim().trim_matches(['[', ']']).trim())
            .filter(|k| !k.is_empty() && k.len() <= 200 && !k.contains('\n'));
        if let Some(k) = named {
            message = format!("duplicate key or table '{k}' (it is defined earlier in the file)");
        }
    }
    ScenarioError::new(format!("invalid TOML: {message}")).with_line(line)
}

/// Turns a deserialisation error into one naming the dotted key; `index` is the key index
/// of the text that was deserialised (the error's span points into it).
pub(crate) fn serde_error(e: &toml_edit::de::Error, index: &KeyIndex) -> ScenarioError {
    let raw = e.message().trim();
    let path = e
        .span()
        .and_then(|s| index.path_at(s.start))
        .map(str::to_owned);
    let message = if let Some(rest) = raw.strip_prefix("unknown field ") {
        let (name, expected) = rest.split_once(", expected ").unwrap_or((rest, ""));
        let name = name.trim_matches('`');
        let expected = expected
            .trim_start_matches("one of ")
            .replace('`', "")
            .replace(" or ", ", ");
        if expected.is_empty() {
            format!("unknown key '{name}'")
        } else {
            format!("unknown key '{name}' (allowed here: {expected})")
        }
    } else if let Some(rest) = raw.strip_prefix("invalid type: ") {
        match rest.split_once(", expected ") {
            Some((found, expected)) => {
                let found = match found {
                    "sequence" => "an array",
                    "map" => "a table",
                    f => f,
                };
                format!(
                    "wrong type: expected {}, found {found}",
                    nice_type(expected)
                )
            }
            None => format!("wrong type: {rest}"),
        }
    } else {
        raw.to_owned()
    };
    match path {
        Some(p) => ScenarioError::at(p, message),
        None => ScenarioError::new(message),
    }
}

fn nice_type(expected: &str) -> String {
    match expected {
        "i64" | "u64" | "usize" | "i32" | "u32" => "an integer".into(),
        "f64" | "f32" => "a number".into(),
        "a boolean" | "bool" => "true or false".into(),
        "a string" => "a string (in quotes)".into(),
        s if s.starts_with("struct ") => "a table".into(),
        s => s.to_owned(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn index(text: &str) -> KeyIndex {
        let doc = toml_edit::Document::parse(text).unwrap();
        KeyIndex::build(text, &doc)
    }

    #[test]
    fn lines_of_keys_tables_and_dotted_keys() {
        let text = "# c\n[domain]\nx_min = 1\ncells.a = 3\n\nh = { table = \"a\" }\n[time.sub]\nq=1\nbed.b = 2\n";
        let ix = index(text);
        assert_eq!(ix.line("domain"), Some(2));
        assert_eq!(ix.line("domain.x_min"), Some(3));
        assert_eq!(ix.line("domain.cells.a"), Some(4));
        assert_eq!(ix.line("domain.h"), Some(6));
        assert_eq!(ix.line("domain.h.table"), Some(6));
        assert_eq!(ix.line("time.sub"), Some(7));
        assert_eq!(ix.line("time.sub.q"), Some(8));
        assert_eq!(ix.line("time.sub.bed.b"), Some(9));
        assert_eq!(ix.line("nothing"), None);
    }

    #[test]
    fn path_at_picks_innermost() {
        let text = "[domain]\nh = { table = \"a.csv\" }\n";
        let ix = index(text);
        let at = text.find("a.csv").unwrap();
        assert_eq!(ix.path_at(at), Some("domain.h.table"));
        assert_eq!(ix.path_at(text.find("h =").unwrap()), Some("domain.h"));
        assert_eq!(ix.path_at(1), Some("domain"));
    }

    #[test]
    fn locator_uses_enclosing_table_and_overrides() {
        let text = "[domain]\nx_min = 0\n\n[time]\nt_end = 1\n";
        let loc = Locator {
            file: index(text),
            overridden: vec!["time.t_end".into(), "foo.bar".into()],
        };
        let e = loc.locate(ScenarioError::at("domain.x_min", "m"));
        assert_eq!(e.line(), Some(2));
        let e = loc.locate(ScenarioError::at("domain.x_max", "missing"));
        assert_eq!(e.line(), Some(1));
        let e = loc.locate(ScenarioError::at("time.t_end", "m"));
        assert!(e.is_from_set() && e.line().is_none());
        let e = loc.locate(ScenarioError::at("foo", "unknown key 'foo'"));
        assert!(e.is_from_set());
        assert_eq!(e.key(), Some("foo.bar"));
        let e = loc.locate(ScenarioError::at("rheology", "missing section"));
        assert_eq!(e.line(), None);
        assert!(!e.is_from_set());
        assert!(is_under("a.b", "a") && !is_under("ab", "a") && is_under("a", "a"));
    }
}
