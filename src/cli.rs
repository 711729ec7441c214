//! The `tdvass` command line: `simulate`, `stability`, `stable`, `frf`,
//! `optimize`, `map` and `car` (names and JSON keys fixed by the interface spec).
//! Every subcommand prints a table, or one JSON object with `--json`.

use crate::json::ToJson;
use clap::FromArgMatches;
use serde_json::json;
use std::fmt::Write as _;
use std::io::{IsTerminal as _, Write as _};
use std::time::{Duration, Instant};
use tdvass::analysis::frf::{frequency_response, peaks_hz};
use tdvass::analysis::optimize::{Objective, Problem, TIRE_LOAD_RATIO_LIMIT, Target, optimize};
use tdvass::analysis::pso::{Bounds, PsoSettings};
use tdvass::analysis::spectrum::StableReport;
use tdvass::analysis::stability::{StabilityReport, stability_map};
use tdvass::error::{Error, Result};
use tdvass::solver::{ComfortValues, Metrics, Outputs, RoadHolding, SimulationConfig, Simulator};

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

mod args;
mod car;
mod deferred;
mod warnings;

use args::*;
use warnings::*;

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
        Command::Simulate(a) => simulate_command(a.0),
        Command::Stability(a) => stability_command(a.0),
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
        Command::Optimize(a) => optimize_command(a.0),
        Command::Map(a) => map_command(a.0),
        Command::Car(a) => car::car_command(*a.0),
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

/// The comfort and road-holding outputs of a run at the
/// [`Metrics::Comfort`] level.
fn metric_outputs(o: &Outputs) -> (ComfortValues, RoadHolding) {
    (
        o.comfort.expect("simulate runs at the comfort level"),
        o.road_holding.expect("simulate runs at the comfort level"),
    )
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
    let config = SimulationConfig {
        // Every metric: ISO 2631-1 comfort, road holding, working space.
        metrics: Metrics::Comfort,
        ..a.run.config(params, variant)?
    };
    let road = config.road.clone();
    let mut sim = Simulator::new(config)?;
    if duration / sim.grid().step > MAX_SIMULATE_STEPS {
        return Err(Error::InvalidParameter {
            name: "duration",
            value: duration,
            reason: "the run would need more than the limit of 1e10 internal steps \
                     (duration / internal step; minutes of wall time or more): shorten \
                     it, loosen --tolerance or raise --max-internal-step",
        });
    }
    a.run.warn_past_road_end(&road);
    let mut progress = SimulationProgress::new(duration);
    if let Some(path) = &a.output {
        write_history(&mut sim, path, a.output_interval, duration, &mut progress)?;
    }
    let mut time = sim.time();
    while time < duration {
        time = (time + PROGRESS_CHUNK).min(duration);
        sim.advance_to(time)?;
        progress.update(time);
    }
    sim.advance_to(duration)?;
    progress.finish();
    let (_, holding) = metric_outputs(&sim.outputs());
    let unilateral = sim.config().tire_contact.is_unilateral();
    // The unilateral tire models the lift-offs (counted in the results);
    // the bilateral one leaves its model there.
    if let Some(loss) = holding.first_contact_loss.filter(|_| !unilateral) {
        eprintln!(
            "warning: the tire leaves the road at t = {} s (dynamic tire load {} N below minus the static load {} N): the linear model no longer holds from there; contact_loss_time = {} s",
            loss.time, loss.dynamic_tire_load, loss.static_load, holding.contact_loss_time
        );
    }
    simulate_report(&a, &mut sim, variant, &params, duration)
}

