//! Reading a crate's sources for its layers, shared by the layers tests of
//! `tdvass` and `tdvass-fmu` (docs/architecture.md draws the layers).
//!
//! A crate is described by the table of its top-level modules and, for
//! each folder read file by file, the table of the folder's files, both
//! from the ground up. Every `use` tree and every inline path
//! (`crate::…`, `super::…`, a bare child module in a `lib.rs` or a folder's
//! `mod.rs`), outside comments, strings and `#[cfg(test)]` items, is
//! resolved to the file it names; a name that a parent re-exports
//! (`pub use piece::RoadPiece` in `road/mod.rs`, `pub use slave::Slave` in
//! `lib.rs`) is resolved to the child that defines it. Two checks follow:
//!
//! - an import must not name a file in a layer above the importer's;
//! - in a folder with a table, a call `.name(` or `Type::name(` must not
//!   reach a function that only files above the caller's layer define (a
//!   name also defined at or below the caller's layer is ambiguous and
//!   passes).
//!
//! Inside a folder the files are compared by the folder's table; across
//! folders, and between a folder and a top-level module, the top-level
//! modules are compared by the crate's table.
//!
//! One file on purpose: both crates' layers tests include it by path, and
//! the parser is one piece (hence its length).

// Each test crate that includes this file uses a part of it.
#![allow(dead_code)]

use std::collections::{BTreeMap, BTreeSet};
use std::fmt;
use std::path::Path;

/// Layers from the ground up: each a name and the modules (or files) in it.
pub type Layers = &'static [(&'static str, &'static [&'static str])];

/// The layering of one crate.
pub struct Layout {
    /// The top-level modules of `src`, from the ground up; `lib` is the
    /// crate root.
    pub crate_layers: Layers,
    /// The folders whose files have layers of their own (the folder's
    /// `mod.rs`, or the `name.rs` beside a folder `name/`, is `mod`); any
    /// other folder is read as one module with its parent file.
    pub folders: &'static [(&'static str, Layers)],
    /// Names of the crate's functions that a method of the standard library
    /// or of a dependency shares (`Iterator::filter`): a call of one cannot
    /// be told from the other by reading, so it is no upward call.
    pub foreign_names: &'static [&'static str],
}

/// A module of the layers: a top-level module (`folder` empty) or a file
/// of a folder with a table.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct Module {
    pub folder: &'static str,
    pub name: String,
}

impl Module {
    fn top(name: &str) -> Module {
        Module {
            folder: "",
            name: name.to_string(),
        }
    }

    fn in_folder(folder: &'static str, name: &str) -> Module {
        Module {
            folder,
            name: name.to_string(),
        }
    }

    /// The top-level module this one belongs to.
    fn top_name(&self) -> &str {
        if self.folder.is_empty() {
            &self.name
        } else {
            self.folder
        }
    }
}

impl fmt::Display for Module {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.folder.is_empty() {
            write!(f, "{}", self.name)
        } else {
            write!(f, "{}/{}", self.folder, self.name)
        }
    }
}

/// What a path's leading `crate`, `super` or `self` (or a bare child
/// name) names, seen from one file.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Scope {
    /// The crate root.
    Root,
    /// A folder with a table: its children, and its `mod` file's names.
    Folder(&'static str),
    /// The file's own module (nothing of the layers to compare).
    Own,
}

/// One source file of the crate, its code stripped ([`code_of`]).
pub struct Source {
    /// The path below `src`, for the messages.
    pub path: String,
    pub module: Module,
    /// What `super` names.
    parent: Scope,
    /// What `self` and bare child names name.
    own: Scope,
    pub code: String,
}

/// A finding of the checks: `from` imports or calls `what` of `to`.
#[derive(Clone, Debug)]
pub struct Finding {
    pub file: String,
    pub line: usize,
    pub from: Module,
    pub to: Module,
    pub what: String,
    pub message: String,
}

/// A crate's sources, classified by the layout.
pub struct Crate {
    layout: &'static Layout,
    pub sources: Vec<Source>,
    /// Each folder's child modules.
    children: BTreeMap<&'static str, BTreeSet<String>>,
    /// The top-level modules.
    tops: BTreeSet<String>,
    /// The names each parent (`None`: `lib.rs`) re-exports or imports
    /// from its children, with the module that defines them.
    reexports: BTreeMap<Option<&'static str>, BTreeMap<String, Module>>,
}

