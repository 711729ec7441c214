//! The `tdvass` command line: `simulate`, `stability`, `stable`, `frf`,
//! `optimize` and `map` (names and JSON keys fixed by the interface spec).
//! Every subcommand prints a table, or one JSON object with `--json`.

use crate::json::ToJson;
use clap::parser::ValueSource;
use clap::{ArgMatches, Args, CommandFactory, FromArgMatches, Parser, Subcommand};
use serde_json::json;
use std::collections::BTreeSet;
use std::fmt::Write as _;
use std::io::{IsTerminal as _, Write as _};
use std::time::{Duration, Instant};
use tdvass::analysis::frf::{frequency_response, peaks_hz};
use tdvass::analysis::optimize::{
    CONTROLLER_DELAY_RANGE, CONTROLLER_GAIN_RANGE, Problem, Target, optimize,
};
use tdvass::analysis::pso::{Bounds, PsoSettings};
use tdvass::analysis::spectrum::StableReport;
use tdvass::analysis::stability::{StabilityReport, stability_map};
use tdvass::error::{Error, Result};
use tdvass::metrics::Weights;
use tdvass::model::{Params, State, Variant};
use tdvass::road::{RandomRoad, RoadClass, RoadSpec};
use tdvass::solver::{DEFAULT_MAX_INTERNAL_STEP, SimulationConfig, Simulator};

/// Wall time after which `simulate` reports its progress on standard error.
const PROGRESS_AFTER: Duration = Duration::from_secs(2);
/// Time between two progress lines when standard error is not a terminal.
const PROGRESS_LINE_INTERVAL: Duration = Duration::from_secs(10);
/// Simulated time between two progress checks of `simulate` without
/// `--output` (s). Results do not depend on how a run is split.
const PROGRESS_CHUNK: f64 = 1.0;
/// Largest number of internal steps (duration / internal step) one
/// `simulate` accepts: about 1e6 s of simulated time at the default
/// internal step of 1e-4 s, a few minutes of wall time.
pub const MAX_SIMULATE_STEPS: f64 = 1e10;

/// Accepted `--road` values (case-insensitive), for error messages.
const ROAD_NAMES: &str = "harmonic, iso8608 (alias iso), paper or file:PATH (any case)";

/// Time-delay feedback controlled suspension with an annular
/// vibration-absorbing structure (CS, PVASS, TDVASS).
#[derive(Debug, Parser)]
#[command(name = "tdvass", version, about)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Time-domain run from rest; RMS of BA, SDD, TDD and the objective J.
    Simulate(SimulateArgs),
    /// Delay-independent range, crossing frequencies, critical delays and
    /// stable delay intervals for a gain g (section 3).
    Stability(StabilityArgs),
    /// Rightmost characteristic roots and stability at one (g, tau).
    Stable(StableArgs),
    /// Amplitude-frequency characteristics, Eq. (4) and (5).
    Frf(FrfArgs),
    /// Particle swarm optimisation of the absorber or the controller.
    Optimize(OptimizeArgs),
    /// The (g, tau) stability map as CSV.
    Map(MapArgs),
}

/// Model parameters, named as the FMU parameters (defaults: Table 1, g1, tau1).
#[derive(Debug, Clone, Args)]
struct ModelArgs {
    /// Body mass m_s (kg).
    #[arg(long, default_value_t = 345.0)]
    m_s: f64,
    /// Absorber mass m_h (kg).
    #[arg(long, default_value_t = 4.05)]
    m_h: f64,
    /// Wheel mass m_t (kg).
    #[arg(long, default_value_t = 40.5)]
    m_t: f64,
    /// Suspension stiffness k_s (N/m).
    #[arg(long, default_value_t = 16000.0)]
    k_s: f64,
    /// Absorber stiffness k_h (N/m).
    #[arg(long, default_value_t = 6444.0)]
    k_h: f64,
    /// Tire stiffness k_t (N/m).
    #[arg(long, default_value_t = 190000.0)]
    k_t: f64,
    /// Suspension damping c_s (N.s/m).
    #[arg(long, default_value_t = 1500.0)]
    c_s: f64,
    /// Absorber damping c_h (N.s/m).
    #[arg(long, default_value_t = 348.0)]
    c_h: f64,
    /// Feedback gain g (N/m).
    #[arg(long, default_value_t = 5386.0)]
    g: f64,
    /// Feedback delay tau (s).
    #[arg(long, default_value_t = 2e-4)]
    tau: f64,
}

impl ModelArgs {
    fn params(&self) -> Params {
        Params {
            m_s: self.m_s,
            m_h: self.m_h,
            m_t: self.m_t,
            k_s: self.k_s,
            k_h: self.k_h,
            k_t: self.k_t,
            c_s: self.c_s,
            c_h: self.c_h,
            g: self.g,
            tau: self.tau,
        }
    }
}