/// Writes the time histories of `simulate --output` to `path`, a row every
/// `interval` s up to `duration`, advancing `sim` there.
fn write_history(
    sim: &mut Simulator,
    path: &str,
    interval: f64,
    duration: f64,
    progress: &mut SimulationProgress,
) -> Result<()> {
    if !(interval.is_finite() && interval > 0.0) {
        return Err(Error::InvalidParameter {
            name: "output_interval",
            value: interval,
            reason: "must be finite and > 0",
        });
    }
    let file = std::fs::File::create(path).map_err(|e| io_error("creating", path, &e))?;
    let mut csv = std::io::BufWriter::new(file);
    let write_error = |e: std::io::Error| io_error("writing", path, &e);
    writeln!(
        csv,
        "time,x_s,v_s,x_h,v_h,x_t,v_t,body_acceleration,suspension_deflection,tire_deflection,road_displacement,control_force,weighted_body_acceleration,dynamic_tire_load,contact_loss_time,max_suspension_deflection,lift_off_count"
    )
    .map_err(write_error)?;
    let rows = (duration / interval).floor() as u64;
    for i in 0..=rows {
        sim.advance_to((i as f64 * interval).min(duration))?;
        let o = sim.outputs();
        let (comfort, holding) = metric_outputs(&o);
        // The state, BA, SDD, TDD, x_g and u: the first columns of the core values.
        let core = &o.core_values()[..11];
        let reals = std::iter::once(o.time).chain(core.iter().copied()).chain([
            comfort.weighted_body_acceleration,
            o.dynamic_tire_load,
            holding.contact_loss_time,
            holding.max_suspension_deflection,
        ]);
        for value in reals {
            write!(csv, "{value},").map_err(write_error)?;
        }
        writeln!(csv, "{}", holding.lift_off_count).map_err(write_error)?;
        progress.update(o.time);
    }
    csv.flush().map_err(write_error)?;
    Ok(())
}

