//! The `tdvass` command line as a user meets it: the built binary, its exit
//! status, standard output and standard error. One test binary on purpose
//! (each file under `tests/` links its own): hence its length.

use serde_json::Value;
use std::path::PathBuf;
use std::process::Command;

/// What one run of the binary gave.
struct Outcome {
    success: bool,
    stdout: String,
    stderr: String,
}

fn tdvass(args: &[&str]) -> Outcome {
    let output = Command::new(env!("CARGO_BIN_EXE_tdvass"))
        .args(args)
        .output()
        .expect("the tdvass binary runs");
    Outcome {
        success: output.status.success(),
        stdout: String::from_utf8_lossy(&output.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&output.stderr).into_owned(),
    }
}

/// Runs a command that must succeed and print one JSON object.
fn tdvass_json(args: &[&str]) -> Value {
    let mut all = args.to_vec();
    all.push("--json");
    let run = tdvass(&all);
    assert!(run.success, "{args:?} failed: {}", run.stderr);
    serde_json::from_str(&run.stdout).unwrap_or_else(|e| panic!("{args:?}: {e}: {}", run.stdout))
}

/// Runs a command that must fail; returns its standard error.
fn failure(args: &[&str]) -> String {
    let run = tdvass(args);
    assert!(!run.success, "{args:?} succeeded: {}", run.stdout);
    run.stderr
}

/// The smallest controller optimization: two particles, one iteration.
const TINY_CONTROLLER_PSO: [&str; 6] = [
    "optimize",
    "controller",
    "--particles",
    "2",
    "--iterations",
    "1",
];

/// A file name in the temporary directory, unique to this test process.
fn temporary(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("tdvass-cli-{}-{name}", std::process::id()))
}

/// The command line's reference, docs/cli.md.
fn command_line_reference() -> String {
    std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/cli.md"))
        .expect("docs/cli.md documents the command line")
}

#[test]
fn negative_numbers_reach_the_model_checks() {
    let cases: [(&[&str], &str); 5] = [
        (&["simulate", "--tau", "-1"], "`tau`"),
        (&["simulate", "--m-s", "-345"], "`m_s`"),
        (&["simulate", "--duration", "-5"], "`duration`"),
        (&["stability", "--tau-max", "-1"], "`tau_max`"),
        (&["frf", "--f-min", "-0.5"], "`f_min`"),
    ];
    for (args, parameter) in cases {
        let stderr = failure(args);
        assert!(
            !stderr.contains("unexpected argument"),
            "{args:?}: {stderr}"
        );
        assert!(
            stderr.contains(parameter) && stderr.contains(args[2]),
            "{args:?} should name {parameter} and its value: {stderr}"
        );
    }
    // Negative values that are admissible run.
    let run = tdvass(&["stable", "--g", "-40000", "--tau", "0.25", "--json"]);
    assert!(run.success, "{}", run.stderr);
    let run = tdvass(&[
        "map",
        "--g-min",
        "-1000",
        "--g-max",
        "-10",
        "--g-points",
        "2",
        "--tau-points",
        "2",
        "--json",
    ]);
    assert!(run.success, "{}", run.stderr);
}

#[test]
fn a_bad_name_is_echoed_with_the_valid_ones() {
    let cases: [(&[&str], &str, &[&str]); 6] = [
        (
            &["simulate", "--road", "bumpy"],
            "`bumpy`",
            &["harmonic", "iso8608", "paper", "file:PATH"],
        ),
        (
            &["simulate", "--variant", "foo"],
            "`foo`",
            &["cs", "pvass", "tdvass"],
        ),
        (
            &["simulate", "--road", "iso8608", "--road-class", "Z"],
            "`Z`",
            &["A..H"],
        ),
        (&["optimize", "foo"], "`foo`", &["absorber", "controller"]),
        (
            &["simulate", "--tire-contact", "sticky"],
            "`sticky`",
            &["bilateral", "unilateral"],
        ),
        (
            &["optimize", "absorber", "--tire-contact", "2"],
            "`2`",
            &["bilateral", "unilateral"],
        ),
    ];
    for (args, echo, valid) in cases {
        let stderr = failure(args);
        assert!(stderr.contains(echo), "{args:?}: {stderr}");
        assert!(!stderr.contains("-1 for"), "{args:?}: {stderr}");
        for name in valid {
            assert!(
                stderr.contains(name),
                "{args:?} should list {name}: {stderr}"
            );
        }
    }
}

