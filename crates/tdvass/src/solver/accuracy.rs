//! The internal step from the tolerance: an error model gives a first step,
//! a step-doubling probe checks it and refines it where it is not enough.
//!
//! **What is not exact.** The step map of Eq. (23) is exact for the plant
//! and for every road piece (a sine, or a straight line between
//! breakpoints), so only three things depend on the internal step h:
//! 1. the delayed input `u = g x_t(t − tau)`: the cubic Hermite interpolant
//!    of `x_t` between history nodes is off by at most
//!    `h⁴/384 max|x_t⁗|`; the force error `g h⁴/384 |x_t⁗|` moves the
//!    outputs in proportion to it;
//! 2. the time averages: the corrected trapezoid of `y²` (see
//!    `time_average`) is off by `h⁴/720 [f‴]` per run of nodes, and a road
//!    breakpoint ends a run;
//! 3. the located extrema and crossings (max |SDD|, the contact-loss
//!    time): the cubic Hermite interpolant of SDD and of the contact margin
//!    over a step is off by `h⁴/384 max|y⁗|`.
//!
//! The road itself is represented exactly. Each term is fourth order in h,
//! with a fourth derivative of a response that moves at the model's own
//! time scales, so the relative error of every metric behaves as
//! `ε(h) ≈ C (ω h)⁴`:
//! - ω is the fastest oscillation of the plant ([`fastest_oscillation`]:
//!   the largest |λ| among the complex eigenvalues of A with the feedback
//!   folded in; about 70 rad/s, the wheel hop, for Table 1), or the
//!   harmonic road's ω when larger. The overdamped real modes (the
//!   absorber's, near −450 1/s) are left out: they decay within a few
//!   milliseconds and are barely excited, and the probe sees what they
//!   add. Where the Schur form does not converge, the rigorous bound
//!   [`rate_bound`] takes its place: for `ẍ = −M⁻¹K x − M⁻¹C ẋ` every
//!   eigenvalue satisfies `|λ|² <= κ + γ |λ|` with `κ = ‖M⁻¹K‖_∞`,
//!   `γ = ‖M⁻¹C‖_∞`, so `|λ| <= γ + √κ`.
//! - C grows with the road's roughness, because each breakpoint of a
//!   piecewise-linear road is a jump of `x_g'` that the wheel turns into a
//!   jump of `x_t‴`: [`ROUGHNESS_SMOOTH`] for the harmonic road,
//!   [`ROUGHNESS_SPARSE`] for roads with breakpoints at least 10 ms apart
//!   (paper-compatible, measured profiles, the input), [`ROUGHNESS_DENSE`]
//!   for the ISO 8608 road (a breakpoint every millisecond).
//!
//! The first step aims at the probe's target, `ε(h_0) = PROBE_SAFETY tol`:
//! `h_0 = (PROBE_SAFETY tol / C)^{1/4} / ω`. The constants were measured
//! (TDVASS, Table 1, ω = 68 rad/s): the probe's estimate at the default
//! tolerance is 1.4e-7 at h = 3.3 ms on the harmonic road (`(ω h)⁴` =
//! 0.026, C ≈ 6e-6), 3.2e-7 at 2.1 ms on the paper-compatible road
//! (C ≈ 7e-4), 4.7e-7 at 1 ms on ISO 8608 (C ≈ 2e-2); the constants are
//! rounded up so that the first step usually passes. Over whole 15 s runs
//! against a run at h = 1e-5 s the errors are smaller still (RMS TDD on the
//! harmonic road: 1.7e-8 at 3 ms); `tests/accuracy_tolerance.rs` checks
//! every metric over a grid of cases.
//!
//! **The ladder.** h is taken from `Δ / n` (n a whole number): Δ is the
//! spacing of the road's breakpoints for the ISO 8608 and paper-compatible
//! roads, so that every breakpoint falls on a node and no step is split,
//! else [`LARGEST_STEP`]. A communication step below that (the FMU's
//! DefaultExperiment stepSize, 1 ms) takes the place of Δ: a master that
//! steps by it, or by a multiple, then meets internal nodes only, and a
//! call costs its internal steps and nothing for a point inside a step.
//! The step is a function of a whole number, the same on every platform.
//!
//! **The probe.** Step doubling checks the choice after the fact: two runs
//! of [`PROBE_DURATION`] from the configured start (the start transient
//! included), at h and at the next finer step h' (about h / 2, on the
//! same ladder and delay grid), estimate the error of the coarse one as
//! `|RMS_h − RMS_h'| / (1 − (h'/h)⁴)` for BA, SDD and TDD, and the same for
//! the largest |SDD| where the run keeps it. Where the estimate exceeds
//! [`PROBE_SAFETY`] × tol, n grows by the factor
//! `1.1 (ε / (PROBE_SAFETY tol))^{1/4}` (at least by one) and the probe
//! runs again, at most [`PROBE_ROUNDS`] times. Where the first estimate is
//! well below the tolerance, the same formula gives a longer step (by at
//! most [`MAX_COARSENING`]), and one more probe confirms it; if it fails,
//! or cannot run, the step that passed is kept. A probe whose finer run
//! would need more than [`MAX_PROBE_WORK`] internal steps and road
//! breakpoints is not run (a tiny `max_internal_step` or road sample
//! interval): the model's step stands, and the caller's work limits apply
//! to the run. The probe runs the caller's own configuration, so it checks
//! the metrics the run reports; a round that accepts the step hands its
//! coarse simulator, as it was before it ran, to [`Simulator::new`], so a
//! round costs one extra simulator and 1.5 × [`PROBE_DURATION`] of
//! simulated time. A probe that diverges (an unstable (g, tau)) or has no
//! response to measure leaves the model's step. The external road input
//! (road = 0) is not known in advance: its step is the model's alone.
//!
//! **The same step everywhere.** The choice uses only IEEE-exact
//! operations (+, ×, ÷, √; `x^{1/4}` as `√√x`) and the Schur form's, so
//! every platform takes the same step; the probe's runs are bit-identical
//! across platforms like any run (see [`crate::math`]).
//!
//! **Delay regimes.** The step bound then goes to [`super::DelayGrid`],
//! which keeps the three regimes (folded, inside the step, whole steps of
//! `h = tau / m`). Each is accurate to the tolerance, so J(tau) is
//! continuous across the regime changes to within the tolerance.
//!
//! Layer: clients (docs/architecture.md); it imports the solver's `config`,
//! `driver`, `grid`, `outputs` and the crate's `error`, `model`, `road`.