/// A `--road` value, read case-insensitively (the path of `file:PATH` is
/// kept as typed).
#[derive(Debug, Clone, PartialEq)]
enum RoadName {
    Harmonic,
    Iso8608,
    Paper,
    File(String),
}

impl RoadName {
    fn parse(text: &str) -> Result<RoadName> {
        let trimmed = text.trim();
        let lower = trimmed.to_ascii_lowercase();
        Ok(match lower.as_str() {
            "harmonic" => RoadName::Harmonic,
            "iso8608" | "iso" => RoadName::Iso8608,
            "paper" => RoadName::Paper,
            _ if lower.starts_with("file:") => RoadName::File(trimmed["file:".len()..].to_string()),
            _ => {
                return Err(Error::UnknownName {
                    what: "road",
                    given: text.to_string(),
                    expected: ROAD_NAMES,
                });
            }
        })
    }

    /// The name a result records (`harmonic`, `iso8608`, `paper`, `file:PATH`).
    fn canonical(&self) -> String {
        match self {
            RoadName::Harmonic => "harmonic".into(),
            RoadName::Iso8608 => "iso8608".into(),
            RoadName::Paper => "paper".into(),
            RoadName::File(path) => format!("file:{path}"),
        }
    }
}

/// Road, solver and objective settings shared by `simulate` and `optimize`.
#[derive(Debug, Clone, Args)]
struct RunArgs {
    /// harmonic, iso8608 (alias iso), paper (the paper-compatible random
    /// road) or file:PATH (CSV rows t,x_g; the last value is held after the
    /// last row). Any case.
    #[arg(long, default_value = "harmonic")]
    road: String,
    /// Harmonic amplitude (m).
    #[arg(long, default_value_t = 0.05)]
    road_amplitude: f64,
    /// Harmonic angular frequency (rad/s).
    #[arg(long, default_value_t = 5.0)]
    road_angular_frequency: f64,
    /// ISO 8608 class of the random roads, A..H (any case) or 1..8.
    #[arg(long, default_value = "C")]
    road_class: String,
    /// Vehicle speed u (m/s).
    #[arg(long, default_value_t = 20.0)]
    vehicle_speed: f64,
    /// Lower cut-off frequency f0 (Hz).
    #[arg(long, default_value_t = 0.1)]
    road_cutoff_frequency: f64,
    /// Random road seed.
    #[arg(long, default_value_t = 1)]
    road_seed: u64,
    /// Paper-compatible road: noise hold interval D (s).
    #[arg(long, default_value_t = 0.1)]
    road_sample_interval: f64,
    /// Upper bound of the internal integration step (s).
    #[arg(long, default_value_t = DEFAULT_MAX_INTERNAL_STEP)]
    max_internal_step: f64,
    /// Weight z1 of RMS(BA) in J.
    #[arg(long, default_value_t = 0.4)]
    w_ba: f64,
    /// Weight z2 of RMS(SDD) in J.
    #[arg(long, default_value_t = 0.2)]
    w_sdd: f64,
    /// Weight z3 of RMS(TDD) in J (TDD in m).
    #[arg(long, default_value_t = 0.4)]
    w_tdd: f64,
    /// Simulated duration of each run (s).
    #[arg(long, default_value_t = 15.0)]
    duration: f64,
}

impl RunArgs {
    fn road_name(&self) -> Result<RoadName> {
        RoadName::parse(&self.road)
    }

    fn road_class(&self) -> Result<RoadClass> {
        match self.road_class.trim().parse::<i64>() {
            Ok(code) => RoadClass::from_code(code),
            Err(_) => self.road_class.parse::<RoadClass>(),
        }
    }

    fn road_spec(&self) -> Result<RoadSpec> {
        let road = self.road_name()?;
        let random = RandomRoad {
            class: self.road_class()?,
            speed: self.vehicle_speed,
            cutoff_frequency: self.road_cutoff_frequency,
            seed: self.road_seed,
        };
        let spec = match road {
            RoadName::Harmonic => RoadSpec::Harmonic {
                amplitude: self.road_amplitude,
                angular_frequency: self.road_angular_frequency,
            },
            RoadName::Iso8608 => RoadSpec::Iso8608(random),
            RoadName::Paper => RoadSpec::PaperCompatible {
                road: random,
                sample_interval: self.road_sample_interval,
            },
            RoadName::File(path) => RoadSpec::from_csv_file(&path)?,
        };
        spec.validate()?;
        Ok(spec)
    }

    fn config(&self, params: Params, variant: Variant) -> Result<SimulationConfig> {
        Ok(SimulationConfig {
            params,
            variant,
            road: self.road_spec()?,
            max_internal_step: self.max_internal_step,
            start_time: 0.0,
            initial_state: State::zeros(),
            weights: Weights {
                body_acceleration: self.w_ba,
                suspension_deflection: self.w_sdd,
                tire_deflection: self.w_tdd,
            },
        })
    }

