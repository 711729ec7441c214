//! Builds the quarter car's FMI 2.0 FMU `target/fmu/tdvass.fmu` and FMI 3.0
//! FMU `target/fmu/tdvass-fmi3.fmu`, the corner's
//! (`tdvass_fmu::Model::Corner`: the suspension of one corner of a vehicle,
//! Co-Simulation only) `target/fmu/tdvass-corner.fmu` and
//! `target/fmu/tdvass-corner-fmi3.fmu`, and the chassis's
//! (`tdvass_fmu::Model::Chassis`: the body of a vehicle on four corners,
//! Co-Simulation only) `target/fmu/tdvass-chassis.fmu` and
//! `target/fmu/tdvass-chassis-fmi3.fmu`, and refreshes the checked-in
//! `modelDescription/modelDescription.xml` (FMI 2.0),
//! `modelDescription/fmi3/modelDescription.xml` (FMI 3.0), the corner's
//! `modelDescription/corner/modelDescription.xml` and
//! `modelDescription/corner/fmi3/modelDescription.xml` and the chassis's
//! `modelDescription/chassis/modelDescription.xml` and
//! `modelDescription/chassis/fmi3/modelDescription.xml`. The build's
//! steps stay in this one file, in the order they run (a long file on
//! purpose).
//!
//! ```text
//! cargo run --release -p fmu-build                   # the host platform only
//! cargo run --release -p fmu-build -- --all-platforms # linux64 + win64, and aarch64 Linux
//! cargo run --release -p fmu-build -- --check        # fail if a checked-in copy is stale
//! cargo run --release -p fmu-build -- --no-profile   # the host, without the profile (quicker)
//! ```
//!
//! Each FMU carries the shared library of its FMI version's crate
//! (`tdvass-fmi2`, `tdvass-fmi3`) under the model identifier; the three
//! models' FMUs of a version carry the same library, built once (the token
//! of the model description picks the model at instantiation). Without a
//! flag that is the
//! library of the host (Linux x86-64: `binaries/linux64/tdvass.so` and
//! `binaries/x86_64-linux/tdvass.so`, Windows x86-64: `binaries/win64/tdvass.dll`
//! and `binaries/x86_64-windows/tdvass.dll`, macOS: `binaries/darwin64/tdvass.dylib`
//! and `binaries/<arch>-darwin/tdvass.dylib`), built with the host's own
//! toolchain. `--all-platforms` works on a Linux x86-64 host: it builds
//! the Linux libraries (x86-64 and aarch64) with zig as the linker, through
//! cargo-zigbuild and its glibc-versioned targets, so that they need no glibc
//! newer than [`GLIBC_FLOOR`], and cross-builds the Windows x86-64 library
//! with MinGW-w64 (`.cargo/config.toml`); the FMI 2.0 FMUs pack linux64 and
//! win64, the FMI 3.0 FMUs `x86_64-linux`, `x86_64-windows` and
//! `aarch64-linux`. FMI 2.0 names no aarch64 platform, so its aarch64
//! library stays in `target/aarch64-unknown-linux-gnu/release/` (tests run
//! it). A missing Rust target, cross toolchain or zig stops the build before
//! anything is compiled or packed, naming the `rustup target add` command,
//! the Debian package or the Python set that provides it.
//!
//! The x86-64 Linux libraries are compiled with the profile of a training
//! run ([`pgo`]): the same bits, fewer instructions a call. `--all-platforms`
//! requires `llvm-profdata` for it; the host build goes without a profile
//! when the tool is missing, and `--no-profile` skips it (the quick start:
//! 1 min 51 s instead of 3 min 27 s from a fresh clone on two cores).
//!
//! The descriptions and documentation come from `tdvass-describe`
//! ([`tdvass_describe::fmi2`], [`tdvass_describe::fmi3`]), generated from
//! the variable table of each model; the FMU libraries carry none of that code. Besides them each FMU carries the icon
//! (`fmu-build/assets/icon.png`, drawn by `tools/draw_icon.py`: `model.png`
//! in FMI 2.0, `terminalsAndIcons/icon.png` in FMI 3.0, and
//! `documentation/diagram.png` in both; the chassis's page shows it too,
//! with a legend of the chassis's own symbols) and the reference results of its
//! default experiment ([`mod@reference`], FMI-LS-REF). Every entry is written
//! in a fixed order with a fixed time stamp and mode, so that two builds of
//! the same sources give byte-identical FMUs.

use std::fs;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};
use tdvass_describe::markdown::{BEGIN_MARKER, END_MARKER, splice_into};
use tdvass_describe::markup::DIAGRAM_FILE;
use tdvass_fmi2::MODEL_IDENTIFIER;
use tdvass_fmu::Model;
use tdvass_fmu::slave::Dialect;
use tdvass_fmu::variables::FmiVersion;
use zip::write::SimpleFileOptions;
use zip::{CompressionMethod, DateTime, ZipArchive, ZipWriter};

