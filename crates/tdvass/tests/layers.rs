//! The layers of the library: a module may import only from its own layer
//! or the layers below it, and may not call a function that only modules
//! above it define (docs/architecture.md draws them).
//!
//! The test reads the sources (`layering`): every `use` tree and every
//! inline path, outside comments and `#[cfg(test)]` modules, is resolved
//! to the file it names, and that file's layer must not lie above the
//! importer's. The top-level modules have the layers of `CRATE_LAYERS`;
//! the files of `solver/`, `model/`, `road/`, `exchange/` and `analysis/`
//! have their folder's table, where `mod.rs` is the top and a child's
//! `super::x` names its sibling `x` (or `mod.rs`). Inside a folder, a call
//! of a function that only files above the caller define is upward too (a
//! method reached through a value needs no import). A new upward import or
//! call fails the test, naming both files and the path or the function;
//! those the code has today are listed, each with what ties the two files.

#[path = "layering/mod.rs"]
mod layering;

use layering::{Crate, Finding, Layout};
use std::path::Path;

/// The top-level modules of `crates/tdvass/src`, from the ground up.
const CRATE_LAYERS: layering::Layers = &[
    ("ground", &["error", "math", "monotone"]),
    ("data", &["bytes", "model", "comfort", "road"]),
    ("checks", &["metrics", "limits"]),
    ("solver", &["solver"]),
    ("engines", &["exchange", "chassis", "car"]),
    ("analysis", &["analysis"]),
    ("root", &["lib"]),
];