#[test]
fn names_are_matched_whatever_their_case() {
    let short = ["--duration", "0.5"];
    let reference = tdvass_json(&[&["simulate", "--road", "iso8608"][..], &short].concat());
    for spelling in ["ISO8608", "Iso8608", "iso", "ISO"] {
        let other = tdvass_json(&[&["simulate", "--road", spelling][..], &short].concat());
        assert_eq!(
            other["rms_body_acceleration"], reference["rms_body_acceleration"],
            "--road {spelling}"
        );
        assert_eq!(other["road"], "iso8608", "--road {spelling}");
    }
    let reference = tdvass_json(&[&["simulate", "--variant", "pvass"][..], &short].concat());
    let upper = tdvass_json(&[&["simulate", "--variant", "PVASS"][..], &short].concat());
    assert_eq!(upper["variant"], "pvass");
    assert_eq!(upper["objective"], reference["objective"]);
    let lower = tdvass_json(
        &[
            &["simulate", "--road", "Paper", "--road-class", "d"][..],
            &short,
        ]
        .concat(),
    );
    let upper = tdvass_json(
        &[
            &["simulate", "--road", "paper", "--road-class", "D"][..],
            &short,
        ]
        .concat(),
    );
    assert_eq!(lower["objective"], upper["objective"]);
    assert_eq!(lower["road_class"], "D");
    let run = tdvass(&[
        "optimize",
        "Controller",
        "--particles",
        "2",
        "--iterations",
        "1",
        "--duration",
        "0.2",
        "--json",
    ]);
    assert!(run.success, "{}", run.stderr);
}

#[test]
fn io_errors_are_labelled_as_io() {
    let missing = "/nonexistent-directory-of-tdvass/o.csv";
    let cases: [&[&str]; 3] = [
        &["simulate", "--duration", "0.1", "--output", missing],
        &["frf", "--points", "3", "--output", missing],
        &[
            "map",
            "--g-points",
            "2",
            "--tau-points",
            "2",
            "--output",
            missing,
        ],
    ];
    for args in cases {
        let stderr = failure(args);
        assert!(stderr.contains("I/O error"), "{args:?}: {stderr}");
        assert!(stderr.contains(missing), "{args:?}: {stderr}");
        assert!(!stderr.contains("numerical"), "{args:?}: {stderr}");
    }
}

#[test]
fn a_flag_that_does_not_apply_warns() {
    let warns = |args: &[&str], flag: &str| {
        let run = tdvass(args);
        assert!(run.success, "{args:?}: {}", run.stderr);
        run.stderr
            .lines()
            .any(|l| l.starts_with("warning:") && l.contains(flag))
    };
    assert!(warns(
        &["simulate", "--variant", "cs", "--g", "2528"],
        "--g"
    ));
    assert!(warns(
        &["simulate", "--variant", "pvass", "--tau", "0.01"],
        "--tau"
    ));
    assert!(warns(
        &["simulate", "--variant", "cs", "--k-h", "5000"],
        "--k-h"
    ));
    assert!(!warns(
        &["simulate", "--variant", "tdvass", "--g", "2528"],
        "--g"
    ));
    assert!(!warns(&["simulate", "--variant", "cs"], "--g"));
    assert!(warns(&["simulate", "--road-seed", "3"], "--road-seed"));
    assert!(!warns(
        &["simulate", "--road", "paper", "--road-seed", "3"],
        "--road-seed"
    ));
    assert!(warns(
        &[
            "simulate",
            "--road",
            "iso8608",
            "--road-sample-interval",
            "0.2"
        ],
        "--road-sample-interval"
    ));
    assert!(warns(
        &["simulate", "--output-interval", "0.01"],
        "--output-interval"
    ));
    assert!(warns(
        &["stability", "--g", "50000", "--tau", "0.1"],
        "--tau"
    ));
    assert!(warns(
        &["frf", "--variant", "cs", "--g", "100", "--points", "3"],
        "--g"
    ));
}

