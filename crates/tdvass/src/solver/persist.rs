//! Byte encoding of a whole [`Simulator`]: configuration and dynamic state
//! (time, committed and current state, the delay history, the road
//! generator, the RMS accumulators, the W_k filter state and its integrals,
//! the road-holding and working-space accumulators). Little-endian,
//! position independent. The bytes start with [`STATE_FORMAT_VERSION`];
//! further framing (magic, checksum) is the caller's business. Written and
//! read with the one codec of [`crate::bytes`]. Each part writes and reads
//! its own bytes (`SimulationConfig::write`, `Trajectory::write_points`,
//! `Inputs::write_history`, `Observers::write_sums`, `Holding::write`,
//! the road's `RoadState::write`, which Model Exchange's state shares);
//! this file puts them in order and checks what relates one part to
//! another. It refuses truncated, foreign-version or inconsistent input
//! with an error, never a panic.
//!
//! Layer: clients (docs/architecture.md); it imports the solver's
//! `accuracy`, `config`, `driver`, `holding`, `integrals` and the crate's
//! `bytes`, `error`, `model`, `road`.

use super::accuracy;
use super::config::SimulationConfig;
use super::driver::Simulator;
use super::holding::Holding;
use super::integrals::{INTEGRALS, WEIGHTED_FOURTH, WEIGHTED_SQUARE};
use crate::bytes::{ByteReader, ByteWriter};
use crate::error::{Error, Result};
use crate::model::dynamics::Mode;
use crate::road::RoadState;

/// Version of the byte layout written by [`Simulator::to_bytes`] (the
/// first u64). Version 2 added the metrics level, the
/// W_k filter state, the integrals of a_w² and a_w⁴, and the road-holding
/// and working-space accumulators; the bytes of version 1 had no version
/// word (they begin with the body mass) and are refused. Version 3 added
/// the tolerance, the communication step the internal step divides and the
/// internal step bound they gave (a restored simulator keeps its step
/// without probing again). Version 4 added the tire's contact law, the
/// lift-off count and the start of the flight in progress. Version 5 added
/// the mode in force as one word ([`crate::model::dynamics::Mode`]);
/// version 4 still loads (its flight in progress says the mode). Version 6
/// added the body ([`crate::model::Body`]) and the road's shift
/// ([`crate::road::RoadShift`]) to the configuration; versions 4 and 5 load
/// with the sprung mass and the road as it is. Version 7 added, after the
/// points, what finds a current state still to be found (`deferred`): such
/// a state is saved as it stands, without computing it, and found when
/// first asked for after a restore, the same value to the bit; versions 4
/// to 6 load with the state computed.
pub const STATE_FORMAT_VERSION: u64 = 7;

/// The oldest version read.
const OLDEST_FORMAT_VERSION: u64 = 4;

/// The internal step bound a saved simulator keeps, within the range the
/// step choice can give for `config`.
fn read_step_bound(r: &mut ByteReader, config: &SimulationConfig) -> Result<f64> {
    let step_bound = r.f64()?;
    let floor = if config.max_internal_step > 0.0 {
        accuracy::SMALLEST_STEP.min(config.max_internal_step)
    } else {
        accuracy::SMALLEST_STEP
    };
    if !(step_bound >= floor && step_bound <= accuracy::LARGEST_STEP) {
        return Err(Error::InvalidState(format!(
            "internal step bound {step_bound} s outside [{floor}, {}] s",
            accuracy::LARGEST_STEP
        )));
    }
    Ok(step_bound)
}

/// [`Simulator::to_bytes`]: each part writes its own bytes, in this order.
/// A deferred current state is written as it stands (nothing is computed
/// or copied).
pub(super) fn to_bytes(sim: &Simulator) -> Vec<u8> {
    let mut w = ByteWriter::default();
    w.u64(STATE_FORMAT_VERSION);
    sim.config.write(&mut w);
    w.f64(sim.step_choice.step_bound);
    sim.trajectory.write_points(&mut w);
    sim.trajectory.write_deferral(&mut w);
    sim.inputs.write_history(&mut w);
    sim.observers.write_sums(&mut w);
    sim.trajectory.write_filter(&mut w);
    sim.observers.holding.write(&mut w);
    sim.trajectory.write_mode(&mut w);
    sim.inputs.road.dynamic_state().write(&mut w);
    w.bytes
}