mod pgo;
mod reference;
mod system;
mod zig;

use zig::GLIBC_FLOOR;
use zig::ZigTools;

/// The icon of every FMU and the diagram of its documentation, drawn by
/// `tools/draw_icon.py`.
const ICON: &[u8] = include_bytes!("../assets/icon.png");

/// The FMU reference, whose variable table is generated.
const VARIABLE_TABLE_DOC: &str = "docs/fmu.md";

/// One FMU of the build: its model, its crate, its archive and its
/// generated files.
#[derive(Debug, Clone)]
struct Fmu {
    /// The model the FMU's description declares (its token picks it).
    model: Model,
    version: FmiVersion,
    /// The cargo package whose shared library the FMU carries.
    package: &'static str,
    /// Its library target: cargo names the shared library after it
    /// (`libtdvass_fmi2.so`, `tdvass_fmi3.dll`), and the FMU holds it under
    /// the model identifier (`tdvass.so`, `tdvass.dll`).
    library: &'static str,
    /// The archive's file name in `target/fmu/`.
    file_name: &'static str,
    /// The checked-in copy of the model description.
    checked_in: &'static str,
    /// `modelDescription.xml`.
    description: String,
    /// `documentation/index.html`.
    documentation: String,
    /// How the description identifies the interface (`GUID ...`,
    /// `instantiationToken ...`), for messages.
    identity: String,
    /// The front-end's dialect of the slave (for the reference results).
    dialect: Dialect,
    /// The GUID or instantiation token the slave's states carry.
    token: String,
    /// Where the FMU holds its icon.
    icon_entry: &'static str,
}

impl Fmu {
    /// Every FMU: the quarter car's FMI 2.0 and FMI 3.0 FMUs, then the
    /// corner's, then the chassis's.
    fn all() -> [Fmu; 6] {
        [
            Fmu::new(Model::QuarterCar, FmiVersion::Fmi2),
            Fmu::new(Model::QuarterCar, FmiVersion::Fmi3),
            Fmu::new(Model::Corner, FmiVersion::Fmi2),
            Fmu::new(Model::Corner, FmiVersion::Fmi3),
            Fmu::new(Model::Chassis, FmiVersion::Fmi2),
            Fmu::new(Model::Chassis, FmiVersion::Fmi3),
        ]
    }

    /// The FMU of `model` in `version`.
    fn new(model: Model, version: FmiVersion) -> Fmu {
        let (file_name, checked_in) = match (model, version) {
            (Model::QuarterCar, FmiVersion::Fmi2) => {
                ("tdvass.fmu", "modelDescription/modelDescription.xml")
            }
            (Model::QuarterCar, FmiVersion::Fmi3) => (
                "tdvass-fmi3.fmu",
                "modelDescription/fmi3/modelDescription.xml",
            ),
            (Model::Corner, FmiVersion::Fmi2) => (
                "tdvass-corner.fmu",
                "modelDescription/corner/modelDescription.xml",
            ),
            (Model::Corner, FmiVersion::Fmi3) => (
                "tdvass-corner-fmi3.fmu",
                "modelDescription/corner/fmi3/modelDescription.xml",
            ),
            (Model::Chassis, FmiVersion::Fmi2) => (
                "tdvass-chassis.fmu",
                "modelDescription/chassis/modelDescription.xml",
            ),
            (Model::Chassis, FmiVersion::Fmi3) => (
                "tdvass-chassis-fmi3.fmu",
                "modelDescription/chassis/fmi3/modelDescription.xml",
            ),
        };
        match version {
            FmiVersion::Fmi2 => Fmu {
                model,
                version,
                package: "tdvass-fmi2",
                library: "tdvass_fmi2",
                file_name,
                checked_in,
                description: tdvass_describe::fmi2::model_description_xml(model),
                documentation: tdvass_describe::fmi2::documentation_html(model),
                identity: format!("GUID {}", tdvass_fmi2::guid(model)),
                dialect: tdvass_fmi2::instance::FMI2_DIALECT,
                token: tdvass_fmi2::guid(model),
                icon_entry: "model.png",
            },
            FmiVersion::Fmi3 => Fmu {
                model,
                version,
                package: "tdvass-fmi3",
                library: "tdvass_fmi3",
                file_name,
                checked_in,
                description: tdvass_describe::fmi3::model_description_xml(model),
                documentation: tdvass_describe::fmi3::documentation_html(model),
                identity: format!(
                    "instantiationToken {}",
                    tdvass_fmi3::instantiation_token(model)
                ),
                dialect: tdvass_fmi3::instance::FMI3_DIALECT,
                token: tdvass_fmi3::instantiation_token(model),
                icon_entry: "terminalsAndIcons/icon.png",
            },
        }
    }

