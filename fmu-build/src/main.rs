//! Builds `target/fmu/tdvass.fmu` and refreshes the checked-in
//! `modelDescription/modelDescription.xml`.
//!
//! ```text
//! cargo run --release -p fmu-build            # build the FMU, refresh the copy
//! cargo run --release -p fmu-build -- --check # fail if the checked-in copy is stale
//! ```
//!
//! The description and documentation come from the library
//! ([`tdvass::fmi2::description`]), generated from the variable table.

use std::fs;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};
use tdvass::fmi2::description::{documentation_html, model_description_xml};
use tdvass::fmi2::markdown::{BEGIN_MARKER, END_MARKER, splice_into};
use tdvass::fmi2::{MODEL_IDENTIFIER, guid};
use zip::write::SimpleFileOptions;
use zip::{CompressionMethod, DateTime, ZipArchive, ZipWriter};

const CHECKED_IN: &str = "modelDescription/modelDescription.xml";
/// The README, whose FMU variable table is generated.
const README: &str = "README.md";

type Result<T> = std::result::Result<T, String>;

fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("fmu-build lives in the workspace")
        .to_path_buf()
}

/// `target/` of the workspace (honours `CARGO_TARGET_DIR`).
fn target_dir(root: &Path) -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .map(|p| if p.is_absolute() { p } else { root.join(p) })
        .unwrap_or_else(|| root.join("target"))
}

fn build_library(root: &Path) -> Result<PathBuf> {
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    eprintln!("fmu-build: cargo build --release -p tdvass --lib");
    let status = Command::new(&cargo)
        .args(["build", "--release", "-p", "tdvass", "--lib"])
        .current_dir(root)
        .status()
        .map_err(|e| format!("cannot run {}: {e}", cargo.to_string_lossy()))?;
    if !status.success() {
        return Err(format!("cargo build of the library failed ({status})"));
    }
    let library = target_dir(root)
        .join("release")
        .join(format!("lib{MODEL_IDENTIFIER}.so"));
    if !library.is_file() {
        return Err(format!(
            "the shared library {} was not built",
            library.display()
        ));
    }
    Ok(library)
}

fn write_fmu(path: &Path, entries: &[(&str, &[u8], u32)]) -> Result<()> {
    let file =
        fs::File::create(path).map_err(|e| format!("cannot create {}: {e}", path.display()))?;
    let mut zip = ZipWriter::new(file);
    for (name, bytes, mode) in entries {
        let options = SimpleFileOptions::default()
            .compression_method(CompressionMethod::Deflated)
            .last_modified_time(DateTime::default())
            .unix_permissions(*mode);
        zip.start_file(*name, options)
            .and_then(|()| zip.write_all(bytes).map_err(Into::into))
            .map_err(|e| format!("cannot write {name} into {}: {e}", path.display()))?;
    }
    zip.finish()
        .map_err(|e| format!("cannot finish {}: {e}", path.display()))?;
    Ok(())
}

/// Re-opens the archive: exactly the expected files, with the expected content.
fn check_fmu(path: &Path, entries: &[(&str, &[u8], u32)]) -> Result<()> {
    let file = fs::File::open(path).map_err(|e| format!("cannot open {}: {e}", path.display()))?;
    let mut archive = ZipArchive::new(file)
        .map_err(|e| format!("{} is not a zip archive: {e}", path.display()))?;
    let mut names = archive
        .file_names()
        .map(|n| n.map(|n| n.into_owned()))
        .collect::<std::result::Result<Vec<String>, _>>()
        .map_err(|e| format!("{}: {e}", path.display()))?;
    names.sort();
    let mut expected: Vec<String> = entries.iter().map(|(n, _, _)| n.to_string()).collect();
    expected.sort();
    if names != expected {
        return Err(format!(
            "{} contains {names:?}, expected {expected:?}",
            path.display()
        ));
    }
    for (name, bytes, _) in entries {
        let mut content = Vec::new();
        archive
            .by_name(name)
            .map_err(|e| format!("{name}: {e}"))?
            .read_to_end(&mut content)
            .map_err(|e| format!("{name}: {e}"))?;
        if content != *bytes {
            return Err(format!(
                "{name} in {} differs from what was written",
                path.display()
            ));
        }
    }
    Ok(())
}