    /// A sentence saying which road a result used.
    fn road_note(&self) -> String {
        let class = self
            .road_class()
            .map_or_else(|_| self.road_class.clone(), |c| format!("{c:?}"));
        match self.road_name() {
            Ok(RoadName::Paper) => "paper-compatible band-limited road (about 10x weaker than true ISO 8608; reproduces the paper's Table 3)".into(),
            Ok(RoadName::Iso8608) => format!("ISO 8608 class {class} road at {} m/s", self.vehicle_speed),
            Ok(RoadName::Harmonic) => format!("harmonic road {} sin({} t)", self.road_amplitude, self.road_angular_frequency),
            Ok(RoadName::File(path)) => format!("road from file:{path}"),
            Err(_) => format!("road {}", self.road),
        }
    }

    /// Every road, solver and objective setting of a run, by the FMU
    /// parameter names (the road by its canonical name, the class as a
    /// letter).
    fn record(&self, value: &mut serde_json::Value) -> Result<()> {
        value["road"] = self.road_name()?.canonical().into();
        value["road_amplitude"] = self.road_amplitude.into();
        value["road_angular_frequency"] = self.road_angular_frequency.into();
        value["road_class"] = format!("{:?}", self.road_class()?).into();
        value["vehicle_speed"] = self.vehicle_speed.into();
        value["road_cutoff_frequency"] = self.road_cutoff_frequency.into();
        value["road_seed"] = self.road_seed.into();
        value["road_sample_interval"] = self.road_sample_interval.into();
        value["max_internal_step"] = self.max_internal_step.into();
        value["w_ba"] = self.w_ba.into();
        value["w_sdd"] = self.w_sdd.into();
        value["w_tdd"] = self.w_tdd.into();
        value["duration"] = self.duration.into();
        Ok(())
    }

    /// Warns (on standard error) when a run of `duration` seconds goes past
    /// the last sample of a road file, whose value is then held.
    fn warn_past_road_end(&self, spec: &RoadSpec) {
        if let Some((last_time, last_value)) = spec.last_sample()
            && self.duration > last_time
        {
            eprintln!(
                "warning: the road file ends at t = {last_time} s; from there to {} s \
                 its last value x_g = {last_value} m is held",
                self.duration
            );
        }
    }
}

#[derive(Debug, Args)]
struct SimulateArgs {
    #[command(flatten)]
    model: ModelArgs,
    #[command(flatten)]
    run: RunArgs,
    /// cs, pvass or tdvass (any case; or the codes 1, 2, 3).
    #[arg(long, default_value = "tdvass")]
    variant: String,
    /// Write the time histories to this CSV file.
    #[arg(long)]
    output: Option<String>,
    /// Time between CSV rows (s).
    #[arg(long, default_value_t = 1e-3)]
    output_interval: f64,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Args)]
struct StabilityArgs {
    #[command(flatten)]
    model: ModelArgs,
    /// Largest delay considered (s).
    #[arg(long, default_value_t = 0.5)]
    tau_max: f64,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Args)]
struct StableArgs {
    #[command(flatten)]
    model: ModelArgs,
    /// cs, pvass or tdvass (any case; or the codes 1, 2, 3).
    #[arg(long, default_value = "tdvass")]
    variant: String,
    /// How many rightmost roots to list.
    #[arg(long, default_value_t = 6)]
    roots: usize,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Args)]
struct FrfArgs {
    #[command(flatten)]
    model: ModelArgs,
    /// cs, pvass or tdvass (any case; or the codes 1, 2, 3).
    #[arg(long, default_value = "tdvass")]
    variant: String,
    /// Lowest frequency (Hz).
    #[arg(long, default_value_t = 0.1)]
    f_min: f64,
    /// Highest frequency (Hz).
    #[arg(long, default_value_t = 30.0)]
    f_max: f64,
    /// Number of log-spaced points.
    #[arg(long, default_value_t = 500)]
    points: usize,
    /// Write the curve here instead of standard output (CSV).
    #[arg(long)]
    output: Option<String>,
    /// Print one JSON object (the peaks) instead of the CSV.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Args)]
struct OptimizeArgs {
    /// absorber (k_h, c_h of PVASS in (0, k_s) x (0, c_s)) or controller
    /// (g, tau of TDVASS in [--g-min, --g-max] x [--tau-min, --tau-max]).
    /// Any case.
    target: String,
    #[command(flatten)]
    model: ModelArgs,
    #[command(flatten)]
    run: RunArgs,
    /// Swarm size.
    #[arg(long, default_value_t = 100)]
    particles: usize,
    /// Iterations.
    #[arg(long, default_value_t = 200)]
    iterations: usize,
    /// Seed of the swarm.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Controller only: lower bound of the gain g (N/m).
    #[arg(long, default_value_t = CONTROLLER_GAIN_RANGE[0])]
    g_min: f64,
    /// Controller only: upper bound of the gain g (N/m).
    #[arg(long, default_value_t = CONTROLLER_GAIN_RANGE[1])]
    g_max: f64,
    /// Controller only: lower bound of the delay tau (s, >= 0).
    #[arg(long, default_value_t = CONTROLLER_DELAY_RANGE[0])]
    tau_min: f64,
    /// Controller only: upper bound of the delay tau (s).
    #[arg(long, default_value_t = CONTROLLER_DELAY_RANGE[1])]
    tau_max: f64,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Args)]