impl Crate {
    /// The sources below `src`; test files (`tests.rs`, a `tests/`
    /// folder) are left out.
    pub fn read(layout: &'static Layout, src: &Path) -> Crate {
        let mut files = Vec::new();
        collect(src, src, &mut files);
        Crate::new(layout, files)
    }

    /// The crate of the given files (`("road/nodes.rs", text)`), for the
    /// tests that show a check can fail.
    pub fn of_texts(layout: &'static Layout, files: &[(&str, &str)]) -> Crate {
        let files = files
            .iter()
            .map(|(path, text)| (path.to_string(), text.to_string()))
            .collect();
        Crate::new(layout, files)
    }

    /// The crate of `files`: paths below `src` (`road/nodes.rs`) with
    /// their text.
    pub fn new(layout: &'static Layout, files: Vec<(String, String)>) -> Crate {
        let mut crate_ = Crate {
            layout,
            sources: Vec::new(),
            children: BTreeMap::new(),
            tops: BTreeSet::new(),
            reexports: BTreeMap::new(),
        };
        for (path, text) in files {
            let parts: Vec<&str> = path.trim_end_matches(".rs").split('/').collect();
            if parts.contains(&"tests") {
                continue;
            }
            let (module, parent, own) = match parts.as_slice() {
                ["lib"] => (Module::top("lib"), Scope::Own, Scope::Root),
                [name] | [name, "mod"] => match layout.folder(name) {
                    Some(folder) => (
                        Module::in_folder(folder, "mod"),
                        Scope::Root,
                        Scope::Folder(folder),
                    ),
                    None => (Module::top(name), Scope::Root, Scope::Own),
                },
                [name, child, rest @ ..] => match layout.folder(name) {
                    Some(folder) => {
                        let parent = if rest.is_empty() {
                            Scope::Folder(folder)
                        } else {
                            Scope::Own
                        };
                        (Module::in_folder(folder, child), parent, Scope::Own)
                    }
                    None => (Module::top(name), Scope::Own, Scope::Own),
                },
                [] => continue,
            };
            crate_.tops.insert(module.top_name().to_string());
            if !module.folder.is_empty() && module.name != "mod" {
                crate_
                    .children
                    .entry(module.folder)
                    .or_default()
                    .insert(module.name.clone());
            }
            crate_.sources.push(Source {
                path,
                module,
                parent,
                own,
                code: code_of(&text),
            });
        }
        let mut reexports = BTreeMap::new();
        for source in &crate_.sources {
            let key = match source.own {
                Scope::Root => None,
                Scope::Folder(folder) => Some(folder),
                Scope::Own => continue,
            };
            let names: &mut BTreeMap<String, Module> = reexports.entry(key).or_default();
            for (_, path) in use_paths(&source.code) {
                let name = path
                    .rsplit(" as ")
                    .next()
                    .and_then(|p| p.rsplit("::").next())
                    .unwrap_or("")
                    .trim();
                if matches!(name, "" | "self" | "*") {
                    continue;
                }
                if let Some(to) = crate_.resolve(source, &path) {
                    names.insert(name.to_string(), to);
                }
            }
        }
        crate_.reexports = reexports;
        crate_
    }

    /// The module `path` names, seen from `source` (`None`: outside the
    /// crate, or the source's own module).
    fn resolve(&self, source: &Source, path: &str) -> Option<Module> {
        let path = path.split(" as ").next().unwrap_or(path);
        let segments: Vec<&str> = path
            .split("::")
            .map(str::trim)
            .filter(|s| !s.is_empty())
            .collect();
        let found = match segments.as_slice() {
            ["crate", rest @ ..] => self.resolve_in(Scope::Root, rest),
            ["super", "super", rest @ ..] => match source.parent {
                Scope::Folder(_) => self.resolve_in(Scope::Root, rest),
                _ => None,
            },
            ["super", rest @ ..] => self.resolve_in(source.parent, rest),
            ["self", rest @ ..] => self.resolve_in(source.own, rest),
            [name, ..] if self.is_child(source.own, name) => self.resolve_in(source.own, &segments),
            _ => None,
        };
        found.filter(|m| *m != source.module)
    }

    fn is_child(&self, scope: Scope, name: &str) -> bool {
        match scope {
            Scope::Root => self.tops.contains(name),
            Scope::Folder(folder) => self.children.get(folder).is_some_and(|c| c.contains(name)),
            Scope::Own => false,
        }
    }