    /// `FMI 2.0` or `FMI 3.0`, for messages.
    fn label(&self) -> &'static str {
        match self.version {
            FmiVersion::Fmi2 => "FMI 2.0",
            FmiVersion::Fmi3 => "FMI 3.0",
        }
    }

    /// The model and the version (`TDVASS corner FMI 3.0`), for messages.
    fn title(&self) -> String {
        format!("{} {}", self.model.name(), self.label())
    }
}

/// The shared libraries the FMUs carry: each package once (the first FMU
/// that names it), with the indices in `fmus` of every FMU that carries
/// its library.
fn libraries(fmus: &[Fmu]) -> Vec<(&Fmu, Vec<usize>)> {
    let mut out: Vec<(&Fmu, Vec<usize>)> = Vec::new();
    for (i, fmu) in fmus.iter().enumerate() {
        match out
            .iter_mut()
            .find(|(first, _)| first.package == fmu.package)
        {
            Some((_, carriers)) => carriers.push(i),
            None => out.push((fmu, vec![i])),
        }
    }
    out
}

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

/// Machine code of a built library, read from its file header.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum BinaryFormat {
    /// ELF shared object for x86-64.
    ElfX86_64,
    /// ELF shared object for 32-bit x86.
    ElfX86,
    /// ELF shared object for AArch64.
    ElfAarch64,
    /// PE (Windows) DLL for x86-64.
    PeX86_64,
    /// PE (Windows) DLL for 32-bit x86.
    PeX86,
    /// Mach-O dynamic library (64-bit, or universal).
    MachO,
}

impl BinaryFormat {
    /// The format of `bytes`, `None` when it is none of the above.
    fn of(bytes: &[u8]) -> Option<BinaryFormat> {
        let u16_le = |at: usize| {
            bytes
                .get(at..at.checked_add(2)?)
                .map(|b| u16::from_le_bytes([b[0], b[1]]))
        };
        let u32_le = |at: usize| {
            bytes
                .get(at..at.checked_add(4)?)
                .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        };
        if bytes.starts_with(b"\x7fELF") {
            // e_machine, little-endian ELF.
            return match u16_le(18)? {
                62 => Some(BinaryFormat::ElfX86_64),
                3 => Some(BinaryFormat::ElfX86),
                183 => Some(BinaryFormat::ElfAarch64),
                _ => None,
            };
        }
        if bytes.starts_with(b"MZ") {
            // e_lfanew points to "PE\0\0", followed by the COFF machine.
            let pe = usize::try_from(u32_le(0x3c)?).ok()?;
            let coff = pe.checked_add(4)?;
            if bytes.get(pe..coff)? != b"PE\0\0" {
                return None;
            }
            return match u16_le(coff)? {
                0x8664 => Some(BinaryFormat::PeX86_64),
                0x014c => Some(BinaryFormat::PeX86),
                _ => None,
            };
        }
        match u32_le(0)? {
            0xfeed_facf | 0xbeba_feca => Some(BinaryFormat::MachO),
            _ => None,
        }
    }
}

/// What a platform build needs beyond the host's Rust toolchain.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Requirement {
    /// An executable that must be on `PATH`, or an absolute path of a file
    /// that must exist.
    file: &'static str,
    /// The Debian package that installs it.
    debian_package: &'static str,
}

/// One platform of the shared libraries.
#[derive(Debug, Clone, PartialEq, Eq)]
struct Platform {
    /// FMI 2.0 platform folder (`binaries/<name>/` in the FMU); `None` when
    /// FMI 2.0 has no name for the platform (built and tested, not packed).
    fmi2_folder: Option<&'static str>,
    /// FMI 3.0 platform tuple (`binaries/<arch>-<sys>/` in the FMU).
    fmi3_folder: &'static str,
    /// Human-readable name, for messages.
    label: &'static str,
    /// Rust target triple of a cross build; `None` builds for the host into
    /// `target/release/`.
    cross_target: Option<&'static str>,
    /// What cargo puts before the library name (`lib` except on Windows).
    prefix: &'static str,
    /// The extension of the library inside the FMU (`so`, `dll`, `dylib`).
    extension: &'static str,
    /// The machine code the built file must contain.
    format: BinaryFormat,
    /// Linkers and C libraries of a cross build (as `.cargo/config.toml`
    /// names them).
    requirements: &'static [Requirement],
    /// The oldest glibc the library must load with: it is then linked by
    /// zig through cargo-zigbuild, for the target `<cross_target>.<glibc>`
    /// (`None`: the toolchain's own linker and C library).
    glibc: Option<&'static str>,
}

