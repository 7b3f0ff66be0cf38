//! The crate's layering, checked on its sources: the graph of top-level modules
//! (`src/<module>.rs` or `src/<module>/`) built from their `crate::<module>` references
//! (use statements and paths, comments left out)
//!
//! - has no cycle (every cycle is listed, edge by edge, with a file that makes each edge);
//! - points downwards in the order docs/architecture.md documents ("Which module may
//!   import which": one line per layer, the highest first); every top-level module is
//!   in that list once, and an upward edge fails unless [`UPWARD_TODAY`] names it;
//! - has none of a few edges forbidden outright (below);
//!
//! and inside each top-level module that is a directory, its children (`src/<m>/<c>.rs`,
//! `src/<m>/<c>/`) import each other (through `crate::<m>::<c>`, `super::<c>`, …; unit
//! tests left out) without a cycle beyond those [`CHILD_CYCLES_TODAY`] lists.
//!
//! The edges forbidden outright:
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

/// The `numerics` → `model` and `numerics` → `scenario` edges, which
/// [`numerics_sees_no_model_nor_scenario`] names file by file.
fn numerics_upward(from: &str, to: &str) -> bool {
    from == "numerics" && (to == "model" || to == "scenario")
}

/// The nodes `from` reaches along the graph's edges (itself only through a cycle).
fn reachable(graph: &Graph, from: &str) -> BTreeSet<String> {
    let mut seen = BTreeSet::new();
    let mut todo: Vec<&str> = vec![from];
    while let Some(node) = todo.pop() {
        for to in graph.get(node).into_iter().flat_map(|m| m.keys()) {
            if seen.insert(to.clone()) {
                todo.push(to);
            }
        }
    }
    seen
}

/// The cycles of a graph, one entry per strongly connected component of more than one
/// module: its modules (sorted) and the shortest cycle through the first of them
/// (breadth-first), the first module repeated at its end.
type Cycle = (Vec<String>, Vec<String>);

fn cycles(graph: &Graph) -> Vec<Cycle> {
    let reach: BTreeMap<&str, BTreeSet<String>> = graph
        .keys()
        .map(|n| (n.as_str(), reachable(graph, n)))
        .collect();
    let mut done = BTreeSet::new();
    let mut found = Vec::new();
    for (&node, from_node) in &reach {
        if done.contains(node) || !from_node.contains(node) {
            continue;
        }
        let component: BTreeSet<&str> = from_node
            .iter()
            .map(String::as_str)
            .filter(|other| reach.get(other).is_some_and(|r| r.contains(node)))
            .collect();
        done.extend(component.iter().copied());
        // Breadth-first from `node` inside the component, back to `node`.
        let mut parent: BTreeMap<&str, &str> = BTreeMap::new();
        let mut queue = std::collections::VecDeque::from([node]);
        'search: while let Some(at) = queue.pop_front() {
            for to in graph[at].keys().map(String::as_str) {
                if to == node {
                    let mut cycle = vec![node.to_owned()];
                    let mut back = at;
                    while back != node {
                        cycle.push(back.to_owned());
                        back = parent[back];
                    }
                    cycle.push(node.to_owned());
                    cycle.reverse();
                    let members = component.iter().map(|m| m.to_string()).collect();
                    found.push((members, cycle));
                    break 'search;
                }
                if component.contains(to) && !parent.contains_key(to) {
                    parent.insert(to, at);
                    queue.push_back(to);
                }
            }
        }
    }
    found
}

/// The cycles of `graph` whose modules `known` does not list, each described by its
/// shortest cycle and every edge between its modules, with a file that makes each.
fn new_cycles(graph: &Graph, known: &[&[&str]]) -> Vec<String> {
    cycles(graph)
        .into_iter()
        .filter(|(members, _)| !known.iter().any(|k| k.iter().eq(members.iter())))
        .map(|(members, cycle)| {
            let edges: Vec<String> = members
                .iter()
                .flat_map(|from| {
                    graph[from]
                        .iter()
                        .filter(|(to, _)| members.contains(to))
                        .map(move |(to, file)| format!("{from} -> {to} ({})", show(file)))
                })
                .collect();
            format!(
                "{} (every edge between them: {})",
                cycle.join(" -> "),
                edges.join(", ")
            )
        })
        .collect()
}