    fn resolve_in(&self, scope: Scope, segments: &[&str]) -> Option<Module> {
        let reexported = |key: Option<&'static str>, name: &str| {
            self.reexports
                .get(&key)
                .and_then(|names| names.get(name))
                .cloned()
        };
        match scope {
            Scope::Own => None,
            Scope::Root => match segments {
                [] => Some(Module::top("lib")),
                [name, rest @ ..] if self.tops.contains(*name) => match self.layout.folder(name) {
                    Some(folder) => self.resolve_in(Scope::Folder(folder), rest),
                    None => Some(Module::top(name)),
                },
                [name, ..] => reexported(None, name).or(Some(Module::top("lib"))),
            },
            Scope::Folder(folder) => match segments {
                [name, ..] if self.is_child(scope, name) => Some(Module::in_folder(folder, name)),
                [name, ..] => {
                    reexported(Some(folder), name).or(Some(Module::in_folder(folder, "mod")))
                }
                [] => Some(Module::in_folder(folder, "mod")),
            },
        }
    }

    /// The layer of a module, as an index of its table.
    pub fn rank(&self, module: &Module) -> Option<usize> {
        self.layers_of(module)?
            .iter()
            .position(|(_, names)| names.contains(&module.name.as_str()))
    }

    fn layers_of(&self, module: &Module) -> Option<Layers> {
        if module.folder.is_empty() {
            Some(self.layout.crate_layers)
        } else {
            self.layout
                .folders
                .iter()
                .find(|(folder, _)| *folder == module.folder)
                .map(|(_, layers)| *layers)
        }
    }

    fn layer_name(&self, module: &Module) -> &'static str {
        match (self.layers_of(module), self.rank(module)) {
            (Some(layers), Some(rank)) => layers[rank].0,
            _ => "?",
        }
    }

    /// The two modules to compare for `from` reaching `to`: the files
    /// themselves in one folder, else their top-level modules.
    fn compared(from: &Module, to: &Module) -> (Module, Module) {
        if from.folder == to.folder {
            (from.clone(), to.clone())
        } else {
            (Module::top(from.top_name()), Module::top(to.top_name()))
        }
    }

    /// The layers of `from` and `to` when `to` lies above `from`.
    fn above(&self, from: &Module, to: &Module) -> Option<(&'static str, &'static str)> {
        let (from, to) = Crate::compared(from, to);
        if from == to {
            return None;
        }
        match (self.rank(&from), self.rank(&to)) {
            (Some(own), Some(other)) if other > own => {
                Some((self.layer_name(&from), self.layer_name(&to)))
            }
            _ => None,
        }
    }

    /// The modules of the sources that are in no layer of their table.
    pub fn unlayered(&self) -> BTreeSet<String> {
        self.sources
            .iter()
            .map(|s| &s.module)
            .filter(|m| self.rank(m).is_none())
            .map(Module::to_string)
            .collect()
    }

    /// The entries of the tables that name no source.
    pub fn stale_entries(&self) -> Vec<String> {
        let mut modules: BTreeSet<Module> = self.sources.iter().map(|s| s.module.clone()).collect();
        modules.extend(self.tops.iter().map(|name| Module::top(name)));
        let mut tables = vec![("", self.layout.crate_layers)];
        tables.extend(self.layout.folders.iter().copied());
        let mut stale = Vec::new();
        for (folder, layers) in tables {
            for name in layers.iter().flat_map(|(_, names)| names.iter()) {
                if !modules.contains(&Module::in_folder(folder, name)) {
                    stale.push(Module::in_folder(folder, name).to_string());
                }
            }
        }
        stale
    }

    /// Every import that names a module above the importer's layer, or a
    /// module in no layer.
    pub fn upward_imports(&self) -> Vec<Finding> {
        let mut found = Vec::new();
        for source in &self.sources {
            let mut seen = BTreeSet::new();
            for (line, path) in paths(&source.code) {
                let Some(to) = self.resolve(source, &path) else {
                    continue;
                };
                if !seen.insert(path.clone()) {
                    continue;
                }
                let (from_cmp, to_cmp) = Crate::compared(&source.module, &to);
                let message = if self.rank(&to_cmp).is_none() {
                    format!(
                        "{}:{line}: `{path}` names {to}, which is in no layer",
                        source.path
                    )
                } else if let Some((own, other)) = self.above(&from_cmp, &to_cmp) {
                    format!(
                        "{}:{line} (layer \"{own}\") imports `{path}` from {to} (layer \"{other}\"), \
                         a layer above it",
                        source.path
                    )
                } else {
                    continue;
                };
                found.push(Finding {
                    file: source.path.clone(),
                    line,
                    from: source.module.clone(),
                    to,
                    what: path,
                    message,
                });
            }
        }
        found
    }

    /// The modules that define each function ([`defined_functions`]).
    fn definitions(&self) -> BTreeMap<String, BTreeSet<Module>> {
        let mut defined: BTreeMap<String, BTreeSet<Module>> = BTreeMap::new();
        for source in &self.sources {
            for name in defined_functions(&source.code) {
                defined
                    .entry(name)
                    .or_default()
                    .insert(source.module.clone());
            }
        }
        defined
    }

    /// Every call, in a folder with a table, of a function that only files
    /// above the caller's layer define, one of them in the caller's folder:
    /// a method reached through a value (`sim.run_for(…)` in a file below
    /// the facade) needs no import. A name defined at or below the caller's
    /// layer anywhere in the crate is ambiguous and passes; across top-level
    /// modules the calls are not compared, as the standard library's and
    /// other crates' methods share too many names with them.
    pub fn upward_calls(&self) -> Vec<Finding> {
        let defined = self.definitions();
        let mut found = Vec::new();
        for source in &self.sources {
            for (line, name) in calls(&source.code) {
                if self.layout.foreign_names.contains(&name.as_str()) {
                    continue;
                }
                let Some(definers) = defined.get(&name) else {
                    continue;
                };
                let in_folder = |definer: &Module| {
                    !definer.folder.is_empty() && definer.folder == source.module.folder
                };
                if !definers.iter().any(in_folder)
                    || definers
                        .iter()
                        .any(|definer| self.above(&source.module, definer).is_none())
                {
                    continue;
                }
                let to = definers
                    .iter()
                    .filter(|definer| in_folder(definer))
                    .min_by_key(|definer| self.rank(definer))
                    .expect("a definer in the folder")
                    .clone();
                let (own, other) = self.above(&source.module, &to).expect("above");
                let names: Vec<String> = definers.iter().map(Module::to_string).collect();
                found.push(Finding {
                    file: source.path.clone(),
                    line,
                    from: source.module.clone(),
                    message: format!(
                        "{}:{line} (layer \"{own}\") calls `{name}`, defined only above it: \
                         in {} ({to}: layer \"{other}\")",
                        source.path,
                        names.join(", "),
                    ),
                    to,
                    what: name,
                });
            }
        }
        found
    }
}