/// The files of `crates/tdvass/src/solver`, from the ground up.
const SOLVER_LAYERS: layering::Layers = &[
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

/// The files of `crates/tdvass/src/model`, from the ground up.
const MODEL_LAYERS: layering::Layers = &[
    ("parameters and state", &["params"]),
    ("element laws", &["equations", "tire", "body", "inputs"]),
    ("plant", &["plant"]),
    ("dynamics", &["dynamics"]),
    ("model", &["mod"]),
];

/// The files of `crates/tdvass/src/road`, from the ground up.
const ROAD_LAYERS: layering::Layers = &[
    ("specification, saved forms", &["spec", "saved"]),
    ("pieces", &["piece"]),
    ("node generator", &["nodes"]),
    ("road", &["mod"]),
];

/// The files of `crates/tdvass/src/exchange`, from the ground up.
const EXCHANGE_LAYERS: layering::Layers = &[
    ("delay history", &["history"]),
    ("instance", &["instance"]),
    (
        "time, partials, saved state",
        &["reach", "jacobian", "persist"],
    ),
    ("engine", &["mod"]),
];

/// The files of `crates/tdvass/src/car`, from the ground up.
const CAR_LAYERS: layering::Layers = &[
    ("system", &["layout", "mirror"]),
    ("step maps, crossings", &["maps", "crossings", "averages"]),
    ("run", &["run"]),
    ("car", &["mod"]),
];

/// The files of `crates/tdvass/src/analysis`, from the ground up.
const ANALYSIS_LAYERS: layering::Layers = &[
    (
        "polynomials, search, response",
        &["polynomial", "pso", "frf", "parallel"],
    ),
    ("characteristic equation", &["characteristic"]),
    ("spectrum", &["spectrum"]),
    ("stability", &["stability"]),
    ("optimisation", &["optimize"]),
    ("analysis", &["mod"]),
];

/// The library's layout: the crate's table and each folder's.
const LAYOUT: Layout = Layout {
    crate_layers: CRATE_LAYERS,
    folders: &[
        ("solver", SOLVER_LAYERS),
        ("model", MODEL_LAYERS),
        ("road", ROAD_LAYERS),
        ("exchange", EXCHANGE_LAYERS),
        ("car", CAR_LAYERS),
        ("analysis", ANALYSIS_LAYERS),
    ],
    // `dense`'s partial-step filter beside `Iterator::filter`.
    foreign_names: &["filter"],
};

/// The upward imports the library has today: `(importer, imported, what
/// ties them)`. Each folder's shared types live in its `mod.rs`, which in
/// turn uses or re-exports the importer, so the two files form a circle
/// until those types move to a file below both. The test fails when an
/// entry is no longer found, so that the list only shrinks.
const KNOWN_UPWARD_IMPORTS: &[(&str, &str, &str)] = &[];

/// The upward calls the library has today: `(caller, function, why it
/// stays)`. The test fails when an entry is no longer found.
const KNOWN_UPWARD_CALLS: &[(&str, &str, &str)] = &[];

fn library() -> Crate {
    Crate::read(&LAYOUT, &Path::new(env!("CARGO_MANIFEST_DIR")).join("src"))
}

/// The findings whose key is not in `known`, and the entries of `known`
/// that no finding has.
fn unexpected(
    found: &[Finding],
    known: &[(String, String)],
    key: impl Fn(&Finding) -> (String, String),
) -> (Vec<String>, Vec<String>) {
    let new: Vec<String> = found
        .iter()
        .filter(|f| !known.contains(&key(f)))
        .map(|f| f.message.clone())
        .collect();
    let keys: Vec<_> = found.iter().map(&key).collect();
    let stale: Vec<String> = known
        .iter()
        .filter(|entry| !keys.contains(entry))
        .map(|entry| format!("{entry:?}"))
        .collect();
    (new, stale)
}

/// The findings of `file`.
fn of_file(found: Vec<Finding>, file: &str) -> Vec<Finding> {
    found.into_iter().filter(|f| f.file == file).collect()
}

#[test]
fn no_module_imports_a_layer_above_its_own() {
    let known: Vec<_> = KNOWN_UPWARD_IMPORTS
        .iter()
        .map(|(from, to, _)| (from.to_string(), to.to_string()))
        .collect();
    let (new, stale) = unexpected(&library().upward_imports(), &known, |f| {
        (f.from.to_string(), f.to.to_string())
    });
    assert!(
        new.is_empty(),
        "imports against the layers (docs/architecture.md):\n{}",
        new.join("\n")
    );
    assert!(
        stale.is_empty(),
        "KNOWN_UPWARD_IMPORTS entries no longer found (remove them): {stale:?}"
    );
}

#[test]
fn no_module_calls_a_function_only_a_layer_above_defines() {
    let known: Vec<_> = KNOWN_UPWARD_CALLS
        .iter()
        .map(|(from, name, _)| (from.to_string(), name.to_string()))
        .collect();
    let (new, stale) = unexpected(&library().upward_calls(), &known, |f| {
        (f.from.to_string(), f.what.clone())
    });
    assert!(
        new.is_empty(),
        "calls against the layers (docs/architecture.md):\n{}",
        new.join("\n")
    );
    assert!(
        stale.is_empty(),
        "KNOWN_UPWARD_CALLS entries no longer found (remove them): {stale:?}"
    );
}

#[test]
fn every_module_has_a_layer() {
    let library = library();
    let missing = library.unlayered();
    assert!(missing.is_empty(), "modules in no layer: {missing:?}");
    let stale = library.stale_entries();
    assert!(stale.is_empty(), "layers naming no source: {stale:?}");
}

#[test]
fn an_upward_import_is_found() {
    for code in [
        "use super::Simulator;\n",
        "use super::{dense::DenseOutput, expm};\n",
        "fn f() { let d = super::dense::offset_key(1.0, 2.0); }\n",
        "use crate::analysis::pso;\n",
        "use crate::solver::Simulator;\n",
        "use crate::solver::{driver::Simulator as Sim};\n",
    ] {
        let crate_ = Crate::of_texts(
            &LAYOUT,
            &[
                ("solver/linalg.rs", code),
                ("solver/dense.rs", ""),
                ("solver/driver.rs", ""),
                ("solver/expm.rs", ""),
                (
                    "solver/mod.rs",
                    "mod dense;\nmod driver;\npub use driver::Simulator;\n",
                ),
            ],
        );
        let found = of_file(crate_.upward_imports(), "solver/linalg.rs");
        assert_eq!(found.len(), 1, "{code}: {found:?}");
    }
    let crate_ = Crate::of_texts(
        &LAYOUT,
        &[
            ("road/mod.rs", "use crate::solver::dense::Augmented;\n"),
            ("solver/dense.rs", ""),
        ],
    );
    assert_eq!(crate_.upward_imports().len(), 1);
}

#[test]
fn comments_strings_and_tests_are_no_imports() {
    let code = "//! See [`super::Simulator`].\n\
         fn f() -> &'static str { \"crate::analysis\" } // super::dense\n\
         fn g() -> String { format!(\"{{ a brace \\\n  super::dense }}\") }\n\
         fn h() -> char { '{' }\n\
         #[cfg(test)]\n\
         mod tests {\n    use super::super::Simulator;\n    use crate::solver::dense;\n}\n\
         use super::expm;\n";
    let crate_ = Crate::of_texts(
        &LAYOUT,
        &[
            ("solver/linalg.rs", code),
            ("solver/dense.rs", ""),
            ("solver/expm.rs", ""),
        ],
    );
    let found = crate_.upward_imports();
    assert!(found.is_empty(), "{code}: {found:?}");
}

#[test]
fn a_folder_file_importing_a_higher_sibling_is_found() {
    let files = |spec: &'static str, nodes: &'static str| {
        Crate::of_texts(
            &LAYOUT,
            &[
                ("road/spec.rs", spec),
                ("road/piece.rs", ""),
                ("road/nodes.rs", nodes),
                (
                    "road/mod.rs",
                    "mod nodes;\npub mod piece;\npub mod spec;\n\
                 use nodes::NodeSequence;\npub use piece::RoadPiece;\npub struct Road;\n",
                ),
            ],
        )
    };
    // A sibling's item re-exported by mod.rs is the sibling's: below nodes.
    let lower = files(
        "",
        "use super::RoadPiece;\nuse crate::road::spec::RoadSpec;\n",
    );
    assert!(lower.upward_imports().is_empty());
    for (spec, what) in [
        ("use super::RoadPiece;\n", "super::RoadPiece"),
        (
            "use super::nodes::NodeSequence;\n",
            "super::nodes::NodeSequence",
        ),
        ("fn f(r: crate::road::Road) {}\n", "crate::road::Road"),
        ("use crate::road::piece;\n", "crate::road::piece"),
    ] {
        let found = of_file(files(spec, "").upward_imports(), "road/spec.rs");
        assert_eq!(found.len(), 1, "{spec}: {found:?}");
        assert_eq!(found[0].what, what);
    }
}

#[test]
fn an_upward_call_is_found() {
    let crate_ = Crate::of_texts(
        &LAYOUT,
        &[
            (
                "solver/linalg.rs",
                "fn f(sim: &mut Simulator) {\n    sim.step();\n    sim\n        .run_for(1.0);\n}\n",
            ),
            ("solver/expm.rs", "impl Exp {\n    fn step(&self) {}\n}\n"),
            (
                "solver/driver.rs",
                "fn g() { let s = Simulator::summary(1); }\n",
            ),
            (
                "solver/outputs.rs",
                "impl Simulator {\n    pub(super) fn summary(n: u8) {}\n}\n",
            ),
            (
                "solver/mod.rs",
                "impl Simulator {\n    pub fn run_for(&mut self, t: f64) {}\n    \
             pub fn step(&mut self) {}\n}\n",
            ),
        ],
    );
    let found = crate_.upward_calls();
    let mut calls: Vec<(&str, usize, &str, String)> = found
        .iter()
        .map(|f| (f.file.as_str(), f.line, f.what.as_str(), f.to.to_string()))
        .collect();
    calls.sort();
    // `step` is defined in `expm`, linalg's own layer: ambiguous.
    assert_eq!(
        calls,
        [
            (
                "solver/driver.rs",
                1,
                "summary",
                "solver/outputs".to_string()
            ),
            ("solver/linalg.rs", 4, "run_for", "solver/mod".to_string()),
        ],
        "{found:?}"
    );
}
