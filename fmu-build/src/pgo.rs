//! Profile-guided optimization of the x86-64 Linux libraries.
//!
//! A master's call spends most of its time in the bookkeeping around a
//! short numerical step (the FMI entry, the state table, the step's checks,
//! the RMS integrals' closure), spread over many small functions. With the
//! counts of a training run, the compiler inlines along the paths masters
//! take and keeps the hot code together: 13–18 % fewer instructions and
//! a quarter fewer instruction-cache misses per communication point of the
//! fmpy loops of `benches/fmu_vs_reference.py` (BENCHMARKS.md § 12).
//!
//! For a target (`None`: the host), [`train`]:
//! 1. builds the training run, `crates/tdvass-fmi2/examples/pgo_training.rs`
//!    (FMI 2.0 master loops over the roads, variants, tires, steps and
//!    getters), with `-Cprofile-generate` into
//!    `target/pgo/<target>/instrumented`;
//! 2. runs it, which writes its counts into `target/pgo/<target>/raw`;
//! 3. merges them with `llvm-profdata` (the rustup component
//!    `llvm-tools`) into `target/pgo/<target>/tdvass.profdata`, rewritten
//!    only when its content changes, so that an unchanged profile rebuilds
//!    nothing.
//!
//! Both FMUs' libraries are then built with `-Cprofile-use` of it into
//! `target/pgo/<target>/optimized` ([`Profile::target_dir`]), apart from the
//! libraries of `target/release`, so that the two builds do not take turns
//! in one directory. The profile changes what is inlined and where code
//! lies, never a floating-point operation: the outputs are the same to the
//! bit (tests/python/test_reference_results.py compares the FMUs with the
//! results fmu-build's own slave computes, exactly).
//!
//! The instrumented code is compiled by the same command as the optimized
//! one (cargo-zigbuild for the glibc floor), so that the symbols match:
//! their hash includes the target and its linker. The training takes the
//! AVX2 loop where the CPU has it (every x86-64 build machine of the last
//! decade); a build machine without AVX2 would train the other loop and
//! give a different, equally correct library. Without `llvm-profdata` the
//! host build goes without a profile and says so; the build of every
//! platform requires it, unless `--no-profile` skips the training.

use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

use crate::Result;

/// The training run's example name.
const TRAINING_EXAMPLE: &str = "pgo_training";
/// The cargo arguments that build the training run (the caller adds the
/// target).
pub const TRAINING_ARGS: [&str; 5] = [
    "--release",
    "-p",
    "tdvass-fmi2",
    "--example",
    TRAINING_EXAMPLE,
];
/// The merged profile's file name.
const PROFILE_FILE: &str = "tdvass.profdata";
/// How to install `llvm-profdata`.
pub const INSTALL_HINT: &str = "`rustup component add llvm-tools`";

/// A merged profile and where the libraries built with it go.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Profile {
    /// The `.profdata` file (absolute).
    pub path: PathBuf,
    /// `CARGO_TARGET_DIR` of the optimized build.
    pub target_dir: PathBuf,
}

impl Profile {
    /// `RUSTFLAGS` of the optimized build: `existing` (the caller's
    /// `RUSTFLAGS`, if any) and `-Cprofile-use`.
    pub fn rustflags(&self, existing: Option<&str>) -> String {
        join_flags(existing, &format!("-Cprofile-use={}", self.path.display()))
    }
}

/// `existing` flags, then `flag`, space-separated.
fn join_flags(existing: Option<&str>, flag: &str) -> String {
    match existing.map(str::trim).filter(|s| !s.is_empty()) {
        Some(existing) => format!("{existing} {flag}"),
        None => flag.to_string(),
    }
}

/// `target/pgo/<target>` (`host` for the host build).
pub fn directory(target: &Path, triple: Option<&str>) -> PathBuf {
    target.join("pgo").join(triple.unwrap_or("host"))
}

/// The `llvm-profdata` of the Rust toolchain (`rustup component add
/// llvm-tools`), if installed: `<sysroot>/lib/rustlib/<host>/bin/`.
pub fn llvm_profdata() -> Option<PathBuf> {
    let rustc = std::env::var_os("RUSTC").unwrap_or_else(|| "rustc".into());
    let text = |args: &[&str]| -> Option<String> {
        let output = Command::new(&rustc).args(args).output().ok()?;
        output
            .status
            .success()
            .then(|| String::from_utf8_lossy(&output.stdout).into_owned())
    };
    let sysroot = text(&["--print", "sysroot"])?;
    let host = text(&["-vV"])?
        .lines()
        .find_map(|l| l.strip_prefix("host: ").map(str::to_string))?;
    let tool = Path::new(sysroot.trim())
        .join("lib/rustlib")
        .join(host.trim())
        .join("bin")
        .join(format!("llvm-profdata{}", std::env::consts::EXE_SUFFIX));
    tool.is_file().then_some(tool)
}

