//! The crate's modules import each other without a circle, and its layers only downwards.
//!
//! The graph is read from the sources (test code excluded): every `use` tree and every `crate::`,
//! `super::` and `self::` path names the module it reaches. A path through a facade's `pub use` is
//! followed to the module that defines the item, and a module's own submodules are part of it (declaring
//! and re-exporting a child is not an import). Checked for the library, the binary's `cli`, and every
//! workspace crate.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

type Graph = BTreeMap<String, BTreeSet<String>>;

/// One source file read as a module.
struct Module {
    path: Vec<String>,
    code: String,
}

/// The library's layers, lowest first: a module may import only modules of its own layer or below.
const LAYERS: &[&[&str]] = &[
    &["geometry"],
    &["io", "model"],
    &["judge", "rules"],
    &["lfs", "generator"],
    &["bridge", "plot"],
    &["campaign"],
];

fn layer_of(module: &str) -> Option<usize> {
    let top = module.split("::").next()?;
    LAYERS.iter().position(|l| l.contains(&top))
}

/// Every `.rs` file under `root` that is not a test module, as a module path relative to the crate root.
fn modules(root: &Path) -> Vec<Module> {
    let mut files = Vec::new();
    collect(root, &mut files);
    files
        .into_iter()
        .filter(|p| {
            let stem = p
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
            let binary_beside_lib = stem == "main" && p.with_file_name("lib.rs").is_file();
            stem != "tests" && !stem.ends_with("_tests") && !binary_beside_lib
        })
        .map(|p| Module {
            path: module_path(root, &p),
            code: strip(&std::fs::read_to_string(&p).expect("read source")),
        })
        .collect()
}