struct MapArgs {
    #[command(flatten)]
    model: ModelArgs,
    /// Smallest gain (N/m).
    #[arg(long, default_value_t = -200000.0)]
    g_min: f64,
    /// Largest gain (N/m).
    #[arg(long, default_value_t = 200000.0)]
    g_max: f64,
    /// Gain samples.
    #[arg(long, default_value_t = 400)]
    g_points: usize,
    /// Largest delay (s).
    #[arg(long, default_value_t = 0.5)]
    tau_max: f64,
    /// Delay samples.
    #[arg(long, default_value_t = 400)]
    tau_points: usize,
    /// CSV file to write (standard output when absent).
    #[arg(long)]
    output: Option<String>,
    /// Print a JSON summary.
    #[arg(long)]
    json: bool,
}

fn parse_variant(name: &str) -> Result<Variant> {
    name.parse()
}

fn parse_target(name: &str) -> Result<Target> {
    match name.trim().to_ascii_lowercase().as_str() {
        "absorber" => Ok(Target::Absorber),
        "controller" => Ok(Target::Controller),
        _ => Err(Error::UnknownName {
            what: "optimisation target",
            given: name.to_string(),
            expected: "absorber or controller (any case)",
        }),
    }
}

fn io_error(action: &'static str, path: &str, error: &std::io::Error) -> Error {
    Error::Io {
        action,
        path: path.to_string(),
        reason: error.to_string(),
    }
}

fn write_text(path: &str, text: &str) -> Result<()> {
    std::fs::write(path, text).map_err(|e| io_error("writing", path, &e))
}

/// The command line: the derived parser, with negative numbers accepted as
/// the value of every flag (`--tau -1` reaches the model's own check).
fn command() -> clap::Command {
    Cli::command().mut_subcommands(|sub| sub.mut_args(|arg| arg.allow_negative_numbers(true)))
}

/// The flags given on the command line (argument ids such as `road_seed`).
#[derive(Debug, Default)]
struct GivenFlags(BTreeSet<String>);

impl GivenFlags {
    fn from_matches(matches: &ArgMatches) -> GivenFlags {
        GivenFlags(
            matches
                .ids()
                .filter(|id| matches.value_source(id.as_str()) == Some(ValueSource::CommandLine))
                .map(|id| id.as_str().to_string())
                .collect(),
        )
    }

    /// A warning naming those of `ids` that were given, saying `why` they do
    /// nothing; `None` when none of them was given.
    fn unused(&self, ids: &[&str], why: &str) -> Option<String> {
        let flags: Vec<String> = ids
            .iter()
            .filter(|id| self.0.contains(**id))
            .map(|id| format!("--{}", id.replace('_', "-")))
            .collect();
        match flags.len() {
            0 => None,
            1 => Some(format!("warning: {} has no effect: {why}", flags[0])),
            _ => Some(format!(
                "warning: {} have no effect: {why}",
                flags.join(", ")
            )),
        }
    }
}

const HARMONIC_ROAD_FLAGS: [&str; 2] = ["road_amplitude", "road_angular_frequency"];
const RANDOM_ROAD_FLAGS: [&str; 4] = [
    "road_class",
    "vehicle_speed",
    "road_cutoff_frequency",
    "road_seed",
];
const PAPER_ROAD_FLAGS: [&str; 1] = ["road_sample_interval"];

fn variant_warnings(variant: &str, given: &GivenFlags, warnings: &mut Vec<String>) {
    match parse_variant(variant) {
        Ok(Variant::Cs) => warnings.extend(given.unused(
            &["g", "tau", "m_h", "k_h", "c_h"],
            "CS has neither the absorber (m_h, k_h, c_h) nor the feedback (g, tau)",
        )),
        Ok(Variant::Pvass) => warnings.extend(given.unused(
            &["g", "tau"],
            "the feedback u = g x_t(t - tau) acts in TDVASS only",
        )),
        Ok(Variant::Tdvass) | Err(_) => {}
    }
}

