//! The layers of the co-simulation slave: a module may import only from its
//! own layer or the layers below it (docs/architecture.md describes the
//! modules; the library's `tests/layers.rs` checks the library alike).
//!
//! The test reads the sources with the library's `layering`: every `use`
//! tree and inline path, outside comments and `#[cfg(test)]` items, is
//! resolved to the module it names (a name `lib.rs` re-exports, such as
//! `crate::Slave`, to the module that defines it). `slave/`, `variables/`
//! and `entry/` are read with `slave.rs`, `variables.rs` and `entry.rs`.

#[path = "../../tdvass/tests/layering/mod.rs"]
mod layering;

use layering::{Crate, Layout};
use std::path::Path;

/// The modules of `crates/tdvass-fmu/src`, from the ground up.
const CRATE_LAYERS: layering::Layers = &[
    ("ground", &["defaults", "error", "phase"]),
    (
        "settings and outputs",
        &["settings", "outputs", "chassis_outputs"],
    ),
    ("variable table", &["variables"]),
    ("guards and engine state", &["guards", "state"]),
    ("FMU states", &["snapshot"]),
    ("slave", &["slave"]),
    ("C glue", &["pointers", "instantiation", "entry"]),
    ("root", &["lib"]),
];

/// The slave's layout: one table, no folder read file by file.
const LAYOUT: Layout = Layout {
    crate_layers: CRATE_LAYERS,
    folders: &[],
    foreign_names: &[],
};

fn slave_crate() -> Crate {
    Crate::read(&LAYOUT, &Path::new(env!("CARGO_MANIFEST_DIR")).join("src"))
}

#[test]
fn no_module_imports_a_layer_above_its_own() {
    let found: Vec<String> = slave_crate()
        .upward_imports()
        .into_iter()
        .map(|f| f.message)
        .collect();
    assert!(
        found.is_empty(),
        "imports against the layers (crates/tdvass-fmu/tests/layers.rs):\n{}",
        found.join("\n")
    );
}

#[test]
fn every_module_has_a_layer() {
    let slave = slave_crate();
    let missing = slave.unlayered();
    assert!(missing.is_empty(), "modules in no layer: {missing:?}");
    let stale = slave.stale_entries();
    assert!(stale.is_empty(), "layers naming no source: {stale:?}");
}

#[test]
fn an_upward_import_is_found() {
    let lib = "pub mod entry;\npub mod settings;\npub mod slave;\npub use slave::Slave;\n";
    for (file, code, upward) in [
        // Through the root's re-export, to the slave: below the C glue.
        ("entry.rs", "use crate::Slave;\n", 0),
        (
            "entry.rs",
            "pub mod fmu_state {\n    use super::FrontEnd;\n    use crate::Slave;\n}\n",
            0,
        ),
        ("settings.rs", "use crate::Slave;\n", 1),
        ("settings.rs", "fn f(s: &crate::slave::Slave) {}\n", 1),
        ("settings.rs", "use crate::entry::{self, call};\n", 2),
        (
            "settings.rs",
            "mod inner {\n    use super::super::entry;\n}\n",
            1,
        ),
        ("slave/values.rs", "use crate::entry::call;\n", 1),
        (
            "slave/values.rs",
            "use super::Slave;\nuse crate::settings::Settings;\n",
            0,
        ),
    ] {
        let mut files = vec![
            ("lib.rs", lib),
            ("entry.rs", ""),
            ("settings.rs", ""),
            ("slave.rs", "mod values;\npub struct Slave;\n"),
            ("slave/values.rs", ""),
        ];
        files.retain(|(path, _)| *path != file);
        files.push((file, code));
        let found = Crate::of_texts(&LAYOUT, &files).upward_imports();
        assert_eq!(found.len(), upward, "{file}: {code}: {found:?}");
    }
}
