//! The layers of the library: a module may import only from its own layer
//! or the layers below it (docs/architecture.md draws them).
//!
//! The test reads the sources: every `use` tree and every inline path
//! (`crate::road::…`, `super::dense::…`, a bare child module in a
//! `mod.rs`), outside comments and `#[cfg(test)]` modules, is resolved to
//! the file it names, and that file's layer must not lie above the
//! importer's. A new upward import fails it, naming both files and the
//! path.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The top-level modules of `crates/tdvass/src`, from the ground up.
const CRATE_LAYERS: &[(&str, &[&str])] = &[
    ("ground", &["error", "math", "monotone"]),
    ("data", &["bytes", "model", "comfort", "road"]),
    ("checks", &["metrics", "limits"]),
    ("solver", &["solver"]),
    ("exchange", &["exchange"]),
    ("analysis", &["analysis"]),
    ("root", &["lib"]),
];

/// The top-level modules that are folders: their files are read as one.
const FOLDERS: &[&str] = &["model", "road", "analysis", "exchange"];

/// The files of `crates/tdvass/src/solver`, from the ground up.
const SOLVER_LAYERS: &[(&str, &[&str])] = &[
    ("linear algebra", &["expm", "linalg"]),
    (
        "system",
        &["system", "grid", "holding", "config", "contact", "reports"],
    ),
    ("step maps and inputs", &["operators", "pieces", "inputs"]),
    ("grid and dense steps", &["grid_step", "dense"]),
    ("hot loop", &["kernel"]),
    ("modes", &["modes"]),
    ("stepping", &["stepping", "integrals", "events", "deferred"]),
    ("observers", &["observers", "trajectory"]),
    ("whole steps", &["whole_steps"]),
    ("driver", &["driver", "setup", "switching"]),
    ("clients", &["accuracy", "outputs", "persist"]),
    ("facade", &["mod"]),
];

/// A module's place: `("", name)` for a top-level module, `("solver",
/// file)` for a solver file.
type Module = (&'static str, String);

fn rank(module: &Module) -> Option<usize> {
    let layers = if module.0.is_empty() {
        CRATE_LAYERS
    } else {
        SOLVER_LAYERS
    };
    layers
        .iter()
        .position(|(_, names)| names.contains(&module.1.as_str()))
}

fn layer_name(module: &Module) -> &'static str {
    let layers = if module.0.is_empty() {
        CRATE_LAYERS
    } else {
        SOLVER_LAYERS
    };
    rank(module).map_or("?", |r| layers[r].0)
}

/// The source without comments, string literals' contents and
/// `#[cfg(test)]` items (a test module, inline or declared).
fn code_of(source: &str) -> String {
    let mut out = String::new();
    let mut lines = source.lines().peekable();
    while let Some(line) = lines.next() {
        let trimmed = line.trim_start();
        if trimmed.starts_with("#[cfg(test)]") {
            // Skip the next item: a declaration line, or a block to its
            // matching closing brace.
            let mut depth = 0i64;
            let mut opened = false;
            for item in lines.by_ref() {
                let item = strip_comment(item);
                depth += item.matches('{').count() as i64;
                depth -= item.matches('}').count() as i64;
                opened |= item.contains('{');
                if (opened && depth <= 0) || (!opened && item.trim_end().ends_with(';')) {
                    break;
                }
            }
            continue;
        }
        out.push_str(&strip_comment(line));
        out.push('\n');
    }
    out
}

/// A line without its `//` comment and without the contents of its
/// string literals (so a path in a message is no import).
fn strip_comment(line: &str) -> String {
    let mut out = String::new();
    let mut in_string = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        if in_string {
            if c == '\\' {
                chars.next();
            } else if c == '"' {
                in_string = false;
                out.push(c);
            }
            continue;
        }
        if c == '"' {
            in_string = true;
            out.push(c);
            continue;
        }
        if c == '/' && chars.peek() == Some(&'/') {
            break;
        }
        out.push(c);
    }
    out
}

