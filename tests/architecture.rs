//! The shape of `src/`, read from the `crate::` and `super::` paths of every source file
//! (outside comments and test modules, inline or in `tests.rs` files), and the rules it keeps:
//!
//! - the layers import only downwards: the foundation; the scene; the services (the spatial
//!   layer, the view, the rasterizer's plugin, the controls); the entity kinds; the app;
//! - the kinds import each other without a cycle, and never another kind's `plugin` or
//!   `panel` module, whether by its path or through the names the kind's `mod.rs` re-exports
//!   from them (a kind may use another's pure cores and its entry, to read what it built);
//! - a kind's `def.rs` (its file format and checks) imports neither its `plugin.rs` nor its
//!   entry file;
//! - the files of a folder import each other without a cycle (`mod.rs`, the folder's table of
//!   contents, is read through: a name it re-exports counts as a use of the file that defines
//!   it);
//! - no file outside `src/cli/` uses the command line's handlers;
//! - no file of `src/` is longer than 800 lines;
//! - and the rasterizer crate's files import each other without a cycle.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

const FOUNDATION: &str = "foundation";
const SCENE: &str = "scene";
const SERVICES: &[&str] = &["spatial", "view", "raster", "controls"];
const KINDS: &[&str] = &["shape", "muscle", "tree", "sloth", "terrain", "world", "soft_body", "elastic", "ar"];
const APP: &[&str] = &["app", "cli", "run", "scene_test", "ui", "lib", "main"];
/// The longest a file of `src/` may be, in lines.
const MAX_LINES: usize = 800;

