//! The crate's layering, checked on its sources: the graph of top-level modules
//! (`src/<module>.rs` or `src/<module>/`) built from their `crate::<module>` references
//! (use statements and paths, comments left out) has no cycle, and a few edges are
//! forbidden outright:
//!
//! - `physics` (the pointwise laws) imports no `numerics` (the schemes built on them);
//! - `numerics` imports neither `model` nor `scenario` (a scheme sees states and the
//!   grid, never a model's assembly or the input file);
//! - `grid` and `state` import none of `numerics`, `model`, `scenario`, `setup`,
//!   `output`, `cli`;
//! - `terminal` (printing to stdout and stderr) imports nothing of the crate.

use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::path::{Path, PathBuf};

/// Edges `(from, to)` between top-level modules, with one file that makes each.
type Graph = BTreeMap<String, BTreeMap<String, PathBuf>>;

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The source without its comments (line, block and doc comments), string literals
/// kept as they are (they hold no `crate::` paths worth counting, and the few that
/// might are messages).
fn strip_comments(text: &str) -> String {
    let b = text.as_bytes();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    let mut in_str = false;
    while i < b.len() {
        let c = b[i];
        if in_str {
            if c == b'\\' && i + 1 < b.len() {
                out.push(' ');
                out.push(' ');
                i += 2;
                continue;
            }
            if c == b'"' {
                in_str = false;
            }
            out.push(' ');
            i += 1;
        } else if c == b'"' {
            in_str = true;
            out.push(' ');
            i += 1;
        } else if c == b'\'' && i + 2 < b.len() && (b[i + 2] == b'\'' || b[i + 1] == b'\\') {
            // A char literal ('"', '\n'): skip it so a quote in it opens no string.
            let end = text[i + 1..].find('\'').map_or(b.len(), |k| i + 1 + k + 1);
            let end = if b[i + 1] == b'\\' {
                text[i + 3..].find('\'').map_or(b.len(), |k| i + 3 + k + 1)
            } else {
                end
            };
            i = end;
            out.push(' ');
        } else if c == b'/' && b.get(i + 1) == Some(&b'/') {
            while i < b.len() && b[i] != b'\n' {
                i += 1;
            }
        } else if c == b'/' && b.get(i + 1) == Some(&b'*') {
            let mut depth = 0;
            while i < b.len() {
                if b[i] == b'/' && b.get(i + 1) == Some(&b'*') {
                    depth += 1;
                    i += 2;
                } else if b[i] == b'*' && b.get(i + 1) == Some(&b'/') {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
        } else {
            let ch = text[i..].chars().next().unwrap();
            out.push(ch);
            i += ch.len_utf8();
        }
    }
    out
}

fn is_ident(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_'
}

/// The top-level modules a source refers to: `crate::a::…`, and in a group
/// `crate::{a::…, b}` each of `a`, `b`.
fn referenced_modules(code: &str) -> BTreeSet<String> {
    let mut found = BTreeSet::new();
    let mut rest = code;
    while let Some(k) = rest.find("crate::") {
        let before = rest[..k].chars().next_back();
        rest = &rest[k + "crate::".len()..];
        if before.is_some_and(|c| is_ident(c) || c == '$') {
            continue; // `$crate::` in a macro, or an identifier ending in "crate".
        }
        let after = rest.trim_start();
        if let Some(group) = after.strip_prefix('{') {
            // Top-level items of the group: split at commas outside nested braces.
            let mut depth = 0;
            let mut item = String::new();
            for c in group.chars() {
                match c {
                    '{' => depth += 1,
                    '}' if depth == 0 => break,
                    '}' => depth -= 1,
                    ',' if depth == 0 => {
                        push_head(&item, &mut found);
                        item.clear();
                        continue;
                    }
                    _ => {}
                }
                item.push(c);
            }
            push_head(&item, &mut found);
        } else {
            push_head(after, &mut found);
        }
    }
    found
}

fn push_head(path: &str, found: &mut BTreeSet<String>) {
    let head: String = path
        .trim_start()
        .chars()
        .take_while(|&c| is_ident(c))
        .collect();
    if !head.is_empty() && head != "self" {
        found.insert(head);
    }
}

/// The top-level module of a file under `src/` (`None` for lib.rs and main.rs).
fn top_module(file: &Path) -> Option<String> {
    let rel = file.strip_prefix(src()).unwrap();
    let first = rel.components().next()?.as_os_str().to_str()?.to_owned();
    if rel.components().count() == 1 {
        let stem = first.strip_suffix(".rs")?;
        if stem == "lib" || stem == "main" {
            return None;
        }
        Some(stem.to_owned())
    } else {
        Some(first)
    }
}

/// The graph of top-level modules, and each file's references (for the rules that look
/// below the top level).
fn graph() -> (Graph, Vec<(PathBuf, BTreeSet<String>)>) {
    let mut files = Vec::new();
    rust_files(&src(), &mut files);
    files.sort();
    let mut graph = Graph::new();
    let mut per_file = Vec::new();
    for file in files {
        let Some(from) = top_module(&file) else {
            continue;
        };
        let refs = referenced_modules(&strip_comments(&fs::read_to_string(&file).unwrap()));
        let node = graph.entry(from.clone()).or_default();
        for to in &refs {
            if *to != from {
                node.entry(to.clone()).or_insert_with(|| file.clone());
            }
        }
        per_file.push((file, refs));
    }
    (graph, per_file)
}

fn show(file: &Path) -> String {
    file.strip_prefix(src().parent().unwrap())
        .unwrap_or(file)
        .display()
        .to_string()
}

/// Edges the rules forbid: `(from, to)` where `from` is a top-level module.
fn forbidden(from: &str, to: &str) -> bool {
    const LOW: [&str; 6] = ["numerics", "model", "scenario", "setup", "output", "cli"];
    match from {
        "physics" => to == "numerics",
        "grid" | "state" => LOW.contains(&to),
        "terminal" => true,
        _ => false,
    }
}

/// The `numerics` → `model` and `numerics` → `scenario` edges, which [`numerics_sees_no_model_nor_scenario`]
/// checks on their own (and the cycle check leaves out, so as not to report them
/// twice).
fn numerics_upward(from: &str, to: &str) -> bool {
    from == "numerics" && (to == "model" || to == "scenario")
}

/// A cycle of the graph, if there is one (depth-first search).
fn find_cycle(graph: &Graph) -> Option<Vec<String>> {
    fn visit(
        node: &str,
        graph: &Graph,
        state: &mut BTreeMap<String, u8>,
        stack: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        state.insert(node.to_owned(), 1);
        stack.push(node.to_owned());
        for to in graph.get(node).into_iter().flat_map(|m| m.keys()) {
            if numerics_upward(node, to) {
                continue;
            }
            match state.get(to.as_str()) {
                Some(1) => {
                    let start = stack.iter().position(|n| n == to).unwrap();
                    let mut cycle = stack[start..].to_vec();
                    cycle.push(to.clone());
                    return Some(cycle);
                }
                Some(_) => {}
                None => {
                    if let Some(c) = visit(to, graph, state, stack) {
                        return Some(c);
                    }
                }
            }
        }
        stack.pop();
        state.insert(node.to_owned(), 2);
        None
    }
    let mut state = BTreeMap::new();
    for node in graph.keys() {
        if !state.contains_key(node) {
            let mut stack = Vec::new();
            if let Some(c) = visit(node, graph, &mut state, &mut stack) {
                return Some(c);
            }
        }
    }
    None
}

#[test]
fn top_level_modules_import_each_other_without_a_cycle() {
    let (graph, _) = graph();
    assert!(graph.contains_key("numerics") && graph.contains_key("cli"));
    if let Some(cycle) = find_cycle(&graph) {
        let edges: Vec<String> = cycle
            .windows(2)
            .map(|w| format!("{} -> {} ({})", w[0], w[1], show(&graph[&w[0]][&w[1]])))
            .collect();
        panic!(
            "import cycle between top-level modules:\n  {}",
            edges.join("\n  ")
        );
    }
}

#[test]
fn forbidden_imports_between_layers() {
    let (graph, _) = graph();
    let bad: Vec<String> = graph
        .iter()
        .flat_map(|(from, tos)| {
            tos.iter()
                .filter(|(to, _)| forbidden(from, to))
                .map(move |(to, file)| format!("{from} -> {to} ({})", show(file)))
        })
        .collect();
    assert!(bad.is_empty(), "forbidden imports:\n  {}", bad.join("\n  "));
}

/// Names every file of `numerics` that imports `model` or `scenario` (the states live
/// in `state`, the grid in `grid`).
#[test]
fn numerics_sees_no_model_nor_scenario() {
    let (_, per_file) = graph();
    let bad: Vec<String> = per_file
        .iter()
        .filter(|(file, _)| top_module(file).as_deref() == Some("numerics"))
        .flat_map(|(file, refs)| {
            refs.iter()
                .filter(|to| numerics_upward("numerics", to))
                .map(move |to| format!("numerics -> {to} ({})", show(file)))
        })
        .collect();
    assert!(
        bad.is_empty(),
        "numerics imports upward:\n  {}",
        bad.join("\n  ")
    );
}

#[test]
fn the_reference_scanner_sees_groups_and_skips_comments() {
    let code = strip_comments(
        "use crate::{a::X, b, c::{d, e}};\n// crate::f\n/* crate::g */ let s = \"crate::h\"; \
         let q = '\"'; crate::i::j(); $crate::k; foo_crate::l;",
    );
    let refs: Vec<String> = referenced_modules(&code).into_iter().collect();
    assert_eq!(refs, ["a", "b", "c", "i"]);
}