/// The modules of each cycle between top-level modules today, with why. None today: a
/// new cycle fails the test.
const CYCLES_TODAY: &[(&[&str], &str)] = &[];

#[test]
fn top_level_modules_import_each_other_without_a_cycle() {
    let (graph, _) = graph();
    assert!(graph.contains_key("numerics") && graph.contains_key("cli"));
    let known: Vec<&[&str]> = CYCLES_TODAY.iter().map(|(c, _)| *c).collect();
    let new = new_cycles(&graph, &known);
    assert!(
        new.is_empty(),
        "import cycles between top-level modules:\n  {}",
        new.join("\n  ")
    );
}

#[test]
fn the_cycle_finder_lists_every_cycle_and_nothing_else() {
    let mut graph = Graph::new();
    for (from, to) in [
        ("a", "b"),
        ("b", "c"),
        ("c", "a"),
        ("c", "d"),
        ("d", "e"),
        ("e", "d"),
        ("f", "a"),
    ] {
        graph
            .entry(from.into())
            .or_default()
            .insert(to.into(), PathBuf::new());
        graph.entry(to.into()).or_default();
    }
    let strings = |v: &[&str]| v.iter().map(|m| m.to_string()).collect::<Vec<_>>();
    assert_eq!(
        cycles(&graph),
        [
            (strings(&["a", "b", "c"]), strings(&["a", "b", "c", "a"])),
            (strings(&["d", "e"]), strings(&["d", "e", "d"]))
        ]
    );
    // A second cycle through a and c joins the same component.
    graph
        .get_mut("a")
        .unwrap()
        .insert("c".into(), PathBuf::new());
    assert_eq!(cycles(&graph)[0].0, strings(&["a", "b", "c"]));
    assert_eq!(
        new_cycles(&graph, &[&["a", "b", "c"], &["d", "e"]]),
        [""; 0]
    );
    assert_eq!(new_cycles(&graph, &[&["a", "b", "c"]]).len(), 1);
    graph.get_mut("c").unwrap().remove("a");
    graph.get_mut("e").unwrap().remove("d");
    assert!(cycles(&graph).is_empty());
}

/// The documented layers, highest first: in docs/architecture.md, the first code block
/// after the heading "Which module may import which", one layer a line, its modules
/// (comma-separated) before the first run of two spaces, a description after it (an
/// indented line continues the description).
fn documented_layers(doc: &str) -> Vec<Vec<String>> {
    const HEADING: &str = "### Which module may import which";
    let after = &doc[doc
        .find(HEADING)
        .unwrap_or_else(|| panic!("docs/architecture.md has no heading {HEADING:?}"))..];
    let block = after
        .split("```")
        .nth(1)
        .unwrap_or_else(|| panic!("no code block after {HEADING:?}"));
    block
        .lines()
        .skip(1) // the rest of the opening fence's line
        .filter(|l| !l.trim().is_empty() && !l.starts_with(' '))
        .map(|line| {
            let names = line.split("  ").next().unwrap();
            names
                .split(',')
                .map(|m| m.trim().to_owned())
                .filter(|m| !m.is_empty())
                .collect()
        })
        .collect()
}

/// Each documented module's layer, 0 the highest.
fn layer_of(layers: &[Vec<String>]) -> BTreeMap<String, usize> {
    let mut of = BTreeMap::new();
    for (k, layer) in layers.iter().enumerate() {
        for m in layer {
            assert!(
                of.insert(m.clone(), k).is_none(),
                "docs/architecture.md lists {m} twice in the module order"
            );
        }
    }
    of
}

fn documented_order() -> BTreeMap<String, usize> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/architecture.md");
    layer_of(&documented_layers(&fs::read_to_string(path).unwrap()))
}

