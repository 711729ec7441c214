//! zig as the linker of the Linux libraries, through cargo-zigbuild: its
//! targets `<triple>.<glibc version>` link against stubs of that glibc
//! version, so the libraries need no newer symbol version and load on every
//! Linux with at least that glibc.
//!
//! Both tools come from PyPI (`fmu-build/requirements.txt`: the `ziglang`
//! package carries zig, `cargo-zigbuild` its binary), installed into the
//! repository's `.venv` by `tests/python_env.sh build` (the full test set
//! includes them). A `cargo-zigbuild` and a `zig` on `PATH` serve as well.

use std::ffi::OsStr;
use std::fmt;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The oldest glibc the Linux libraries of `--all-platforms` load with
/// (that of manylinux2014: RHEL/CentOS 7).
pub const GLIBC_FLOOR: &str = "2.17";

/// How to install the tools, for messages.
pub const INSTALL_HINT: &str = "`tests/python_env.sh build` installs fmu-build/requirements.txt (PyPI: ziglang, cargo-zigbuild) into .venv";

/// cargo-zigbuild and the zig it drives.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ZigTools {
    /// The cargo-zigbuild executable.
    cargo_zigbuild: PathBuf,
    /// The Python whose `ziglang` package provides zig
    /// (`CARGO_ZIGBUILD_PYTHON_PATH`); `None`: the `zig` on `PATH`.
    python: Option<PathBuf>,
    /// `zig version`.
    zig_version: String,
    /// `cargo-zigbuild --version`.
    version: String,
}

/// The first line a command prints, when it succeeds.
fn first_line(program: &Path, args: &[&str]) -> Option<String> {
    let output = Command::new(program).args(args).output().ok()?;
    if !output.status.success() {
        return None;
    }
    let text = String::from_utf8_lossy(&output.stdout);
    text.lines().next().map(|l| l.trim().to_string())
}

/// `name` in one of the directories of `paths` (a `PATH` value).
fn on_path(paths: Option<&OsStr>, name: &str) -> Option<PathBuf> {
    std::env::split_paths(paths?)
        .map(|dir| dir.join(name))
        .find(|p| p.is_file())
}

impl ZigTools {
    /// The tools in the repository's `.venv`, else on `PATH`; `Err` names
    /// what is missing and how to install it.
    pub fn find(root: &Path) -> Result<ZigTools, String> {
        Self::find_in(root, std::env::var_os("PATH").as_deref())
    }

    /// [`ZigTools::find`] with `paths` as the `PATH`.
    pub fn find_in(root: &Path, paths: Option<&OsStr>) -> Result<ZigTools, String> {
        let venv = root.join(".venv").join("bin");
        let (cargo_zigbuild, python) = if venv.join("cargo-zigbuild").is_file() {
            (venv.join("cargo-zigbuild"), Some(venv.join("python")))
        } else if let Some(found) = on_path(paths, "cargo-zigbuild") {
            (found, None)
        } else {
            return Err(format!(
                "cargo-zigbuild, the linker driver of the Linux libraries for glibc {GLIBC_FLOOR} ({INSTALL_HINT})"
            ));
        };
        let zig_version = match &python {
            Some(python) => first_line(python, &["-m", "ziglang", "version"]),
            None => on_path(paths, "zig").and_then(|zig| first_line(&zig, &["version"])),
        }
        .ok_or_else(|| {
            format!(
                "zig, the linker of the Linux libraries for glibc {GLIBC_FLOOR} ({INSTALL_HINT})"
            )
        })?;
        let version = first_line(&cargo_zigbuild, &["--version"])
            .ok_or_else(|| format!("a working {} ({INSTALL_HINT})", cargo_zigbuild.display()))?;
        Ok(ZigTools {
            cargo_zigbuild,
            python,
            zig_version,
            version,
        })
    }

    /// `cargo-zigbuild zigbuild ARGS`, told where zig is.
    pub fn command(&self, args: &[&str]) -> Command {
        let mut command = Command::new(&self.cargo_zigbuild);
        command.arg("zigbuild").args(args);
        if let Some(python) = &self.python {
            command.env("CARGO_ZIGBUILD_PYTHON_PATH", python);
        }
        command
    }
}

impl fmt::Display for ZigTools {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} ({}), zig {}",
            self.version,
            self.cargo_zigbuild.display(),
            self.zig_version
        )
    }
}