impl Platform {
    /// The platform folder of `version`, `None` if that version names none.
    fn folder(&self, version: FmiVersion) -> Option<&'static str> {
        match version {
            FmiVersion::Fmi2 => self.fmi2_folder,
            FmiVersion::Fmi3 => Some(self.fmi3_folder),
        }
    }

    /// The library's path inside the FMU of `version`, `None` if it is not
    /// packed.
    fn fmu_entry(&self, version: FmiVersion) -> Option<String> {
        self.folder(version)
            .map(|folder| format!("binaries/{folder}/{MODEL_IDENTIFIER}.{}", self.extension))
    }

    /// The file name cargo gives the library target `library`
    /// (`libtdvass_fmi2.so`, `tdvass_fmi3.dll`).
    fn built_file(&self, library: &str) -> String {
        format!("{}{library}.{}", self.prefix, self.extension)
    }

    /// Whether its libraries are built with a profile ([`pgo`]): x86-64
    /// Linux, the machine the training runs on.
    fn profile_guided(&self) -> bool {
        self.format == BinaryFormat::ElfX86_64
    }

    /// Where cargo writes the library target `library`.
    fn built_path(&self, target: &Path, library: &str) -> PathBuf {
        match self.cross_target {
            Some(triple) => target.join(triple).join("release"),
            None => target.join("release"),
        }
        .join(self.built_file(library))
    }
}

/// The host platform for an operating system and architecture as
/// [`std::env::consts`] names them, `Err` when FMI 2.0 names no platform for it.
fn host_platform(os: &str, arch: &str) -> Result<Platform> {
    let (fmi2_folder, fmi3_folder, label, prefix, extension, format) = match (os, arch) {
        ("linux", "x86_64") => (
            "linux64",
            "x86_64-linux",
            "Linux x86-64",
            "lib",
            "so",
            BinaryFormat::ElfX86_64,
        ),
        ("linux", "x86") => (
            "linux32",
            "x86-linux",
            "Linux x86",
            "lib",
            "so",
            BinaryFormat::ElfX86,
        ),
        ("windows", "x86_64") => (
            "win64",
            "x86_64-windows",
            "Windows x86-64",
            "",
            "dll",
            BinaryFormat::PeX86_64,
        ),
        ("windows", "x86") => (
            "win32",
            "x86-windows",
            "Windows x86",
            "",
            "dll",
            BinaryFormat::PeX86,
        ),
        // FMI 2.0 has one macOS folder; importers use it for Apple silicon
        // too. FMI 3.0 names the architecture.
        ("macos", "x86_64") => (
            "darwin64",
            "x86_64-darwin",
            "macOS",
            "lib",
            "dylib",
            BinaryFormat::MachO,
        ),
        ("macos", "aarch64") => (
            "darwin64",
            "aarch64-darwin",
            "macOS",
            "lib",
            "dylib",
            BinaryFormat::MachO,
        ),
        _ => {
            return Err(format!(
                "FMI 2.0 defines no platform folder for {arch} {os}; build on Linux, \
                 Windows or macOS (x86-64, or Apple silicon)"
            ));
        }
    };
    Ok(Platform {
        fmi2_folder: Some(fmi2_folder),
        fmi3_folder,
        label,
        cross_target: None,
        prefix,
        extension,
        format,
        requirements: &[],
        glibc: None,
    })
}

/// The Windows x86-64 cross build (MinGW-w64).
const WINDOWS_TARGET: &str = "x86_64-pc-windows-gnu";
/// The Linux aarch64 cross build.
const AARCH64_TARGET: &str = "aarch64-unknown-linux-gnu";

/// The host's target triple of `--all-platforms`, built as a cross target so
/// that zig links it against the glibc floor.
const LINUX_X86_64_TARGET: &str = "x86_64-unknown-linux-gnu";

