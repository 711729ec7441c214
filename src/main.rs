//! The `tdvass` command line: simulate, stability, stable, frf, optimize and
//! map, each with a human-readable table or one JSON object (`--json`).
//!
//! This crate owns the argument parsing (clap), the progress display
//! (indicatif) and all JSON formatting (serde_json); the physics comes from
//! the `tdvass` library, which imports none of them.

mod cli;
mod json;

fn main() -> std::process::ExitCode {
    cli::main_entry()
}