#[test]
fn simulate_json_records_every_parameter_of_the_run() {
    let value = tdvass_json(&[
        "simulate",
        "--variant",
        "TDVASS",
        "--road",
        "iso",
        "--road-class",
        "b",
        "--road-seed",
        "9",
        "--vehicle-speed",
        "15",
        "--g",
        "1234.5",
        "--tau",
        "0.001",
        "--k-h",
        "6000",
        "--duration",
        "0.5",
    ]);
    let expected = [
        ("variant", Value::from("tdvass")),
        ("road", Value::from("iso8608")),
        ("road_class", Value::from("B")),
        ("road_seed", Value::from(9)),
        ("vehicle_speed", Value::from(15.0)),
        ("g", Value::from(1234.5)),
        ("tau", Value::from(0.001)),
        ("k_h", Value::from(6000.0)),
        ("m_s", Value::from(345.0)),
        ("duration", Value::from(0.5)),
        ("tolerance", Value::from(1e-6)),
        ("max_internal_step", Value::from(0.0)),
    ];
    for (key, value_expected) in expected {
        assert_eq!(value[key], value_expected, "key {key}");
    }
    for key in [
        "rms_body_acceleration",
        "rms_suspension_deflection",
        "rms_tire_deflection",
        "objective",
        "road_note",
        "road_amplitude",
        "road_angular_frequency",
        "road_cutoff_frequency",
        "road_sample_interval",
        "w_ba",
        "w_sdd",
        "w_tdd",
    ] {
        assert!(!value[key].is_null(), "key {key} missing: {value}");
    }
}

#[test]
fn optimize_help_documents_every_bound_and_a_bad_bound_names_its_flag() {
    let run = tdvass(&["optimize", "--help"]);
    assert!(run.success);
    for (flag, default) in [
        ("--g-min", "[default: 0]"),
        ("--g-max", "[default: 20000]"),
        ("--tau-min", "[default: 0]"),
        ("--tau-max", "[default: 0.05]"),
    ] {
        let mut lines = run
            .stdout
            .lines()
            .skip_while(|l| !l.trim_start().starts_with(flag));
        assert!(lines.next().is_some(), "{flag} missing from the help");
        let text = lines.next().unwrap_or_default();
        assert!(
            text.contains("bound") && text.contains(default),
            "{flag}: `{text}`"
        );
    }
    let cases: [(&[&str], &str); 3] = [
        (&["optimize", "controller", "--g-max", "-5"], "`--g-max`"),
        (
            &["optimize", "controller", "--tau-min", "-0.1"],
            "`--tau-min`",
        ),
        (
            &[
                "optimize",
                "controller",
                "--tau-min",
                "0.1",
                "--tau-max",
                "0.05",
            ],
            "`--tau-max`",
        ),
    ];
    for (args, flag) in cases {
        let stderr = failure(args);
        assert!(stderr.contains(flag), "{args:?}: {stderr}");
        assert!(!stderr.contains("bounds."), "{args:?}: {stderr}");
    }
}

#[test]
fn a_long_simulation_reports_progress_and_an_endless_one_is_refused() {
    // About 4e8 internal steps: several seconds of wall time.
    let run = tdvass(&[
        "simulate",
        "--duration",
        "4000",
        "--max-internal-step",
        "1e-5",
    ]);
    assert!(run.success, "{}", run.stderr);
    assert!(
        run.stderr.contains("simulate: t = ") && run.stderr.contains(" of 4000 s"),
        "no progress on standard error: {}",
        run.stderr
    );
    // A short one stays silent.
    let run = tdvass(&["simulate", "--duration", "1"]);
    assert!(run.success && run.stderr.is_empty(), "{}", run.stderr);
    let stderr = failure(&["simulate", "--duration", "1e9"]);
    assert!(
        stderr.contains("`duration`") && stderr.contains("1e10 internal steps"),
        "{stderr}"
    );
}

#[test]
fn map_and_simulate_json_keys_are_documented_in_the_readme() {
    let readme = command_line_reference();
    let map = tdvass_json(&["map", "--g-points", "2", "--tau-points", "2"]);
    let simulate = tdvass_json(&["simulate", "--duration", "0.1"]);
    for value in [map, simulate] {
        for key in value.as_object().unwrap().keys() {
            assert!(
                readme.contains(&format!("`{key}`")),
                "JSON key `{key}` is not documented in docs/cli.md"
            );
        }
    }
}