fn layer(group: &str) -> u8 {
    match group {
        FOUNDATION => 0,
        SCENE => 1,
        _ if SERVICES.contains(&group) => 2,
        _ if KINDS.contains(&group) => 3,
        _ if APP.contains(&group) => 4,
        other => panic!("`{other}` is in no layer: add it to one of the lists above"),
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

/// A file's code without its test module and its comments.
fn code_of(text: &str) -> String {
    let code = text.split("#[cfg(test)]").next().unwrap_or(text);
    code.lines().map(|line| line.split("//").next().unwrap_or("")).collect::<Vec<_>>().join("\n")
}

/// Every path a file names after `prefix` (`crate::` or `super::`), as its segments, with the
/// names of a `{...}` group spread into one path each (one level deep).
fn paths(code: &str, prefix: &str) -> Vec<Vec<String>> {
    let mut found = Vec::new();
    for (at, _) in code.match_indices(prefix) {
        let before = code[..at].chars().next_back();
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == '$' || c == ':') {
            continue;
        }
        let rest = &code[at + prefix.len()..];
        let mut segments = Vec::new();
        let mut rest = rest;
        loop {
            let name: String = rest.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
            if name.is_empty() {
                break;
            }
            rest = &rest[name.len()..];
            segments.push(name);
            if let Some(next) = rest.strip_prefix("::") {
                rest = next;
            } else {
                break;
            }
        }
        if let Some(group) = rest.strip_prefix('{') {
            for item in group_items(group) {
                if item != "self" {
                    let mut path = segments.clone();
                    path.push(item);
                    found.push(path);
                }
            }
            if !segments.is_empty() {
                found.push(segments);
            }
        } else if !segments.is_empty() {
            found.push(segments);
        }
    }
    found
}

/// The first name of each item of a `{...}` group that `text` starts inside of (items nested
/// in an inner group are that inner group's).
fn group_items(text: &str) -> Vec<String> {
    let mut items = Vec::new();
    let mut depth = 0;
    let mut at_item = true;
    for (i, c) in text.char_indices() {
        match c {
            '{' => depth += 1,
            '}' if depth == 0 => break,
            '}' => depth -= 1,
            ',' if depth == 0 => at_item = true,
            c if at_item && (c.is_alphanumeric() || c == '_') => {
                let name: String = text[i..].chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
                items.push(name);
                at_item = false;
            }
            _ => {}
        }
    }
    items
}

/// The top-level modules a file names through `crate::`.
fn imports(text: &str) -> BTreeSet<String> {
    paths(&code_of(text), "crate::").into_iter().map(|path| path[0].clone()).collect()
}

/// Every file of `src/` with its text, but test modules kept in files of their own
/// (`tests.rs`).
fn files() -> Vec<(PathBuf, String)> {
    let mut files = Vec::new();
    sources(Path::new("src"), &mut files);
    files.retain(|file| !file.ends_with("tests.rs"));
    files.sort();
    files.into_iter().map(|file| (file.clone(), std::fs::read_to_string(&file).unwrap())).collect()
}

/// A file's path from `src/`, for messages.
fn shown(file: &Path) -> String {
    file.strip_prefix("src").unwrap().display().to_string()
}

/// Every use of one group by another: (from, to) -> the files that make it.
fn edges() -> BTreeMap<(String, String), Vec<String>> {
    let src = PathBuf::from("src");
    let mut edges: BTreeMap<(String, String), Vec<String>> = BTreeMap::new();
    for (file, text) in files() {
        let from = group_of(&src, &file);
        for to in imports(&text) {
            if to != from {
                edges.entry((from.clone(), to)).or_default().push(shown(&file));
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

/// The names a folder's `mod.rs` re-exports, each with the module of the folder it comes from.
fn reexports(mod_rs: &str) -> BTreeMap<String, String> {
    let mut names = BTreeMap::new();
    for statement in code_of(mod_rs).split(';') {
        let Some(rest) = statement.trim().strip_prefix("pub use ") else { continue };
        let rest = rest.trim_start_matches("self::");
        let module: String = rest.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
        let items = rest[module.len()..].trim_start_matches("::");
        let items = items.trim_start_matches('{').trim_end_matches('}');
        for item in items.split(',') {
            let item = item.split(" as ").last().unwrap_or(item).trim();
            let name: String = item.rsplit("::").next().unwrap_or(item).to_string();
            if !name.is_empty() && name != "self" {
                names.insert(name, module.clone());
            }
        }
    }
    names
}

/// The module of `folder` a path (already past `crate::<folder>::` or `super::`) leads to:
/// its first segment if that is a file of the folder, else the file a `mod.rs` re-export of
/// that name comes from.
fn module_of(path: &[String], modules: &BTreeSet<String>, reexported: &BTreeMap<String, String>) -> Option<String> {
    let first = path.first()?;
    if modules.contains(first) {
        return Some(first.clone());
    }
    reexported.get(first).cloned()
}

/// One folder of `src/`: its files' module names and texts, and what its `mod.rs` re-exports.
struct Folder {
    name: String,
    files: BTreeMap<String, String>,
    reexported: BTreeMap<String, String>,
}

/// Every folder of `src/` with a `mod.rs`.
fn folders() -> Vec<Folder> {
    let mut folders = Vec::new();
    for entry in std::fs::read_dir("src").unwrap() {
        let path = entry.unwrap().path();
        if !path.is_dir() || !path.join("mod.rs").exists() {
            continue;
        }
        let mut files = BTreeMap::new();
        for file in std::fs::read_dir(&path).unwrap() {
            let file = file.unwrap().path();
            if file.extension().is_some_and(|e| e == "rs") {
                let module = file.file_stem().unwrap().to_string_lossy().into_owned();
                files.insert(module, std::fs::read_to_string(&file).unwrap());
            }
        }
        let reexported = reexports(&files["mod"]);
        folders.push(Folder { name: path.file_name().unwrap().to_string_lossy().into_owned(), files, reexported });
    }
    folders.sort_by(|a, b| a.name.cmp(&b.name));
    folders
}

/// The modules of `folder` that the file `text` (one of its own) uses.
fn uses_within(folder: &Folder, text: &str) -> BTreeSet<String> {
    let modules: BTreeSet<String> = folder.files.keys().filter(|m| *m != "mod").cloned().collect();
    let code = code_of(text);
    let own = format!("crate::{}::", folder.name);
    let mut paths = paths(&code, "super::");
    paths.extend(paths_after(&code, &own));
    paths.iter().filter_map(|path| module_of(path, &modules, &folder.reexported)).collect()
}

/// The paths a file names after `prefix`, a `crate::folder::` path.
fn paths_after(code: &str, prefix: &str) -> Vec<Vec<String>> {
    paths(code, "crate::")
        .into_iter()
        .filter(|path| prefix == format!("crate::{}::", path[0]))
        .map(|path| path[1..].to_vec())
        .filter(|path| !path.is_empty())
        .collect()
}

/// For every folder, the files on an import cycle with their uses; empty when there is none.
fn folder_cycles() -> Vec<String> {
    let mut found = Vec::new();
    for folder in folders() {
        let uses: BTreeMap<String, BTreeSet<String>> = folder
            .files
            .iter()
            .filter(|(module, _)| *module != "mod")
            .map(|(module, text)| {
                let mut used = uses_within(&folder, text);
                used.remove(module);
                (module.clone(), used)
            })
            .collect();
        let graph: BTreeMap<&str, BTreeSet<&str>> =
            uses.iter().map(|(module, used)| (module.as_str(), used.iter().map(String::as_str).collect())).collect();
        let cycles = on_cycles(&graph);
        if !cycles.is_empty() {
            found.push(format!("src/{}: {cycles:?} (uses: {graph:?})", folder.name));
        }
    }
    found
}

/// Every use of another kind's `plugin` or `panel` module by a kind, directly or through
/// that kind's re-exports.
fn kinds_in_other_kinds_plugins() -> Vec<String> {
    let folders = folders();
    let mut found = Vec::new();
    for (file, text) in files() {
        let from = group_of(Path::new("src"), &file);
        if !KINDS.contains(&from.as_str()) {
            continue;
        }
        for path in paths(&code_of(&text), "crate::") {
            let to = &path[0];
            if to == &from || !KINDS.contains(&to.as_str()) || path.len() < 2 {
                continue;
            }
            let Some(folder) = folders.iter().find(|f| &f.name == to) else { continue };
            let modules: BTreeSet<String> = folder.files.keys().cloned().collect();
            let module = module_of(&path[1..], &modules, &folder.reexported);
            if matches!(module.as_deref(), Some("plugin" | "panel")) {
                found.push(format!("{}: crate::{}", shown(&file), path.join("::")));
            }
        }
    }
    found
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
    let grouped = paths("use super::{def, plugin::{self, A}};\nuse crate::tree::bvh::Bvh;", "super::");
    assert_eq!(grouped, [vec!["def".to_string()], vec!["plugin".into()]]);
}

#[test]
fn re_exports_are_traced_to_the_file_that_defines_them() {
    let names = reexports("pub mod def;\npub use def::{TreeDef, Thing as Other};\npub use plugin::TreeBody;\n");
    assert_eq!(names["TreeDef"], "def");
    assert_eq!(names["Other"], "def");
    assert_eq!(names["TreeBody"], "plugin");
    let folder = Folder {
        name: "tree".into(),
        files: [("mod", ""), ("def", ""), ("plugin", "")].map(|(m, t)| (m.to_string(), t.to_string())).into(),
        reexported: names,
    };
    let used = uses_within(&folder, "use super::TreeBody;\nuse crate::tree::def::TreeDef;\n");
    assert_eq!(used.into_iter().collect::<Vec<_>>(), ["def", "plugin"]);
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
fn kinds_import_each_other_without_a_cycle() {
    let edges = edges();
    let kind_edges: BTreeMap<&str, BTreeSet<&str>> = edges
        .keys()
        .filter(|(from, to)| KINDS.contains(&from.as_str()) && KINDS.contains(&to.as_str()))
        .fold(BTreeMap::new(), |mut map, (f, t)| {
            map.entry(f.as_str()).or_default().insert(t.as_str());
            map
        });
    let cycles = on_cycles(&kind_edges);
    assert!(cycles.is_empty(), "kinds on an import cycle: {cycles:?} (uses: {kind_edges:?})");
    // The check sees the uses that exist: the sloth walks on the trees' model.
    assert!(kind_edges.get("sloth").is_some_and(|uses| uses.contains("tree")), "{kind_edges:?}");
}

#[test]
fn no_kind_uses_another_kinds_plugin_or_panel() {
    let found = kinds_in_other_kinds_plugins();
    assert!(found.is_empty(), "kinds reaching into another kind's plugin or panel:\n{}", found.join("\n"));
}

#[test]
fn a_kinds_file_format_imports_neither_its_plugin_nor_its_entry() {
    let mut found = Vec::new();
    for folder in folders().iter().filter(|f| KINDS.contains(&f.name.as_str())) {
        assert!(folder.files.contains_key("kind"), "src/{}: no entry file kind.rs", folder.name);
        let Some(def) = folder.files.get("def") else { continue };
        for used in uses_within(folder, def) {
            if used == "plugin" || used == "kind" || used == "panel" {
                found.push(format!("src/{}/def.rs uses {used}", folder.name));
            }
        }
    }
    assert!(found.is_empty(), "{}", found.join("\n"));
}

#[test]
fn the_files_of_a_folder_import_each_other_without_a_cycle() {
    let found = folder_cycles();
    assert!(found.is_empty(), "files on an import cycle:\n{}", found.join("\n"));
}

#[test]
fn only_the_command_line_uses_its_handlers() {
    let found: Vec<String> = files()
        .into_iter()
        .filter(|(file, _)| !file.starts_with("src/cli"))
        .filter(|(_, text)| imports(text).contains("cli"))
        .map(|(file, _)| shown(&file))
        .collect();
    assert!(found.is_empty(), "files outside src/cli/ using it: {found:?}");
}

#[test]
fn no_file_is_longer_than_the_limit() {
    let long: Vec<String> = files()
        .into_iter()
        .map(|(file, text)| (file, text.lines().count()))
        .filter(|(_, lines)| *lines > MAX_LINES)
        .map(|(file, lines)| format!("{}: {lines} lines", shown(&file)))
        .collect();
    assert!(long.is_empty(), "files over {MAX_LINES} lines:\n{}", long.join("\n"));
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