fn collect(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).expect("read dir").flatten() {
        let p = e.path();
        if p.is_dir() {
            collect(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

fn module_path(root: &Path, p: &Path) -> Vec<String> {
    let rel = p.strip_prefix(root).expect("under root").with_extension("");
    let mut parts: Vec<String> = rel
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    if matches!(parts.last().map(String::as_str), Some("mod" | "lib" | "main")) {
        parts.pop();
    }
    parts
}

/// The code outside tests, without comments and string contents.
fn strip(text: &str) -> String {
    let code = text.split("#[cfg(test)]").next().unwrap_or("");
    let mut out = String::with_capacity(code.len());
    let mut chars = code.chars().peekable();
    let mut in_str = false;
    while let Some(c) = chars.next() {
        match (in_str, c) {
            (true, '\\') => {
                chars.next();
            }
            (true, '"') => {
                in_str = false;
                out.push('"');
            }
            (true, _) => {}
            (false, '"') => {
                in_str = true;
                out.push('"');
            }
            (false, '/') if chars.peek() == Some(&'/') => {
                for n in chars.by_ref() {
                    if n == '\n' {
                        out.push('\n');
                        break;
                    }
                }
            }
            (false, _) => out.push(c),
        }
    }
    out
}

fn is_ident(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// The paths of a use tree such as `a::{b, c::{d as e, *}}`, each as (segments, name it binds).
fn expand_tree(tree: &str) -> Vec<(Vec<String>, String)> {
    fn rec(prefix: &[String], tree: &str, out: &mut Vec<(Vec<String>, String)>) {
        let tree = tree.trim();
        if let Some(inner) = tree.strip_prefix('{') {
            let inner = inner.strip_suffix('}').unwrap_or(inner);
            let (mut depth, mut start) = (0, 0);
            for (i, c) in inner.char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' => depth -= 1,
                    ',' if depth == 0 => {
                        rec(prefix, &inner[start..i], out);
                        start = i + 1;
                    }
                    _ => {}
                }
            }
            rec(prefix, &inner[start..], out);
            return;
        }
        let head: String = tree.chars().take_while(|&c| is_ident(c) || c == '*').collect();
        if head.is_empty() {
            return;
        }
        let rest = tree[head.len()..].trim_start();
        let mut path = prefix.to_vec();
        path.push(head.clone());
        if let Some(sub) = rest.strip_prefix("::") {
            rec(&path, sub, out);
        } else {
            let bound = rest.strip_prefix("as").map(|a| a.trim().to_string()).unwrap_or(head);
            out.push((path, bound));
        }
    }
    let mut out = Vec::new();
    rec(&[], tree, &mut out);
    out
}

/// The bodies of the `use` declarations in `code`, with whether each is `pub`.
fn use_trees(code: &str) -> Vec<(bool, String)> {
    let mut out = Vec::new();
    for (i, _) in code.match_indices("use ") {
        let before = &code[..i];
        if before.chars().last().is_some_and(is_ident) {
            continue;
        }
        let line_start = before.rfind(['\n', ';', '{', '}']).map_or(0, |p| p + 1);
        let lead = before[line_start..].trim();
        if !(lead.is_empty() || lead.starts_with("pub")) {
            continue;
        }
        let Some(end) = code[i..].find(';') else { continue };
        out.push((lead.starts_with("pub"), code[i + 4..i + end].to_string()));
    }
    out
}

/// The module paths that `from` reaches through `path` (relative to `from` unless it starts at the root).
fn absolute(from: &[String], path: &[String], known: &BTreeSet<Vec<String>>) -> Option<Vec<String>> {
    let first = path.first()?.as_str();
    match first {
        "crate" => Some(path[1..].to_vec()),
        "self" => Some([from, &path[1..]].concat()),
        "super" => {
            let mut base = from.to_vec();
            let mut i = 0;
            while path.get(i).is_some_and(|s| s == "super") {
                base.pop();
                i += 1;
            }
            Some([&base[..], &path[i..]].concat())
        }
        _ => {
            let child = [from, &path[..1]].concat();
            known.contains(&child).then(|| [from, path].concat())
        }
    }
}

struct Crate {
    modules: BTreeSet<Vec<String>>,
    /// Module -> name it re-exports -> the absolute path it names.
    reexports: BTreeMap<Vec<String>, BTreeMap<String, Vec<String>>>,
}

impl Crate {
    /// The module that defines what `path` names: its longest module prefix, through facades' re-exports.
    fn resolve(&self, path: &[String], depth: usize) -> Option<Vec<String>> {
        let k = (0..=path.len()).rev().find(|&k| self.modules.contains(&path[..k]))?;
        let (module, rest) = (path[..k].to_vec(), &path[k..]);
        if depth < 8
            && let Some(first) = rest.first()
            && let Some(target) = self.reexports.get(&module).and_then(|r| r.get(first))
        {
            let next = [&target[..], &rest[1..]].concat();
            return self.resolve(&next, depth + 1).or(Some(module));
        }
        Some(module)
    }
}

/// The crate rooted at `root` as a graph: module -> the modules it imports (outside itself).
fn graph(root: &Path) -> Graph {
    let mods = modules(root);
    let known: BTreeSet<Vec<String>> = mods.iter().map(|m| m.path.clone()).collect();
    let mut krate = Crate {
        modules: known.clone(),
        reexports: BTreeMap::new(),
    };
    for m in &mods {
        for (public, tree) in use_trees(&m.code) {
            for (path, bound) in expand_tree(&tree) {
                if public && let Some(abs) = absolute(&m.path, &path, &known) {
                    krate.reexports.entry(m.path.clone()).or_default().insert(bound, abs);
                }
            }
        }
    }
    let mut out = Graph::new();
    for m in &mods {
        let mut paths: Vec<Vec<String>> = use_trees(&m.code)
            .into_iter()
            .flat_map(|(_, t)| expand_tree(&t).into_iter().map(|(p, _)| p))
            .collect();
        paths.extend(inline_paths(&m.code));
        let deps: BTreeSet<String> = paths
            .iter()
            .filter_map(|p| absolute(&m.path, p, &known))
            .filter_map(|abs| krate.resolve(&abs, 0))
            .filter(|d| !d.is_empty() && !d.starts_with(&m.path))
            .map(|d| d.join("::"))
            .collect();
        out.insert(m.path.join("::"), deps);
    }
    out
}

/// Paths written in code (not in `use`) that start at `crate`, `super` or `self`.
fn inline_paths(code: &str) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    for start in ["crate::", "super::", "self::"] {
        for (i, _) in code.match_indices(start) {
            if code[..i].chars().last().is_some_and(|c| is_ident(c) || c == ':') {
                continue;
            }
            let path: Vec<String> = code[i..]
                .split("::")
                .map(|s| s.chars().take_while(|&c| is_ident(c)).collect::<String>())
                .take_while(|s| !s.is_empty())
                .collect();
            out.push(path);
        }
    }
    out
}

/// A circle in `graph`, as the path that closes it, if there is one.
fn find_circle(graph: &Graph) -> Option<Vec<String>> {
    fn visit(m: &str, g: &Graph, done: &mut BTreeSet<String>, path: &mut Vec<String>) -> Option<Vec<String>> {
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

/// Every group of modules that import each other round a circle (strongly connected, two or more).
fn circles(graph: &Graph) -> Vec<BTreeSet<String>> {
    let reach = |from: &str| {
        let mut seen = BTreeSet::new();
        let mut todo = vec![from.to_string()];
        while let Some(m) = todo.pop() {
            for d in graph.get(&m).into_iter().flatten() {
                if seen.insert(d.clone()) {
                    todo.push(d.clone());
                }
            }
        }
        seen
    };
    let reachable: BTreeMap<&String, BTreeSet<String>> = graph.keys().map(|m| (m, reach(m))).collect();
    let mut out: Vec<BTreeSet<String>> = Vec::new();
    for m in graph.keys() {
        let group: BTreeSet<String> = reachable[m]
            .iter()
            .filter(|d| reachable.get(d).is_some_and(|r| r.contains(m)))
            .cloned()
            .collect();
        if group.len() > 1 && !out.contains(&group) {
            out.push(group);
        }
    }
    out
}

fn library() -> Graph {
    let mut g = graph(&super::repo().join("src"));
    // The binary's modules are read as their own crate below.
    g.retain(|m, _| !(m == "cli" || m.starts_with("cli::")));
    g
}

/// The workspace's other crates (each folder beside `src/` with its own Cargo.toml and `src/`).
fn member_crates() -> Vec<PathBuf> {
    let mut out: Vec<PathBuf> = std::fs::read_dir(super::repo())
        .expect("read repo")
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.join("Cargo.toml").is_file() && p.join("src").is_dir())
        .collect();
    out.sort();
    out
}

#[test]
fn the_library_has_no_import_circle() {
    let g = library();
    assert!(g.len() > 50, "the scanner read too few modules: {}", g.len());
    if let Some(c) = find_circle(&g) {
        let all: Vec<String> = circles(&g)
            .iter()
            .map(|c| c.iter().cloned().collect::<Vec<_>>().join(", "))
            .collect();
        panic!(
            "import circle: {}\nall circles:\n  {}",
            c.join(" -> "),
            all.join("\n  ")
        );
    }
}

/// The graph of the top-level modules (`model`, `io`, `lfs`, ...): two files may not circle through them.
fn top_level(g: &Graph) -> Graph {
    let top = |m: &str| m.split("::").next().unwrap_or("").to_string();
    let mut out = Graph::new();
    for (m, deps) in g {
        let entry = out.entry(top(m)).or_default();
        entry.extend(deps.iter().map(|d| top(d)).filter(|d| *d != top(m)));
    }
    out
}

#[test]
fn the_library_top_level_modules_have_no_import_circle() {
    let g = top_level(&library());
    assert!(g["campaign"].contains("lfs"), "{g:?}");
    if let Some(c) = find_circle(&g) {
        panic!("import circle between top-level modules: {}", c.join(" -> "));
    }
}

#[test]
fn the_binary_and_every_workspace_crate_have_no_import_circle() {
    let mut roots = vec![super::repo().join("src/cli")];
    roots.extend(member_crates().into_iter().map(|p| p.join("src")));
    assert!(roots.len() >= 2, "{roots:?}");
    for root in roots {
        let g = graph(&root);
        if let Some(c) = find_circle(&g) {
            panic!("{}: import circle: {}", root.display(), c.join(" -> "));
        }
    }
}

#[test]
fn the_library_layers_import_only_downwards() {
    let g = library();
    for (m, deps) in &g {
        let Some(a) = layer_of(m) else {
            assert!(m.is_empty(), "module {m} belongs to no layer: add it to LAYERS");
            continue;
        };
        for d in deps {
            let b = layer_of(d).unwrap_or(usize::MAX);
            assert!(a >= b, "{m} imports {d}, a higher layer");
        }
    }
}

/// The workspace crates every other crate may stand on: they depend on no crate of ours themselves.
const FOUNDATIONS: &[&str] = &["geodesy"];

/// The workspace dependencies that are crates of this workspace (a `path`).
fn workspace_paths() -> Vec<String> {
    let manifest: toml::Table = std::fs::read_to_string(super::repo().join("Cargo.toml"))
        .expect("read manifest")
        .parse()
        .expect("parse manifest");
    let deps = manifest["workspace"]["dependencies"]
        .as_table()
        .cloned()
        .unwrap_or_default();
    deps.into_iter()
        .filter(|(_, spec)| spec.get("path").is_some())
        .map(|(n, _)| n)
        .collect()
}

#[test]
fn foundations_depend_on_no_crate_of_ours() {
    for name in FOUNDATIONS {
        let dir = super::repo().join(name);
        let text = std::fs::read_to_string(dir.join("Cargo.toml")).expect("read manifest");
        let manifest: toml::Table = text.parse().expect("parse manifest");
        let deps = manifest
            .get("dependencies")
            .and_then(|d| d.as_table())
            .cloned()
            .unwrap_or_default();
        for (dep, spec) in deps {
            let ours = spec.get("path").is_some() || workspace_paths().contains(&dep);
            assert!(!ours, "{name} depends on {dep}, a crate of this workspace");
        }
    }
    assert!(
        workspace_paths().contains(&"geodesy".to_string()),
        "{:?}",
        workspace_paths()
    );
}

#[test]
fn workspace_crates_below_the_library_import_nothing_of_ours() {
    for dir in member_crates() {
        let manifest: toml::Table = std::fs::read_to_string(dir.join("Cargo.toml"))
            .expect("read manifest")
            .parse()
            .expect("parse manifest");
        let deps = manifest
            .get("dependencies")
            .and_then(|d| d.as_table())
            .cloned()
            .unwrap_or_default();
        for (name, spec) in deps {
            let ours =
                spec.get("path").is_some() || (spec.get("workspace").is_some() && workspace_paths().contains(&name));
            assert!(
                !ours || FOUNDATIONS.contains(&name.as_str()),
                "{}: depends on {name}, a crate of this workspace; it may stand only on {FOUNDATIONS:?}",
                dir.display()
            );
        }
        let g = graph(&dir.join("src"));
        let text: String = modules(&dir.join("src")).into_iter().map(|m| m.code).collect();
        assert!(!text.contains("prgenuav::"), "{} names prgenuav", dir.display());
        assert!(!g.is_empty());
    }
}

/// The campaign's floors, lowest first: the settings, the ground floor every stage shares, the stages in the
/// order data flows through them, and the conductor and the run on top.
const CAMPAIGN_FLOORS: &[&str] = &[
    "settings",
    "ground",
    "store",
    "screen",
    "fly",
    "learn",
    "plan",
    "report",
    "evaluation",
    "conductor",
    "run",
];

#[test]
fn campaign_floors_import_only_downwards() {
    let floor = |m: &str| {
        let room = m.strip_prefix("campaign::")?.split("::").next()?;
        Some(
            CAMPAIGN_FLOORS
                .iter()
                .position(|f| *f == room)
                .unwrap_or_else(|| panic!("campaign::{room} stands on no floor: add it to CAMPAIGN_FLOORS")),
        )
    };
    let g = library();
    assert!(g.contains_key("campaign::ground::candidate") && g.contains_key("campaign::conductor"));
    let mut up = Vec::new();
    for (m, deps) in &g {
        for d in deps {
            if let (Some(a), Some(b)) = (floor(m), floor(d))
                && a < b
            {
                up.push(format!("{m} imports {d}, a floor above it"));
            }
        }
    }
    assert!(up.is_empty(), "{}", up.join("\n"));
}

#[test]
fn bridge_groups_import_only_downwards() {
    let rank = |m: &str| match m.strip_prefix("bridge::")?.split("::").next() {
        Some("wire") => Some(0),
        Some("companion") => Some(1),
        Some("session") => Some(2),
        _ => None,
    };
    let g = library();
    assert!(g.contains_key("bridge::session::flight") && g.contains_key("bridge::wire::link"));
    for (m, deps) in &g {
        for d in deps {
            if let (Some(a), Some(b)) = (rank(m), rank(d)) {
                assert!(a >= b, "{m} (a lower group) imports {d}");
            }
        }
    }
}

#[test]
fn the_scanner_sees_use_trees_facades_and_circles() {
    let paths: Vec<Vec<String>> = expand_tree("crate::{a::{B, c::D as E}, f::*}")
        .into_iter()
        .map(|p| p.0)
        .collect();
    let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>();
    assert_eq!(
        paths,
        vec![
            s(&["crate", "a", "B"]),
            s(&["crate", "a", "c", "D"]),
            s(&["crate", "f", "*"])
        ]
    );
    assert_eq!(expand_tree("x as y")[0].1, "y");
    // Real edges, one through a facade's re-export, are seen.
    let g = library();
    assert!(
        g["bridge::session::run"].contains("bridge::session::flight"),
        "{:?}",
        g["bridge::session::run"]
    );
    assert!(
        g.values().flatten().any(|d| d.starts_with("geometry::")),
        "facades are followed to the definer"
    );
    let edge = |a: &str, b: &[&str]| (a.to_string(), b.iter().map(|s| s.to_string()).collect());
    let circle: Graph = [edge("a", &["b"]), edge("b", &["c"]), edge("c", &["a"]), edge("d", &[])]
        .into_iter()
        .collect();
    assert_eq!(find_circle(&circle), Some(s(&["a", "b", "c", "a"])));
    assert_eq!(circles(&circle), vec![s(&["a", "b", "c"]).into_iter().collect()]);
    let dag: Graph = [edge("a", &["b", "c"]), edge("b", &["c"]), edge("c", &[])]
        .into_iter()
        .collect();
    assert_eq!(find_circle(&dag), None);
    assert!(circles(&dag).is_empty());
}