/// Every top-level module of the crate (`src/<m>.rs`, `src/<m>/`), lib.rs and main.rs
/// aside.
fn top_level_modules() -> BTreeSet<String> {
    let mut files = Vec::new();
    rust_files(&src(), &mut files);
    files.iter().filter_map(|f| top_module(f)).collect()
}

/// Upward edges (`from` in a lower layer than `to`) the code has today, with why.
/// None today: a new upward edge fails the test. An entry names an edge to remove, not
/// a permission; the test fails when the edge is gone so that the entry goes too.
const UPWARD_TODAY: &[(&str, &str, &str)] = &[];

#[test]
fn the_documented_order_lists_every_top_level_module_once() {
    let order = documented_order();
    let documented: BTreeSet<String> = order.keys().cloned().collect();
    let modules = top_level_modules();
    let missing: Vec<&String> = modules.difference(&documented).collect();
    let gone: Vec<&String> = documented.difference(&modules).collect();
    assert!(
        missing.is_empty() && gone.is_empty(),
        "docs/architecture.md's module order (\"Which module may import which\") misses \
         {missing:?} and lists {gone:?}, which src/ does not have"
    );
}

#[test]
fn no_module_imports_a_higher_layer() {
    let order = documented_order();
    let (graph, _) = graph();
    let mut upward = Vec::new();
    for (from, tos) in &graph {
        for (to, file) in tos {
            let (Some(&f), Some(&t)) = (order.get(from), order.get(to)) else {
                continue; // the test above names the module the order misses
            };
            if t < f {
                upward.push((from.as_str(), to.as_str(), file));
            }
        }
    }
    let new: Vec<String> = upward
        .iter()
        .filter(|(f, t, _)| !UPWARD_TODAY.iter().any(|(a, b, _)| a == f && b == t))
        .map(|(f, t, file)| format!("{f} -> {t} ({})", show(file)))
        .collect();
    assert!(
        new.is_empty(),
        "imports upward in docs/architecture.md's module order:\n  {}",
        new.join("\n  ")
    );
    let stale: Vec<String> = UPWARD_TODAY
        .iter()
        .filter(|(a, b, _)| !upward.iter().any(|(f, t, _)| a == f && b == t))
        .map(|(a, b, _)| format!("{a} -> {b}"))
        .collect();
    assert!(
        stale.is_empty(),
        "UPWARD_TODAY names edges the code no longer has (remove them): {stale:?}"
    );
}