use super::config::SimulationConfig;
use super::driver::Simulator;
use super::grid::DelayGrid;
use crate::error::{Error, Result};
use crate::model::{Plant, V_H, V_S, V_T, X_H, X_S, X_T};
use crate::road::{ISO_NODE_INTERVAL, RoadShift, RoadSpec};
use nalgebra::{Matrix6, Schur};

pub use super::config::{
    DEFAULT_TOLERANCE, MAX_TOLERANCE, MIN_TOLERANCE, StepChoice, check_communication_step,
    check_max_internal_step, check_tolerance,
};
/// Largest internal step (s).
pub const LARGEST_STEP: f64 = 0.01;
/// Smallest internal step a tolerance may ask for (s); a tolerance that
/// needs less is refused (the work of a run would pass every limit).
pub const SMALLEST_STEP: f64 = 1e-6;
/// Simulated time of each probe run (s).
pub const PROBE_DURATION: f64 = 0.5;
/// The probe accepts a step whose estimated error is at most this fraction
/// of the tolerance.
pub const PROBE_SAFETY: f64 = 0.5;
/// Most rounds of the probe.
pub const PROBE_ROUNDS: usize = 6;
/// Most internal steps plus road breakpoints of one probe run (2^20, a
/// few milliseconds); a probe that would need more is not run.
pub const MAX_PROBE_WORK: f64 = 1_048_576.0;
/// Largest factor by which the probe may lengthen the model's step.
pub const MAX_COARSENING: f64 = 8.0;
/// `C` of the harmonic road.
pub const ROUGHNESS_SMOOTH: f64 = 1e-4;
/// `C` of roads whose breakpoints are at least 10 ms apart.
pub const ROUGHNESS_SPARSE: f64 = 1e-3;
/// `C` of the ISO 8608 road (a breakpoint every millisecond).
pub const ROUGHNESS_DENSE: f64 = 2e-2;
/// A road's breakpoint spacing below this (s) is not made a divisor of
/// the step (the breakpoints then split steps, and the work limit per call
/// counts them).
const MIN_ROAD_BASE: f64 = 10.0 * SMALLEST_STEP;
/// Most QR sweeps of the Schur form that finds the plant's eigenvalues.
const SCHUR_ITERATIONS: usize = 200;

