//! No module circles (issue 33): inside each crate, no module uses one that uses it back, however
//! long the way round. A module "uses" another where its code (comments and its test module left
//! out) names a path into it — `crate::a::b`, `super::x`, `self::x` — other than its own
//! submodules, which it contains rather than uses. So a newcomer can read the modules from the
//! leaves up, and a helper never lives in a module that imports its users.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The library and binary crates whose modules are checked.
const CRATES: &[&str] = &["scenes", "structures", "kernels", "harness", "reports"];

/// Every module of `crate_dir/src` by its path (`esvo::build`; the crate root is ""), with its file.
fn modules(crate_dir: &Path) -> BTreeMap<String, PathBuf> {
    let src = crate_dir.join("src");
    let files = tests::files_under(&src, &[], |path| path.extension().is_some_and(|e| e == "rs"));
    files
        .into_iter()
        .map(|path| {
            let relative = path.strip_prefix(&src).unwrap_or(&path).with_extension("");
            let mut parts: Vec<String> = relative.iter().map(|p| p.to_string_lossy().into_owned()).collect();
            if parts.last().is_some_and(|l| ["mod", "lib", "main"].contains(&l.as_str())) {
                parts.pop();
            }
            (parts.join("::"), path)
        })
        .collect()
}

/// The code of a module's text: comment lines dropped, and its unit-test module (`#[cfg(test)]`
/// followed by `mod tests`) cut off, since tests may use what they test from anywhere.
fn code(text: &str) -> String {
    let text = match text.find("#[cfg(test)]\nmod tests") {
        Some(at) => &text[..at],
        None => text,
    };
    text.lines().filter(|l| !l.trim_start().starts_with("//")).collect::<Vec<_>>().join("\n")
}

/// The identifiers of a `::` path starting at byte `at` of `text`.
fn path_at(text: &str, at: usize) -> Vec<&str> {
    let rest = &text[at..];
    let end = rest.find(|c: char| !(c.is_ascii_alphanumeric() || c == '_' || c == ':')).unwrap_or(rest.len());
    rest[..end].split("::").filter(|s| !s.is_empty()).collect()
}

/// The longest prefix of `path` that is a module, if any.
fn module_of(path: &[&str], modules: &BTreeMap<String, PathBuf>) -> Option<String> {
    (1..=path.len()).rev().map(|n| path[..n].join("::")).find(|m| modules.contains_key(m))
}

/// Whether `text[at..]` starts a path of its own (not the tail of `a::crate::…` or an identifier).
fn starts_path(text: &str, at: usize) -> bool {
    let before = text[..at].chars().next_back();
    !before.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_' || c == ':')
}

/// The modules `me` uses (its own submodules aside).
fn uses(me: &str, code: &str, modules: &BTreeMap<String, PathBuf>) -> BTreeSet<String> {
    let mine: Vec<&str> = if me.is_empty() { Vec::new() } else { me.split("::").collect() };
    let mut out = BTreeSet::new();
    for (at, _) in code.match_indices("crate::").filter(|(at, _)| starts_path(code, *at)) {
        if let Some(m) = module_of(&path_at(code, at + "crate::".len()), modules) {
            out.insert(m);
        }
    }
    for (at, _) in code.match_indices("super::").filter(|(at, _)| starts_path(code, *at)) {
        let path = path_at(code, at);
        let ups = path.iter().take_while(|p| **p == "super").count();
        let base = &mine[..mine.len().saturating_sub(ups)];
        let full: Vec<&str> = base.iter().copied().chain(path[ups..].iter().copied()).collect();
        if let Some(m) = module_of(&full, modules).or_else(|| Some(base.join("::"))) {
            out.insert(m);
        }
    }
    for (at, _) in code.match_indices("self::").filter(|(at, _)| starts_path(code, *at)) {
        let full: Vec<&str> = mine.iter().copied().chain(path_at(code, at).into_iter().skip(1)).collect();
        if let Some(m) = module_of(&full, modules) {
            out.insert(m);
        }
    }
    out.retain(|m| m != me && !(me.is_empty() || m.starts_with(&format!("{me}::"))));
    out
}

/// A circle through `from`, as the modules along it, if there is one.
fn circle(from: &str, graph: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    // Breadth first from `from`'s uses, back to `from`.
    let mut came_from: BTreeMap<&str, &str> = BTreeMap::new();
    let mut queue: std::collections::VecDeque<&str> = std::collections::VecDeque::new();
    for next in graph.get(from).into_iter().flatten() {
        came_from.entry(next).or_insert(from);
        queue.push_back(next);
    }
    while let Some(m) = queue.pop_front() {
        if m == from {
            let mut way = vec![from.to_string()];
            let mut at = came_from[from];
            while at != from {
                way.push(at.to_string());
                at = came_from[at];
            }
            way.push(from.to_string());
            way.reverse();
            return Some(way);
        }
        for next in graph.get(m).into_iter().flatten() {
            if !came_from.contains_key(next.as_str()) {
                came_from.insert(next, m);
                queue.push_back(next);
            }
        }
    }
    None
}

fn graph_of(crate_name: &str) -> BTreeMap<String, BTreeSet<String>> {
    let modules = modules(&Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(crate_name));
    modules
        .iter()
        .map(|(me, path)| (me.clone(), uses(me, &code(&std::fs::read_to_string(path).unwrap_or_default()), &modules)))
        .collect()
}

#[test]
fn no_module_uses_one_that_uses_it_back() {
    let mut circles = Vec::new();
    let mut edges = 0;
    for crate_name in CRATES {
        let graph = graph_of(crate_name);
        edges += graph.values().map(BTreeSet::len).sum::<usize>();
        let mut reported = BTreeSet::new();
        for me in graph.keys() {
            if reported.contains(me) {
                continue;
            }
            if let Some(way) = circle(me, &graph) {
                reported.extend(way.iter().cloned());
                circles.push(format!("{crate_name}: {}", way.join(" → ")));
            }
        }
    }
    assert!(edges > 100, "only {edges} uses found between modules: is the scan broken?");
    assert!(circles.is_empty(), "module circles:\n{}", circles.join("\n"));
}

/// The scan itself: it finds a circle made on purpose, and ignores comments and containment.
#[test]
fn the_scan_finds_a_circle_and_ignores_comments_and_submodules() {
    let modules: BTreeMap<String, PathBuf> =
        ["", "a", "a::inner", "b"].iter().map(|m| (m.to_string(), PathBuf::new())).collect();
    let a = uses("a", "use crate::b::Thing;\nuse self::inner::X;\n", &modules);
    assert_eq!(a, BTreeSet::from(["b".to_string()]), "a uses b; its own inner is contained");
    let b = uses("b", "fn f() { super::a::inner::go() }\n", &modules);
    assert_eq!(b, BTreeSet::from(["a::inner".to_string()]));
    let inner = uses("a::inner", "use super::super::b;\nlet x = some::crate::b;\n", &modules);
    assert_eq!(inner, BTreeSet::from(["b".to_string()]), "super::super is the crate root's b");
    let graph: BTreeMap<String, BTreeSet<String>> =
        [("a", a), ("b", b), ("a::inner", inner)].into_iter().map(|(k, v)| (k.to_string(), v)).collect();
    assert_eq!(circle("b", &graph), Some(vec!["b".into(), "a::inner".into(), "b".into()]));
    assert_eq!(circle("a", &graph), None, "a uses b, and b uses a's submodule, not a");
    let commented = code("// use crate::b;\nfn f() {}\n#[cfg(test)]\nmod tests { use crate::b; }\n");
    assert!(!commented.contains("crate::b"), "{commented}");
}