/// Every platform of `--all-platforms`, from a Linux x86-64 host: Linux
/// x86-64 and Linux aarch64 (zig, glibc [`GLIBC_FLOOR`]) and Windows x86-64
/// (MinGW-w64).
fn all_platforms() -> Result<Vec<Platform>> {
    let host = host_platform(std::env::consts::OS, std::env::consts::ARCH)?;
    if host.fmi2_folder != Some("linux64") {
        return Err(format!(
            "--all-platforms cross-builds from a Linux x86-64 host with Debian's toolchains; \
             on {} run `cargo run --release -p fmu-build` for an FMU of this host",
            host.label
        ));
    }
    Ok(vec![
        Platform {
            cross_target: Some(LINUX_X86_64_TARGET),
            glibc: Some(GLIBC_FLOOR),
            ..host
        },
        Platform {
            fmi2_folder: Some("win64"),
            fmi3_folder: "x86_64-windows",
            label: "Windows x86-64",
            cross_target: Some(WINDOWS_TARGET),
            prefix: "",
            extension: "dll",
            format: BinaryFormat::PeX86_64,
            requirements: &[Requirement {
                file: "x86_64-w64-mingw32-gcc",
                debian_package: "gcc-mingw-w64-x86-64",
            }],
            glibc: None,
        },
        Platform {
            fmi2_folder: None,
            fmi3_folder: "aarch64-linux",
            label: "Linux aarch64",
            cross_target: Some(AARCH64_TARGET),
            prefix: "lib",
            extension: "so",
            format: BinaryFormat::ElfAarch64,
            // zig brings its own linker and glibc stubs: no cross toolchain
            // (the tests' harness still needs Debian's, tests/platforms).
            requirements: &[],
            glibc: Some(GLIBC_FLOOR),
        },
    ])
}

/// Whether `file` is an existing absolute path or an executable on `PATH`.
fn file_available(file: &str) -> bool {
    let path = Path::new(file);
    if path.is_absolute() {
        return path.is_file();
    }
    std::env::var_os("PATH")
        .map(|paths| std::env::split_paths(&paths).any(|dir| dir.join(file).is_file()))
        .unwrap_or(false)
}

/// Whether the Rust standard library for `triple` is installed (its
/// `target-libdir` holds a `libstd`).
fn rust_target_installed(root: &Path, triple: &str) -> bool {
    let output = Command::new("rustc")
        .args(["--print", "target-libdir", "--target", triple])
        .current_dir(root)
        .output();
    let Ok(output) = output else {
        return false;
    };
    if !output.status.success() {
        return false;
    }
    let dir = PathBuf::from(String::from_utf8_lossy(&output.stdout).trim());
    fs::read_dir(dir)
        .map(|entries| {
            entries
                .flatten()
                .any(|e| e.file_name().to_string_lossy().starts_with("libstd-"))
        })
        .unwrap_or(false)
}

/// Every missing Rust target, cross toolchain, zig and (for the build of
/// every platform with `profile`) `llvm-profdata`, as instructions to
/// install them; empty when everything is there.
fn missing_requirements(root: &Path, platforms: &[Platform], profile: Profiling) -> Vec<String> {
    let mut missing = Vec::new();
    if platforms.iter().any(|p| p.glibc.is_some())
        && let Err(message) = ZigTools::find(root)
    {
        missing.push(message);
    }
    let mut targets = Vec::new();
    for platform in platforms {
        if let Some(triple) = platform.cross_target
            && !rust_target_installed(root, triple)
        {
            targets.push(triple);
        }
        for requirement in platform.requirements {
            if !file_available(requirement.file) {
                missing.push(format!(
                    "{} for {} (Debian: `apt-get install {}`)",
                    requirement.file, platform.label, requirement.debian_package
                ));
            }
        }
    }
    if profile_tool_required(platforms, profile) && pgo::llvm_profdata().is_none() {
        missing.push(format!(
            "llvm-profdata, for the profile-guided x86-64 Linux libraries ({})",
            pgo::INSTALL_HINT
        ));
    }
    if !targets.is_empty() {
        missing.insert(
            0,
            format!(
                "the Rust standard library for {} (`rustup target add {}`)",
                targets.join(", "),
                targets.join(" ")
            ),
        );
    }
    missing
}

/// The cargo command that builds `args` for `platform`: cargo-zigbuild
/// for a glibc floor (target `<triple>.<glibc>`), else cargo itself (with
/// `--target` for a cross build).
fn platform_build(platform: &Platform, zig: Option<&ZigTools>, args: &[&str]) -> Result<Command> {
    match (platform.glibc, zig) {
        (Some(glibc), Some(zig)) => {
            let triple = platform
                .cross_target
                .ok_or("a glibc floor needs a target triple")?;
            let target = format!("{triple}.{glibc}");
            let mut all = args.to_vec();
            all.extend(["--target", &target]);
            Ok(zig.command(&all))
        }
        (Some(_), None) => Err(format!("{} needs zig", platform.label)),
        (None, _) => {
            let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
            let mut command = Command::new(cargo);
            command.arg("build").args(args);
            if let Some(triple) = platform.cross_target {
                command.args(["--target", triple]);
            }
            Ok(command)
        }
    }
}

/// Whether building `platforms` with `profile` needs `llvm-profdata`: the
/// build of every platform ships the profile-guided x86-64 Linux libraries
/// (a cross build there) unless told not to; the host build goes without a
/// profile when the tool is missing, and says so.
fn profile_tool_required(platforms: &[Platform], profile: Profiling) -> bool {
    profile == Profiling::Trained
        && platforms
            .iter()
            .any(|p| p.profile_guided() && p.cross_target.is_some())
}

