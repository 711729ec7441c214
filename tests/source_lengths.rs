//! No source file of the workspace (Rust, Python, C, shell) is longer than
//! 700 lines unless its opening comment says why (docs/architecture.md).
//!
//! A reason is recognised by its wording: "hence its length", "hence the
//! length", "its length is", "its length (", "a long file on purpose" or
//! "over 700 lines", in the first 40 lines with the comment markers and
//! line breaks taken out.

use std::path::{Path, PathBuf};

/// The longest a source file may be without a stated reason.
const MOST_LINES: usize = 700;
/// How far from its top a file's reason must be stated.
const OPENING_LINES: usize = 40;
/// The extensions of the files that are checked.
const SOURCE_EXTENSIONS: [&str; 5] = ["rs", "py", "c", "h", "sh"];
/// Folders that hold no sources of the project (build output, local
/// environments, fuzzing inputs).
const SKIPPED_FOLDERS: [&str; 5] = ["target", "corpus", "artifacts", "out", "__pycache__"];
/// The wordings that state why a file is long.
const REASONS: [&str; 6] = [
    "hence its length",
    "hence the length",
    "its length is",
    "its length (",
    "long file on purpose",
    "over 700 lines",
];

/// Every source file under `folder`, skipping hidden and skipped folders.
fn sources(folder: &Path, found: &mut Vec<PathBuf>) {
    let mut entries: Vec<_> = std::fs::read_dir(folder)
        .unwrap_or_else(|e| panic!("reading {}: {e}", folder.display()))
        .map(|entry| entry.expect("a directory entry").path())
        .collect();
    entries.sort();
    for path in entries {
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
        if path.is_dir() {
            if !name.starts_with('.') && !SKIPPED_FOLDERS.contains(&name) {
                sources(&path, found);
            }
        } else if path
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| SOURCE_EXTENSIONS.contains(&e))
        {
            found.push(path);
        }
    }
}

/// The opening of `text` as prose: its first [`OPENING_LINES`] lines with
/// comment markers taken out, joined by single spaces, in lower case.
fn opening_prose(text: &str) -> String {
    text.lines()
        .take(OPENING_LINES)
        .map(|line| {
            line.trim()
                .trim_start_matches("//!")
                .trim_start_matches("//")
                .trim_start_matches("/*")
                .trim_start_matches('*')
                .trim_start_matches('#')
                .trim_start_matches("\"\"\"")
                .trim()
        })
        .collect::<Vec<_>>()
        .join(" ")
        .to_lowercase()
}

/// Whether a file of `text` may be as long as it is.
fn length_allowed(text: &str) -> bool {
    let prose = opening_prose(text);
    text.lines().count() <= MOST_LINES || REASONS.iter().any(|reason| prose.contains(reason))
}

#[test]
fn no_source_file_is_longer_than_700_lines_without_a_stated_reason() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut found = Vec::new();
    sources(root, &mut found);
    assert!(
        found.iter().any(|p| p.ends_with("src/main.rs")),
        "the walk found no sources under {}",
        root.display()
    );
    let long: Vec<String> = found
        .iter()
        .filter(|path| {
            let text = std::fs::read_to_string(path).unwrap_or_default();
            !length_allowed(&text)
        })
        .map(|path| {
            path.strip_prefix(root)
                .unwrap_or(path)
                .display()
                .to_string()
        })
        .collect();
    assert!(
        long.is_empty(),
        "longer than {MOST_LINES} lines with no reason stated at the top: {long:?}"
    );
}

#[test]
fn a_long_file_passes_only_with_its_reason_in_its_opening() {
    let body = "fn f() {}\n".repeat(MOST_LINES);
    assert!(!length_allowed(&format!("//! A module.\n{body}")));
    assert!(length_allowed(&format!(
        "//! A module, one table on purpose\n//! (hence its\n//! length).\n{body}"
    )));
    assert!(length_allowed(&format!(
        "\"\"\"A test file: a long file on purpose.\"\"\"\n{body}"
    )));
    let late = format!(
        "{}// hence its length\n",
        "fn f() {}\n".repeat(OPENING_LINES)
    );
    assert!(!length_allowed(&format!("{late}{body}")));
    assert!(length_allowed(&"fn f() {}\n".repeat(MOST_LINES)));
}