#[test]
fn stability_lists_no_empty_delay_line_and_one_interval_notation() {
    let run = tdvass(&["stability", "--g", "200000"]);
    assert!(run.success, "{}", run.stderr);
    for line in run.stdout.lines() {
        assert!(
            !line.trim_end().ends_with(':'),
            "a line ends without its values: `{line}`"
        );
    }
    for g in ["50000", "-50000", "200000"] {
        let table = tdvass(&["stability", "--g", g]).stdout;
        let json = tdvass_json(&["stability", "--g", g]);
        let expected: Vec<String> = json["stable_intervals"]
            .as_array()
            .unwrap()
            .iter()
            .map(|i| {
                let (from, to) = (i[0].as_f64().unwrap(), i[1].as_f64().unwrap());
                if from == 0.0 {
                    format!("[0, {to:.4})")
                } else {
                    format!("({from:.4}, {to:.4})")
                }
            })
            .collect();
        let line = table
            .lines()
            .find(|l| l.starts_with("stable delays"))
            .unwrap();
        assert!(
            line.ends_with(&expected.join(" ∪ ")),
            "g = {g}: `{line}`, expected {expected:?}"
        );
    }
}

#[test]
fn a_csv_road_warns_past_its_last_sample_and_accepts_the_documented_formats() {
    let path = temporary("road.csv");
    // A header, a comment, semicolons, a tab, spaces and an extra numeric
    // column.
    std::fs::write(
        &path,
        "time;x_g;speed\n# measured\n0;0;20\n0.5\t0.01\t20\n1.0 , 0.02 , 20\n2.0;0.0;20\n",
    )
    .unwrap();
    let road = format!("file:{}", path.display());
    let past = tdvass(&["simulate", "--road", &road, "--duration", "3", "--json"]);
    let within = tdvass(&["simulate", "--road", &road, "--duration", "1.5", "--json"]);
    std::fs::remove_file(&path).unwrap();
    assert!(past.success, "{}", past.stderr);
    assert!(
        past.stderr
            .contains("warning: the road file ends at t = 2 s"),
        "{}",
        past.stderr
    );
    assert!(
        within.success && within.stderr.is_empty(),
        "{}",
        within.stderr
    );
}

#[test]
fn cli_defaults_are_the_library_defaults_and_the_fmu_start_values() {
    // One declaration: what `simulate` runs with when no flag is given must
    // be Params::default() (Table 1, g1, tau1) and the FMU's start values.
    let run = tdvass_json(&["simulate", "--duration", "0"]);
    let params = tdvass::model::Params::default();
    for (name, library) in params.named_values() {
        let cli = run[name]
            .as_f64()
            .unwrap_or_else(|| panic!("`{name}` missing in {run}"));
        let fmu = tdvass_fmu::variables::by_name(
            tdvass_fmu::Model::QuarterCar,
            tdvass_fmu::variables::FmiVersion::Fmi3,
            name,
        )
        .and_then(|v| v.start)
        .unwrap_or_else(|| panic!("no FMU start value for `{name}`"));
        assert_eq!(
            cli, library,
            "`{name}`: CLI default against Params::default()"
        );
        assert_eq!(
            cli, fmu,
            "`{name}`: CLI default against the FMU start value"
        );
    }
    for name in [
        "road_amplitude",
        "road_angular_frequency",
        "vehicle_speed",
        "road_cutoff_frequency",
        "road_sample_interval",
        "max_internal_step",
        "w_ba",
        "w_sdd",
        "w_tdd",
    ] {
        let cli = run[name]
            .as_f64()
            .unwrap_or_else(|| panic!("`{name}` missing in {run}"));
        let fmu = tdvass_fmu::variables::by_name(
            tdvass_fmu::Model::QuarterCar,
            tdvass_fmu::variables::FmiVersion::Fmi3,
            name,
        )
        .and_then(|v| v.start)
        .unwrap();
        assert_eq!(
            cli, fmu,
            "`{name}`: CLI default against the FMU start value"
        );
    }
    let seed = tdvass_fmu::variables::by_name(
        tdvass_fmu::Model::QuarterCar,
        tdvass_fmu::variables::FmiVersion::Fmi3,
        "road_seed",
    )
    .and_then(|v| v.start)
    .unwrap();
    assert_eq!(run["road_seed"].as_f64(), Some(seed));
    // The tire: the library's default, and the item of the FMU's start code.
    let contact = tdvass_fmu::variables::by_name(
        tdvass_fmu::Model::QuarterCar,
        tdvass_fmu::variables::FmiVersion::Fmi3,
        "tire_contact",
    )
    .unwrap();
    let start = contact.start.unwrap() as i32;
    let item = contact
        .enumeration
        .unwrap()
        .items
        .iter()
        .find(|i| i.value == start)
        .unwrap();
    assert_eq!(run["tire_contact"], item.name);
    assert_eq!(run["tire_contact"], tdvass::TireContact::default().name());
}

