//! The crate's layer order, written once, and the tests that hold the source to it: a module imports
//! only modules before it in [`LAYERS`], and no chain of imports between files leaves a folder and
//! comes back. Both read the `crate::` / `super::` paths of every file under src/ (comments skipped,
//! test modules included).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Top-level modules, lowest first: dependency-free helpers, the Vulkan plumbing, the CPU scene, its
/// GPU copy, acceleration data, PRT (it traces the CPU BVH and packs for the GPU), the frame, and the
/// commands, report and viewer built on them.
pub const LAYERS: &[&str] = &[
    "progress",
    "par",
    "disk_cache",
    "csv",
    "image_diff",
    "vk",
    "scene",
    "gpu",
    "accel",
    "prt",
    "render",
    "app",
    "report",
    "viewer",
];

/// A source file: its path under src/ and its module path from the crate root.
struct Source {
    file: String,
    module: Vec<String>,
    text: String,
    /// The text before an inline `mod tests { .. }` (at a file's end by convention): the module's own
    /// imports, without the tests' (whose `super` is the file itself, not its parent).
    code: String,
}

fn sources() -> Vec<Source> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut out = Vec::new();
    let mut stack = vec![root.clone()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") {
                let rel = path.strip_prefix(&root).unwrap().to_string_lossy().replace('\\', "/");
                if rel == "main.rs" {
                    continue; // the binary, above everything
                }
                let mut module: Vec<String> =
                    rel.trim_end_matches(".rs").split('/').map(String::from).collect();
                if module.last().is_some_and(|m| m == "mod" || m == "lib") {
                    module.pop();
                }
                let text = strip_comments(&std::fs::read_to_string(&path).unwrap());
                let code = text.split("#[cfg(test)]\nmod tests {").next().unwrap_or_default().to_string();
                out.push(Source { file: rel, module, text, code });
            }
        }
    }
    out.sort_by(|a, b| a.file.cmp(&b.file));
    out
}

/// The text without `//` comments (outside string literals; good enough here: no string holds an
/// unbalanced quote before a `//`).
fn strip_comments(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for line in text.lines() {
        let mut in_str = false;
        let mut prev = ' ';
        let mut cut = line.len();
        for (i, c) in line.char_indices() {
            if c == '"' && prev != '\\' {
                in_str = !in_str;
            }
            if !in_str && c == '/' && prev == '/' {
                cut = i - 1;
                break;
            }
            prev = c;
        }
        out.push_str(&line[..cut]);
        out.push('\n');
    }
    out
}

fn is_ident(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_'
}

/// Every path a file names: `use` trees expanded (`a::{b, c::d}` gives `a::b` and `a::c::d`) and paths
/// in code starting with crate, super or self. Segments are identifiers; a glob or `self` ends a path.
fn paths(text: &str) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    let bytes: Vec<char> = text.chars().collect();
    let mut i = 0;
    while i < bytes.len() {
        let starts_word = i == 0 || !is_ident(bytes[i - 1]) && bytes[i - 1] != ':';
        let word: String = bytes[i..].iter().take_while(|c| is_ident(**c)).collect();
        // A `use` item starts its line (after a visibility), which keeps the word in strings and prose out.
        let line_start = bytes[..i].iter().rposition(|c| *c == '\n').map_or(0, |p| p + 1);
        let before: String = bytes[line_start..i].iter().collect();
        let item_start = matches!(before.trim(), "" | "pub" | "pub(crate)" | "pub(super)");
        if item_start && word == "use" && bytes.get(i + 3).is_some_and(|c| c.is_whitespace()) {
            let end = bytes[i..].iter().position(|c| *c == ';').map_or(bytes.len(), |p| i + p);
            let tree: String = bytes[i + 3..end].iter().collect();
            let tree = tree.split_whitespace().collect::<Vec<_>>().join(" ");
            use_tree(&[], &tree, &mut out);
            i = end;
        } else if starts_word && matches!(word.as_str(), "crate" | "super" | "self") {
            let path: String = bytes[i..].iter().take_while(|c| is_ident(**c) || **c == ':').collect();
            // `pub(super)` and a method's `self` name no path.
            if path.contains("::") {
                out.push(path.split("::").filter(|s| !s.is_empty()).map(String::from).collect());
            }
            i += path.len();
        } else {
            i += word.len().max(1);
        }
    }
    out
}