/// The bound `γ + √κ` (1/s) on the plant's eigenvalues (module docs), from
/// the solver matrix (A with the feedback folded in).
pub fn rate_bound(plant: &Plant) -> f64 {
    let a = folded_matrix(plant);
    let (mut stiffness, mut damping) = (0.0f64, 0.0f64);
    for row in [V_S, V_H, V_T] {
        let k: f64 = [X_S, X_H, X_T].iter().map(|&c| a[(row, c)].abs()).sum();
        let c: f64 = [V_S, V_H, V_T].iter().map(|&c| a[(row, c)].abs()).sum();
        stiffness = stiffness.max(k);
        damping = damping.max(c);
    }
    damping + stiffness.sqrt()
}

/// The plant matrix with the delayed feedback folded in (`u = g x_t`).
fn folded_matrix(plant: &Plant) -> Matrix6<f64> {
    let mut a = plant.a;
    for row in 0..6 {
        a[(row, X_T)] += plant.b[row];
    }
    a
}

/// The fastest oscillation of the plant (rad/s): the largest |λ| among its
/// complex eigenvalues (feedback folded in), the rate at which the
/// response's derivatives grow. Real modes are left out: they are
/// overdamped, and the probe sees what they add. Where the Schur form does
/// not converge in 200 QR sweeps, the bound [`rate_bound`].
pub fn fastest_oscillation(plant: &Plant) -> f64 {
    let a = folded_matrix(plant);
    match Schur::try_new(a, f64::EPSILON, SCHUR_ITERATIONS) {
        Some(schur) => schur
            .complex_eigenvalues()
            .iter()
            .filter(|λ| λ.im != 0.0)
            .map(|λ| (λ.re * λ.re + λ.im * λ.im).sqrt())
            .fold(0.0, f64::max),
        None => rate_bound(plant),
    }
}

/// The spacing Δ of the ladder `Δ / n` (s): the road's breakpoint spacing
/// where it has one of its own, else [`LARGEST_STEP`]; a communication
/// step (when > 0) below that takes its place.
fn ladder_base(road: &RoadSpec, communication_step: f64) -> f64 {
    let road_base = match road {
        RoadSpec::Iso8608(_) => ISO_NODE_INTERVAL,
        RoadSpec::PaperCompatible {
            sample_interval, ..
        } if (MIN_ROAD_BASE..=LARGEST_STEP * 100.0).contains(sample_interval) => *sample_interval,
        _ => LARGEST_STEP,
    };
    if communication_step > 0.0 {
        road_base.min(communication_step)
    } else {
        road_base
    }
}

/// The roughness constant C of the error model for this road.
fn roughness(road: &RoadSpec) -> f64 {
    match road {
        RoadSpec::Harmonic { .. } => ROUGHNESS_SMOOTH,
        RoadSpec::Iso8608(_) => ROUGHNESS_DENSE,
        _ => ROUGHNESS_SPARSE,
    }
}

/// The step on the ladder `base / n`, capped by `max_internal_step` (when
/// > 0).
fn ladder_step(base: f64, n: f64, max_internal_step: f64) -> f64 {
    let h = base / n;
    if max_internal_step > 0.0 {
        h.min(max_internal_step)
    } else {
        h
    }
}