/// Builds the library of `fmu` for `platform` (release, library only) and
/// returns its bytes, checked to be machine code of that platform. Each
/// crate is built by a cargo run of its own, so that the FMI 2.0 library is
/// built exactly as without the FMI 3.0 one; once per platform, whatever
/// the number of FMUs that carry it ([`libraries`]).
fn build_library(
    root: &Path,
    platform: &Platform,
    fmu: &Fmu,
    zig: Option<&ZigTools>,
    profile: Option<&pgo::Profile>,
) -> Result<Vec<u8>> {
    let mut command = platform_build(platform, zig, &["--release", "-p", fmu.package, "--lib"])?;
    let target = match profile {
        Some(profile) => {
            let flags = profile.rustflags(std::env::var("RUSTFLAGS").ok().as_deref());
            command
                .env("CARGO_TARGET_DIR", &profile.target_dir)
                .env("RUSTFLAGS", &flags);
            eprintln!("fmu-build: RUSTFLAGS={flags}");
            profile.target_dir.clone()
        }
        None => target_dir(root),
    };
    let shown: Vec<String> = std::iter::once(command.get_program())
        .chain(command.get_args())
        .map(|a| a.to_string_lossy().into_owned())
        .collect();
    eprintln!(
        "fmu-build: {} {}: {}",
        fmu.label(),
        platform.label,
        shown.join(" ")
    );
    let status = command
        .current_dir(root)
        .status()
        .map_err(|e| format!("cannot run {}: {e}", shown[0]))?;
    if !status.success() {
        return Err(format!(
            "cargo build of the {} library for {} failed ({status})",
            fmu.label(),
            platform.label
        ));
    }
    let library = platform.built_path(&target, fmu.library);
    let bytes = fs::read(&library).map_err(|e| {
        format!(
            "the shared library {} was not built: {e}",
            library.display()
        )
    })?;
    match BinaryFormat::of(&bytes) {
        Some(format) if format == platform.format => Ok(bytes),
        other => Err(format!(
            "{} is {other:?}, expected {:?} for {}",
            library.display(),
            platform.format,
            platform.label
        )),
    }
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

/// The checked-in copies: the model description of each FMU, and the
/// variable table in docs/fmu.md (between its markers).
fn checked_in(root: &Path, fmus: &[Fmu]) -> Result<Vec<CheckedIn>> {
    let read = |path: &str| fs::read_to_string(root.join(path)).ok();
    let reference =
        read(VARIABLE_TABLE_DOC).ok_or(format!("{VARIABLE_TABLE_DOC} cannot be read"))?;
    let reference_expected = splice_into(&reference).ok_or(format!(
        "{VARIABLE_TABLE_DOC} lacks the lines `{BEGIN_MARKER}` and `{END_MARKER}` around the variable table"
    ))?;
    let mut copies: Vec<CheckedIn> = fmus
        .iter()
        .map(|fmu| CheckedIn {
            path: fmu.checked_in,
            expected: fmu.description.clone(),
            current: read(fmu.checked_in),
        })
        .collect();
    copies.push(CheckedIn {
        path: VARIABLE_TABLE_DOC,
        expected: reference_expected,
        current: Some(reference),
    });
    Ok(copies)
}

fn check_only(root: &Path, fmus: &[Fmu]) -> Result<()> {
    for copy in checked_in(root, fmus)? {
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
    for fmu in fmus {
        eprintln!(
            "fmu-build: {} is up to date ({} {})",
            fmu.checked_in,
            fmu.title(),
            fmu.identity
        );
    }
    eprintln!("fmu-build: the variable table of {VARIABLE_TABLE_DOC} is up to date");
    Ok(())
}

/// Every file of `fmu` but its binaries, in the order of the archive:
/// (path, content). The reference results are `results` (CSV).
fn fixed_entries(fmu: &Fmu, results: &str) -> Vec<(String, Vec<u8>)> {
    vec![
        (fmu.icon_entry.to_string(), ICON.to_vec()),
        (
            "documentation/index.html".to_string(),
            fmu.documentation.as_bytes().to_vec(),
        ),
        (format!("documentation/{DIAGRAM_FILE}"), ICON.to_vec()),
        (
            reference::manifest_entry(),
            reference::manifest_xml().into_bytes(),
        ),
        (reference::csv_entry(), results.as_bytes().to_vec()),
    ]
}

/// Writes `fmu` with `binaries` (path in the archive, bytes) and the
/// reference `results` into `out_dir`, and returns its path.
fn pack(
    out_dir: &Path,
    fmu: &Fmu,
    binaries: &[(String, Vec<u8>)],
    results: &str,
) -> Result<PathBuf> {
    let mut entries: Vec<(&str, &[u8], u32)> =
        vec![("modelDescription.xml", fmu.description.as_bytes(), 0o644)];
    for (name, bytes) in binaries {
        entries.push((name.as_str(), bytes, 0o755));
    }
    let fixed = fixed_entries(fmu, results);
    for (name, bytes) in &fixed {
        entries.push((name.as_str(), bytes, 0o644));
    }
    let path = out_dir.join(fmu.file_name);
    // Written beside, checked, then renamed: an interrupted run never leaves
    // a truncated FMU under the final name.
    let partial = out_dir.join(format!("{}.partial", fmu.file_name));
    write_fmu(&partial, &entries)?;
    check_fmu(&partial, &entries)?;
    fs::rename(&partial, &path).map_err(|e| {
        format!(
            "cannot rename {} to {}: {e}",
            partial.display(),
            path.display()
        )
    })?;
    Ok(path)
}

fn build(root: &Path, fmus: &[Fmu], platforms: &[Platform], profile: Profiling) -> Result<()> {
    let missing = missing_requirements(root, platforms, profile);
    if !missing.is_empty() {
        return Err(format!(
            "nothing was built or packed; missing: {}",
            missing.join("; ")
        ));
    }
    let zig = if platforms.iter().any(|p| p.glibc.is_some()) {
        let zig = ZigTools::find(root)?;
        eprintln!("fmu-build: Linux libraries for glibc {GLIBC_FLOOR}: {zig}");
        Some(zig)
    } else {
        None
    };
    // The reference results first: they need no build, and a failure
    // stops before the long part.
    let mut results = Vec::new();
    for fmu in fmus {
        let csv = reference::results_csv(fmu.model, fmu.dialect, fmu.token.clone())
            .map_err(|e| format!("the reference results of the {} FMU: {e}", fmu.title()))?;
        results.push(csv);
    }
    // Every library is built before anything is packed: a failed build
    // leaves no FMU with some of its platforms.
    let mut binaries: Vec<Vec<(String, Vec<u8>)>> = vec![Vec::new(); fmus.len()];
    for platform in platforms {
        let trained = if profile == Profiling::Trained && platform.profile_guided() {
            let training = platform_build(platform, zig.as_ref(), &pgo::TRAINING_ARGS)?;
            pgo::train(
                root,
                &target_dir(root),
                platform.cross_target,
                training,
                platform.glibc.is_some(),
            )?
        } else {
            None
        };
        // Each library once; the FMUs of its version carry the same bytes.
        for (fmu, carriers) in libraries(fmus) {
            let bytes = build_library(root, platform, fmu, zig.as_ref(), trained.as_ref())?;
            match platform.fmu_entry(fmu.version) {
                Some(entry) => {
                    for &i in &carriers {
                        binaries[i].push((entry.clone(), bytes.clone()));
                    }
                }
                None => eprintln!(
                    "fmu-build: {} library (not in the {} FMUs): {}",
                    platform.label,
                    fmu.label(),
                    platform
                        .built_path(&target_dir(root), fmu.library)
                        .display()
                ),
            }
        }
    }
    let out_dir = target_dir(root).join("fmu");
    fs::create_dir_all(&out_dir)
        .map_err(|e| format!("cannot create {}: {e}", out_dir.display()))?;
    let mut written = Vec::new();
    for ((fmu, packed), csv) in fmus.iter().zip(&binaries).zip(&results) {
        written.push(pack(&out_dir, fmu, packed, csv)?);
    }
    let mut refreshed = Vec::new();
    for copy in checked_in(root, fmus)? {
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
    let car = write_full_car(&out_dir, fmus)?;
    for ((fmu, packed), path) in fmus.iter().zip(&binaries).zip(&written) {
        eprintln!(
            "fmu-build: wrote {} ({} bytes; {}; {} {})",
            path.display(),
            fs::metadata(path).map(|m| m.len()).unwrap_or(0),
            packed
                .iter()
                .map(|(name, _)| name.as_str())
                .collect::<Vec<_>>()
                .join(", "),
            fmu.title(),
            fmu.identity
        );
    }
    for path in &car {
        eprintln!(
            "fmu-build: wrote {} ({} bytes; the full car)",
            path.display(),
            fs::metadata(path).map(|m| m.len()).unwrap_or(0)
        );
    }
    eprintln!(
        "fmu-build: refreshed: {}",
        if refreshed.is_empty() {
            "nothing".to_string()
        } else {
            refreshed.join(", ")
        }
    );
    Ok(())
}

/// The assembled car beside the FMUs in `out_dir` ([`system`]): the SSP
/// archive `full-car.ssp` (its `SystemStructure.ssd` and, under
/// `resources/`, the corner's and the chassis's FMI 2.0 FMUs, which
/// libcosim and ecos import), and libcosim's `full-car/OspSystemStructure.xml`
/// (fixed step) and `full-car/OspSystemStructure_ecco.xml` (ECCO), whose
/// simulators are the FMUs in `out_dir`. Returns the paths written.
fn write_full_car(out_dir: &Path, fmus: &[Fmu]) -> Result<Vec<PathBuf>> {
    let file_of = |model| {
        fmus.iter()
            .find(|f| f.model == model && f.version == FmiVersion::Fmi2)
            .map(|f| f.file_name)
            .ok_or(format!("the full car needs the FMI 2.0 FMU of {model:?}"))
    };
    let (corner, chassis) = (file_of(Model::Corner)?, file_of(Model::Chassis)?);
    let read = |name: &str| {
        let path = out_dir.join(name);
        fs::read(&path).map_err(|e| format!("cannot read {}: {e}", path.display()))
    };
    let (corner_bytes, chassis_bytes) = (read(corner)?, read(chassis)?);
    let ssd = system::system_structure_description(corner, chassis);
    let resource = |name: &str| format!("{}/{name}", system::SSP_RESOURCES);
    let (corner_entry, chassis_entry) = (resource(corner), resource(chassis));
    let entries: Vec<(&str, &[u8], u32)> = vec![
        ("SystemStructure.ssd", ssd.as_bytes(), 0o644),
        (corner_entry.as_str(), &corner_bytes, 0o644),
        (chassis_entry.as_str(), &chassis_bytes, 0o644),
    ];
    let ssp = out_dir.join(format!("{}.ssp", system::SYSTEM_NAME));
    let partial = out_dir.join(format!("{}.ssp.partial", system::SYSTEM_NAME));
    write_fmu(&partial, &entries)?;
    check_fmu(&partial, &entries)?;
    fs::rename(&partial, &ssp).map_err(|e| {
        format!(
            "cannot rename {} to {}: {e}",
            partial.display(),
            ssp.display()
        )
    })?;
    let folder = out_dir.join(system::SYSTEM_NAME);
    fs::create_dir_all(&folder).map_err(|e| format!("cannot create {}: {e}", folder.display()))?;
    let mut written = vec![ssp];
    for (name, ecco) in [
        ("OspSystemStructure.xml", false),
        ("OspSystemStructure_ecco.xml", true),
    ] {
        let path = folder.join(name);
        fs::write(&path, system::osp_system_structure(corner, chassis, ecco))
            .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
        written.push(path);
    }
    Ok(written)
}

/// The flag that builds the libraries without a profile ([`pgo`]).
const NO_PROFILE: &str = "--no-profile";

/// Whether the x86-64 Linux libraries are built with a trained profile.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Profiling {
    /// Trained and used ([`pgo::train`]); `--all-platforms` requires it.
    Trained,
    /// Not trained (`--no-profile`: a quicker build, the same bits).
    Skipped,
}

/// What the command line asks for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Mode {
    /// Build the FMUs for the host platform.
    Host,
    /// Build every platform (Linux x86-64, Windows x86-64, Linux aarch64).
    AllPlatforms,
    /// Only check the checked-in copies.
    Check,
}

/// The mode and the profiling the arguments ask for: at most one of
/// `--check` and `--all-platforms`, and [`NO_PROFILE`] anywhere; `None` for
/// anything else.
fn parse_args(args: &[String]) -> Option<(Mode, Profiling)> {
    let profile = if args.iter().any(|a| a == NO_PROFILE) {
        Profiling::Skipped
    } else {
        Profiling::Trained
    };
    let flags: Vec<&str> = args
        .iter()
        .map(String::as_str)
        .filter(|a| *a != NO_PROFILE)
        .collect();
    let mode = match flags.as_slice() {
        [] => Mode::Host,
        ["--check"] => Mode::Check,
        ["--all-platforms"] => Mode::AllPlatforms,
        _ => return None,
    };
    Some((mode, profile))
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some((mode, profile)) = parse_args(&args) else {
        eprintln!("usage: fmu-build [--check | --all-platforms] [{NO_PROFILE}]");
        return ExitCode::from(2);
    };
    let root = workspace_root();
    let fmus = Fmu::all();
    let result = match mode {
        Mode::Check => check_only(&root, &fmus),
        Mode::Host => host_platform(std::env::consts::OS, std::env::consts::ARCH)
            .and_then(|host| build(&root, &fmus, &[host], profile)),
        Mode::AllPlatforms => {
            all_platforms().and_then(|platforms| build(&root, &fmus, &platforms, profile))
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("fmu-build: error: {message}");
            ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests;