/// [`Simulator::from_bytes`]: each part reads its own bytes; the checks
/// that relate parts (times on the grid, the runs' samples, the
/// accumulators against the run) are made here.
pub(super) fn from_bytes(bytes: &[u8]) -> Result<Simulator> {
    let mut r = ByteReader::new(bytes);
    let version = r.u64()?;
    if !(OLDEST_FORMAT_VERSION..=STATE_FORMAT_VERSION).contains(&version) {
        return Err(Error::InvalidState(format!(
            "state format version {version}: versions {OLDEST_FORMAT_VERSION} to {STATE_FORMAT_VERSION} are read"
        )));
    }
    let config = SimulationConfig::read(&mut r, version)?;
    let step_bound = read_step_bound(&mut r, &config)?;
    let mut sim = Simulator::with_step_bound(config, step_bound)?;
    sim.trajectory.read_points(&mut r)?;
    let deferral = if version >= 7 {
        sim.trajectory.read_deferral(&mut r)?
    } else {
        None
    };
    sim.inputs.read_history(&mut r)?;
    sim.observers.read_sums(&mut r)?;
    sim.trajectory.read_filter(&mut r)?;
    let initial_holding = sim.observers.holding;
    sim.observers.holding = Holding::read(&mut r)?;
    sim.trajectory.read_mode(&mut r, version >= 5)?;
    let mode = sim.trajectory.mode;
    if !Mode::reachable(&sim.modes.grid_step.switching).any(|reachable| reachable == mode) {
        return Err(Error::InvalidState(format!(
            "mode {}: a run with this configuration cannot reach it (a flight in progress with the bilateral tire)",
            mode.index()
        )));
    }
    sim.enter_recorded_mode();
    let road = RoadState::read(&mut r)?;
    if !r.is_empty() {
        return Err(Error::InvalidState("trailing bytes".into()));
    }
    let values_finite = sim
        .trajectory
        .committed_state
        .iter()
        .chain(sim.trajectory.current_state.iter())
        .all(|v| v.is_finite());
    if !values_finite {
        return Err(Error::InvalidState("non-finite state".into()));
    }
    check_times(&sim)?;
    check_rms(&sim)?;
    check_comfort(&sim)?;
    if sim.config.metrics.road_holding() || sim.config.tire_contact.is_unilateral() {
        check_holding(&sim)?;
    } else if sim.observers.holding != initial_holding {
        return Err(Error::InvalidState(
            "road-holding accumulators moved, but road holding is off".into(),
        ));
    }
    let horizon = sim.grid_time(sim.trajectory.grid_index.saturating_add(2));
    sim.inputs
        .road
        .restore_dynamic_state(&road, sim.trajectory.committed_time, horizon)?;
    // A deferred state's bounds, found again from the same values (they
    // passed when it was saved).
    if let Some(kind) = deferral
        && !sim.defer(sim.trajectory.current_time, kind)
    {
        return Err(Error::InvalidState(format!(
            "the current state at {} s is saved to be found later ({kind:?}), but its bounds do not show that it passes the divergence check",
            sim.trajectory.current_time
        )));
    }
    Ok(sim)
}

/// The RMS accumulators of [`Simulator::from_bytes`]: one sample per
/// grid node of the open run, which starts at the anchor node
/// (`anchor_index + samples = grid_index`, the anchor on its node when
/// the run holds nodes, else at the committed point); sums of squares
/// that are finite and not negative; a finite closed integral and
/// anchor squares.
fn check_rms(sim: &Simulator) -> Result<()> {
    let (samples, k) = (sim.observers.rms.samples, sim.trajectory.grid_index);
    let anchor = sim.observers.integral.anchor_index;
    if anchor.checked_add(samples) != Some(k) {
        return Err(Error::InvalidState(format!(
            "rms samples {samples}: one per grid node after the anchor node {anchor} was expected, grid_index = {k}"
        )));
    }
    let anchor_time = sim.observers.integral.anchor_time;
    let expected = if samples > 0 {
        sim.grid_time(anchor)
    } else {
        sim.trajectory.committed_time
    };
    if anchor_time != expected {
        return Err(Error::InvalidState(format!(
            "rms anchor time {anchor_time} s: {expected} s was expected"
        )));
    }
    let integral = &sim.observers.integral;
    let values = integral
        .closed
        .iter()
        .chain(&integral.anchor.value)
        .chain(&integral.anchor.rate);
    if let Some(bad) = values.copied().find(|v| !v.is_finite()) {
        return Err(Error::InvalidState(format!(
            "rms integral value {bad} is not finite"
        )));
    }
    for (name, sum) in ["BA", "SDD", "TDD"]
        .iter()
        .zip(sim.observers.rms.sums_of_squares)
    {
        if !(sum.is_finite() && sum >= 0.0) {
            return Err(Error::InvalidState(format!(
                "rms sum of squares of {name} {sum} is not finite and >= 0"
            )));
        }
    }
    Ok(())
}