/// Expands a `use` tree (`a::{b, c::{d, e}}`) into its paths.
fn expand(tree: &str) -> Vec<String> {
    let tree = tree.trim();
    let Some(open) = tree.find('{') else {
        return vec![tree.to_string()];
    };
    let prefix = &tree[..open];
    let inner = &tree[open + 1..tree.rfind('}').unwrap_or(tree.len())];
    let mut parts = Vec::new();
    let (mut depth, mut start) = (0, 0);
    for (i, c) in inner.char_indices() {
        match c {
            '{' => depth += 1,
            '}' => depth -= 1,
            ',' if depth == 0 => {
                parts.push(&inner[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    parts.push(&inner[start..]);
    parts
        .into_iter()
        .filter(|p| !p.trim().is_empty())
        .flat_map(expand)
        .map(|p| format!("{prefix}{p}"))
        .collect()
}

/// The paths a file names, each once: its `use` trees expanded, and the
/// inline paths of the code outside them.
fn paths(code: &str) -> BTreeSet<String> {
    let mut found = BTreeSet::new();
    let mut outside = String::new();
    let mut rest = code;
    while let Some(at) = find_use(rest) {
        outside.push_str(&rest[..at]);
        let after = &rest[at..];
        let end = after.find(';').unwrap_or(after.len());
        let tree = after[..end].trim_start_matches("use").trim();
        found.extend(expand(tree));
        rest = &after[end..];
    }
    outside.push_str(rest);
    let bytes = outside.as_bytes();
    for prefix in ["crate::", "super::"] {
        for (at, _) in outside.match_indices(prefix) {
            let boundary =
                at == 0 || !(bytes[at - 1].is_ascii_alphanumeric() || bytes[at - 1] == b'_');
            if boundary {
                let path: String = outside[at..]
                    .chars()
                    .take_while(|c| c.is_ascii_alphanumeric() || *c == '_' || *c == ':')
                    .collect();
                found.insert(path.trim_end_matches(':').to_string());
            }
        }
    }
    found
}

/// The next `use` keyword at the start of a statement.
fn find_use(code: &str) -> Option<usize> {
    let bytes = code.as_bytes();
    code.match_indices("use ")
        .map(|(i, _)| i)
        .find(|&i| i == 0 || matches!(bytes[i - 1], b'\n' | b' ' | b'{' | b';' | b')'))
}

/// The module a path names, seen from `from` (`None`: outside the crate
/// or not a module of the tables).
fn target(from: &Module, path: &str, solver_children: &[String]) -> Option<Module> {
    let segments: Vec<&str> = path.split("::").map(str::trim).collect();
    let top = |name: &str| Some(("", name.to_string()));
    match segments.as_slice() {
        ["crate", "solver", child, ..] if solver_children.iter().any(|c| c == child) => {
            Some(("solver", child.to_string()))
        }
        ["crate", "solver", ..] => Some(("solver", "mod".to_string())),
        ["crate", name, ..] => top(name),
        ["super", name, ..] if from.0 == "solver" => {
            if solver_children.iter().any(|c| c == name) {
                Some(("solver", name.to_string()))
            } else {
                Some(("solver", "mod".to_string()))
            }
        }
        // Inside a folder module (`model/`, `road/`, `analysis/`) `super`
        // is the folder itself.
        ["super", ..] if FOLDERS.contains(&from.1.as_str()) => None,
        ["super", ..] => top("lib"),
        [name, ..] if from == &("solver", "mod".to_string()) => solver_children
            .iter()
            .any(|c| c == name)
            .then(|| ("solver", name.to_string())),
        _ => None,
    }
}

/// Upward imports of a file's code: `(importer, imported, path)`.
fn violations(from: &Module, code: &str, solver_children: &[String]) -> Vec<String> {
    let Some(own) = rank(from) else {
        return vec![format!("{from:?} is in no layer: add it to the tables")];
    };
    let mut out = Vec::new();
    for path in paths(code) {
        let Some(to) = target(from, &path, solver_children) else {
            continue;
        };
        // A solver file reaching a crate module, or the crate reaching
        // the solver, compares the solver as one module of the crate.
        let (from_cmp, to_cmp) = if from.0 != to.0 {
            (("", top_name(from)), ("", top_name(&to)))
        } else {
            (from.clone(), to.clone())
        };
        if from_cmp == to_cmp {
            continue;
        }
        match rank(&to_cmp) {
            Some(r) if r <= own_rank(&from_cmp, own) => {}
            Some(_) => out.push(format!(
                "{}/{} (layer \"{}\") imports `{path}` from {}/{} (layer \"{}\"), a layer above it",
                from.0,
                from.1,
                layer_name(&from_cmp),
                to.0,
                to.1,
                layer_name(&to_cmp)
            )),
            None => out.push(format!("`{path}` names {to:?}, which is in no layer")),
        }
    }
    out
}

fn top_name(module: &Module) -> String {
    if module.0.is_empty() {
        module.1.clone()
    } else {
        module.0.to_string()
    }
}

fn own_rank(module: &Module, fallback: usize) -> usize {
    rank(module).unwrap_or(fallback)
}

fn source_files(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .expect("the source folder")
        .map(|entry| entry.expect("an entry").path())
        .collect();
    files.sort();
    files
}

/// Every module of the crate with its code.
fn modules() -> (BTreeMap<Module, String>, Vec<String>) {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let solver = src.join("solver");
    let mut children = Vec::new();
    let mut out = BTreeMap::new();
    for path in source_files(&solver) {
        if path.extension().is_some_and(|e| e == "rs") {
            let name = path.file_stem().unwrap().to_string_lossy().to_string();
            if name == "tests" {
                continue;
            }
            let code = code_of(&std::fs::read_to_string(&path).unwrap());
            children.push(name.clone());
            out.insert(("solver", name), code);
        }
    }
    for path in source_files(&src) {
        let name = path.file_stem().unwrap().to_string_lossy().to_string();
        let text = if path.is_dir() {
            if name == "solver" {
                continue;
            }
            // A folder module: its files together.
            assert!(
                FOLDERS.contains(&name.as_str()),
                "{name}/ is not in FOLDERS"
            );
            source_files(&path)
                .iter()
                .filter(|p| p.extension().is_some_and(|e| e == "rs"))
                .filter(|p| p.file_stem().is_some_and(|s| s != "tests"))
                .map(|p| std::fs::read_to_string(p).unwrap())
                .collect::<Vec<_>>()
                .join("\n")
        } else if path.extension().is_some_and(|e| e == "rs") {
            std::fs::read_to_string(&path).unwrap()
        } else {
            continue;
        };
        out.entry(("", name))
            .or_insert_with(String::new)
            .push_str(&code_of(&text));
    }
    (out, children)
}

#[test]
fn no_module_imports_a_layer_above_its_own() {
    let (modules, children) = modules();
    let found: Vec<String> = modules
        .iter()
        .flat_map(|(module, code)| violations(module, code, &children))
        .collect();
    assert!(
        found.is_empty(),
        "imports against the layers (docs/architecture.md):\n{}",
        found.join("\n")
    );
}

#[test]
fn every_module_has_a_layer() {
    let (modules, _) = modules();
    let missing: Vec<String> = modules
        .keys()
        .filter(|m| rank(m).is_none())
        .map(|m| format!("{}/{}", m.0, m.1))
        .collect();
    assert!(missing.is_empty(), "modules in no layer: {missing:?}");
}

#[test]
fn an_upward_import_is_found() {
    let children: Vec<String> = ["linalg", "dense", "expm", "mod"].map(String::from).into();
    let linalg = ("solver", "linalg".to_string());
    for code in [
        "use super::Simulator;\n",
        "use super::{dense::DenseOutput, expm};\n",
        "fn f() { let d = super::dense::offset_key(1.0, 2.0); }\n",
        "use crate::analysis::pso;\n",
        "use crate::solver::Simulator;\n",
    ] {
        let code = code_of(code);
        assert_eq!(violations(&linalg, &code, &children).len(), 1, "{code}");
    }
    let road = ("", "road".to_string());
    assert_eq!(
        violations(&road, "use crate::solver::dense::Augmented;\n", &children).len(),
        1
    );
}

#[test]
fn comments_strings_and_tests_are_no_imports() {
    let children: Vec<String> = ["dense", "expm"].map(String::from).into();
    let linalg = ("solver", "linalg".to_string());
    let code = code_of(
        "//! See [`super::Simulator`].\n\
         fn f() -> &'static str { \"crate::analysis\" } // super::dense\n\
         #[cfg(test)]\n\
         mod tests {\n    use super::super::Simulator;\n    use crate::solver::dense;\n}\n\
         use super::expm;\n",
    );
    assert!(violations(&linalg, &code, &children).is_empty(), "{code}");
}