#[test]
fn the_cli_refuses_the_runaway_inputs_the_fmu_refuses_with_the_same_message() {
    use tdvass_fmi2::instance::FMI2_DIALECT;
    use tdvass_fmu::slave::Logger;
    use tdvass_fmu::variables::{FmiVersion, by_name};
    // Each case is within the declared range, beyond a numerical limit.
    for (flag, name, value) in [
        ("--k-t", "k_t", 1e30),
        ("--c-s", "c_s", 1e300),
        ("--road-amplitude", "road_amplitude", 2e3),
        ("--road-angular-frequency", "road_angular_frequency", 1e7),
        ("--w-ba", "w_ba", 1e13),
    ] {
        let text = value.to_string();
        let cli = failure(&["simulate", "--duration", "0.01", flag, &text]);
        let mut slave = tdvass_fmu::Slave::new(
            FMI2_DIALECT,
            tdvass_fmu::Model::QuarterCar,
            tdvass_fmu::guid(tdvass_fmu::Model::QuarterCar),
            Logger::new(Box::new(|_, _, _| {}), false),
        );
        let vr = by_name(tdvass_fmu::Model::QuarterCar, FmiVersion::Fmi3, name)
            .unwrap()
            .vr;
        // The FMU refuses the value when it is set, or the settings when
        // the simulation is built.
        let fmu = slave
            .set_real(&[vr], &[value])
            .and_then(|_| slave.enter_initialization_mode())
            .and_then(|_| slave.exit_initialization_mode())
            .expect_err(name)
            .message;
        assert!(
            cli.contains(&fmu),
            "`{name}` = {value}: the CLI says\n{cli}\nthe FMU says\n{fmu}"
        );
    }
}

#[test]
fn simulate_reports_the_field_metrics_and_the_csv_bounds_the_working_space() {
    let csv = temporary("metrics.csv");
    let csv_path = csv.to_str().unwrap();
    let run = tdvass_json(&[
        "simulate",
        "--road",
        "iso8608",
        "--road-class",
        "E",
        "--duration",
        "1",
        "--output",
        csv_path,
        "--output-interval",
        "0.0001",
    ]);
    for key in [
        "weighted_body_acceleration",
        "rms_weighted_body_acceleration",
        "vibration_dose_value",
        "dynamic_tire_load",
        "rms_dynamic_tire_load_ratio",
        "contact_loss_time",
        "max_suspension_deflection",
    ] {
        assert!(run[key].is_f64(), "`{key}` missing in {run}");
    }
    let a_w = run["rms_weighted_body_acceleration"].as_f64().unwrap();
    assert!(a_w > 0.0 && a_w < run["rms_body_acceleration"].as_f64().unwrap());
    assert!(run["comfort_reaction"].is_string());
    // The dynamic tire load ratio is k_t RMS(TDD) over the static load.
    let static_load = (345.0 + 4.05 + 40.5) * 9.80665;
    let ratio = 190000.0 * run["rms_tire_deflection"].as_f64().unwrap() / static_load;
    let reported = run["rms_dynamic_tire_load_ratio"].as_f64().unwrap();
    assert!(
        (reported - ratio).abs() <= 1e-12 * ratio,
        "{reported} {ratio}"
    );
    // The CSV rows sample every 0.1 ms: the running maximum, located inside
    // the internal steps (to the tolerance, 1e-6), is above the largest
    // |SDD| over them by at most what that sampling can miss,
    // `(5e-5 s)² |SDD''| / 2`, some 6e-6 relative with the 20 Hz wheel hop.
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let column = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (sdd, max) = (
        column("suspension_deflection"),
        column("max_suspension_deflection"),
    );
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 10001);
    let over_rows = rows.iter().map(|r| r[sdd].abs()).fold(0.0, f64::max);
    let running = run["max_suspension_deflection"].as_f64().unwrap();
    assert_eq!(rows.last().unwrap()[max], running);
    assert!(
        running >= over_rows * (1.0 - 1e-6) && running <= over_rows * (1.0 + 1e-5),
        "{over_rows} over the CSV rows, {running} reported"
    );
    let _ = std::fs::remove_file(&csv);
}