impl Layout {
    fn folder(&self, name: &str) -> Option<&'static str> {
        self.folders
            .iter()
            .map(|(folder, _)| *folder)
            .find(|folder| *folder == name)
    }
}

/// The `.rs` files below `dir`, as paths below `src` with their text.
fn collect(src: &Path, dir: &Path, files: &mut Vec<(String, String)>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .expect("the source folder")
        .map(|entry| entry.expect("an entry").path())
        .collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            collect(src, &path, files);
        } else if path.extension().is_some_and(|e| e == "rs") {
            let relative = path.strip_prefix(src).expect("below src");
            let relative = relative.to_string_lossy().replace('\\', "/");
            files.push((relative, std::fs::read_to_string(&path).expect("a source")));
        }
    }
}

/// The source without comments, the contents of string and character
/// literals, and `#[cfg(test)]` items (a test module, inline or declared);
/// what is removed leaves its line breaks, so lines keep their numbers.
pub fn code_of(source: &str) -> String {
    let stripped = strip_comments_and_strings(source);
    let mut out = String::new();
    let mut lines = stripped.lines();
    while let Some(line) = lines.next() {
        out.push_str(line);
        out.push('\n');
        if !line.trim_start().starts_with("#[cfg(test)]") {
            continue;
        }
        // Skip the next item: a declaration line, or a block to its
        // matching closing brace.
        let mut depth = 0i64;
        let mut opened = false;
        for item in lines.by_ref() {
            out.push('\n');
            depth += item.matches('{').count() as i64;
            depth -= item.matches('}').count() as i64;
            opened |= item.contains('{');
            if (opened && depth <= 0) || (!opened && item.trim_end().ends_with(';')) {
                break;
            }
        }
    }
    out
}

