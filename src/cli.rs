//! The `tdvass` command line: `simulate`, `stability`, `stable`, `frf`,
//! `optimize` and `map` (names and JSON keys fixed by the interface spec).
//! Every subcommand prints a table, or one JSON object with `--json`.

use crate::analysis::frf::{frequency_response, peaks_hz};
use crate::analysis::optimize::{Problem, Target, optimize};
use crate::analysis::pso::{Bounds, PsoSettings};
use crate::analysis::spectrum::StableReport;
use crate::analysis::stability::{StabilityReport, stability_map};
use crate::error::{Error, Result};
use crate::metrics::Weights;
use crate::model::{Params, State, Variant};
use crate::road::{RandomRoad, RoadClass, RoadSpec};
use crate::solver::{DEFAULT_MAX_INTERNAL_STEP, SimulationConfig, Simulator};
use clap::{Args, Parser, Subcommand};
use serde_json::json;
use std::fmt::Write as _;
use std::io::Write as _;

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
    #[arg(long, default_value_t = 5386.0, allow_negative_numbers = true)]
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

/// Road, solver and objective settings shared by `simulate` and `optimize`.
#[derive(Debug, Clone, Args)]
struct RunArgs {
    /// harmonic, iso8608, paper (the paper-compatible random road) or file:PATH (CSV t,x_g).
    #[arg(long, default_value = "harmonic")]
    road: String,
    /// Harmonic amplitude (m).
    #[arg(long, default_value_t = 0.05)]
    road_amplitude: f64,
    /// Harmonic angular frequency (rad/s).
    #[arg(long, default_value_t = 5.0)]
    road_angular_frequency: f64,
    /// ISO 8608 class, A..H or 1..8.
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
    fn road_spec(&self) -> Result<RoadSpec> {
        let class = match self.road_class.parse::<i64>() {
            Ok(code) => RoadClass::from_code(code)?,
            Err(_) => self.road_class.parse::<RoadClass>()?,
        };
        let random = RandomRoad {
            class,
            speed: self.vehicle_speed,
            cutoff_frequency: self.road_cutoff_frequency,
            seed: self.road_seed,
        };
        let spec = match self.road.as_str() {
            "harmonic" => RoadSpec::Harmonic {
                amplitude: self.road_amplitude,
                angular_frequency: self.road_angular_frequency,
            },
            "iso8608" | "iso" => RoadSpec::Iso8608(random),
            "paper" => RoadSpec::PaperCompatible {
                road: random,
                sample_interval: self.road_sample_interval,
            },
            other => match other.strip_prefix("file:") {
                Some(path) => RoadSpec::from_csv_file(path)?,
                None => {
                    return Err(Error::InvalidSetting {
                        name: "road",
                        value: -1,
                        reason: "must be harmonic, iso8608, paper or file:PATH",
                    });
                }
            },
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
        match self.road.as_str() {
            "paper" => "paper-compatible band-limited road (about 10x weaker than true ISO 8608; reproduces the paper's Table 3)".into(),
            "iso8608" | "iso" => format!("ISO 8608 class {} road at {} m/s", self.road_class, self.vehicle_speed),
            "harmonic" => format!("harmonic road {} sin({} t)", self.road_amplitude, self.road_angular_frequency),
            other => format!("road from {other}"),
        }
    }
}

#[derive(Debug, Args)]
struct SimulateArgs {
    #[command(flatten)]
    model: ModelArgs,
    #[command(flatten)]
    run: RunArgs,
    /// cs, pvass or tdvass.
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
    /// cs, pvass or tdvass.
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
    /// cs, pvass or tdvass.
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
    /// absorber (k_h, c_h of PVASS) or controller (g, tau of TDVASS).
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
    /// Controller bounds (N/m, s); absorber bounds are (0, k_s) x (0, c_s).
    #[arg(long, allow_negative_numbers = true)]
    g_min: Option<f64>,
    #[arg(long, allow_negative_numbers = true)]
    g_max: Option<f64>,
    #[arg(long)]
    tau_min: Option<f64>,
    #[arg(long)]
    tau_max: Option<f64>,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Args)]