#[test]
fn the_comfort_objective_keeps_its_constraints_at_its_optimum() {
    let run = tdvass_json(&[
        "optimize",
        "absorber",
        "--objective",
        "comfort",
        "--road",
        "iso8608",
        "--particles",
        "8",
        "--iterations",
        "6",
        "--duration",
        "5",
    ]);
    assert_eq!(run["objective_function"], "comfort");
    let e = &run["best_evaluation"];
    assert_eq!(e["feasible"], true, "{run}");
    assert!(e["rms_dynamic_tire_load_ratio"].as_f64().unwrap() <= 1.0 / 3.0);
    assert!(
        e["max_suspension_deflection"].as_f64().unwrap()
            <= run["limits"]["max_suspension_deflection"].as_f64().unwrap()
    );
    assert!(
        e["static_deflection"].as_f64().unwrap()
            <= run["limits"]["static_deflection"].as_f64().unwrap()
    );
    assert_eq!(
        run["objective"].as_f64(),
        e["rms_weighted_body_acceleration"].as_f64()
    );
    // Not the degenerate design that disconnects the body.
    assert!(run["best"]["k_h"].as_f64().unwrap() > 1000.0, "{run}");
    assert!(
        failure(&["optimize", "absorber", "--objective", "softest"]).contains("paper or comfort")
    );
}

#[test]
fn the_tolerance_sets_the_internal_step_and_bad_ones_are_refused_naming_the_value() {
    let run =
        |tolerance: &str| tdvass_json(&["simulate", "--duration", "1", "--tolerance", tolerance]);
    let (loose, tight) = (run("1e-4"), run("1e-9"));
    assert_eq!(loose["tolerance"], Value::from(1e-4));
    let step = |v: &Value| v["internal_step"].as_f64().unwrap();
    assert!(step(&loose) > step(&tight), "{loose} {tight}");
    // The cap bounds the step the tolerance gives.
    let capped = tdvass_json(&["simulate", "--duration", "1", "--max-internal-step", "1e-4"]);
    assert_eq!(step(&capped), 1e-4);
    for subcommand in [&["simulate"][..], &TINY_CONTROLLER_PSO[..]] {
        for (bad, shown) in [("0.5", "0.5"), ("-1e-6", "-0.000001"), ("NaN", "NaN")] {
            let flag = format!("--tolerance={bad}");
            let mut args = subcommand.to_vec();
            args.push(&flag);
            let stderr = failure(&args);
            assert!(
                stderr.contains("`tolerance`") && stderr.contains(shown),
                "{args:?}: {stderr}"
            );
        }
    }
}