/// The text without `//` comments and without what string and character
/// literals hold (their quotes stay), so a path in a message is no import
/// and a brace in a message opens no block; a string may span lines.
fn strip_comments_and_strings(source: &str) -> String {
    let chars: Vec<char> = source.chars().collect();
    let mut out = String::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        if c == '/' && chars.get(i + 1) == Some(&'/') {
            while i < chars.len() && chars[i] != '\n' {
                i += 1;
            }
            continue;
        }
        if c == '"' {
            out.push('"');
            i += 1;
            while i < chars.len() && chars[i] != '"' {
                if chars[i] == '\\' {
                    i += 1;
                }
                if chars.get(i) == Some(&'\n') {
                    out.push('\n');
                }
                i += 1;
            }
            out.push('"');
            i += 1;
            continue;
        }
        if c == '\'' {
            // A character literal ('x', '\n', '\u{7f}'); a lifetime has no
            // closing quote.
            let close = if chars.get(i + 1) == Some(&'\\') {
                (i + 3..(i + 12).min(chars.len())).find(|&j| chars[j] == '\'')
            } else {
                (chars.get(i + 2) == Some(&'\'')).then_some(i + 2)
            };
            if let Some(close) = close {
                out.push_str("''");
                i = close + 1;
                continue;
            }
        }
        out.push(c);
        i += 1;
    }
    out
}

/// The lines of a text, to find the line (from 1) of a byte offset.
struct LineIndex(Vec<usize>);

impl LineIndex {
    fn of(code: &str) -> LineIndex {
        LineIndex(code.match_indices('\n').map(|(at, _)| at).collect())
    }

    fn line(&self, at: usize) -> usize {
        self.0.partition_point(|&n| n < at) + 1
    }
}

/// Expands a `use` tree (`a::{b, c::{d, e}}`) into its paths.
pub fn expand(tree: &str) -> Vec<String> {
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

/// The paths of the code's `use` trees, each with its line, as the file
/// sees them.
fn use_paths(code: &str) -> Vec<(usize, String)> {
    let lines = LineIndex::of(code);
    let modules = inline_modules(code);
    use_trees(code)
        .into_iter()
        .flat_map(|(at, end)| {
            let line = lines.line(at);
            let depth = depth_at(&modules, at);
            let tree = code[at..end].trim_start_matches("use").trim();
            expand(tree)
                .into_iter()
                .filter_map(move |p| seen_from_file(&p, depth))
                .map(move |p| (line, p))
        })
        .collect()
}

/// The spans of the inline modules (`mod name { … }`) of the code.
fn inline_modules(code: &str) -> Vec<(usize, usize)> {
    let words = identifiers(code);
    let mut spans = Vec::new();
    for pair in words.windows(2) {
        let [(at, word), (name_at, name)] = pair else {
            continue;
        };
        if *word != "mod" || !code[*at + 3..].trim_start().starts_with(name) {
            continue;
        }
        let after = &code[name_at + name.len()..];
        if !after.trim_start().starts_with('{') {
            continue;
        }
        let open = name_at + name.len() + after.find('{').expect("a brace");
        let mut depth = 0i64;
        for (i, c) in code[open..].char_indices() {
            depth += match c {
                '{' => 1,
                '}' => -1,
                _ => 0,
            };
            if depth == 0 {
                spans.push((open, open + i));
                break;
            }
        }
    }
    spans
}

/// How many inline modules hold the offset.
fn depth_at(modules: &[(usize, usize)], at: usize) -> usize {
    modules
        .iter()
        .filter(|(open, close)| *open < at && at < *close)
        .count()
}

/// A path written `depth` inline modules deep, as the file itself would
/// write it (`None`: a name of the inline modules themselves).
fn seen_from_file(path: &str, depth: usize) -> Option<String> {
    if depth == 0 || path.trim_start().starts_with("crate") {
        return Some(path.to_string());
    }
    let segments: Vec<&str> = path.split("::").map(str::trim).collect();
    let supers = segments.iter().take_while(|s| **s == "super").count();
    let rest = segments[supers.min(depth)..].join("::");
    match supers.cmp(&depth) {
        std::cmp::Ordering::Less => None,
        std::cmp::Ordering::Equal => Some(format!("self::{rest}")),
        std::cmp::Ordering::Greater => Some(rest),
    }
}

/// The spans of the `use` trees: from the keyword to the semicolon.
fn use_trees(code: &str) -> Vec<(usize, usize)> {
    let bytes = code.as_bytes();
    let mut spans = Vec::new();
    let mut from = 0;
    while let Some(at) = code[from..]
        .match_indices("use ")
        .map(|(i, _)| from + i)
        .find(|&i| i == 0 || matches!(bytes[i - 1], b'\n' | b' ' | b'{' | b';' | b')'))
    {
        let end = code[at..].find(';').map_or(code.len(), |e| at + e);
        spans.push((at, end));
        from = end;
    }
    spans
}

/// The paths a file names, each with its line: its `use` trees expanded,
/// and the inline `crate::`/`super::` paths of the code outside them.
pub fn paths(code: &str) -> Vec<(usize, String)> {
    let mut found = use_paths(code);
    let mut bytes = code.as_bytes().to_vec();
    for (at, end) in use_trees(code) {
        for b in &mut bytes[at..end] {
            if *b != b'\n' {
                *b = b' ';
            }
        }
    }
    let outside = String::from_utf8(bytes).expect("blanks keep the text UTF-8");
    let lines = LineIndex::of(&outside);
    let modules = inline_modules(&outside);
    let bytes = outside.as_bytes();
    for prefix in ["crate::", "super::"] {
        for (at, _) in outside.match_indices(prefix) {
            let boundary = at == 0 || !is_ident_byte(bytes[at - 1]) && bytes[at - 1] != b':';
            if boundary {
                let path: String = outside[at..]
                    .chars()
                    .take_while(|c| c.is_ascii_alphanumeric() || *c == '_' || *c == ':')
                    .collect();
                let path = path.trim_end_matches(':');
                if let Some(path) = seen_from_file(path, depth_at(&modules, at)) {
                    found.push((lines.line(at), path));
                }
            }
        }
    }
    found
}

fn is_ident_byte(b: u8) -> bool {
    b.is_ascii_alphanumeric() || b == b'_'
}

/// The identifiers of the code with their byte offsets.
fn identifiers(code: &str) -> Vec<(usize, &str)> {
    let bytes = code.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        if is_ident_byte(bytes[i]) && (i == 0 || !is_ident_byte(bytes[i - 1])) {
            let end = (i..bytes.len())
                .find(|&j| !is_ident_byte(bytes[j]))
                .unwrap_or(bytes.len());
            if !bytes[i].is_ascii_digit() {
                out.push((i, &code[i..end]));
            }
            i = end;
        } else {
            i += 1;
        }
    }
    out
}