/// The internal step bound for `config` (module docs): the error model's
/// step on the ladder, checked and refined by the probe.
pub fn choose_step(plant: &Plant, config: &SimulationConfig) -> Result<StepChoice> {
    Ok(choose(plant, config)?.0)
}

/// [`choose_step`], with the coarse simulator of the probe that accepted
/// the step, as it was before the probe ran (the run itself, when it can
/// be used as it is).
pub(super) fn choose(
    plant: &Plant,
    config: &SimulationConfig,
) -> Result<(StepChoice, Option<Box<Simulator>>)> {
    check_tolerance(config.tolerance)?;
    check_max_internal_step(config.max_internal_step)?;
    check_communication_step(config.communication_step)?;
    let tolerance = config.tolerance;
    let allowed = PROBE_SAFETY * tolerance;
    let mut rate = fastest_oscillation(plant);
    if let RoadSpec::Harmonic {
        angular_frequency, ..
    } = config.road
    {
        rate = rate.max(angular_frequency.abs());
    }
    let model_step = (allowed / roughness(&config.road)).sqrt().sqrt() / rate.max(1.0);
    let base = ladder_base(&config.road, config.communication_step);
    let coarsest = (base / LARGEST_STEP).ceil().max(1.0);
    let mut n = (base / model_step).ceil().max(coarsest);
    let capped = config.max_internal_step > 0.0 && config.max_internal_step <= SMALLEST_STEP;
    let check_work = |n: f64| {
        if base / n < SMALLEST_STEP && !capped {
            Err(Error::InvalidParameter {
                name: "tolerance",
                value: tolerance,
                reason: "the relative tolerance needs an internal step below 1e-6 s, beyond the work limit",
            })
        } else {
            Ok(())
        }
    };
    check_work(n)?;
    let mut choice = StepChoice {
        step_bound: ladder_step(base, n, config.max_internal_step),
        model_step,
        probe_error: f64::NAN,
        probe_rounds: 0,
    };
    if matches!(config.road, RoadSpec::Input) {
        return Ok((choice, None));
    }
    // A shift of the road (a wheel behind another, or on the other track)
    // moves its profile in time and keeps its roughness: the probe runs on
    // the road as it is, so that every wheel of a car gets the same step
    // (its simulator is then not the run's).
    let unshifted;
    let probed = if config.road_shift == RoadShift::NONE {
        config
    } else {
        unshifted = SimulationConfig {
            road_shift: RoadShift::NONE,
            ..config.clone()
        };
        &unshifted
    };
    // What passed the probe, while a coarser step is tried.
    let mut accepted: Option<(f64, f64, Option<Box<Simulator>>)> = None;
    let mut pristine = None;
    while choice.probe_rounds < PROBE_ROUNDS {
        let coarse = ladder_step(base, n, config.max_internal_step);
        let fine = ladder_step(base, 2.0 * n, config.max_internal_step);
        if fine >= coarse || probe_work(config, fine) > MAX_PROBE_WORK {
            // max_internal_step caps both (nothing to refine), or the probe
            // would pass its work limit: the model's step stands.
            break;
        }
        choice.probe_rounds += 1;
        let Some(probe) = probe(plant, probed, coarse, fine)? else {
            break;
        };
        pristine = Some(probe.pristine);
        // `n` for which the error would be `allowed` (ε ∝ h⁴ = (Δ/n)⁴),
        // with a margin of 10 %.
        let needed = n * (probe.error / allowed).sqrt().sqrt() * 1.1;
        if probe.error <= allowed {
            choice.probe_error = probe.error;
            if accepted.take().is_some() {
                // The coarser step passed its check too.
                break;
            }
            let coarser = needed.ceil().max(coarsest).max((n / MAX_COARSENING).ceil());
            if coarser >= n {
                break;
            }
            accepted = Some((n, probe.error, pristine.take()));
            n = coarser;
        } else if accepted.is_some() {
            break;
        } else {
            n = needed.ceil().max(n + 1.0);
            check_work(n)?;
            pristine = None;
        }
    }
    if let Some((previous, error, kept)) = accepted {
        // A coarser step that failed its check, or could not be checked:
        // back to the one that passed.
        n = previous;
        choice.probe_error = error;
        pristine = kept;
    }
    choice.step_bound = ladder_step(base, n, config.max_internal_step);
    let pristine = pristine.filter(|sim| {
        sim.step_choice.step_bound == choice.step_bound && config.road_shift == RoadShift::NONE
    });
    Ok((choice, pristine))
}

