//! The bridge's modules import each other without a circle, and its groups only downwards:
//! `session` -> `companion` -> `wire` (read from the sources, test modules excluded).

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Module path (e.g. `session::flight`) -> the bridge modules it names outside its tests and comments.
fn bridge_imports() -> BTreeMap<String, BTreeSet<String>> {
    let root = super::repo().join("src/bridge");
    let mut files = Vec::new();
    collect(&root, &mut files);
    let modules: BTreeSet<String> = files.iter().map(|p| module_of(&root, p)).collect();
    let mut out = BTreeMap::new();
    for p in &files {
        let name = module_of(&root, p);
        let text = std::fs::read_to_string(p).expect("read source");
        let code: String = text
            .split("#[cfg(test)]")
            .next()
            .unwrap_or("")
            .lines()
            .filter(|l| !l.trim_start().starts_with("//"))
            .collect::<Vec<_>>()
            .join("\n");
        let group = name.split_once("::").map(|(g, _)| g.to_string());
        let mut deps = BTreeSet::new();
        for (prefix, base) in [("crate::bridge::", None), ("super::", group.as_deref())] {
            for (i, _) in code.match_indices(prefix) {
                // `super::super::` and `x::super::` are not this module's own sibling paths.
                if prefix == "super::" && code[..i].ends_with("::") {
                    continue;
                }
                let rest = &code[i + prefix.len()..];
                let mut parts = rest.split("::").map(|s| {
                    s.chars()
                        .take_while(|c| c.is_alphanumeric() || *c == '_')
                        .collect::<String>()
                });
                let first = parts.next().unwrap_or_default();
                let second = parts.next().unwrap_or_default();
                let candidates = match (prefix, base) {
                    ("super::", Some(g)) => vec![format!("{g}::{first}"), g.to_string()],
                    ("super::", None) => vec![first.clone(), "bridge".into()],
                    _ => vec![format!("{first}::{second}"), first.clone()],
                };
                if let Some(dep) = candidates.into_iter().find(|c| modules.contains(c))
                    && dep != name
                {
                    deps.insert(dep);
                }
            }
        }
        out.insert(name, deps);
    }
    out
}

fn collect(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    for e in std::fs::read_dir(dir).expect("read dir").flatten() {
        let p = e.path();
        if p.is_dir() {
            collect(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

fn module_of(root: &Path, p: &Path) -> String {
    let rel = p.strip_prefix(root).expect("under root").with_extension("");
    let parts: Vec<String> = rel
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .filter(|c| c != "mod")
        .collect();
    if parts.is_empty() {
        "bridge".into()
    } else {
        parts.join("::")
    }
}

fn rank(module: &str) -> Option<u8> {
    match module.split("::").next() {
        Some("wire") => Some(0),
        Some("companion") => Some(1),
        Some("session") => Some(2),
        _ => None,
    }
}

#[test]
fn bridge_groups_import_only_downwards() {
    let graph = bridge_imports();
    assert!(
        graph.contains_key("session::flight") && graph.contains_key("wire::link"),
        "{graph:?}"
    );
    for (m, deps) in &graph {
        for d in deps {
            if let (Some(a), Some(b)) = (rank(m), rank(d)) {
                assert!(a >= b, "{m} (a lower group) imports {d}");
            }
        }
    }
}

/// A circle in `graph`, as the path that closes it, if there is one.
fn find_circle(graph: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    // Depth-first search with colours: reaching a module still on the path again closes a circle.
    fn visit(
        m: &str,
        g: &BTreeMap<String, BTreeSet<String>>,
        done: &mut BTreeSet<String>,
        path: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        path.push(m.to_string());
        for d in g.get(m).into_iter().flatten() {
            if path.contains(d) {
                let mut circle = path.clone();
                circle.push(d.clone());
                return Some(circle);
            }
            if !done.contains(d)
                && let Some(c) = visit(d, g, done, path)
            {
                return Some(c);
            }
        }
        path.pop();
        done.insert(m.to_string());
        None
    }
    let mut done = BTreeSet::new();
    graph.keys().find_map(|m| {
        if done.contains(m) {
            None
        } else {
            visit(m, graph, &mut done, &mut Vec::new())
        }
    })
}

#[test]
fn bridge_has_no_import_circle() {
    let graph = bridge_imports();
    if let Some(c) = find_circle(&graph) {
        panic!("import circle: {}", c.join(" -> "));
    }
    // The scanner sees imports in both directions of the pair that used to be a circle.
    assert!(graph["session::flight"].contains("session::context"));
    assert!(graph["session::run"].contains("session::flight"));
}

#[test]
fn the_circle_check_finds_a_circle() {
    let edge = |a: &str, b: &[&str]| (a.to_string(), b.iter().map(|s| s.to_string()).collect());
    let g: BTreeMap<String, BTreeSet<String>> =
        [edge("a", &["b"]), edge("b", &["c"]), edge("c", &["a"]), edge("d", &[])]
            .into_iter()
            .collect();
    assert_eq!(
        find_circle(&g),
        Some(vec!["a".into(), "b".into(), "c".into(), "a".into()])
    );
    let dag: BTreeMap<String, BTreeSet<String>> = [edge("a", &["b", "c"]), edge("b", &["c"]), edge("c", &[])]
        .into_iter()
        .collect();
    assert_eq!(find_circle(&dag), None);
}
