//! What is written about the tdvass FMUs, at build time: their model
//! descriptions, documentation pages and the table of variables in docs/fmu.md,
//! all generated from the one variable table
//! ([`tdvass_fmu::variables`]). `fmu-build` is its only user: it packs the
//! descriptions and pages into the FMUs and keeps the checked-in copies
//! current.
//!
//! - [`fmi2`]: the FMI 2.0 `modelDescription.xml` and
//!   `documentation/index.html`.
//! - [`fmi3`]: the FMI 3.0 `modelDescription.xml` and
//!   `documentation/index.html`.
//! - [`markup`]: what both versions write alike: the header of a model
//!   description and its unit definitions (the units its variables use),
//!   numbers, text elements,
//!   paragraphs, lists, tables, the model's diagram with its legend, and
//!   the HTML page around a body.
//! - [`markdown`]: the variable table as Markdown for docs/fmu.md (the
//!   quarter car's).
//! - `component`: the documentation page of a component of a vehicle
//!   (the corner, the chassis), which both versions write from what
//!   differs between them.
//!
//! Every model the library serves ([`tdvass_fmu::Model`]: the quarter car,
//! the corner, the chassis) has its own model description and page in each
//! version; the corner's and the chassis's have no Model Exchange, and the
//! chassis declares its own Co-Simulation capabilities (no directional or
//! output derivatives, no intermediate update).
//!
//! Every document is written with quick-xml (no markup by hand, so every
//! value is escaped) and is deterministic: no timestamps.
//!
//! **Why a crate of its own.** The FMU libraries (`tdvass-fmi2`,
//! `tdvass-fmi3`) carry runtime code only: neither the writers nor
//! quick-xml are linked into the shared library an importer loads. A cargo
//! feature of the front-ends would not guarantee that: features are
//! unified across the workspace, so building the front-ends together with
//! fmu-build would switch the writers on in the shipped libraries too. A
//! separate crate that only fmu-build depends on cannot leak into them.
//!
//! **What this crate owns and must never import.** It owns the text of the
//! descriptions and documentation. It reads the variable table and the
//! constants of the slave (`tdvass-fmu`), the FMI version, token and
//! FMI 3.0 types of each front-end, and the solver's default tolerance
//! (`tdvass`); nothing depends on it but fmu-build. It has no `unsafe`.

#![forbid(unsafe_code)]

mod component;
pub mod fmi2;
pub mod fmi3;
pub mod markdown;
pub mod markup;

#[cfg(test)]
mod parsed;