/// Internal steps and road breakpoints of the finer probe run at step
/// `fine`.
fn probe_work(config: &SimulationConfig, fine: f64) -> f64 {
    let breakpoints = match &config.road {
        RoadSpec::Iso8608(_) => PROBE_DURATION / ISO_NODE_INTERVAL,
        RoadSpec::PaperCompatible {
            sample_interval, ..
        } => PROBE_DURATION / sample_interval,
        RoadSpec::Samples(samples) => {
            let (from, to) = (config.start_time, config.start_time + PROBE_DURATION);
            let first = samples.partition_point(|&(t, _)| t < from);
            let last = samples.partition_point(|&(t, _)| t <= to);
            last.saturating_sub(first) as f64
        }
        RoadSpec::Harmonic { .. } | RoadSpec::Input => 0.0,
    };
    PROBE_DURATION / fine + breakpoints
}

/// What one probe round measured.
struct Probe {
    /// The estimated relative error of the run at the coarse step.
    error: f64,
    /// The coarse simulator before it ran.
    pristine: Box<Simulator>,
}

/// The estimated relative error of the metrics of a run at step bound
/// `coarse` (module docs), from two runs of [`PROBE_DURATION`]: the RMS
/// values, and the largest |SDD| where the run keeps it; `None` when it
/// cannot be measured (divergence, no response).
fn probe(
    plant: &Plant,
    config: &SimulationConfig,
    coarse: f64,
    fine: f64,
) -> Result<Option<Probe>> {
    let tau = if config.variant.has_control() {
        config.params.tau
    } else {
        0.0
    };
    let (coarse_grid, fine_grid) = (DelayGrid::new(tau, coarse)?, DelayGrid::new(tau, fine)?);
    let ratio = (fine_grid.step / coarse_grid.step).powi(4);
    if ratio >= 1.0 {
        return Ok(None);
    }
    // Boxed: a simulator is several kilobytes, and it moves.
    let start = |grid: DelayGrid, bound: f64| -> Option<Box<Simulator>> {
        let mut sim = Box::new(Simulator::with_grid(config.clone(), plant.clone(), grid).ok()?);
        sim.step_choice.step_bound = bound;
        Some(sim)
    };
    let measure = |mut sim: Box<Simulator>| -> Option<[f64; 4]> {
        sim.advance_to(sim.time() + PROBE_DURATION).ok()?;
        let summary = super::outputs::outputs(&mut sim);
        let largest = summary
            .road_holding
            .map_or(0.0, |h| h.max_suspension_deflection);
        Some([
            summary.rms.body_acceleration,
            summary.rms.suspension_deflection,
            summary.rms.tire_deflection,
            largest,
        ])
    };
    let Some(pristine) = start(coarse_grid, coarse) else {
        return Ok(None);
    };
    let a = measure(pristine.clone());
    let b = start(fine_grid, fine).and_then(measure);
    let (Some(a), Some(b)) = (a, b) else {
        return Ok(None);
    };
    let mut error: Option<f64> = None;
    for i in 0..a.len() {
        if b[i] > 0.0 && b[i].is_finite() && a[i].is_finite() {
            let relative = (a[i] - b[i]).abs() / b[i] / (1.0 - ratio);
            error = Some(error.map_or(relative, |e| e.max(relative)));
        }
    }
    Ok(error.map(|error| Probe { error, pristine }))
}