/// Runs `command` (shown as `what`) and fails unless it succeeds.
fn run(command: &mut Command, what: &str) -> Result<()> {
    eprintln!("fmu-build: {what}");
    let status = command
        .status()
        .map_err(|e| format!("cannot run {what}: {e}"))?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("{what} failed ({status})"))
    }
}

/// Trains the profile of the libraries for `triple` (`None`: the host)
/// under the workspace `root` with target directory `target`: `build` is
/// the command that builds [`TRAINING_ARGS`] for the platform as its
/// libraries are built, so that the symbols match; with `zig_linked` its
/// instrumented binary is linked by the host's `cc` instead (zig's linker
/// driver does not take rustc's `-u __llvm_profile_runtime`; the target
/// linker cargo knows of, which the symbols' hash includes, stays zig's).
/// `None` when `llvm-profdata` is not installed.
pub fn train(
    root: &Path,
    target: &Path,
    triple: Option<&str>,
    mut build: Command,
    zig_linked: bool,
) -> Result<Option<Profile>> {
    let Some(profdata) = llvm_profdata() else {
        eprintln!(
            "fmu-build: llvm-profdata not found ({INSTALL_HINT}): \
             the libraries are built without profile-guided optimization"
        );
        return Ok(None);
    };
    let dir = directory(target, triple);
    let raw = dir.join("raw");
    let instrumented = dir.join("instrumented");
    let existing = std::env::var("RUSTFLAGS").ok();
    let mut flags = join_flags(
        existing.as_deref(),
        &format!("-Cprofile-generate={}", raw.display()),
    );
    if zig_linked {
        flags = join_flags(Some(&flags), "-Clinker=cc");
    }
    build
        .current_dir(root)
        .env("CARGO_TARGET_DIR", &instrumented)
        .env("RUSTFLAGS", flags);
    run(
        &mut build,
        &format!(
            "the training run of the profile-guided build, instrumented ({})",
            instrumented.display()
        ),
    )?;
    // Counts of the training alone: the build's own instrumented build
    // scripts write theirs here too.
    if raw.exists() {
        fs::remove_dir_all(&raw).map_err(|e| format!("cannot clear {}: {e}", raw.display()))?;
    }
    fs::create_dir_all(&raw).map_err(|e| format!("cannot create {}: {e}", raw.display()))?;
    let mut binary = instrumented;
    if let Some(triple) = triple {
        binary.push(triple);
    }
    binary.push("release/examples");
    binary.push(format!(
        "{TRAINING_EXAMPLE}{}",
        std::env::consts::EXE_SUFFIX
    ));
    run(
        Command::new(&binary).current_dir(root),
        &format!("the training run {}", binary.display()),
    )?;
    let mut counts: Vec<PathBuf> = fs::read_dir(&raw)
        .map_err(|e| format!("cannot read {}: {e}", raw.display()))?
        .filter_map(|entry| entry.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "profraw"))
        .collect();
    counts.sort();
    if counts.is_empty() {
        return Err(format!(
            "the training run wrote no counts into {}",
            raw.display()
        ));
    }
    let merged = dir.join(format!("{PROFILE_FILE}.new"));
    run(
        Command::new(&profdata)
            .arg("merge")
            .arg("-o")
            .arg(&merged)
            .args(&counts),
        &format!("llvm-profdata merge into {}", merged.display()),
    )?;
    let path = dir.join(PROFILE_FILE);
    let fresh = fs::read(&merged).map_err(|e| format!("cannot read {}: {e}", merged.display()))?;
    if fs::read(&path).ok().as_deref() == Some(fresh.as_slice()) {
        fs::remove_file(&merged).map_err(|e| format!("cannot remove {}: {e}", merged.display()))?;
    } else {
        fs::rename(&merged, &path).map_err(|e| {
            format!(
                "cannot rename {} to {}: {e}",
                merged.display(),
                path.display()
            )
        })?;
    }
    let path = fs::canonicalize(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(Some(Profile {
        path,
        target_dir: dir.join("optimized"),
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_profile_flag_follows_the_callers_flags() {
        let profile = Profile {
            path: PathBuf::from("/t/pgo/host/tdvass.profdata"),
            target_dir: PathBuf::from("/t/pgo/host/optimized"),
        };
        assert_eq!(
            profile.rustflags(None),
            "-Cprofile-use=/t/pgo/host/tdvass.profdata"
        );
        assert_eq!(
            profile.rustflags(Some("  ")),
            "-Cprofile-use=/t/pgo/host/tdvass.profdata"
        );
        assert_eq!(
            profile.rustflags(Some("-Ctarget-cpu=x86-64-v2")),
            "-Ctarget-cpu=x86-64-v2 -Cprofile-use=/t/pgo/host/tdvass.profdata"
        );
    }

    #[test]
    fn each_target_has_its_own_directory() {
        let target = Path::new("/t");
        assert_eq!(directory(target, None), Path::new("/t/pgo/host"));
        assert_eq!(
            directory(target, Some("x86_64-unknown-linux-gnu")),
            Path::new("/t/pgo/x86_64-unknown-linux-gnu")
        );
    }
}