fn road_warnings(run: &RunArgs, given: &GivenFlags, warnings: &mut Vec<String>) {
    let random_and_paper: Vec<&str> = RANDOM_ROAD_FLAGS
        .iter()
        .chain(&PAPER_ROAD_FLAGS)
        .copied()
        .collect();
    match run.road_name() {
        Ok(RoadName::Harmonic) => warnings.extend(given.unused(
            &random_and_paper,
            "they set the random roads (--road iso8608 or paper)",
        )),
        Ok(RoadName::Iso8608) => {
            warnings.extend(given.unused(&HARMONIC_ROAD_FLAGS, "harmonic road only"));
            warnings.extend(given.unused(
                &PAPER_ROAD_FLAGS,
                "paper-compatible road (--road paper) only",
            ));
        }
        Ok(RoadName::Paper) => {
            warnings.extend(given.unused(&HARMONIC_ROAD_FLAGS, "harmonic road only"));
        }
        Ok(RoadName::File(_)) => {
            let all: Vec<&str> = HARMONIC_ROAD_FLAGS
                .iter()
                .chain(&random_and_paper)
                .copied()
                .collect();
            warnings.extend(given.unused(&all, "the road comes from the file"));
        }
        Err(_) => {}
    }
}

/// Warnings about flags that the command line accepted but that do not
/// apply to this run.
fn warnings(command: &Command, given: &GivenFlags) -> Vec<String> {
    let mut warnings = Vec::new();
    match command {
        Command::Simulate(a) => {
            variant_warnings(&a.variant, given, &mut warnings);
            road_warnings(&a.run, given, &mut warnings);
            if a.output.is_none() {
                warnings.extend(given.unused(&["output_interval"], "it needs --output"));
            }
        }
        Command::Stability(_) => {
            warnings.extend(given.unused(&["tau"], "stability scans tau from 0 to --tau-max"))
        }
        Command::Stable(a) => variant_warnings(&a.variant, given, &mut warnings),
        Command::Frf(a) => variant_warnings(&a.variant, given, &mut warnings),
        Command::Optimize(a) => {
            road_warnings(&a.run, given, &mut warnings);
            match parse_target(&a.target) {
                Ok(Target::Absorber) => {
                    warnings.extend(given.unused(
                        &["g", "tau"],
                        "the absorber is optimised as PVASS, without feedback",
                    ));
                    warnings.extend(
                        given.unused(&["k_h", "c_h"], "the absorber optimisation searches them"),
                    );
                    warnings.extend(given.unused(
                        &["g_min", "g_max", "tau_min", "tau_max"],
                        "they bound the controller optimisation only",
                    ));
                }
                Ok(Target::Controller) => warnings.extend(
                    given.unused(&["g", "tau"], "the controller optimisation searches them"),
                ),
                Err(_) => {}
            }
        }
        Command::Map(_) => warnings.extend(given.unused(
            &["g", "tau"],
            "the map scans g from --g-min to --g-max and tau from 0 to --tau-max",
        )),
    }
    warnings
}

/// Runs the command line `args` (including the program name); returns what
/// to print on standard output. Warnings about flags that do not apply,
/// and the progress of long runs, go to standard error.
pub fn run<I, T>(args: I) -> std::result::Result<String, String>
where
    I: IntoIterator<Item = T>,
    T: Into<std::ffi::OsString> + Clone,
{
    let matches = match command().try_get_matches_from(args) {
        Ok(matches) => matches,
        Err(e)
            if matches!(
                e.kind(),
                clap::error::ErrorKind::DisplayHelp | clap::error::ErrorKind::DisplayVersion
            ) =>
        {
            return Ok(e.to_string());
        }
        Err(e) => return Err(e.to_string()),
    };
    let cli = Cli::from_arg_matches(&matches).map_err(|e| e.to_string())?;
    let given = matches
        .subcommand()
        .map(|(_, sub)| GivenFlags::from_matches(sub))
        .unwrap_or_default();
    for warning in warnings(&cli.command, &given) {
        eprintln!("{warning}");
    }
    execute(cli).map_err(|e| format!("error: {e}"))
}

/// Stable delay intervals in the notation used throughout: `[0, b)` for the
/// interval that starts at tau = 0, `(a, b)` for the others (the critical
/// delays themselves are not stable), `b]` when the interval reaches
/// `tau_max` (stable up to the end of the scan), joined by ` ∪ `.
pub fn format_stable_intervals(intervals: &[(f64, f64)], tau_max: f64) -> String {
    if intervals.is_empty() {
        return "none".into();
    }
    intervals
        .iter()
        .map(|&(from, to)| {
            let open = if from == 0.0 { "[0" } else { "(" };
            let from = if from == 0.0 {
                String::new()
            } else {
                format!("{from:.4}")
            };
            let close = if to >= tau_max { "]" } else { ")" };
            format!("{open}{from}, {to:.4}{close}")
        })
        .collect::<Vec<_>>()
        .join(" ∪ ")
}