/// A generated file kept in the repository, with the content it must have.
struct CheckedIn {
    path: &'static str,
    expected: String,
    current: Option<String>,
}

/// The checked-in copies: the model description, and the variable table in
/// README.md (between its markers).
fn checked_in(root: &Path, description: &str) -> Result<Vec<CheckedIn>> {
    let read = |path: &str| fs::read_to_string(root.join(path)).ok();
    let readme = read(README).ok_or(format!("{README} cannot be read"))?;
    let readme_expected = splice_into(&readme).ok_or(format!(
        "{README} lacks the lines `{BEGIN_MARKER}` and `{END_MARKER}` around the variable table"
    ))?;
    Ok(vec![
        CheckedIn {
            path: CHECKED_IN,
            expected: description.to_string(),
            current: read(CHECKED_IN),
        },
        CheckedIn {
            path: README,
            expected: readme_expected,
            current: Some(readme),
        },
    ])
}

fn check_only(root: &Path, description: &str) -> Result<()> {
    for copy in checked_in(root, description)? {
        let current = copy.current.as_deref().ok_or(format!(
            "{} cannot be read; run `cargo run --release -p fmu-build` and commit it",
            copy.path
        ))?;
        if current != copy.expected {
            let line = current
                .lines()
                .zip(copy.expected.lines())
                .position(|(a, b)| a != b)
                .map(|i| i + 1)
                .unwrap_or(current.lines().count().min(copy.expected.lines().count()) + 1);
            return Err(format!(
                "{} is stale (first difference at line {line}); run `cargo run --release -p fmu-build` and commit the result",
                copy.path
            ));
        }
    }
    eprintln!(
        "fmu-build: {CHECKED_IN} and the variable table of {README} are up to date (GUID {})",
        guid()
    );
    Ok(())
}

fn build(root: &Path, description: &str) -> Result<()> {
    let library = build_library(root)?;
    let binary =
        fs::read(&library).map_err(|e| format!("cannot read {}: {e}", library.display()))?;
    let documentation = documentation_html();
    let binary_name = format!("binaries/linux64/{MODEL_IDENTIFIER}.so");
    let entries: [(&str, &[u8], u32); 3] = [
        ("modelDescription.xml", description.as_bytes(), 0o644),
        (binary_name.as_str(), &binary, 0o755),
        ("documentation/index.html", documentation.as_bytes(), 0o644),
    ];
    let out_dir = target_dir(root).join("fmu");
    fs::create_dir_all(&out_dir)
        .map_err(|e| format!("cannot create {}: {e}", out_dir.display()))?;
    let fmu = out_dir.join(format!("{MODEL_IDENTIFIER}.fmu"));
    write_fmu(&fmu, &entries)?;
    check_fmu(&fmu, &entries)?;
    let mut refreshed = Vec::new();
    for copy in checked_in(root, description)? {
        if copy.current.as_deref() != Some(copy.expected.as_str()) {
            let path = root.join(copy.path);
            if let Some(dir) = path.parent() {
                fs::create_dir_all(dir)
                    .map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
            }
            fs::write(&path, &copy.expected)
                .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
            refreshed.push(copy.path);
        }
    }
    eprintln!(
        "fmu-build: wrote {} ({} bytes; GUID {}); refreshed: {}",
        fmu.display(),
        fs::metadata(&fmu).map(|m| m.len()).unwrap_or(0),
        guid(),
        if refreshed.is_empty() {
            "nothing".to_string()
        } else {
            refreshed.join(", ")
        }
    );
    Ok(())
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let check = match args.as_slice() {
        [] => false,
        [flag] if flag == "--check" => true,
        _ => {
            eprintln!("usage: fmu-build [--check]");
            return ExitCode::from(2);
        }
    };
    let root = workspace_root();
    let description = model_description_xml();
    let result = if check {
        check_only(&root, &description)
    } else {
        build(&root, &description)
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("fmu-build: error: {message}");
            ExitCode::FAILURE
        }
    }
}