#[test]
fn the_unilateral_tire_lifts_off_on_a_class_d_road_and_is_recorded() {
    let road = [
        "simulate",
        "--road",
        "iso8608",
        "--road-class",
        "D",
        "--duration",
        "2",
    ];
    let csv = temporary("lift-offs.csv");
    let csv_path = csv.to_str().unwrap();
    let unilateral = tdvass(
        &[
            &road[..],
            &[
                "--tire-contact",
                "unilateral",
                "--output",
                csv_path,
                "--output-interval",
                "0.01",
                "--json",
            ],
        ]
        .concat(),
    );
    assert!(unilateral.success, "{}", unilateral.stderr);
    let u: Value = serde_json::from_str(&unilateral.stdout).unwrap();
    assert_eq!(u["tire_contact"], "unilateral");
    let count = u["lift_off_count"].as_u64().expect("an integer count");
    assert!(count > 0, "{u}");
    assert!(u["contact_loss_time"].as_f64().unwrap() > 0.0, "{u}");
    // The unilateral tire models the flight: no warning that the model
    // stops holding.
    assert!(
        !unilateral.stderr.contains("leaves the road"),
        "{}",
        unilateral.stderr
    );
    // The default is the bilateral tire, recorded as such, which warns.
    let bilateral = tdvass(&[&road[..], &["--json"]].concat());
    assert!(bilateral.success, "{}", bilateral.stderr);
    let b: Value = serde_json::from_str(&bilateral.stdout).unwrap();
    assert_eq!(b["tire_contact"], "bilateral");
    assert!(b["lift_off_count"].as_u64().unwrap() > 0, "{b}");
    assert!(
        bilateral.stderr.contains("the tire leaves the road"),
        "{}",
        bilateral.stderr
    );
    // The flag reaches the run: flights change the tire deflection.
    assert_ne!(u["rms_tire_deflection"], b["rms_tire_deflection"]);
    // The CSV's count never decreases, in whole numbers, and ends at the
    // JSON's.
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let column = header.iter().position(|h| *h == "lift_off_count").unwrap();
    let counts: Vec<u64> = lines
        .map(|l| l.split(',').nth(column).unwrap().parse().unwrap())
        .collect();
    assert_eq!(counts.len(), 201);
    assert_eq!(counts[0], 0);
    assert!(counts.windows(2).all(|w| w[0] <= w[1]));
    assert_eq!(*counts.last().unwrap(), count);
    let _ = std::fs::remove_file(&csv);
    // Where the wheel never lifts off (the default harmonic road) both
    // tires give the same run.
    let run = |contact: &str| {
        let mut value = tdvass_json(&["simulate", "--duration", "2", "--tire-contact", contact]);
        assert_eq!(value["lift_off_count"], 0);
        value["tire_contact"] = Value::Null;
        value
    };
    assert_eq!(run("unilateral"), run("bilateral"));
}

#[test]
fn optimize_takes_the_tire_contact_with_both_objectives() {
    for (target, objective) in [
        ("absorber", "paper"),
        ("absorber", "comfort"),
        ("controller", "paper"),
        ("controller", "comfort"),
    ] {
        let run = |contact: &str| {
            tdvass_json(&[
                "optimize",
                target,
                "--objective",
                objective,
                "--road",
                "iso8608",
                "--road-class",
                "D",
                "--particles",
                "3",
                "--iterations",
                "2",
                "--duration",
                "1",
                "--tire-contact",
                contact,
            ])
        };
        let (unilateral, bilateral) = (run("unilateral"), run("bilateral"));
        assert_eq!(unilateral["tire_contact"], "unilateral");
        assert_eq!(bilateral["tire_contact"], "bilateral");
        // Every candidate runs with the tire asked for: the wheel lifts off
        // on this road, so the scores differ.
        assert_ne!(
            unilateral["objective"], bilateral["objective"],
            "{target}, {objective}: {unilateral}"
        );
    }
    // Without lift-offs the two tires are the same model: the same scores,
    // bit for bit.
    let controller = |contact: &str| {
        tdvass_json(
            &[
                &TINY_CONTROLLER_PSO[..],
                &["--duration", "1", "--tire-contact", contact],
            ]
            .concat(),
        )
    };
    let (unilateral, bilateral) = (controller("unilateral"), controller("bilateral"));
    assert_eq!(unilateral["objective"], bilateral["objective"]);
    let points = |v: &Value| v["paper_points"].as_array().unwrap().clone();
    assert_eq!(points(&unilateral).len(), 2);
    for (u, b) in points(&unilateral).iter().zip(&points(&bilateral)) {
        assert_eq!(u["objective"], b["objective"], "{u} {b}");
    }
}