fn stability_command(a: StabilityArgs) -> Result<String> {
    let report = StabilityReport::compute(&a.model.params(), a.model.g, a.tau_max)?;
    if a.json {
        return Ok(report.to_json().to_string());
    }
    let mut out = String::new();
    let _ = writeln!(out, "g = {} N/m, tau up to {} s", a.model.g, a.tau_max);
    let _ = writeln!(
        out,
        "Routh-Hurwitz (tau = 0): stable for g < {:.2} N/m",
        report.routh_hurwitz_g_max
    );
    let _ = writeln!(
        out,
        "delay-independent stability: |g| <= {:.2} N/m",
        report.delay_independent_g_max
    );
    for c in &report.crossings {
        let delays = if c.critical_delays.is_empty() {
            format!("none up to {} s", a.tau_max)
        } else {
            c.critical_delays
                .iter()
                .map(|d| format!("{d:.4}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let _ = writeln!(
            out,
            "crossing omega = {:.4} rad/s, direction {:+} ({}), critical delays (s): {delays}",
            c.crossing.omega,
            c.crossing.direction,
            match c.crossing.direction {
                1 => "destabilising",
                -1 => "stabilising",
                _ => "tangent",
            },
        );
    }
    let _ = writeln!(
        out,
        "stable delays (s): {}",
        format_stable_intervals(&report.stable_intervals, a.tau_max)
    );
    Ok(out)
}

fn execute(cli: Cli) -> Result<String> {
    match cli.command {
        Command::Simulate(a) => simulate_command(a),
        Command::Stability(a) => stability_command(a),
        Command::Stable(a) => {
            let report =
                StableReport::compute(&a.model.params(), parse_variant(&a.variant)?, a.roots)?;
            if a.json {
                return Ok(report.to_json().to_string());
            }
            let mut out = format!(
                "g = {} N/m, tau = {} s: {} (spectral abscissa {:.6} 1/s)\nrightmost roots:\n",
                a.model.g,
                a.model.tau,
                if report.stable { "stable" } else { "UNSTABLE" },
                report.spectral_abscissa
            );
            for r in &report.rightmost_roots {
                let _ = writeln!(out, "  {:+.6} {:+.6} i", r.re, r.im);
            }
            Ok(out)
        }
        Command::Frf(a) => {
            let variant = parse_variant(&a.variant)?;
            let curve = frequency_response(&a.model.params(), variant, a.f_min, a.f_max, a.points)?;
            let mut csv =
                String::from("frequency_hz,body_displacement_gain,body_acceleration_gain\n");
            for p in &curve {
                let _ = writeln!(
                    csv,
                    "{},{},{}",
                    p.frequency_hz, p.body_displacement, p.body_acceleration
                );
            }
            if let Some(path) = &a.output {
                write_text(path, &csv)?;
            }
            if a.json {
                let peaks = peaks_hz(&a.model.params(), variant, &curve)?;
                return Ok(json!({
                    "variant": variant.name(),
                    "peaks_hz": peaks.to_json(),
                })
                .to_string());
            }
            Ok(if a.output.is_some() {
                String::new()
            } else {
                csv
            })
        }
        Command::Optimize(a) => optimize_command(a),
        Command::Map(a) => map_command(a),
    }
}

fn map_command(a: MapArgs) -> Result<String> {
    let params = a.model.params();
    let grid = |lo: f64, hi: f64, n: usize| -> Vec<f64> {
        (0..n)
            .map(|i| {
                if n == 1 {
                    lo
                } else {
                    lo + (hi - lo) * i as f64 / (n - 1) as f64
                }
            })
            .collect()
    };
    let gains = grid(a.g_min, a.g_max, a.g_points.max(1));
    let delays = grid(0.0, a.tau_max, a.tau_points.max(1));
    let points = stability_map(&params, &gains, &delays)?;
    let mut csv = String::from("g,tau,stable,spectral_abscissa\n");
    for p in &points {
        let _ = writeln!(
            csv,
            "{},{},{},{}",
            p.g,
            p.tau,
            u8::from(p.stable),
            p.spectral_abscissa
        );
    }
    if let Some(path) = &a.output {
        write_text(path, &csv)?;
    }
    if a.json {
        let stable = points.iter().filter(|p| p.stable).count();
        return Ok(json!({
            "points": points.len(),
            "stable_points": stable,
            "output": a.output,
            "g_min": a.g_min,
            "g_max": a.g_max,
            "g_points": gains.len(),
            "tau_max": a.tau_max,
            "tau_points": delays.len(),
        })
        .to_string());
    }
    Ok(if a.output.is_some() {
        format!(
            "wrote {} points to {}\n",
            points.len(),
            a.output.unwrap_or_default()
        )
    } else {
        csv
    })
}

/// Reports a long simulation's progress on standard error: nothing during
/// the first [`PROGRESS_AFTER`] of wall time, then a progress bar on a
/// terminal, or otherwise one line every [`PROGRESS_LINE_INTERVAL`].
struct SimulationProgress {
    /// Simulated time of the whole run (s).
    duration: f64,
    started: Instant,
    terminal: bool,
    bar: Option<indicatif::ProgressBar>,
    last_line: Option<Instant>,
}

impl SimulationProgress {
    fn new(duration: f64) -> SimulationProgress {
        SimulationProgress {
            duration,
            started: Instant::now(),
            terminal: std::io::stderr().is_terminal(),
            bar: None,
            last_line: None,
        }
    }

    /// The run has reached simulated time `time` (s).
    fn update(&mut self, time: f64) {
        let elapsed = self.started.elapsed();
        if elapsed < PROGRESS_AFTER {
            return;
        }
        let fraction = if self.duration > 0.0 {
            (time / self.duration).clamp(0.0, 1.0)
        } else {
            1.0
        };
        if self.terminal {
            let bar = self.bar.get_or_insert_with(|| {
                let bar = indicatif::ProgressBar::new(1000);
                bar.set_style(
                    indicatif::ProgressStyle::with_template(
                        "{bar:40} {percent:>3} % simulated, {msg} [{elapsed_precise}, ETA {eta}]",
                    )
                    .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
                );
                bar
            });
            bar.set_position((fraction * 1000.0) as u64);
            bar.set_message(format!("t = {time:.1} of {} s", self.duration));
        } else if self
            .last_line
            .is_none_or(|last| last.elapsed() >= PROGRESS_LINE_INTERVAL)
        {
            eprintln!(
                "simulate: t = {time:.1} of {} s ({:.0} %), {:.0} s elapsed",
                self.duration,
                100.0 * fraction,
                elapsed.as_secs_f64()
            );
            self.last_line = Some(Instant::now());
        }
    }

    fn finish(self) {
        if let Some(bar) = self.bar {
            bar.finish_and_clear();
        }
    }
}

fn simulate_command(a: SimulateArgs) -> Result<String> {
    let variant = parse_variant(&a.variant)?;
    let params = a.model.params();
    let duration = a.run.duration;
    if !(duration.is_finite() && duration >= 0.0) {
        return Err(Error::InvalidParameter {
            name: "duration",
            value: duration,
            reason: "must be finite and >= 0",
        });
    }
    let config = a.run.config(params, variant)?;
    let road = config.road.clone();
    let mut sim = Simulator::new(config)?;
    if duration / a.run.max_internal_step > MAX_SIMULATE_STEPS {
        return Err(Error::InvalidParameter {
            name: "duration",
            value: duration,
            reason: "the run would need more than the limit of 1e10 internal steps \
                     (duration / max_internal_step; 1e6 s at the default 1e-4 s step, \
                     minutes of wall time): shorten it or raise --max-internal-step",
        });
    }
    a.run.warn_past_road_end(&road);
    let mut progress = SimulationProgress::new(duration);
    if let Some(path) = &a.output {
        if !(a.output_interval.is_finite() && a.output_interval > 0.0) {
            return Err(Error::InvalidParameter {
                name: "output_interval",
                value: a.output_interval,
                reason: "must be finite and > 0",
            });
        }
        let file = std::fs::File::create(path).map_err(|e| io_error("creating", path, &e))?;
        let mut csv = std::io::BufWriter::new(file);
        let write_error = |e: std::io::Error| io_error("writing", path, &e);
        writeln!(
            csv,
            "time,x_s,v_s,x_h,v_h,x_t,v_t,body_acceleration,suspension_deflection,tire_deflection,road_displacement,control_force"
        )
        .map_err(write_error)?;
        let rows = (duration / a.output_interval).floor() as u64;
        for i in 0..=rows {
            sim.advance_to((i as f64 * a.output_interval).min(duration))?;
            let o = sim.outputs();
            let s = o.state;
            writeln!(
                csv,
                "{},{},{},{},{},{},{},{},{},{},{},{}",
                o.time,
                s[0],
                s[1],
                s[2],
                s[3],
                s[4],
                s[5],
                o.performance.body_acceleration,
                o.performance.suspension_deflection,
                o.performance.tire_deflection,
                o.road_displacement,
                o.control_force
            )
            .map_err(write_error)?;
            progress.update(o.time);
        }
        csv.flush().map_err(write_error)?;
    }
    let mut time = sim.time();
    while time < duration {
        time = (time + PROGRESS_CHUNK).min(duration);
        sim.advance_to(time)?;
        progress.update(time);
    }
    sim.advance_to(duration)?;
    progress.finish();
    let o = sim.outputs();
    if a.json {
        let mut value = json!({
            "variant": variant.name(),
            "road_note": a.run.road_note(),
            "rms_body_acceleration": o.rms.body_acceleration,
            "rms_suspension_deflection": o.rms.suspension_deflection,
            "rms_tire_deflection": o.rms.tire_deflection,
            "objective": o.objective,
        });
        for (name, parameter) in params.named_values() {
            value[name] = parameter.into();
        }
        a.run.record(&mut value)?;
        return Ok(value.to_string());
    }
    Ok(format!(
        "{} on the {}, {} s from rest\n  RMS body acceleration      {:.4} m/s^2\n  RMS suspension deflection  {:.4} m\n  RMS tire deflection        {:.4} mm\n  objective J                {:.6}\n",
        variant.label(),
        a.run.road_note(),
        duration,
        o.rms.body_acceleration,
        o.rms.suspension_deflection,
        o.rms.tire_deflection * 1e3,
        o.objective
    ))
}

/// The controller's search box from `--g-min/--g-max/--tau-min/--tau-max`;
/// an error names the flag at fault.
fn controller_bounds(a: &OptimizeArgs) -> Result<Bounds> {
    for (flag, value) in [
        ("--g-min", a.g_min),
        ("--g-max", a.g_max),
        ("--tau-min", a.tau_min),
        ("--tau-max", a.tau_max),
    ] {
        if !value.is_finite() {
            return Err(Error::InvalidParameter {
                name: flag,
                value,
                reason: "must be finite",
            });
        }
    }
    if a.tau_min < 0.0 {
        return Err(Error::InvalidParameter {
            name: "--tau-min",
            value: a.tau_min,
            reason: "a delay must be >= 0",
        });
    }
    if a.g_max <= a.g_min {
        return Err(Error::InvalidParameter {
            name: "--g-max",
            value: a.g_max,
            reason: "must be greater than --g-min",
        });
    }
    if a.tau_max <= a.tau_min {
        return Err(Error::InvalidParameter {
            name: "--tau-max",
            value: a.tau_max,
            reason: "must be greater than --tau-min",
        });
    }
    Ok(Bounds {
        lower: vec![a.g_min, a.tau_min],
        upper: vec![a.g_max, a.tau_max],
    })
}

fn optimize_command(a: OptimizeArgs) -> Result<String> {
    let target = parse_target(&a.target)?;
    let base = a.run.config(a.model.params(), target.variant())?;
    a.run.warn_past_road_end(&base.road);
    let mut problem = Problem::new(target, base, a.run.duration);
    if target == Target::Controller {
        problem.bounds = controller_bounds(&a)?;
    }
    let settings = PsoSettings {
        particles: a.particles,
        iterations: a.iterations,
        seed: a.seed,
        ..PsoSettings::default()
    };
    let bar = indicatif::ProgressBar::new(a.iterations as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{bar:40} {pos}/{len} iterations, best J {msg} [{elapsed_precise}]",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let progress = |iteration: usize, best: f64| {
        bar.set_position(iteration as u64);
        bar.set_message(format!("{best:.6}"));
    };
    let report = optimize(&problem, &settings, Some(&progress))?;
    bar.finish_and_clear();
    let mut value = report.to_json();
    value["road_note"] = a.run.road_note().into();
    if a.json {
        return Ok(value.to_string());
    }
    let names = target.parameter_names();
    let mut out = format!(
        "{} optimisation on the {}\n",
        match target {
            Target::Absorber => "absorber",
            Target::Controller => "controller",
        },
        a.run.road_note()
    );
    let _ = writeln!(
        out,
        "  best: {} = {:.6}, {} = {:.6}, J = {:.6} ({} evaluations)",
        names[0],
        report.swarm.best_position[0],
        names[1],
        report.swarm.best_position[1],
        report.swarm.best_value,
        report.swarm.evaluations
    );
    for p in &report.paper {
        let j = p
            .objective
            .map_or("unstable or invalid".to_string(), |j| format!("{j:.6}"));
        let _ = writeln!(
            out,
            "  {}: {} = {}, {} = {}, J = {j}",
            p.label, names[0], p.position[0], names[1], p.position[1]
        );
    }
    Ok(out)
}

/// Entry point of the `tdvass` binary.
pub fn main_entry() -> std::process::ExitCode {
    match run(std::env::args_os()) {
        Ok(text) => {
            let mut stdout = std::io::stdout().lock();
            let _ = stdout.write_all(text.as_bytes());
            if !text.is_empty() && !text.ends_with('\n') {
                let _ = stdout.write_all(b"\n");
            }
            std::process::ExitCode::SUCCESS
        }
        Err(message) => {
            eprint!("{message}");
            if !message.ends_with('\n') {
                eprintln!();
            }
            std::process::ExitCode::from(2)
        }
    }
}