/// The functions the code defines in inherent `impl` blocks and `trait`
/// definitions, and its free functions with a `pub` (a trait's
/// implementation defines the trait's names, not new ones).
pub fn defined_functions(code: &str) -> BTreeSet<String> {
    let mut defined = BTreeSet::new();
    // Per open brace: whether it opened an `impl` or `trait` block.
    let mut blocks: Vec<bool> = Vec::new();
    let mut pending = false;
    let words = identifiers(code);
    let mut next_word = 0;
    for (at, c) in code.char_indices() {
        while next_word < words.len() && words[next_word].0 < at {
            next_word += 1;
        }
        match c {
            '{' => blocks.push(std::mem::take(&mut pending)),
            '}' => {
                blocks.pop();
            }
            ';' => pending = false,
            _ => {}
        }
        let Some(&(word_at, word)) = words.get(next_word) else {
            continue;
        };
        if word_at != at {
            continue;
        }
        let before = code[..at].trim_end();
        match word {
            "impl" | "trait" => {
                let item_start = before.is_empty()
                    || before.ends_with(['}', ';', '{', ']', ')'])
                    || before.ends_with("pub")
                    || before.ends_with("unsafe");
                // `impl Trait for Type`: the trait's names, not the crate's.
                let header = &code[at..code[at..].find('{').map_or(code.len(), |e| at + e)];
                let trait_impl = word == "impl" && identifiers(header).iter().any(|w| w.1 == "for");
                pending |= item_start && !trait_impl;
            }
            "fn" => {
                let Some(&(_, name)) = words.get(next_word + 1) else {
                    continue;
                };
                let name_follows = code[at + 2..].trim_start().starts_with(name);
                let line_start = before.rfind('\n').map_or(0, |n| n + 1);
                let public = code[line_start..at].contains("pub");
                if name_follows && (blocks.iter().any(|b| *b) || public) {
                    defined.insert(name.to_string());
                }
            }
            _ => {}
        }
    }
    defined
}

/// The calls `.name(` and `Path::name(` of the code (a turbofish
/// allowed), each with its line.
pub fn calls(code: &str) -> Vec<(usize, String)> {
    let lines = LineIndex::of(code);
    let mut found = Vec::new();
    for (at, name) in identifiers(code) {
        let before = code[..at].trim_end();
        let through = (before.ends_with('.') && !before.ends_with(".."))
            || (before.ends_with("::") && !before.ends_with(":::"));
        let after = &code[at + name.len()..];
        if through && (after.starts_with('(') || after.starts_with("::<")) {
            found.push((lines.line(at), name.to_string()));
        }
    }
    found
}