#[test]
fn the_linear_analyses_say_so_and_take_no_tire_contact() {
    for subcommand in ["stability", "stable", "frf", "map"] {
        let help = tdvass(&[subcommand, "--help"]);
        assert!(help.success);
        assert!(
            help.stdout.contains("linear model") && !help.stdout.contains("--tire-contact <"),
            "{subcommand}: {}",
            help.stdout
        );
        let stderr = failure(&[subcommand, "--tire-contact", "unilateral"]);
        assert!(stderr.contains("--tire-contact"), "{subcommand}: {stderr}");
    }
    for subcommand in [&["simulate"][..], &["optimize", "absorber"][..]] {
        let help = tdvass(&[subcommand, &["--help"]].concat());
        assert!(
            help.stdout.contains("--tire-contact <TIRE_CONTACT>")
                && help.stdout.contains("[default: bilateral]"),
            "{subcommand:?}: {}",
            help.stdout
        );
    }
}

#[test]
fn the_decoupled_car_s_corner_is_tdvass_simulate() {
    // The default chassis and one road on both tracks: the front left
    // corner is the quarter car of `simulate` (the same step) to 1e-10.
    let car = tdvass_json(&[
        "car",
        "--road",
        "iso8608",
        "--duration",
        "1",
        "--right-seed",
        "1",
    ]);
    let quarter = tdvass_json(&["simulate", "--road", "iso8608", "--duration", "1"]);
    assert_eq!(car["internal_step"], quarter["internal_step"]);
    let corner = &car["corners"]["fl"];
    for key in [
        "rms_suspension_deflection",
        "rms_tire_deflection",
        "rms_dynamic_tire_load_ratio",
    ] {
        let (ours, theirs) = (
            corner[key].as_f64().unwrap(),
            quarter[key].as_f64().unwrap(),
        );
        assert!(
            (ours - theirs).abs() <= 1e-10 * theirs.abs(),
            "{key}: {ours} vs {theirs}"
        );
    }
    assert_eq!(corner["lift_off_count"], quarter["lift_off_count"]);
    let reference = command_line_reference();
    for key in car
        .as_object()
        .unwrap()
        .keys()
        .chain(corner.as_object().unwrap().keys())
    {
        assert!(
            reference.contains(&format!("`{key}`")),
            "JSON key `{key}` of `tdvass car` is not documented in docs/cli.md"
        );
    }
    let refused = failure(&["car", "--vehicle-speed", "0"]);
    assert!(
        refused.contains("`vehicle_speed`") && refused.contains('0'),
        "{refused}"
    );
}

#[test]
fn a_step_under_one_wheel_rolls_the_car_and_its_mirror_rolls_it_back() {
    // `--corner-road`: a 2 cm step under one front wheel from the start,
    // the other wheels on flat roads, no wheelbase delay.
    let step = temporary("step.csv");
    std::fs::write(&step, "t,x_g\n0,0.02\n").unwrap();
    let road = |corner: &str| format!("{corner}=file:{}", step.display());
    let run =
        |corner: &str| tdvass_json(&["car", "--duration", "0.5", "--corner-road", &road(corner)]);
    let (left, right) = (run("fl"), run("fr"));
    assert_eq!(left["rear_road_delay"], 0.0);
    assert_eq!(left["corner_roads"][0], road("fl").as_str());
    let deflection = |car: &Value, corner: &str| {
        car["corners"][corner]["rms_suspension_deflection"]
            .as_f64()
            .unwrap()
    };
    // The stepped wheel works hardest, and the mirror of the step is the
    // mirror of the car (the seat on the centre line).
    assert!(deflection(&left, "fl") > 5.0 * deflection(&left, "fr"));
    for (a, b) in [("fl", "fr"), ("rl", "rr")] {
        let (ours, mirrored) = (deflection(&left, a), deflection(&right, b));
        assert!(
            (ours - mirrored).abs() <= 1e-12 * ours,
            "{a}: {ours} vs {mirrored}"
        );
    }
    assert!(left["rms_roll_acceleration"].as_f64().unwrap() > 0.01);
    let unknown = failure(&["car", "--corner-road", "front=file:x.csv"]);
    assert!(
        unknown.contains("corner road") && unknown.contains("front=file:x.csv"),
        "{unknown}"
    );
    let twice = failure(&[
        "car",
        "--corner-road",
        &road("fl"),
        "--corner-road",
        &road("fl"),
    ]);
    assert!(twice.contains("each named once"), "{twice}");
    std::fs::remove_file(&step).unwrap();
}