struct MapArgs {
    #[command(flatten)]
    model: ModelArgs,
    /// Smallest gain (N/m).
    #[arg(long, default_value_t = -200000.0, allow_negative_numbers = true)]
    g_min: f64,
    /// Largest gain (N/m).
    #[arg(long, default_value_t = 200000.0, allow_negative_numbers = true)]
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

fn write_text(path: &str, text: &str) -> Result<()> {
    std::fs::write(path, text).map_err(|e| Error::Numerical {
        what: "writing output",
        reason: format!("{path}: {e}"),
    })
}

/// Runs the command line `args` (including the program name); returns what
/// to print on standard output.
pub fn run<I, T>(args: I) -> std::result::Result<String, String>
where
    I: IntoIterator<Item = T>,
    T: Into<std::ffi::OsString> + Clone,
{
    let cli = match Cli::try_parse_from(args) {
        Ok(cli) => cli,
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
    execute(cli).map_err(|e| format!("error: {e}"))
}

fn execute(cli: Cli) -> Result<String> {
    match cli.command {
        Command::Simulate(a) => simulate_command(a),
        Command::Stability(a) => {
            let report = StabilityReport::compute(&a.model.params(), a.model.g, a.tau_max)?;
            if a.json {
                return Ok(report.to_json().to_string());
            }
            let value = report.to_json();
            let mut out = String::new();
            let _ = writeln!(out, "g = {} N/m, tau up to {} s", a.model.g, a.tau_max);
            let _ = writeln!(
                out,
                "Routh-Hurwitz (tau = 0): stable for g < {:.2} N/m",
                value["routh_hurwitz_g_max"].as_f64().unwrap_or(f64::NAN)
            );
            let _ = writeln!(
                out,
                "delay-independent stability: |g| <= {:.2} N/m",
                value["delay_independent_g_max"]
                    .as_f64()
                    .unwrap_or(f64::NAN)
            );
            for c in value["crossings"].as_array().into_iter().flatten() {
                let delays: Vec<String> = c["critical_delays"]
                    .as_array()
                    .into_iter()
                    .flatten()
                    .filter_map(|d| d.as_f64())
                    .map(|d| format!("{d:.4}"))
                    .collect();
                let _ = writeln!(
                    out,
                    "crossing omega = {:.4} rad/s, direction {:+} ({}), critical delays: {}",
                    c["omega"].as_f64().unwrap_or(f64::NAN),
                    c["direction"].as_i64().unwrap_or(0),
                    if c["direction"].as_i64() == Some(1) {
                        "destabilising"
                    } else {
                        "stabilising"
                    },
                    delays.join(", ")
                );
            }
            let intervals: Vec<String> = value["stable_intervals"]
                .as_array()
                .into_iter()
                .flatten()
                .map(|i| {
                    format!(
                        "[{:.4}, {:.4})",
                        i[0].as_f64().unwrap_or(f64::NAN),
                        i[1].as_f64().unwrap_or(f64::NAN)
                    )
                })
                .collect();
            let _ = writeln!(
                out,
                "stable delays: {}",
                if intervals.is_empty() {
                    "none".into()
                } else {
                    intervals.join(" U ")
                }
            );
            Ok(out)
        }
        Command::Stable(a) => {
            let report =
                StableReport::compute(&a.model.params(), parse_variant(&a.variant)?, a.roots)?;
            if a.json {
                return Ok(report.to_json().to_string());
            }
            let value = report.to_json();
            let mut out = format!(
                "g = {} N/m, tau = {} s: {} (spectral abscissa {:.6} 1/s)\nrightmost roots:\n",
                a.model.g,
                a.model.tau,
                if value["stable"].as_bool() == Some(true) {
                    "stable"
                } else {
                    "UNSTABLE"
                },
                value["spectral_abscissa"].as_f64().unwrap_or(f64::NAN)
            );
            for r in value["rightmost_roots"].as_array().into_iter().flatten() {
                let _ = writeln!(
                    out,
                    "  {:+.6} {:+.6} i",
                    r[0].as_f64().unwrap_or(f64::NAN),
                    r[1].as_f64().unwrap_or(f64::NAN)
                );
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
        Command::Map(a) => {
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
                return Ok(
                    json!({"points": points.len(), "stable_points": stable, "output": a.output})
                        .to_string(),
                );
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
    }
}

fn simulate_command(a: SimulateArgs) -> Result<String> {
    let variant = parse_variant(&a.variant)?;
    let config = a.run.config(a.model.params(), variant)?;
    let mut sim = Simulator::new(config)?;
    let duration = a.run.duration;
    if !(duration.is_finite() && duration >= 0.0) {
        return Err(Error::InvalidParameter {
            name: "duration",
            value: duration,
            reason: "must be finite and >= 0",
        });
    }
    if let Some(path) = &a.output {
        if !(a.output_interval.is_finite() && a.output_interval > 0.0) {
            return Err(Error::InvalidParameter {
                name: "output_interval",
                value: a.output_interval,
                reason: "must be finite and > 0",
            });
        }
        let mut csv = String::from(
            "time,x_s,v_s,x_h,v_h,x_t,v_t,body_acceleration,suspension_deflection,tire_deflection,road_displacement,control_force\n",
        );
        let rows = (duration / a.output_interval).floor() as u64;
        for i in 0..=rows {
            sim.advance_to((i as f64 * a.output_interval).min(duration))?;
            let o = sim.outputs();
            let s = o.state;
            let _ = writeln!(
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
            );
        }
        write_text(path, &csv)?;
    }
    sim.advance_to(duration)?;
    let o = sim.outputs();
    if a.json {
        return Ok(json!({
            "variant": variant.name(),
            "road": a.run.road,
            "road_note": a.run.road_note(),
            "duration": duration,
            "rms_body_acceleration": o.rms.body_acceleration,
            "rms_suspension_deflection": o.rms.suspension_deflection,
            "rms_tire_deflection": o.rms.tire_deflection,
            "objective": o.objective,
        })
        .to_string());
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

fn optimize_command(a: OptimizeArgs) -> Result<String> {
    let target = match a.target.as_str() {
        "absorber" => Target::Absorber,
        "controller" => Target::Controller,
        _ => {
            return Err(Error::InvalidSetting {
                name: "target",
                value: -1,
                reason: "must be absorber or controller",
            });
        }
    };
    let base = a.run.config(a.model.params(), target.variant())?;
    let mut problem = Problem::new(target, base, a.run.duration);
    if target == Target::Controller {
        let d = problem.bounds.clone();
        problem.bounds = Bounds {
            lower: vec![
                a.g_min.unwrap_or(d.lower[0]),
                a.tau_min.unwrap_or(d.lower[1]),
            ],
            upper: vec![
                a.g_max.unwrap_or(d.upper[0]),
                a.tau_max.unwrap_or(d.upper[1]),
            ],
        };
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
    let mut out = format!("{} optimisation on the {}\n", a.target, a.run.road_note());
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