fn use_tree(prefix: &[String], tree: &str, out: &mut Vec<Vec<String>>) {
    let mut depth = 0;
    let mut start = 0;
    let mut items = Vec::new();
    for (i, c) in tree.char_indices() {
        match c {
            '{' => depth += 1,
            '}' => depth -= 1,
            ',' if depth == 0 => {
                items.push(&tree[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    items.push(&tree[start..]);
    let segments = |s: &str| -> Vec<String> {
        s.split("::").map(str::trim).filter(|s| !s.is_empty() && *s != "*").map(String::from).collect()
    };
    for item in items.into_iter().map(str::trim).filter(|s| !s.is_empty()) {
        let item = item.split(" as ").next().unwrap();
        if let Some(open) = item.find('{') {
            let head = segments(&item[..open]);
            let close = item.rfind('}').filter(|c| *c > open).unwrap_or(item.len());
            let inner = &item[open + 1..close];
            use_tree(&[prefix, &head[..]].concat(), inner, out);
        } else {
            out.push([prefix, &segments(item)[..]].concat());
        }
    }
}

/// The file of a module path, if it is a module (not an item in one).
fn module_file(files: &BTreeMap<Vec<String>, String>, module: &[String]) -> Option<String> {
    files.get(module).cloned()
}

/// The file a path leads into: the deepest module on it.
fn resolve(files: &BTreeMap<Vec<String>, String>, from: &Source, path: &[String]) -> Option<String> {
    let absolute: Vec<String> = match path.first().map(String::as_str) {
        Some("crate") => path[1..].to_vec(),
        Some("super") => {
            let mut base = from.module.clone();
            let mut rest = path;
            while rest.first().is_some_and(|s| s == "super") {
                base.pop();
                rest = &rest[1..];
            }
            [base, rest.to_vec()].concat()
        }
        Some("self") => [from.module.clone(), path[1..].to_vec()].concat(),
        Some(first) => {
            // A path relative to this module's children (`use passes::x`).
            let child = [from.module.clone(), vec![first.to_string()]].concat();
            module_file(files, &child)?;
            [from.module.clone(), path.to_vec()].concat()
        }
        None => return None,
    };
    (1..=absolute.len()).rev().find_map(|n| module_file(files, &absolute[..n]))
}

/// A module's folder: the directory its children live in (`app.rs` and `app/x.rs` are one folder, as
/// are `render/mod.rs` and `render/x.rs`).
fn folder(module: &[String], file: &str) -> String {
    let dir = Path::new("src").join(file);
    let has_children = file.ends_with("mod.rs")
        || Path::new(env!("CARGO_MANIFEST_DIR")).join(dir.with_extension("")).is_dir();
    if has_children {
        module.join("/")
    } else {
        module[..module.len().saturating_sub(1)].join("/")
    }
}

/// Every file's imports of other files.
fn file_graph(sources: &[Source]) -> BTreeMap<String, BTreeSet<String>> {
    let files: BTreeMap<Vec<String>, String> =
        sources.iter().map(|s| (s.module.clone(), s.file.clone())).collect();
    let mut graph = BTreeMap::new();
    for s in sources {
        let targets: BTreeSet<String> =
            paths(&s.code).iter().filter_map(|p| resolve(&files, s, p)).filter(|t| *t != s.file).collect();
        graph.insert(s.file.clone(), targets);
    }
    graph
}

/// Strongly connected components of more than one file (Tarjan).
fn cycles(graph: &BTreeMap<String, BTreeSet<String>>) -> Vec<Vec<String>> {
    struct State<'a> {
        graph: &'a BTreeMap<String, BTreeSet<String>>,
        index: BTreeMap<&'a str, usize>,
        low: BTreeMap<&'a str, usize>,
        stack: Vec<&'a str>,
        on_stack: BTreeSet<&'a str>,
        out: Vec<Vec<String>>,
    }
    fn visit<'a>(st: &mut State<'a>, v: &'a str) {
        let n = st.index.len();
        st.index.insert(v, n);
        st.low.insert(v, n);
        st.stack.push(v);
        st.on_stack.insert(v);
        for w in st.graph.get(v).into_iter().flatten() {
            if !st.index.contains_key(w.as_str()) {
                visit(st, w);
                let lw = st.low[w.as_str()];
                st.low.entry(v).and_modify(|l| *l = (*l).min(lw));
            } else if st.on_stack.contains(w.as_str()) {
                let iw = st.index[w.as_str()];
                st.low.entry(v).and_modify(|l| *l = (*l).min(iw));
            }
        }
        if st.low[v] == st.index[v] {
            let mut comp = Vec::new();
            while let Some(w) = st.stack.pop() {
                st.on_stack.remove(w);
                comp.push(w.to_string());
                if w == v {
                    break;
                }
            }
            if comp.len() > 1 {
                comp.sort();
                st.out.push(comp);
            }
        }
    }
    let mut st = State {
        graph,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on_stack: BTreeSet::new(),
        out: Vec::new(),
    };
    for v in graph.keys() {
        if !st.index.contains_key(v.as_str()) {
            visit(&mut st, v);
        }
    }
    st.out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn layer(name: &str) -> Option<usize> {
        LAYERS.iter().position(|l| *l == name)
    }

    #[test]
    fn every_top_level_module_has_a_layer() {
        let lib =
            std::fs::read_to_string(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("src/lib.rs")).unwrap();
        let declared: Vec<&str> = lib
            .lines()
            .filter_map(|l| l.strip_prefix("pub mod ").and_then(|m| m.strip_suffix(';')))
            .collect();
        assert!(declared.len() >= LAYERS.len(), "lib.rs declares {declared:?}");
        for m in declared {
            assert!(layer(m).is_some(), "src/lib.rs: module `{m}` is missing from layering::LAYERS");
        }
    }

    #[test]
    fn no_module_imports_a_layer_above_its_own() {
        let mut upward = Vec::new();
        for s in sources() {
            let Some(own) = s.module.first().and_then(|m| layer(m)) else { continue };
            for p in paths(&s.text).iter().filter(|p| p.first().is_some_and(|f| f == "crate")) {
                if let Some(target) = p.get(1).and_then(|t| layer(t)) {
                    if target > own {
                        upward.push(format!("src/{}: crate::{}", s.file, p[1..].join("::")));
                    }
                }
            }
        }
        upward.sort();
        upward.dedup();
        assert!(upward.is_empty(), "imports up a layer (order: {LAYERS:?}):\n{}", upward.join("\n"));
    }

    #[test]
    fn no_import_cycle_leaves_a_folder() {
        let sources = sources();
        let folder_of: BTreeMap<&str, String> =
            sources.iter().map(|s| (s.file.as_str(), folder(&s.module, &s.file))).collect();
        let graph = file_graph(&sources);
        let mut report = Vec::new();
        for cycle in cycles(&graph) {
            let folders: BTreeSet<&String> = cycle.iter().map(|f| &folder_of[f.as_str()]).collect();
            if folders.len() > 1 {
                // The imports that leave a folder inside the cycle: where to cut it.
                let members: BTreeSet<&String> = cycle.iter().collect();
                report.push(format!("cycle of {} files through {folders:?}:", cycle.len()));
                for a in &cycle {
                    for b in graph[a].iter().filter(|b| members.contains(b)) {
                        if folder_of[a.as_str()] != folder_of[b.as_str()] {
                            report.push(format!("  {a} -> {b}"));
                        }
                    }
                }
            }
        }
        assert!(report.is_empty(), "import cycles across folders:\n{}", report.join("\n"));
    }

    /// The parser and the cycle finder on known input, so a parser that finds nothing cannot pass the two
    /// checks above.
    #[test]
    fn the_checks_see_imports_and_cycles() {
        let text = strip_comments(
            "use crate::{gpu::shared::{A, B}, vk};\n// use crate::report;\nlet x = super::super::y::Z;\n\
             pub use passes::{self, x as y};",
        );
        let p = paths(&text);
        let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>();
        assert!(p.contains(&s(&["crate", "gpu", "shared", "A"])), "{p:?}");
        assert!(p.contains(&s(&["crate", "vk"])), "{p:?}");
        assert!(p.contains(&s(&["super", "super", "y", "Z"])), "{p:?}");
        assert!(p.contains(&s(&["passes", "x"])), "{p:?}");
        assert!(!p.iter().any(|x| x.contains(&"report".to_string())), "a comment was read: {p:?}");
        let g: BTreeMap<String, BTreeSet<String>> = [
            ("a/x.rs", &["b/y.rs"][..]),
            ("b/y.rs", &["a/z.rs"][..]),
            ("a/z.rs", &["a/x.rs"][..]),
            ("c.rs", &["a/x.rs"][..]),
        ]
        .iter()
        .map(|(k, v)| (k.to_string(), v.iter().map(|s| s.to_string()).collect()))
        .collect();
        assert_eq!(cycles(&g), vec![s(&["a/x.rs", "a/z.rs", "b/y.rs"])]);
        // The real tree: the graph reaches across layers (so it is read).
        let graph = file_graph(&sources());
        assert!(graph["render/mod.rs"].contains("gpu/mod.rs"), "{:?}", graph["render/mod.rs"]);
        assert!(
            graph["render/passes/mod.rs"].contains("render/frame.rs"),
            "{:?}",
            graph["render/passes/mod.rs"]
        );
    }
}