/// The answer of `simulate` at the end of the run: JSON, or a short text.
fn simulate_report(
    a: &SimulateArgs,
    sim: &mut Simulator,
    variant: tdvass::Variant,
    params: &tdvass::Params,
    duration: f64,
) -> Result<String> {
    let o = sim.outputs();
    let (comfort, holding) = metric_outputs(&o);
    let reaction = tdvass::comfort::comfort_reaction(comfort.rms_weighted_body_acceleration)?;
    if a.json {
        let mut value = json!({
            "variant": variant.name(),
            "road_note": a.run.road_note(),
            "rms_body_acceleration": o.rms.body_acceleration,
            "rms_suspension_deflection": o.rms.suspension_deflection,
            "rms_tire_deflection": o.rms.tire_deflection,
            "objective": o.objective,
            "weighted_body_acceleration": comfort.weighted_body_acceleration,
            "rms_weighted_body_acceleration": comfort.rms_weighted_body_acceleration,
            "comfort_reaction": reaction,
            "vibration_dose_value": comfort.vibration_dose_value,
            "dynamic_tire_load": o.dynamic_tire_load,
            "rms_dynamic_tire_load_ratio": o.rms_dynamic_tire_load_ratio,
            "contact_loss_time": holding.contact_loss_time,
            "max_suspension_deflection": holding.max_suspension_deflection,
            "lift_off_count": holding.lift_off_count,
        });
        for (name, parameter) in params.named_values() {
            value[name] = parameter.into();
        }
        a.run.record(&mut value)?;
        value["internal_step"] = sim.grid().step.into();
        return Ok(value.to_string());
    }
    Ok(format!(
        "{} on the {}, {} tire, {} s from rest\n  RMS body acceleration      {:.4} m/s^2\n  RMS suspension deflection  {:.4} m\n  RMS tire deflection        {:.4} mm\n  objective J                {:.6}\n  ISO 2631-1 a_w             {:.4} m/s^2 ({reaction})\n  vibration dose value       {:.4} m/s^1.75\n  RMS tire load / static     {:.4}\n  time without tire contact  {:.4} s\n  lift-offs                  {}\n  max suspension deflection  {:.4} mm\n",
        variant.label(),
        a.run.road_note(),
        sim.config().tire_contact.name(),
        duration,
        o.rms.body_acceleration,
        o.rms.suspension_deflection,
        o.rms.tire_deflection * 1e3,
        o.objective,
        comfort.rms_weighted_body_acceleration,
        comfort.vibration_dose_value,
        o.rms_dynamic_tire_load_ratio,
        holding.contact_loss_time,
        holding.lift_off_count,
        holding.max_suspension_deflection * 1e3
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
    problem.objective = parse_objective(&a)?;
    if target == Target::Controller {
        problem.bounds = controller_bounds(&a)?;
    }
    let settings = PsoSettings {
        particles: a.particles,
        iterations: a.iterations,
        seed: a.seed,
        ..PsoSettings::default()
    };
    let bar = iteration_bar(a.iterations, problem.objective);
    let progress = |iteration: usize, best: f64| {
        bar.set_position(iteration as u64);
        bar.set_message(format!("{best:.6}"));
    };
    let report = optimize(&problem, &settings, Some(&progress))?;
    bar.finish_and_clear();
    let mut value = report.to_json();
    value["road_note"] = a.run.road_note().into();
    value["objective_function"] = problem.objective.name().into();
    value["tire_contact"] = problem.base.tire_contact.name().into();
    let evaluation = problem.comfort_evaluation(&report.swarm.best_position);
    if let (
        Objective::Comfort {
            travel_limit,
            static_deflection_limit,
        },
        Some(e),
    ) = (problem.objective, evaluation)
    {
        value["limits"] = json!({
            "rms_dynamic_tire_load_ratio": TIRE_LOAD_RATIO_LIMIT,
            "max_suspension_deflection": travel_limit,
            "static_deflection": static_deflection_limit,
        });
        value["best_evaluation"] = json!({
            "rms_weighted_body_acceleration": e.rms_weighted_body_acceleration,
            "rms_dynamic_tire_load_ratio": e.rms_dynamic_tire_load_ratio,
            "max_suspension_deflection": e.max_suspension_deflection,
            "static_deflection": e.static_deflection,
            "feasible": e.feasible,
        });
    }
    if a.json {
        return Ok(value.to_string());
    }
    Ok(optimize_text(
        target,
        &a.run.road_note(),
        &problem,
        &report,
        evaluation,
    ))
}

/// The progress bar of an optimisation: iterations, and the best J or
/// score so far.
fn iteration_bar(iterations: usize, objective: Objective) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(iterations as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(match objective {
            Objective::Paper => "{bar:40} {pos}/{len} iterations, best J {msg} [{elapsed_precise}]",
            Objective::Comfort { .. } => {
                "{bar:40} {pos}/{len} iterations, best score {msg} [{elapsed_precise}]"
            }
        })
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar
}

/// The text answer of `optimize`: the best point, the comfort objective's
/// evaluation of it, and the paper's points.
fn optimize_text(
    target: Target,
    road_note: &str,
    problem: &Problem,
    report: &tdvass::analysis::optimize::Report,
    evaluation: Option<tdvass::analysis::optimize::ComfortEvaluation>,
) -> String {
    let names = target.parameter_names();
    let mut out = format!(
        "{} optimisation on the {}, {} tire\n",
        match target {
            Target::Absorber => "absorber",
            Target::Controller => "controller",
        },
        road_note,
        problem.base.tire_contact.name()
    );
    let score = match problem.objective {
        Objective::Paper => "J",
        Objective::Comfort { .. } => "score",
    };
    let _ = writeln!(
        out,
        "  best: {} = {:.6}, {} = {:.6}, {score} = {:.6} ({} evaluations)",
        names[0],
        report.swarm.best_position[0],
        names[1],
        report.swarm.best_position[1],
        report.swarm.best_value,
        report.swarm.evaluations
    );
    if let (Objective::Comfort { .. }, Some(e)) = (problem.objective, evaluation) {
        let _ = writeln!(
            out,
            "  comfort objective: a_w = {:.4} m/s^2, RMS tire load / static = {:.4} (<= 1/3), max |SDD| = {:.4} m, static deflection = {:.4} m; {}",
            e.rms_weighted_body_acceleration,
            e.rms_dynamic_tire_load_ratio,
            e.max_suspension_deflection,
            e.static_deflection,
            if e.feasible {
                "every constraint holds"
            } else {
                "a constraint is violated (the least violating candidate found)"
            }
        );
    }
    for p in &report.paper {
        let j = p
            .objective
            .map_or("unstable or invalid".to_string(), |j| format!("{j:.6}"));
        let _ = writeln!(
            out,
            "  {}: {} = {}, {} = {}, {score} = {j}",
            p.label, names[0], p.position[0], names[1], p.position[1]
        );
    }
    out
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
