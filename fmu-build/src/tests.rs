//! The builder's tests: platforms, archives, the generated files and the
//! system structures, in one file beside the one binary they test (hence
//! its length).

use super::*;
use tdvass_fmu::Model;

#[test]
fn host_platforms_use_the_folders_and_library_names_of_the_host() {
    let cases = [
        (
            "linux",
            "x86_64",
            "binaries/linux64/tdvass.so",
            "binaries/x86_64-linux/tdvass.so",
            "libtdvass_fmi2.so",
        ),
        (
            "windows",
            "x86_64",
            "binaries/win64/tdvass.dll",
            "binaries/x86_64-windows/tdvass.dll",
            "tdvass_fmi2.dll",
        ),
        (
            "windows",
            "x86",
            "binaries/win32/tdvass.dll",
            "binaries/x86-windows/tdvass.dll",
            "tdvass_fmi2.dll",
        ),
        (
            "macos",
            "aarch64",
            "binaries/darwin64/tdvass.dylib",
            "binaries/aarch64-darwin/tdvass.dylib",
            "libtdvass_fmi2.dylib",
        ),
        (
            "macos",
            "x86_64",
            "binaries/darwin64/tdvass.dylib",
            "binaries/x86_64-darwin/tdvass.dylib",
            "libtdvass_fmi2.dylib",
        ),
    ];
    for (os, arch, fmi2_entry, fmi3_entry, built) in cases {
        let platform = host_platform(os, arch).unwrap();
        assert_eq!(
            platform.fmu_entry(FmiVersion::Fmi2).as_deref(),
            Some(fmi2_entry),
            "{os} {arch}"
        );
        assert_eq!(
            platform.fmu_entry(FmiVersion::Fmi3).as_deref(),
            Some(fmi3_entry),
            "{os} {arch}"
        );
        assert_eq!(platform.built_file("tdvass_fmi2"), built, "{os} {arch}");
        assert_eq!(
            platform.built_path(Path::new("t"), "tdvass_fmi2"),
            Path::new("t/release").join(built)
        );
        assert_eq!(
            platform.built_file("tdvass_fmi3"),
            built.replace("fmi2", "fmi3"),
            "{os} {arch}"
        );
    }
    let error = host_platform("linux", "aarch64").unwrap_err();
    assert!(
        error.contains("no platform folder for aarch64 linux"),
        "{error}"
    );
}

#[test]
#[cfg(all(target_os = "linux", target_arch = "x86_64"))]
fn all_platforms_pack_linux64_and_win64_for_fmi2_and_all_three_for_fmi3() {
    let platforms = all_platforms().unwrap();
    let entries = |version| -> Vec<Option<String>> {
        platforms.iter().map(|p| p.fmu_entry(version)).collect()
    };
    assert_eq!(
        entries(FmiVersion::Fmi2),
        [
            Some("binaries/linux64/tdvass.so".to_string()),
            Some("binaries/win64/tdvass.dll".to_string()),
            None,
        ]
    );
    assert_eq!(
        entries(FmiVersion::Fmi3),
        [
            Some("binaries/x86_64-linux/tdvass.so".to_string()),
            Some("binaries/x86_64-windows/tdvass.dll".to_string()),
            Some("binaries/aarch64-linux/tdvass.so".to_string()),
        ]
    );
    assert_eq!(
        platforms[2].built_path(Path::new("t"), "tdvass_fmi2"),
        Path::new("t/aarch64-unknown-linux-gnu/release/libtdvass_fmi2.so")
    );
    // The Linux libraries are linked by zig against the glibc floor, so the
    // x86-64 one is a cross build too (cargo-zigbuild writes it under the
    // triple without the glibc suffix).
    assert_eq!(
        platforms[0].built_path(Path::new("t"), "tdvass_fmi3"),
        Path::new("t/x86_64-unknown-linux-gnu/release/libtdvass_fmi3.so")
    );
    let floors: Vec<Option<&str>> = platforms.iter().map(|p| p.glibc).collect();
    assert_eq!(floors, [Some("2.17"), None, Some("2.17")]);
    // The host-only build keeps the host's own toolchain.
    let host = host_platform("linux", "x86_64").unwrap();
    assert_eq!((host.cross_target, host.glibc), (None, None));
    assert_eq!(
        platforms[1].built_path(Path::new("t"), "tdvass_fmi3"),
        Path::new("t/x86_64-pc-windows-gnu/release/tdvass_fmi3.dll")
    );
}

