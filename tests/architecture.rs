//! The layers of `src/` import only downwards, the domains import each other without a cycle,
//! and the rasterizer crate's files import each other without a cycle: read from the
//! `crate::` paths of every source file (outside comments and test modules).
//!
//! Layers of `src/`, lowest first: the foundation; the scene; the domains (each a folder or
//! file of its own); the app. A module may use its own group and any lower layer; a domain
//! may use another domain as long as no chain of such uses leads back to it.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

const FOUNDATION: &str = "foundation";
const SCENE: &str = "scene";
const APP: &[&str] = &["app", "run", "ui", "lib", "main"];

fn layer(group: &str) -> u8 {
    match group {
        FOUNDATION => 0,
        SCENE => 1,
        _ if APP.contains(&group) => 3,
        _ => 2,
    }
}

/// Every `.rs` file under `folder`.
fn sources(folder: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(folder).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            sources(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The group a file of `src/` belongs to: its top-level module.
fn group_of(src: &Path, file: &Path) -> String {
    let relative = file.strip_prefix(src).unwrap();
    let first = relative.components().next().unwrap().as_os_str().to_string_lossy().into_owned();
    first.trim_end_matches(".rs").to_string()
}

/// The top-level modules a file names through `crate::`, outside comments and its test
/// module.
fn imports(text: &str) -> BTreeSet<String> {
    let mut found = BTreeSet::new();
    let code = text.split("#[cfg(test)]").next().unwrap_or(text);
    for line in code.lines() {
        let code = line.split("//").next().unwrap_or("");
        for (at, _) in code.match_indices("crate::") {
            let before = code[..at].chars().next_back();
            if before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == '$') {
                continue;
            }
            let rest = &code[at + "crate::".len()..];
            let name: String = rest.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
            if !name.is_empty() {
                found.insert(name);
            }
        }
    }
    found
}

/// Every use of one group by another: (from, to) -> the files that make it.
fn edges() -> BTreeMap<(String, String), Vec<String>> {
    let src = PathBuf::from("src");
    let mut files = Vec::new();
    sources(&src, &mut files);
    let mut edges: BTreeMap<(String, String), Vec<String>> = BTreeMap::new();
    for file in files {
        let from = group_of(&src, &file);
        let text = std::fs::read_to_string(&file).unwrap();
        for to in imports(&text) {
            if to != from {
                let shown = file.strip_prefix(&src).unwrap().display().to_string();
                edges.entry((from.clone(), to)).or_default().push(shown);
            }
        }
    }
    edges
}

/// Whether a chain of uses leads from `from` to `to`.
fn reaches<'a>(graph: &BTreeMap<&'a str, BTreeSet<&'a str>>, from: &'a str, to: &str, seen: &mut Vec<&'a str>) -> bool {
    for &next in graph.get(from).into_iter().flatten() {
        if next == to {
            return true;
        }
        if !seen.contains(&next) {
            seen.push(next);
            if reaches(graph, next, to, seen) {
                return true;
            }
        }
    }
    false
}

/// The nodes of `graph` that a chain of uses leads back to.
fn on_cycles<'a>(graph: &BTreeMap<&'a str, BTreeSet<&'a str>>) -> Vec<&'a str> {
    graph.keys().copied().filter(|&node| reaches(graph, node, node, &mut Vec::new())).collect()
}

#[test]
fn the_cycle_finder_finds_a_cycle_and_only_that() {
    let graph: BTreeMap<&str, BTreeSet<&str>> = [
        ("a", BTreeSet::from(["b"])),
        ("b", BTreeSet::from(["c"])),
        ("c", BTreeSet::from(["a"])),
        ("d", BTreeSet::from(["a"])),
    ]
    .into_iter()
    .collect();
    assert_eq!(on_cycles(&graph), ["a", "b", "c"]);
}

#[test]
fn the_path_reader_finds_crate_paths_outside_comments() {
    let text = "use crate::tree::TreeBody;\n// crate::ui is only named here\nlet x = crate::scene::FIRST;\n\
                $crate::foundation::values::shown(v)\n";
    let found: Vec<String> = imports(text).into_iter().collect();
    assert_eq!(found, ["scene", "tree"]);
    let with_tests = "use crate::view::CameraParams;\n#[cfg(test)]\nmod tests {\n    use crate::ui::UiPlugin;\n}\n";
    assert_eq!(imports(with_tests).into_iter().collect::<Vec<_>>(), ["view"]);
}

#[test]
fn layers_import_only_downwards() {
    let upward: Vec<String> = edges()
        .into_iter()
        .filter(|((from, to), _)| layer(to) > layer(from))
        .map(|((from, to), files)| format!("{from} -> {to} ({})", files.join(", ")))
        .collect();
    assert!(upward.is_empty(), "imports against the layers:\n{}", upward.join("\n"));
}

#[test]
fn domains_import_each_other_without_a_cycle() {
    let edges = edges();
    let domain_edges: BTreeMap<&str, BTreeSet<&str>> = edges
        .keys()
        .filter(|(from, to)| layer(from) == 2 && layer(to) == 2)
        .fold(BTreeMap::new(), |mut map, (f, t)| {
            map.entry(f.as_str()).or_default().insert(t.as_str());
            map
        });
    let cycles = on_cycles(&domain_edges);
    assert!(cycles.is_empty(), "domains on an import cycle: {cycles:?} (uses: {domain_edges:?})");
    // The check sees the uses that exist: the sloth walks on the trees' queries.
    assert!(domain_edges.get("sloth").is_some_and(|uses| uses.contains("tree")), "{domain_edges:?}");
}

#[test]
fn the_rasterizer_files_import_each_other_without_a_cycle() {
    let src = PathBuf::from("crates/canopy_raster/src");
    let mut files = Vec::new();
    sources(&src, &mut files);
    let texts: Vec<(String, String)> = files
        .iter()
        .filter(|file| !file.ends_with("lib.rs"))
        .map(|file| (group_of(&src, file), std::fs::read_to_string(file).unwrap()))
        .collect();
    let modules: BTreeSet<&str> = texts.iter().map(|(module, _)| module.as_str()).collect();
    let graph: BTreeMap<&str, BTreeSet<&str>> = texts
        .iter()
        .map(|(module, text)| {
            let uses = imports(text).into_iter().filter_map(|used| modules.get(used.as_str()).copied());
            (module.as_str(), uses.filter(|used| used != module).collect())
        })
        .collect();
    let cycles = on_cycles(&graph);
    assert!(cycles.is_empty(), "rasterizer files on an import cycle: {cycles:?} (uses: {graph:?})");
    // The check sees the uses that exist: the pipeline orders the passes.
    assert!(graph["pipeline"].contains("color_pass"), "{graph:?}");
}