/// The W_k accumulators of [`Simulator::from_bytes`]: finite, the node
/// sums not negative, and all zero without the filter.
fn check_comfort(sim: &Simulator) -> Result<()> {
    let integral = &sim.observers.integral;
    let weighted = [WEIGHTED_SQUARE, WEIGHTED_FOURTH];
    let values: Vec<f64> = weighted
        .iter()
        .flat_map(|&i| {
            [
                integral.closed[i],
                integral.anchor.value[i],
                integral.anchor.rate[i],
            ]
        })
        .chain(sim.observers.weighted)
        .chain(sim.trajectory.committed_filter.iter().copied())
        .collect();
    if let Some(bad) = values.iter().find(|v| !v.is_finite()) {
        return Err(Error::InvalidState(format!(
            "comfort (a_w) accumulator {bad} is not finite"
        )));
    }
    if let Some(bad) = sim.observers.weighted.iter().find(|v| **v < 0.0) {
        return Err(Error::InvalidState(format!(
            "comfort (a_w) sum {bad} is negative"
        )));
    }
    if sim.modes.coupling.is_none() && values.iter().any(|v| *v != 0.0) {
        return Err(Error::InvalidState(
            "comfort (a_w) accumulators are not zero, but the W_k filter is off".into(),
        ));
    }
    debug_assert_eq!(INTEGRALS, 5);
    Ok(())
}

/// The road-holding accumulators of [`Simulator::from_bytes`].
fn check_holding(sim: &Simulator) -> Result<()> {
    let holding = &sim.observers.holding;
    let x = sim.trajectory.committed_state;
    let committed = (x[crate::model::X_S] - x[crate::model::X_T]).abs();
    let deflection = holding.max_deflection;
    // Below road holding (a unilateral tire at the paper level) the
    // largest |SDD| is not kept.
    let kept = sim.config.metrics.road_holding();
    if kept && !(deflection.is_finite() && deflection >= committed) {
        return Err(Error::InvalidState(format!(
            "max suspension deflection {deflection} m is not finite or below the committed |SDD| {committed} m"
        )));
    }
    let elapsed = sim.trajectory.committed_time - sim.config.start_time;
    let lost = holding.lost_steps as f64 * sim.grid.step + holding.lost_time;
    let tolerance = sim.snap_tolerance(sim.trajectory.committed_time) + 1e-9 * elapsed.abs();
    if holding.lost_steps > sim.trajectory.grid_index
        || !(holding.lost_time.is_finite()
            && holding.lost_time >= 0.0
            && lost <= elapsed + tolerance)
    {
        return Err(Error::InvalidState(format!(
            "contact loss time {lost} s ({} whole steps and {} s) does not fit in the {elapsed} s run",
            holding.lost_steps, holding.lost_time
        )));
    }
    match holding.first_loss {
        None if lost > 0.0 => Err(Error::InvalidState(format!(
            "contact loss time {lost} s without a first contact loss"
        ))),
        Some(time)
            if !(time >= sim.config.start_time
                && time <= sim.trajectory.committed_time + tolerance) =>
        {
            Err(Error::InvalidState(format!(
                "first contact loss at {time} s lies outside the run up to the committed_time {} s",
                sim.trajectory.committed_time
            )))
        }
        _ => Ok(()),
    }?;
    if holding.lift_offs > 0 && holding.first_loss.is_none() {
        return Err(Error::InvalidState(format!(
            "{} lift-offs without a first contact loss",
            holding.lift_offs
        )));
    }
    // A flight with the bilateral tire was refused with its mode.
    match sim.trajectory.flight_start {
        Some(time)
            if !(time >= sim.config.start_time
                && time <= sim.trajectory.committed_time + tolerance
                && holding.lift_offs > 0) =>
        {
            Err(Error::InvalidState(format!(
                "a flight from {time} s does not fit in the run up to the committed time {} s after {} lift-offs",
                sim.trajectory.committed_time, holding.lift_offs
            )))
        }
        _ => Ok(()),
    }
}

/// The time checks of [`Simulator::from_bytes`] on `grid_index`,
/// `committed_time` and `current_time`.
fn check_times(sim: &Simulator) -> Result<()> {
    let (k, committed, current) = (
        sim.trajectory.grid_index,
        sim.trajectory.committed_time,
        sim.trajectory.current_time,
    );
    for (name, t) in [("committed_time", committed), ("current_time", current)] {
        if !t.is_finite() {
            return Err(Error::InvalidState(format!("{name} {t} s is not finite")));
        }
    }
    let node = sim.grid_time(k);
    let next = sim.grid_time(k.saturating_add(1));
    if k == u64::MAX || node >= next {
        return Err(Error::InvalidState(format!(
            "grid_index {k}: internal step {k} starts at {node} s and has no positive length"
        )));
    }
    if !((committed >= node || sim.coincide(committed, node)) && committed < next) {
        return Err(Error::InvalidState(format!(
            "committed_time {committed} s does not lie in internal step grid_index = {k}, \
             [{node} s, {next} s)"
        )));
    }
    if !((current >= committed || sim.snaps(current, committed))
        && (current <= next || sim.snaps(current, next)))
    {
        return Err(Error::InvalidState(format!(
            "current_time {current} s does not lie between committed_time {committed} s \
             and the end of internal step grid_index = {k} at {next} s"
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests;