#[test]
fn each_fmu_has_its_crate_archive_and_checked_in_description() {
    let [fmi2, fmi3, corner2, corner3, chassis2, chassis3] = Fmu::all();
    assert_eq!(
        (fmi2.package, fmi2.library, fmi2.file_name, fmi2.checked_in),
        (
            "tdvass-fmi2",
            "tdvass_fmi2",
            "tdvass.fmu",
            "modelDescription/modelDescription.xml"
        )
    );
    assert_eq!(
        (fmi3.package, fmi3.library, fmi3.file_name, fmi3.checked_in),
        (
            "tdvass-fmi3",
            "tdvass_fmi3",
            "tdvass-fmi3.fmu",
            "modelDescription/fmi3/modelDescription.xml"
        )
    );
    assert_eq!(
        (
            corner2.package,
            corner2.library,
            corner2.file_name,
            corner2.checked_in
        ),
        (
            "tdvass-fmi2",
            "tdvass_fmi2",
            "tdvass-corner.fmu",
            "modelDescription/corner/modelDescription.xml"
        )
    );
    assert_eq!(
        (
            corner3.package,
            corner3.library,
            corner3.file_name,
            corner3.checked_in
        ),
        (
            "tdvass-fmi3",
            "tdvass_fmi3",
            "tdvass-corner-fmi3.fmu",
            "modelDescription/corner/fmi3/modelDescription.xml"
        )
    );
    assert_eq!(
        (
            chassis2.package,
            chassis2.library,
            chassis2.file_name,
            chassis2.checked_in
        ),
        (
            "tdvass-fmi2",
            "tdvass_fmi2",
            "tdvass-chassis.fmu",
            "modelDescription/chassis/modelDescription.xml"
        )
    );
    assert_eq!(
        (
            chassis3.package,
            chassis3.library,
            chassis3.file_name,
            chassis3.checked_in
        ),
        (
            "tdvass-fmi3",
            "tdvass_fmi3",
            "tdvass-chassis-fmi3.fmu",
            "modelDescription/chassis/fmi3/modelDescription.xml"
        )
    );
    let models: Vec<(Model, FmiVersion)> =
        Fmu::all().iter().map(|f| (f.model, f.version)).collect();
    assert_eq!(
        models,
        [
            (Model::QuarterCar, FmiVersion::Fmi2),
            (Model::QuarterCar, FmiVersion::Fmi3),
            (Model::Corner, FmiVersion::Fmi2),
            (Model::Corner, FmiVersion::Fmi3),
            (Model::Chassis, FmiVersion::Fmi2),
            (Model::Chassis, FmiVersion::Fmi3),
        ]
    );
    for fmu in Fmu::all() {
        // The archive is named after the model's stem.
        let suffix = match fmu.version {
            FmiVersion::Fmi2 => "",
            FmiVersion::Fmi3 => "-fmi3",
        };
        assert_eq!(
            fmu.file_name,
            format!("{}{suffix}.fmu", fmu.model.fmu_stem())
        );
        let version = match fmu.version {
            FmiVersion::Fmi2 => r#"fmiVersion="2.0""#,
            FmiVersion::Fmi3 => r#"fmiVersion="3.0""#,
        };
        assert!(fmu.description.contains(version), "{}", fmu.title());
        assert!(
            fmu.description
                .contains(&format!(r#"modelName="{}""#, fmu.model.name())),
            "{}",
            fmu.title()
        );
        assert!(fmu.identity.contains(&fmu.token), "{}", fmu.title());
    }
    assert!(
        fmi3.identity
            .contains(&tdvass_fmi3::instantiation_token(Model::QuarterCar))
    );
    // Six checked-in copies, each its own file.
    let copies: std::collections::HashSet<&str> = Fmu::all().iter().map(|f| f.checked_in).collect();
    assert_eq!(copies.len(), 6);
    // The package names the library target that cargo builds.
    for fmu in [&fmi2, &fmi3, &corner2, &corner3, &chassis2, &chassis3] {
        let manifest = fs::read_to_string(
            workspace_root()
                .join("crates")
                .join(fmu.package)
                .join("Cargo.toml"),
        )
        .unwrap();
        assert!(
            manifest.contains(&format!("name = \"{}\"", fmu.library)),
            "{}",
            fmu.package
        );
    }
}

/// The linkers that fmu-build looks for are the ones cargo is told to use.
#[test]
#[cfg(all(target_os = "linux", target_arch = "x86_64"))]
fn cross_linkers_match_the_cargo_configuration() {
    let config = fs::read_to_string(workspace_root().join(".cargo/config.toml")).unwrap();
    for platform in all_platforms().unwrap() {
        let Some(triple) = platform.cross_target else {
            continue;
        };
        if platform.glibc.is_some() {
            // zig links it (cargo-zigbuild sets the linker itself).
            assert!(platform.requirements.is_empty(), "{}", platform.label);
            continue;
        }
        let section = config
            .split("\n[")
            .find(|s| s.starts_with(&format!("target.{triple}]")))
            .unwrap_or_else(|| panic!("no [target.{triple}] in .cargo/config.toml"));
        let linker = platform.requirements[0].file;
        assert!(
            section.contains(&format!("linker = \"{linker}\"")),
            "[target.{triple}] must set linker = \"{linker}\""
        );
    }
}

#[test]
fn missing_targets_and_toolchains_are_named_with_their_install_command() {
    let platform = Platform {
        fmi2_folder: Some("win64"),
        fmi3_folder: "x86_64-windows",
        label: "Windows x86-64",
        cross_target: Some("x86_64-unknown-none-such"),
        prefix: "",
        extension: "dll",
        format: BinaryFormat::PeX86_64,
        requirements: &[Requirement {
            file: "no-such-linker-gcc",
            debian_package: "gcc-no-such",
        }],
        glibc: None,
    };
    let missing = missing_requirements(&workspace_root(), &[platform], Profiling::Trained);
    assert_eq!(missing.len(), 2, "{missing:?}");
    assert!(missing[0].contains("`rustup target add x86_64-unknown-none-such`"));
    assert!(missing[1].contains("`apt-get install gcc-no-such`"));
    // The host needs nothing beyond its own toolchain.
    let host = host_platform(std::env::consts::OS, std::env::consts::ARCH).unwrap();
    assert!(missing_requirements(&workspace_root(), &[host], Profiling::Trained).is_empty());
}

#[test]
fn binary_formats_are_read_from_the_headers() {
    let mut elf = vec![0u8; 64];
    elf[..4].copy_from_slice(b"\x7fELF");
    elf[18] = 62;
    assert_eq!(BinaryFormat::of(&elf), Some(BinaryFormat::ElfX86_64));
    elf[18] = 183;
    assert_eq!(BinaryFormat::of(&elf), Some(BinaryFormat::ElfAarch64));
    elf[18] = 40; // 32-bit ARM: not a platform of the FMU
    assert_eq!(BinaryFormat::of(&elf), None);
    let mut pe = vec![0u8; 0x100];
    pe[..2].copy_from_slice(b"MZ");
    pe[0x3c] = 0x80;
    pe[0x80..0x84].copy_from_slice(b"PE\0\0");
    pe[0x84..0x86].copy_from_slice(&0x8664u16.to_le_bytes());
    assert_eq!(BinaryFormat::of(&pe), Some(BinaryFormat::PeX86_64));
    pe[0x80] = b'X';
    assert_eq!(BinaryFormat::of(&pe), None);
    pe[0x3c..0x40].copy_from_slice(&u32::MAX.to_le_bytes()); // past the end
    assert_eq!(BinaryFormat::of(&pe), None);
    assert_eq!(
        BinaryFormat::of(&0xfeed_facfu32.to_le_bytes()),
        Some(BinaryFormat::MachO)
    );
    assert_eq!(BinaryFormat::of(b"MZ"), None);
    assert_eq!(BinaryFormat::of(b""), None);
}

#[test]
fn missing_zig_is_named_with_the_python_set_that_installs_it() {
    let nowhere = std::env::temp_dir().join("fmu-build-test-no-venv");
    let empty_path = std::ffi::OsString::new();
    let error = ZigTools::find_in(&nowhere, Some(&empty_path)).unwrap_err();
    assert!(error.contains("cargo-zigbuild"), "{error}");
    assert!(error.contains("tests/python_env.sh build"), "{error}");
    assert!(error.contains(GLIBC_FLOOR), "{error}");
}

/// Width and height of a PNG, from its IHDR chunk.
fn png_size(bytes: &[u8]) -> Option<(u32, u32)> {
    if !bytes.starts_with(b"\x89PNG\r\n\x1a\n") || bytes.get(12..16)? != b"IHDR" {
        return None;
    }
    let be = |at: usize| u32::from_be_bytes(bytes[at..at + 4].try_into().unwrap());
    Some((be(16), be(20)))
}

#[test]
fn each_fmu_carries_the_icon_the_diagram_and_the_reference_results() {
    let size = tdvass_describe::markup::DIAGRAM_SIZE_PX;
    assert_eq!(png_size(ICON), Some((size, size)));
    assert_eq!(png_size(b"not a png"), None);
    for fmu in &Fmu::all() {
        let icon = match fmu.version {
            FmiVersion::Fmi2 => "model.png",
            FmiVersion::Fmi3 => "terminalsAndIcons/icon.png",
        };
        let entries = fixed_entries(fmu, "time\n0\n");
        let names: Vec<&str> = entries.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(
            names,
            [
                icon,
                "documentation/index.html",
                "documentation/diagram.png",
                "extra/org.fmi-standard.fmi-ls-ref/fmi-ls-manifest.xml",
                "extra/org.fmi-standard.fmi-ls-ref/tdvass_out.csv",
            ],
            "{}",
            fmu.label()
        );
        assert_eq!(entries[0].1, ICON);
        assert_eq!(entries[2].1, ICON);
        assert_eq!(entries[4].1, b"time\n0\n");
        // The page shows the diagram beside it, with the legend of its
        // symbols, and names the reference results.
        let page = &fmu.documentation;
        assert!(
            page.contains(r#"<img src="diagram.png" width="320" height="320""#),
            "{}",
            fmu.label()
        );
        let suspension = [
            "m_s",
            "k_s, c_s",
            "m_h",
            "k_h, c_h",
            "m_t",
            "k_t",
            "x_g",
            "u = g x_t(t - tau)",
        ];
        // ("m" is a unit on every page.)
        let chassis = [
            "I_theta, I_phi",
            "a, b",
            "z, theta, phi",
            "f_fl, f_fr, f_rl, f_rr",
            "z + x theta + y phi",
        ];
        // The chassis's legend is its own: none of the suspension's symbols.
        let (own, other) = match fmu.model {
            Model::Chassis => (&chassis[..], &suspension[..]),
            Model::QuarterCar | Model::Corner => (&suspension[..], &chassis[..]),
        };
        for symbol in own {
            assert!(page.contains(&format!("<td>{symbol}</td>")), "{symbol}");
        }
        for symbol in other {
            assert!(
                !page.contains(&format!("<td>{symbol}</td>")),
                "{symbol} on the page of the {}",
                fmu.title()
            );
        }
        // The body is the quarter car's own; the corner's is outside, its
        // weight on the corner the static load; the chassis is the body.
        let (body, force) = match fmu.model {
            Model::QuarterCar => ("m_s (start 345 kg)", "control_force (output, N)"),
            Model::Corner => (
                "static_load (start 3383.29425 N)",
                "control_force (output, N)",
            ),
            Model::Chassis => ("mass (start 1380 kg)", "force_fl (input, N)"),
        };
        assert!(page.contains(body), "{}", fmu.title());
        assert!(page.contains(force), "{}", fmu.title());
        assert!(page.contains(&reference::csv_entry()), "{}", fmu.label());
        assert!(
            page.contains(&format!("every {} s", reference::OUTPUT_INTERVAL)),
            "{}",
            fmu.label()
        );
    }
}

#[test]
fn the_manifest_names_the_results_beside_it() {
    let xml = reference::manifest_xml();
    assert!(xml.starts_with(r#"<?xml version="1.0" encoding="UTF-8"?>"#));
    assert!(xml.contains(r#"<fmiReferences xmlns:fmi-ls="http://fmi-standard.org/fmi-ls-manifest" fmi-ls:fmi-ls-name="org.fmi-standard.fmi-ls-ref" fmi-ls:fmi-ls-version="1.0.0-alpha.1""#), "{xml}");
    assert!(
        xml.contains(r#"<Related type="text/csv" source="tdvass_out.csv" role="result""#),
        "{xml}"
    );
    assert_eq!(
        reference::manifest_entry().rsplit_once('/').unwrap().0,
        reference::csv_entry().rsplit_once('/').unwrap().0
    );
}

#[test]
fn numbers_are_written_in_their_shortest_round_trip_form() {
    for v in [
        0.0,
        -0.0,
        0.01,
        15.0,
        1e-300,
        -2.5e-7,
        0.1 + 0.2,
        123456.789,
        f64::MIN_POSITIVE,
    ] {
        let text = reference::number(v);
        assert_eq!(
            text.parse::<f64>().unwrap().to_bits(),
            v.to_bits(),
            "{text}"
        );
        assert!(text.len() <= format!("{v}").len() && text.len() <= format!("{v:e}").len());
    }
    assert_eq!(reference::number(0.01), "0.01");
    assert_eq!(reference::number(-2.5e-7), "-2.5e-7");
}

/// The reference results are the default experiment as fmpy runs it: one
/// row per 0.05 s from 0 to 15 s, every scalar Real output, the values of
/// a slave stepped the same way; and the FMI 2.0 and 3.0 slaves agree.
#[test]
fn reference_results_are_the_default_experiment_of_each_fmu() {
    let [fmi2, fmi3, ..] = Fmu::all();
    let csv2 = reference::results_csv(fmi2.model, fmi2.dialect, fmi2.token.clone()).unwrap();
    let csv3 = reference::results_csv(fmi3.model, fmi3.dialect, fmi3.token.clone()).unwrap();
    for (fmu, csv) in [(&fmi2, &csv2), (&fmi3, &csv3)] {
        let mut lines = csv.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let outputs = reference::outputs(fmu.model, &fmu.dialect);
        assert_eq!(header[0], "time");
        assert_eq!(header.len(), outputs.len() + 1);
        for name in [
            "x_s",
            "body_acceleration",
            "rms_body_acceleration",
            "objective",
            "control_force",
        ] {
            assert!(header.contains(&name), "{name} in {header:?}");
        }
        let rows: Vec<Vec<f64>> = lines
            .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
            .collect();
        assert_eq!(rows.len(), 301);
        assert!(rows.iter().all(|r| r.len() == header.len()));
        for (k, row) in rows.iter().enumerate() {
            assert_eq!(row[0], k as f64 * 0.05);
        }
        assert_eq!(rows[300][0], 15.0);
        // The body moves on the harmonic road, from rest.
        let x_s = header.iter().position(|h| *h == "x_s").unwrap();
        assert_eq!(rows[0][x_s], 0.0);
        assert!(rows.iter().any(|r| r[x_s].abs() > 1e-3));
        // The running RMS of BA at 15 s is the TDVASS row of Table 2.
        let ba = header
            .iter()
            .position(|h| *h == "rms_body_acceleration")
            .unwrap();
        assert!((rows[300][ba] - 0.3068).abs() < 1.5e-4, "{}", rows[300][ba]);
    }
    // The columns both versions have carry the same numbers.
    assert_columns_agree(&csv2, &csv3);
    // Deterministic.
    assert_eq!(
        csv2,
        reference::results_csv(fmi2.model, fmi2.dialect, fmi2.token.clone()).unwrap()
    );
}

/// The columns of `csv` by header, each with its cells as written.
fn columns(csv: &str) -> Vec<Vec<String>> {
    let mut columns: Vec<Vec<String>> = Vec::new();
    for line in csv.lines() {
        for (i, cell) in line.split(',').enumerate() {
            if columns.len() <= i {
                columns.push(Vec::new());
            }
            columns[i].push(cell.to_string());
        }
    }
    columns
}

/// Every column of the FMI 2.0 results is in the FMI 3.0 ones, cell for
/// cell.
fn assert_columns_agree(csv2: &str, csv3: &str) {
    let (t2, t3) = (columns(csv2), columns(csv3));
    for column in &t2 {
        let other = t3.iter().find(|c| c[0] == column[0]);
        assert_eq!(Some(column), other, "{}", column[0]);
    }
}

/// The corner's reference results: its own outputs (the body force, not
/// the body's), a corner slave under a body fixed at the static
/// equilibrium on the default harmonic road; both versions agree.
#[test]
fn the_corner_reference_results_are_the_suspension_under_a_fixed_body() {
    let [_, _, corner2, corner3, ..] = Fmu::all();
    let csv2 =
        reference::results_csv(corner2.model, corner2.dialect, corner2.token.clone()).unwrap();
    let csv3 =
        reference::results_csv(corner3.model, corner3.dialect, corner3.token.clone()).unwrap();
    for (fmu, csv) in [(&corner2, &csv2), (&corner3, &csv3)] {
        let mut lines = csv.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let outputs = reference::outputs(Model::Corner, &fmu.dialect);
        assert_eq!(header[0], "time");
        assert_eq!(header.len(), outputs.len() + 1);
        let names: Vec<&str> = outputs.iter().map(|v| v.name).collect();
        assert_eq!(header[1..], names[..]);
        for name in [
            "body_force",
            "x_t",
            "suspension_deflection",
            "tire_deflection",
        ] {
            assert!(header.contains(&name), "{name} in {header:?}");
        }
        for name in ["x_s", "body_acceleration", "objective"] {
            assert!(!header.contains(&name), "{name} in {header:?}");
        }
        let rows: Vec<Vec<f64>> = lines
            .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
            .collect();
        assert_eq!(rows.len(), 301);
        assert!(rows.iter().all(|r| r.len() == header.len()));
        assert_eq!(rows[300][0], 15.0);
        let column = |name: &str| header.iter().position(|h| *h == name).unwrap();
        // From rest at the static equilibrium: no force at the start; the
        // harmonic road moves the wheel, and the suspension pulls on the
        // fixed body.
        let (force, x_t, sdd) = (
            column("body_force"),
            column("x_t"),
            column("suspension_deflection"),
        );
        assert_eq!(rows[0][force], 0.0);
        assert_eq!(rows[0][x_t], 0.0);
        assert!(rows.iter().any(|r| r[x_t].abs() > 1e-3));
        assert!(rows.iter().any(|r| r[force].abs() > 1.0));
        assert!(rows.iter().all(|r| r.iter().all(|x| x.is_finite())));
        // The body is fixed: SDD = 0 - x_t.
        for r in &rows {
            assert_eq!(r[sdd], -r[x_t]);
        }
    }
    assert_columns_agree(&csv2, &csv3);
}

/// The chassis's reference results: its own outputs, a chassis slave
/// under the start values of the forces (0), at rest at its static
/// equilibrium throughout; both versions agree.
#[test]
fn the_chassis_reference_results_are_the_body_at_rest() {
    let [.., chassis2, chassis3] = Fmu::all();
    let csv2 =
        reference::results_csv(chassis2.model, chassis2.dialect, chassis2.token.clone()).unwrap();
    let csv3 =
        reference::results_csv(chassis3.model, chassis3.dialect, chassis3.token.clone()).unwrap();
    for (fmu, csv) in [(&chassis2, &csv2), (&chassis3, &csv3)] {
        assert_eq!(fmu.model, Model::Chassis);
        let mut lines = csv.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let outputs = reference::outputs(Model::Chassis, &fmu.dialect);
        let names: Vec<&str> = outputs.iter().map(|v| v.name).collect();
        assert_eq!(header[0], "time");
        assert_eq!(header[1..], names[..]);
        for name in [
            "displacement_fl",
            "velocity_rr",
            "heave",
            "pitch",
            "roll",
            "heave_acceleration",
            "weighted_seat_acceleration",
            "seat_vibration_dose_value",
        ] {
            assert!(header.contains(&name), "{name} in {header:?}");
        }
        for name in ["x_s", "body_force", "objective"] {
            assert!(!header.contains(&name), "{name} in {header:?}");
        }
        let rows: Vec<Vec<f64>> = lines
            .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
            .collect();
        assert_eq!(rows.len(), 301);
        assert_eq!(rows[300][0], 15.0);
        // No force, no motion: every output is 0 at every point.
        for row in &rows {
            assert_eq!(row.len(), header.len());
            assert!(row[1..].iter().all(|&x| x == 0.0), "{row:?}");
        }
    }
    assert_columns_agree(&csv2, &csv3);
}

/// The corner's and the chassis's FMUs carry the quarter car's library of
/// their version (built once, the same bytes under the same entry) with
/// their own model description, documentation and reference results.
#[test]
fn the_component_fmus_carry_the_quarter_cars_library_with_their_own_description() {
    let fmus = Fmu::all();
    // One library per package, packed into every FMU of its version.
    let built: Vec<(&str, Vec<usize>)> = libraries(&fmus)
        .into_iter()
        .map(|(fmu, carriers)| (fmu.package, carriers))
        .collect();
    assert_eq!(
        built,
        [
            ("tdvass-fmi2", vec![0, 2, 4]),
            ("tdvass-fmi3", vec![1, 3, 5])
        ]
    );
    let host = host_platform(std::env::consts::OS, std::env::consts::ARCH).unwrap();
    let out_dir =
        std::env::temp_dir().join(format!("fmu-build-test-component-{}", std::process::id()));
    fs::create_dir_all(&out_dir).unwrap();
    for (quarter_car, component) in [
        (&fmus[0], &fmus[2]),
        (&fmus[1], &fmus[3]),
        (&fmus[0], &fmus[4]),
        (&fmus[1], &fmus[5]),
    ] {
        assert!(matches!(component.model, Model::Corner | Model::Chassis));
        assert_eq!(quarter_car.model, Model::QuarterCar);
        assert_eq!(
            (component.version, component.package, component.library),
            (
                quarter_car.version,
                quarter_car.package,
                quarter_car.library
            )
        );
        assert_eq!(component.icon_entry, quarter_car.icon_entry);
        assert_eq!(
            component.token,
            tdvass_fmu::variables::token(component.model, component.version)
        );
        assert_ne!(component.token, quarter_car.token);
        // Its own description: both interfaces, the same model identifier.
        let description = &component.description;
        assert!(description.contains(&format!(r#"modelName="{}""#, component.model.name())));
        assert!(description.contains(&component.token));
        assert!(description.contains(r#"<ModelExchange modelIdentifier="tdvass""#));
        assert!(description.contains(r#"<CoSimulation modelIdentifier="tdvass""#));
        assert!(!component.documentation.contains(&quarter_car.token));
        assert!(component.documentation.contains(&component.token));
        // The archive: the same entries as the quarter car's, the library
        // bytes as given.
        let library = b"the library of both".to_vec();
        let entry = host.fmu_entry(component.version).unwrap();
        let binaries = vec![(entry.clone(), library.clone())];
        let path = pack(
            &out_dir, component, &binaries, "time
0
",
        )
        .unwrap();
        assert_eq!(path, out_dir.join(component.file_name));
        let mut archive = ZipArchive::new(fs::File::open(&path).unwrap()).unwrap();
        let mut names: Vec<String> = archive
            .file_names()
            .map(|n| n.unwrap().into_owned())
            .collect();
        names.sort();
        let mut expected: Vec<String> = fixed_entries(quarter_car, "")
            .into_iter()
            .map(|(name, _)| name)
            .chain(["modelDescription.xml".to_string(), entry.clone()])
            .collect();
        expected.sort();
        assert_eq!(names, expected, "{}", component.title());
        let read = |archive: &mut ZipArchive<fs::File>, name: &str| {
            let mut bytes = Vec::new();
            archive
                .by_name(name)
                .unwrap()
                .read_to_end(&mut bytes)
                .unwrap();
            bytes
        };
        assert_eq!(read(&mut archive, &entry), library);
        assert_eq!(
            read(&mut archive, "modelDescription.xml"),
            component.description.as_bytes()
        );
        assert_eq!(
            read(&mut archive, "documentation/index.html"),
            component.documentation.as_bytes()
        );
    }
    fs::remove_dir_all(&out_dir).unwrap();
}

#[test]
fn arguments_name_a_mode_and_whether_to_train() {
    let parse = |args: &[&str]| parse_args(&args.iter().map(|a| a.to_string()).collect::<Vec<_>>());
    assert_eq!(parse(&[]), Some((Mode::Host, Profiling::Trained)));
    assert_eq!(
        parse(&["--no-profile"]),
        Some((Mode::Host, Profiling::Skipped))
    );
    assert_eq!(
        parse(&["--all-platforms"]),
        Some((Mode::AllPlatforms, Profiling::Trained))
    );
    assert_eq!(
        parse(&["--no-profile", "--all-platforms"]),
        Some((Mode::AllPlatforms, Profiling::Skipped))
    );
    assert_eq!(parse(&["--check"]), Some((Mode::Check, Profiling::Trained)));
    assert_eq!(parse(&["--check", "--all-platforms"]), None);
    assert_eq!(parse(&["--no-pgo"]), None);
}

#[test]
fn the_profile_tool_is_required_by_the_build_of_every_platform_unless_skipped() {
    let host = host_platform(std::env::consts::OS, std::env::consts::ARCH).unwrap();
    let platforms = all_platforms().unwrap();
    assert!(profile_tool_required(&platforms, Profiling::Trained));
    assert!(!profile_tool_required(&platforms, Profiling::Skipped));
    // The host build trains when it can and goes on without otherwise.
    assert!(!profile_tool_required(&[host], Profiling::Trained));
    // Windows and aarch64 alone have no profile.
    assert!(!profile_tool_required(&platforms[1..], Profiling::Trained));
}