#[test]
fn the_order_is_read_from_the_code_block_after_the_heading() {
    let doc = "# A\n```\nz  not this block\n```\n### Which module may import which\n\n\
               Downwards:\n\n```\ncli, runner  the commands\n\nmodel\ngrid, physics   \
               cells;\n                laws, constants\n```\n```\nother\n```\n";
    let layers = documented_layers(doc);
    assert_eq!(
        layers,
        [
            vec!["cli", "runner"],
            vec!["model"],
            vec!["grid", "physics"]
        ]
    );
    let of = layer_of(&layers);
    assert_eq!((of["runner"], of["model"], of["physics"]), (0, 1, 2));
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

/// A file's module path: `src/model/granular/mod.rs` → `["model", "granular"]`.
fn module_path(file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(src()).unwrap().with_extension("");
    let mut path: Vec<String> = rel
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    if path.last().is_some_and(|last| last == "mod") {
        path.pop();
    }
    path
}

/// The identifiers of a path `a::b::c` at the start of `s` (none if `s` starts with no
/// identifier).
fn path_segments(s: &str) -> Vec<String> {
    let mut segments = Vec::new();
    let mut rest = s.trim_start();
    loop {
        let ident: String = rest.chars().take_while(|&c| is_ident(c)).collect();
        if ident.is_empty() {
            break;
        }
        rest = &rest[ident.len()..];
        segments.push(ident);
        match rest.strip_prefix("::") {
            Some(r) if r.starts_with(|c: char| is_ident(c)) => rest = r,
            _ => break,
        }
    }
    segments
}

/// The paths a file's code names through `crate::`, `super::` and `self::`, resolved
/// to paths from the crate root against the module each one is written in: `here`, or
/// an inline `mod name { … }` in it. In a group (`super::{a::X, b}`) each item counts.
/// Paths in an inline `mod tests` are left out.
fn referenced_paths(code: &str, here: &[String]) -> Vec<Vec<String>> {
    let b = code.as_bytes();
    let mut found = Vec::new();
    let mut depth = 0usize;
    let mut inline: Vec<(String, usize)> = Vec::new(); // (name, depth inside its braces)
    let mut pending_mod: Option<String> = None;
    let mut i = 0;
    while i < b.len() {
        let boundary = i == 0 || !(is_ident(b[i - 1] as char) || b[i - 1] == b'$');
        match b[i] {
            b'{' => {
                depth += 1;
                if let Some(name) = pending_mod.take() {
                    inline.push((name, depth));
                }
                i += 1;
                continue;
            }
            b'}' => {
                if inline.last().is_some_and(|(_, d)| *d == depth) {
                    inline.pop();
                }
                depth = depth.saturating_sub(1);
                i += 1;
                continue;
            }
            b';' => pending_mod = None, // `mod name;`: a file of its own
            _ => {}
        }
        let rest = &code[i..];
        if boundary && rest.starts_with("mod ") {
            pending_mod = path_segments(&rest[4..]).into_iter().next();
            i += 4;
            continue;
        }
        let starts = ["crate::", "super::", "self::"];
        if !boundary
            || !starts.iter().any(|s| rest.starts_with(s))
            || i >= 2 && &b[i - 2..i] == b"::"
        {
            i += rest.chars().next().map_or(1, char::len_utf8);
            continue;
        }
        if inline.iter().any(|(name, _)| name == "tests") {
            // A file's unit tests may reach into any sibling: no dependency of the code.
            i += 1;
            continue;
        }
        let mut base: Vec<String> = here
            .iter()
            .cloned()
            .chain(inline.iter().map(|(n, _)| n.clone()))
            .collect();
        let mut tail = rest;
        loop {
            if let Some(r) = tail.strip_prefix("crate::") {
                base.clear();
                tail = r;
            } else if let Some(r) = tail.strip_prefix("super::") {
                base.pop();
                tail = r;
            } else if let Some(r) = tail.strip_prefix("self::") {
                tail = r;
            } else {
                break;
            }
        }
        let prefix = path_segments(tail);
        let after = &tail[prefix
            .iter()
            .map(|s| s.len() + 2)
            .sum::<usize>()
            .saturating_sub(2)..];
        let group = if prefix.is_empty() {
            tail.trim_start().strip_prefix('{')
        } else {
            after.strip_prefix("::{")
        };
        let mut push = |item: &str| {
            let segments = path_segments(item);
            if segments
                .first()
                .is_some_and(|s| s != "self" && s != "super")
            {
                let mut full = base.clone();
                full.extend(prefix.iter().cloned());
                full.extend(segments);
                found.push(full);
            }
        };
        match group {
            Some(group) => {
                let mut level = 0;
                let mut item = String::new();
                for c in group.chars() {
                    match c {
                        '{' => level += 1,
                        '}' if level == 0 => break,
                        '}' => level -= 1,
                        ',' if level == 0 => {
                            push(&item);
                            item.clear();
                            continue;
                        }
                        _ => {}
                    }
                    item.push(c);
                }
                push(&item);
            }
            None if !prefix.is_empty() => {
                let mut full = base.clone();
                full.extend(prefix.iter().cloned());
                found.push(full);
            }
            None => {}
        }
        i += rest.find("::").unwrap() + 2;
    }
    found
}

/// For each top-level module that is a directory, the graph of its children
/// (`src/<m>/<child>.rs`, `src/<m>/<child>/`; `mod.rs` is the module itself) built from
/// the paths each child's files name in a sibling.
fn child_graphs() -> BTreeMap<String, Graph> {
    let mut files = Vec::new();
    rust_files(&src(), &mut files);
    files.sort();
    let mut children: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for file in &files {
        let path = module_path(file);
        if path.len() >= 2 {
            children
                .entry(path[0].clone())
                .or_default()
                .insert(path[1].clone());
        }
    }
    let mut graphs: BTreeMap<String, Graph> = BTreeMap::new();
    for file in &files {
        let path = module_path(file);
        if path.len() < 2 {
            continue;
        }
        let (top, child) = (&path[0], &path[1]);
        let code = strip_comments(&fs::read_to_string(file).unwrap());
        let node = graphs
            .entry(top.clone())
            .or_default()
            .entry(child.clone())
            .or_default();
        for full in referenced_paths(&code, &path) {
            if full.len() >= 2
                && full[0] == *top
                && full[1] != *child
                && children[top].contains(&full[1])
            {
                node.entry(full[1].clone()).or_insert_with(|| file.clone());
            }
        }
    }
    graphs
}

/// The cycles between the children of a top-level module today: the module, the
/// cycle's children, why they need each other. Each is a knot to untie (the shared
/// part moved into a child both import), not a permission: a new cycle, or a child
/// joining one of these, fails the test.
const CHILD_CYCLES_TODAY: &[(&str, &[&str], &str)] = &[
    (
        "gis",
        &["release", "validity"],
        "validity checks release's Polygon and Ring (with release::ring_area); release \
         asks validity::invalid_reason of every polygon it reads",
    ),
    (
        "results",
        &["avaframe", "export"],
        "avaframe names export's map fields (export::Field, MAP_FIELDS) in AvaFrame's \
         layout; export calls avaframe for that layout's files",
    ),
    (
        "scenario",
        &["compiled", "profile", "validate"],
        "compiled calls profile's expression functions (unary_function, noise); profile \
         builds Compiled expressions and checks raster cells against \
         validate::MIN_RELATIVE_DX; validate builds the profiles",
    ),
];

#[test]
fn children_of_a_module_import_each_other_without_a_new_cycle() {
    let graphs = child_graphs();
    assert!(graphs["numerics"].contains_key("hydrostatic"));
    let mut new = Vec::new();
    for (top, graph) in &graphs {
        let known: Vec<&[&str]> = CHILD_CYCLES_TODAY
            .iter()
            .filter(|(t, _, _)| t == top)
            .map(|(_, c, _)| *c)
            .collect();
        new.extend(
            new_cycles(graph, &known)
                .into_iter()
                .map(|c| format!("{top}: {c}")),
        );
    }
    assert!(
        new.is_empty(),
        "import cycles between the children of a module:\n  {}",
        new.join("\n  ")
    );
    let stale: Vec<String> = CHILD_CYCLES_TODAY
        .iter()
        .filter(|(top, known, _)| {
            !cycles(&graphs[*top])
                .iter()
                .any(|(members, _)| known.iter().eq(members.iter()))
        })
        .map(|(top, known, _)| format!("{top}: {known:?}"))
        .collect();
    assert!(
        stale.is_empty(),
        "CHILD_CYCLES_TODAY names cycles the code no longer has (remove them): {stale:?}"
    );
}

#[test]
fn paths_resolve_against_the_module_they_are_written_in() {
    let here: Vec<String> = ["scenario", "validate", "granular"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    let code =
        "use super::{check::finite, self, Scenario};\nuse crate::grid::{line::Line, Grid};\n\
                let x = super::super::profile::f(self::g());\nmod inner { use super::h; }\n\
                mod tests { use crate::sweep::X; }\nx::super::y;";
    let found: Vec<String> = referenced_paths(code, &here)
        .iter()
        .map(|p| p.join("::"))
        .collect();
    assert_eq!(
        found,
        [
            "scenario::validate::check::finite",
            "scenario::validate::Scenario",
            "grid::line::Line",
            "grid::Grid",
            "scenario::profile::f",
            "scenario::validate::granular::g",
            "scenario::validate::granular::h",
        ]
    );
}
