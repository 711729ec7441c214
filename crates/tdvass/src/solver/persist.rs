//! Byte encoding of a whole [`Simulator`]: configuration and dynamic state
//! (time, committed and current state, the delay history, the road
//! generator, the RMS accumulators, the W_k filter state and its integrals,
//! the road-holding and working-space accumulators). Little-endian,
//! position independent. The bytes start with [`STATE_FORMAT_VERSION`];
//! further framing (magic, checksum) is the caller's business. Written and
//! read with the one codec of [`crate::bytes`]. This layer
//! refuses truncated, foreign-version or inconsistent input with an error,
//! never a panic.
//!
//! Layer: clients (docs/architecture.md); it imports the solver's
//! `accuracy`, `config`, `driver`, `grid`, `holding`, `integrals` and the
//! crate's `bytes`, `error`, `metrics`, `model`, `road`.

use super::accuracy;
use super::config::{Metrics, SimulationConfig};
use super::driver::Simulator;
use super::holding::Holding;
use super::integrals::{INTEGRALS, WEIGHTED_FOURTH, WEIGHTED_SQUARE};
use crate::bytes::{ByteReader, ByteWriter};
use crate::error::{Error, Result};
use crate::metrics::{RunningRms, Weights};
use crate::model::{Params, State, TireContact, Variant};
use crate::road::{RandomRoad, RoadClass, RoadSpec, RoadState, RoadType};
use std::sync::Arc;

/// Version of the byte layout written by [`Simulator::to_bytes`] (the
/// first u64), and the only one read. Version 2 added the metrics level, the
/// W_k filter state, the integrals of a_w² and a_w⁴, and the road-holding
/// and working-space accumulators; the bytes of version 1 had no version
/// word (they begin with the body mass) and are refused. Version 3 added
/// the tolerance, the communication step the internal step divides and the
/// internal step bound they gave (a restored simulator keeps its step
/// without probing again). Version 4 added the tire's contact law, the
/// lift-off count and the start of the flight in progress.
pub const STATE_FORMAT_VERSION: u64 = 4;

fn write_random_road(w: &mut ByteWriter, r: &RandomRoad) {
    w.u64(r.class.code() as u64);
    w.f64(r.speed);
    w.f64(r.cutoff_frequency);
    w.u64(r.seed);
}

fn read_random_road(r: &mut ByteReader) -> Result<RandomRoad> {
    Ok(RandomRoad {
        class: RoadClass::from_code(r.u64()? as i64)?,
        speed: r.f64()?,
        cutoff_frequency: r.f64()?,
        seed: r.u64()?,
    })
}

fn write_config(w: &mut ByteWriter, c: &SimulationConfig) {
    c.params.named_values().iter().for_each(|(_, v)| w.f64(*v));
    w.u64(c.variant.code() as u64);
    w.u64(c.road.road_type().code() as u64);
    match &c.road {
        RoadSpec::Input => {}
        RoadSpec::Harmonic {
            amplitude,
            angular_frequency,
        } => {
            w.f64(*amplitude);
            w.f64(*angular_frequency);
        }
        RoadSpec::Iso8608(road) => {
            write_random_road(w, road);
        }
        RoadSpec::PaperCompatible {
            road,
            sample_interval,
        } => {
            write_random_road(w, road);
            w.f64(*sample_interval);
        }
        RoadSpec::Samples(samples) => {
            let flat: Vec<f64> = samples.iter().flat_map(|&(t, x)| [t, x]).collect();
            w.f64s(&flat);
        }
    }
    w.f64(c.tolerance);
    w.f64(c.max_internal_step);
    w.f64(c.communication_step);
    w.f64(c.start_time);
    c.initial_state.iter().for_each(|&v| w.f64(v));
    w.f64(c.weights.body_acceleration);
    w.f64(c.weights.suspension_deflection);
    w.f64(c.weights.tire_deflection);
    w.u64(c.metrics.code());
    w.u64(c.tire_contact.code() as u64);
}

fn read_config(r: &mut ByteReader) -> Result<SimulationConfig> {
    let mut p = [0.0; 10];
    for v in p.iter_mut() {
        *v = r.f64()?;
    }
    let params = Params {
        m_s: p[0],
        m_h: p[1],
        m_t: p[2],
        k_s: p[3],
        k_h: p[4],
        k_t: p[5],
        c_s: p[6],
        c_h: p[7],
        g: p[8],
        tau: p[9],
    };
    let variant = Variant::from_code(r.u64()? as i64)?;
    let code = r.u64()?;
    let road_type = i64::try_from(code).ok().and_then(RoadType::from_code);
    let road = match road_type {
        Some(RoadType::Input) => RoadSpec::Input,
        Some(RoadType::Harmonic) => RoadSpec::Harmonic {
            amplitude: r.f64()?,
            angular_frequency: r.f64()?,
        },
        Some(RoadType::Iso8608) => RoadSpec::Iso8608(read_random_road(r)?),
        Some(RoadType::PaperCompatible) => RoadSpec::PaperCompatible {
            road: read_random_road(r)?,
            sample_interval: r.f64()?,
        },
        Some(RoadType::Samples) => {
            let flat = r.f64s(1 << 28)?;
            if flat.len() % 2 != 0 {
                return Err(Error::InvalidState("odd road sample count".into()));
            }
            RoadSpec::Samples(Arc::new(flat.chunks(2).map(|c| (c[0], c[1])).collect()))
        }
        None => return Err(Error::InvalidState(format!("unknown road kind {code}"))),
    };
    let tolerance = r.f64()?;
    let max_internal_step = r.f64()?;
    let communication_step = r.f64()?;
    let start_time = r.f64()?;
    let mut initial_state = State::zeros();
    for v in initial_state.iter_mut() {
        *v = r.f64()?;
    }
    let weights = Weights {
        body_acceleration: r.f64()?,
        suspension_deflection: r.f64()?,
        tire_deflection: r.f64()?,
    };
    let metrics = Metrics::from_code(r.u64()?)
        .map_err(|e| Error::InvalidState(format!("metrics level: {e}")))?;
    let tire_contact = TireContact::from_code(i64::try_from(r.u64()?).unwrap_or(i64::MAX))
        .map_err(|e| Error::InvalidState(format!("tire contact: {e}")))?;
    Ok(SimulationConfig {
        params,
        variant,
        road,
        tolerance,
        max_internal_step,
        communication_step,
        tire_contact,
        start_time,
        initial_state,
        weights,
        metrics,
    })
}

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

/// The road-holding accumulators and the start of the flight in
/// progress.
fn read_holding(r: &mut ByteReader) -> Result<(Holding, Option<f64>)> {
    let optional_time = |r: &mut ByteReader, what: &str| -> Result<Option<f64>> {
        match r.u64()? {
            0 => Ok(None),
            1 => Ok(Some(r.f64()?)),
            other => Err(Error::InvalidState(format!("{what} tag {other}"))),
        }
    };
    let holding = Holding {
        max_deflection: r.f64()?,
        lost_steps: r.u64()?,
        lost_time: r.f64()?,
        first_loss: optional_time(r, "first contact loss")?,
        lift_offs: r.u64()?,
    };
    Ok((holding, optional_time(r, "flight")?))
}

/// The road's dynamic state (random road position and nodes, external
/// input).
fn read_road_state(r: &mut ByteReader) -> Result<RoadState> {
    let mut road = RoadState {
        word_position: r.u128()?,
        first_node: r.u64()?,
        nodes: r.f64s(1 << 28)?,
        input: None,
    };
    if r.u64()? == 1 {
        road.input = Some((r.f64()?, r.f64()?, r.f64()?));
    }
    Ok(road)
}

/// [`Simulator::to_bytes`].
pub(super) fn to_bytes(sim: &Simulator) -> Vec<u8> {
    if sim.computed_state().is_none() {
        // The same bytes as when the state was computed at once.
        let mut settled = sim.clone();
        settled.settle();
        return settled.to_bytes();
    }
    let mut w = ByteWriter::default();
    w.u64(STATE_FORMAT_VERSION);
    write_config(&mut w, &sim.config);
    w.f64(sim.step_choice.step_bound);
    w.u64(sim.trajectory.grid_index);
    w.f64(sim.trajectory.committed_time);
    sim.trajectory
        .committed_state
        .iter()
        .for_each(|&v| w.f64(v));
    w.f64(sim.trajectory.current_time);
    sim.trajectory.current_state.iter().for_each(|&v| w.f64(v));
    let flat: Vec<f64> = sim.inputs.history.iter().flatten().copied().collect();
    w.f64s(&flat);
    sim.observers
        .rms
        .sums_of_squares
        .iter()
        .for_each(|&v| w.f64(v));
    w.u64(sim.observers.rms.samples);
    let integral = &sim.observers.integral;
    integral.closed.iter().for_each(|&v| w.f64(v));
    w.u64(integral.anchor_index);
    w.f64(integral.anchor_time);
    integral.anchor.value.iter().for_each(|&v| w.f64(v));
    integral.anchor.rate.iter().for_each(|&v| w.f64(v));
    sim.observers.weighted.iter().for_each(|&v| w.f64(v));
    sim.trajectory
        .committed_filter
        .iter()
        .for_each(|&v| w.f64(v));
    let holding = &sim.observers.holding;
    w.f64(holding.max_deflection);
    w.u64(holding.lost_steps);
    w.f64(holding.lost_time);
    match holding.first_loss {
        Some(time) => {
            w.u64(1);
            w.f64(time);
        }
        None => w.u64(0),
    }
    w.u64(holding.lift_offs);
    match sim.trajectory.flight_start {
        Some(time) => {
            w.u64(1);
            w.f64(time);
        }
        None => w.u64(0),
    }
    let road = sim.inputs.road.dynamic_state();
    w.u128(road.word_position);
    w.u64(road.first_node);
    w.f64s(&road.nodes);
    match road.input {
        Some((start, value, slope)) => {
            w.u64(1);
            w.f64(start);
            w.f64(value);
            w.f64(slope);
        }
        None => w.u64(0),
    }
    w.bytes
}

/// [`Simulator::from_bytes`].
pub(super) fn from_bytes(bytes: &[u8]) -> Result<Simulator> {
    let mut r = ByteReader::new(bytes);
    let version = r.u64()?;
    if version != STATE_FORMAT_VERSION {
        return Err(Error::InvalidState(format!(
            "state format version {version}: only version {STATE_FORMAT_VERSION} is read"
        )));
    }
    let config = read_config(&mut r)?;
    let step_bound = read_step_bound(&mut r, &config)?;
    let mut sim = Simulator::with_step_bound(config, step_bound)?;
    read_trajectory(&mut sim, &mut r)?;
    read_accumulators(&mut sim, &mut r)?;
    let initial_holding = sim.observers.holding;
    (sim.observers.holding, sim.trajectory.flight_start) = read_holding(&mut r)?;
    sim.enter_recorded_mode();
    let road = read_road_state(&mut r)?;
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
    Ok(sim)
}

/// The grid node, the committed and current points and the delay
/// history, as [`Simulator::to_bytes`] wrote them.
fn read_trajectory(sim: &mut Simulator, r: &mut ByteReader) -> Result<()> {
    sim.trajectory.grid_index = r.u64()?;
    sim.trajectory.committed_time = r.f64()?;
    for v in sim.trajectory.committed_state.iter_mut() {
        *v = r.f64()?;
    }
    sim.trajectory.current_time = r.f64()?;
    for v in sim.trajectory.current_state.iter_mut() {
        *v = r.f64()?;
    }
    let flat = r.f64s(2 * super::grid::MAX_HISTORY_NODES + 2)?;
    if flat.len() != 2 * sim.inputs.history.len() {
        return Err(Error::InvalidState(format!(
            "history of {} values where {} were expected",
            flat.len(),
            2 * sim.inputs.history.len()
        )));
    }
    for (slot, pair) in sim.inputs.history.iter_mut().zip(flat.chunks(2)) {
        *slot = [pair[0], pair[1]];
    }
    Ok(())
}

/// The RMS sums, the time integral with its anchor, the a_w sums and
/// the filter state, as [`Simulator::to_bytes`] wrote them.
fn read_accumulators(sim: &mut Simulator, r: &mut ByteReader) -> Result<()> {
    let mut rms = RunningRms::default();
    for v in rms.sums_of_squares.iter_mut() {
        *v = r.f64()?;
    }
    rms.samples = r.u64()?;
    sim.observers.rms = rms;
    for v in sim.observers.integral.closed.iter_mut() {
        *v = r.f64()?;
    }
    sim.observers.integral.anchor_index = r.u64()?;
    sim.observers.integral.anchor_time = r.f64()?;
    for v in sim.observers.integral.anchor.value.iter_mut() {
        *v = r.f64()?;
    }
    for v in sim.observers.integral.anchor.rate.iter_mut() {
        *v = r.f64()?;
    }
    for v in sim.observers.weighted.iter_mut() {
        *v = r.f64()?;
    }
    for v in sim.trajectory.committed_filter.iter_mut() {
        *v = r.f64()?;
    }
    Ok(())
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
    match sim.trajectory.flight_start {
        Some(_) if !sim.config.tire_contact.is_unilateral() => Err(Error::InvalidState(
            "a flight in progress, but the tire is bilateral".into(),
        )),
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
mod tests {
    use super::*;
    use crate::road::RandomRoad;

    /// Offset of `grid_index` in [`Simulator::to_bytes`]: right after the
    /// configuration. `committed_time` follows it, then the committed state
    /// (6 values), then `current_time`.
    fn grid_index_at(sim: &Simulator) -> usize {
        let mut w = ByteWriter::default();
        w.u64(STATE_FORMAT_VERSION);
        write_config(&mut w, &sim.config);
        w.f64(sim.step_choice.step_bound);
        w.bytes.len()
    }

    fn committed_time_at(sim: &Simulator) -> usize {
        grid_index_at(sim) + 8
    }

    fn current_time_at(sim: &Simulator) -> usize {
        grid_index_at(sim) + 16 + 6 * 8
    }

    fn put(bytes: &mut [u8], at: usize, bits: u64) {
        bytes[at..at + 8].copy_from_slice(&bits.to_le_bytes());
    }

    /// Asserts that `bytes` are refused with [`Error::InvalidState`] whose
    /// message names every one of `words`.
    fn refused(bytes: &[u8], words: &[&str]) {
        match Simulator::from_bytes(bytes) {
            Err(Error::InvalidState(message)) => {
                for word in words {
                    assert!(message.contains(word), "`{word}` not in: {message}");
                }
            }
            Err(other) => panic!("expected an invalid state naming {words:?}, got {other}"),
            Ok(_) => panic!("accepted a state that should name {words:?}"),
        }
    }

    /// A simulator at 0.0623 s on the harmonic road: grid node 623.
    fn running() -> Simulator {
        let mut sim = Simulator::new(SimulationConfig::default().at_fixed_step()).unwrap();
        sim.advance_to(0.0623).unwrap();
        assert_eq!(
            (sim.trajectory.grid_index, sim.trajectory.committed_time),
            (623, 0.0623)
        );
        sim
    }

    #[test]
    fn grid_index_inconsistent_with_the_committed_time_is_refused() {
        let sim = running();
        let bytes = sim.to_bytes();
        Simulator::from_bytes(&bytes).unwrap();
        let k = sim.trajectory.grid_index;
        let at = grid_index_at(&sim);
        for forged in [
            0,
            k - 1,
            k + 1,
            k + 1_000_000,
            1 << 60,
            u64::MAX - 1,
            u64::MAX,
        ] {
            let mut bytes = bytes.clone();
            put(&mut bytes, at, forged);
            refused(&bytes, &["grid_index", &forged.to_string()]);
        }
    }

    #[test]
    fn rms_accumulators_inconsistent_with_the_grid_index_are_refused() {
        let sim = running();
        let bytes = sim.to_bytes();
        // After the history ring (its length, then 2 values per node) come
        // the three sums of squares and the sample count.
        let sums_at = current_time_at(&sim) + 8 + 6 * 8 + 8 + 16 * sim.inputs.history.len();
        let samples_at = sums_at + 3 * 8;
        assert_eq!(
            bytes[samples_at..samples_at + 8],
            sim.trajectory.grid_index.to_le_bytes()
        );
        for forged in [0, 622, 624, u64::MAX] {
            let mut bytes = bytes.clone();
            put(&mut bytes, samples_at, forged);
            refused(&bytes, &["rms samples", &forged.to_string()]);
        }
        for forged in [f64::NAN, f64::INFINITY, -1.0] {
            let mut bytes = bytes.clone();
            put(&mut bytes, sums_at + 8, forged.to_bits());
            refused(&bytes, &["SDD", &forged.to_string()]);
        }
    }

    #[test]
    fn times_moved_away_from_the_grid_index_are_refused() {
        // The times moved to 1e6 s with the grid index left at node 623:
        // accepting it would make the next step integrate ~1e10 steps, from
        // node 623 to 1e6 s.
        let sim = running();
        let bytes = sim.to_bytes();
        let mut forged = bytes.clone();
        put(&mut forged, committed_time_at(&sim), 1e6f64.to_bits());
        put(&mut forged, current_time_at(&sim), 1e6f64.to_bits());
        refused(&forged, &["committed_time", "1000000", "grid_index"]);

        let (h, k) = (sim.grid.step, sim.trajectory.grid_index);
        let next = sim.grid_time(k + 1);
        for (time, words) in [
            (
                sim.trajectory.committed_time - 0.5 * h,
                ["current_time", "committed_time"],
            ),
            (next + 0.5 * h, ["current_time", "grid_index"]),
            (sim.grid_time(k + 2), ["current_time", "grid_index"]),
            (f64::NAN, ["current_time", "NaN"]),
        ] {
            let mut forged = bytes.clone();
            put(&mut forged, current_time_at(&sim), time.to_bits());
            refused(&forged, &words);
        }
        // The committed time one step early, or on the next node, with both
        // times still ordered.
        for time in [sim.grid_time(k - 1), next] {
            let mut forged = bytes.clone();
            put(&mut forged, committed_time_at(&sim), time.to_bits());
            put(&mut forged, current_time_at(&sim), time.to_bits());
            refused(&forged, &["committed_time", "grid_index"]);
        }
    }

    #[test]
    fn every_state_the_simulator_saves_is_accepted() {
        // On a node, inside a step, a hair before and after a node (within
        // the solver's tolerance, where the current time may lie just before
        // the committed node), and after an external input changes inside a
        // step or just before a node.
        for road in [
            RoadSpec::paper_harmonic(),
            RoadSpec::Iso8608(RandomRoad::default()),
            RoadSpec::PaperCompatible {
                road: RandomRoad::default(),
                sample_interval: 0.1,
            },
            RoadSpec::Input,
        ] {
            let mut sim = Simulator::new(SimulationConfig {
                road: road.clone(),
                ..SimulationConfig::default()
            })
            .unwrap();
            let h = sim.grid.step;
            let node = |sim: &Simulator, k: u64| sim.grid_time(k);
            let stops = [
                node(&sim, 100),
                node(&sim, 250) + 0.3 * h,
                node(&sim, 400) - 0.4e-9 * h,
                node(&sim, 500) + 0.4e-9 * h,
                node(&sim, 5000) + 0.7 * h,
                node(&sim, 9000) - 0.4e-9 * h,
            ];
            for t in stops {
                sim.advance_to(t).unwrap();
                if sim.inputs.road.is_input() {
                    sim.set_road_input(0.01 * t, 0.1).unwrap();
                }
                let bytes = sim.to_bytes();
                let mut restored = Simulator::from_bytes(&bytes)
                    .unwrap_or_else(|e| panic!("{road:?} at {t}: {e}"));
                assert_eq!(restored.to_bytes(), bytes);
                let mut ahead = sim.clone();
                ahead.advance_to(t + 0.01).unwrap();
                restored.advance_to(t + 0.01).unwrap();
                assert_eq!(restored.to_bytes(), ahead.to_bytes(), "{road:?} at {t}");
            }
        }
    }

    #[test]
    fn comfort_and_holding_accumulators_inconsistent_with_the_run_are_refused() {
        use crate::solver::Metrics;
        let config = |metrics| SimulationConfig {
            road: RoadSpec::Iso8608(RandomRoad {
                class: RoadClass::H,
                speed: 30.0,
                ..RandomRoad::default()
            }),
            metrics,
            ..SimulationConfig::default()
        };
        let mut sim = Simulator::new(config(Metrics::Comfort)).unwrap();
        sim.advance_to(0.5).unwrap();
        let holding = sim.observers.holding;
        assert!(holding.lost_steps > 0 && holding.first_loss.is_some());
        let bytes = sim.to_bytes();
        Simulator::from_bytes(&bytes).unwrap();
        // Offsets from the end: the road state (input tag, the nodes with
        // their count, first_node, word position), then the flight in
        // progress (tag 0), the lift-offs, the first loss (tag and time),
        // the lost time, the lost steps, the max deflection, the 8 filter
        // states and the 2 a_w sums.
        let road = sim.inputs.road.dynamic_state();
        let road_len = 16 + 8 + 8 + 8 * road.nodes.len() + 8;
        let flight_at = bytes.len() - road_len - 8;
        let lift_offs_at = flight_at - 8;
        let first_loss_at = lift_offs_at - 16;
        assert_eq!(
            bytes[lift_offs_at..lift_offs_at + 8],
            holding.lift_offs.to_le_bytes()
        );
        let lost_time_at = first_loss_at - 8;
        let lost_steps_at = lost_time_at - 8;
        let max_at = lost_steps_at - 8;
        let filter_at = max_at - 8 * 8;
        let sums_at = filter_at - 16;
        assert_eq!(
            bytes[lost_steps_at..lost_steps_at + 8],
            holding.lost_steps.to_le_bytes()
        );
        for (at, value, words) in [
            (sums_at, (-1.0f64).to_bits(), ["comfort", "negative"]),
            (filter_at, f64::NAN.to_bits(), ["comfort", "NaN"]),
            (
                max_at,
                0.0f64.to_bits(),
                ["max suspension deflection", "below"],
            ),
            (
                lost_steps_at,
                sim.trajectory.grid_index + 1,
                ["contact loss time", "whole steps"],
            ),
            (lost_time_at, 1e3f64.to_bits(), ["contact loss time", "run"]),
            (
                first_loss_at + 8,
                1e3f64.to_bits(),
                ["first contact loss", "outside"],
            ),
        ] {
            let mut forged = bytes.clone();
            put(&mut forged, at, value);
            refused(&forged, &words);
        }
        // No first loss recorded (tag 0, without its time).
        let mut forged = bytes[..first_loss_at].to_vec();
        forged.extend(0u64.to_le_bytes());
        forged.extend(&bytes[first_loss_at + 16..]);
        refused(&forged, &["contact loss time", "without a first"]);
        // A flight in progress with the bilateral tire.
        let mut forged = bytes[..flight_at].to_vec();
        forged.extend(1u64.to_le_bytes());
        forged.extend(0.25f64.to_le_bytes());
        forged.extend(&bytes[flight_at + 8..]);
        refused(&forged, &["flight in progress", "bilateral"]);
        // A foreign version.
        let mut forged = bytes.clone();
        put(&mut forged, 0, 1);
        refused(&forged, &["format version 1"]);
        // Filter state or holding accumulators where they are not kept.
        let mut paper = Simulator::new(config(Metrics::Paper)).unwrap();
        paper.advance_to(0.5).unwrap();
        paper.trajectory.committed_filter[3] = 1e-3;
        refused(&paper.to_bytes(), &["comfort", "off"]);
        paper.trajectory.committed_filter[3] = 0.0;
        Simulator::from_bytes(&paper.to_bytes()).unwrap();
        paper.observers.holding.lost_steps = 1;
        refused(&paper.to_bytes(), &["road holding is off"]);
    }

    /// The bytes of `sim` with its random road state replaced.
    fn with_road(sim: &Simulator, first_node: u64, nodes: &[f64]) -> Vec<u8> {
        let bytes = sim.to_bytes();
        let saved = sim.inputs.road.dynamic_state();
        // first_node, the node count, the nodes, the input tag.
        let first_at = bytes.len() - 8 * (3 + saved.nodes.len());
        let mut w = ByteWriter {
            bytes: bytes[..first_at].to_vec(),
        };
        w.u64(first_node);
        w.f64s(nodes);
        w.u64(0);
        w.bytes
    }

    #[test]
    fn road_nodes_inconsistent_with_the_committed_time_are_refused() {
        for road in [
            RoadSpec::Iso8608(RandomRoad::default()),
            RoadSpec::PaperCompatible {
                road: RandomRoad::default(),
                sample_interval: 0.01,
            },
        ] {
            let mut sim = Simulator::new(SimulationConfig {
                road,
                ..SimulationConfig::default()
            })
            .unwrap();
            sim.advance_to(0.5).unwrap();
            let saved = sim.inputs.road.dynamic_state();
            let (first, nodes) = (saved.first_node, saved.nodes);
            assert!(first > 0);
            assert_eq!(with_road(&sim, first, &nodes), sim.to_bytes());
            Simulator::from_bytes(&with_road(&sim, first, &nodes)).unwrap();
            // The node holding the committed time released.
            refused(&with_road(&sim, first + 1, &nodes), &["first_node"]);
            // From node 0, without the nodes up to the committed time: the
            // next step would generate them all again.
            refused(&with_road(&sim, 0, &nodes), &["first_node 0"]);
            refused(&with_road(&sim, 0, &[0.0]), &["first_node 0", "1 nodes"]);
            // Far too many nodes, and node indices that would overflow.
            let mut many = nodes.clone();
            many.resize(nodes.len() + 10_000, 0.0);
            refused(
                &with_road(&sim, first, &many),
                &["first_node", "extends past"],
            );
            refused(&with_road(&sim, u64::MAX - 1, &nodes), &["first_node"]);
            refused(&with_road(&sim, first, &[]), &["without nodes"]);
        }
    }

    #[test]
    fn road_input_after_the_committed_time_is_refused() {
        let mut sim = Simulator::new(SimulationConfig {
            road: RoadSpec::Input,
            ..SimulationConfig::default()
        })
        .unwrap();
        sim.advance_to(0.05).unwrap();
        sim.set_road_input(0.01, 0.2).unwrap();
        sim.advance_to(0.0712).unwrap();
        let bytes = sim.to_bytes();
        Simulator::from_bytes(&bytes).unwrap();
        // The input's start time, value and slope are the last 24 bytes.
        let start_at = bytes.len() - 24;
        for (at, value) in [
            (start_at, 0.08),
            (start_at, f64::NAN),
            (start_at + 8, f64::INFINITY),
            (start_at + 16, f64::NAN),
        ] {
            let mut forged = bytes.clone();
            put(&mut forged, at, value.to_bits());
            refused(&forged, &["road input", "committed_time"]);
        }
    }

    #[test]
    fn last_node_until_finds_the_last_node_reached() {
        // Ends on a node, a few ulps either side of it, at the edge of the
        // snap tolerance and inside steps, one to three steps ahead: the
        // node found is the last one a scan finds.
        let mut sim = Simulator::new(SimulationConfig::default()).unwrap();
        sim.advance_to(0.25).unwrap();
        let k = sim.trajectory.grid_index;
        for ahead in 1..=3 {
            let node = sim.grid_time(k + ahead);
            let tolerance = sim.snap_tolerance(node);
            let h = sim.grid.step;
            for t_end in [
                node,
                node.next_up(),
                node.next_down(),
                node.next_down().next_down(),
                node - 0.9 * tolerance,
                node - 1.1 * tolerance,
                node + 1.1 * tolerance,
                node - 0.5 * h,
                node + 0.5 * h,
            ] {
                let scan = (k..k + 8)
                    .take_while(|&j| {
                        let t = sim.grid_time(j);
                        t < t_end || sim.snaps(t_end, t)
                    })
                    .last()
                    .unwrap();
                assert_eq!(
                    sim.last_node_until(t_end),
                    scan,
                    "{ahead} ahead, t_end {t_end}"
                );
            }
        }
    }

    #[test]
    fn last_node_until_is_bounded_where_node_times_do_not_resolve_steps() {
        // States no simulator reaches (`Simulator::new` refuses such start
        // times), built field by field: the search for the last node reached
        // returns without scanning the nodes that share one floating-point
        // time, and without overflowing the node index.
        let mut sim = Simulator::new(SimulationConfig::default()).unwrap();
        let k = u64::MAX - 10;
        sim.trajectory.grid_index = k;
        sim.trajectory.committed_time = sim.grid_time(k);
        sim.trajectory.current_time = sim.trajectory.committed_time;
        for t_end in [
            sim.trajectory.committed_time,
            sim.trajectory.committed_time * 1.5,
            f64::MAX,
        ] {
            let j = sim.last_node_until(t_end);
            assert!(j >= k && j < u64::MAX, "{j}");
        }
        let mut sim = Simulator::new(SimulationConfig::default().at_fixed_step()).unwrap();
        sim.config.start_time = 1e22;
        sim.inputs.move_start_for_tests(1e22);
        sim.trajectory.committed_time = 1e22;
        sim.trajectory.current_time = 1e22;
        let reached = |sim: &Simulator, j: u64| {
            let t = sim.grid_time(j);
            t <= 1e22 || sim.coincide(t, 1e22)
        };
        let j = sim.last_node_until(1e22);
        // About 1.8e11 nodes coincide with 1e22 s.
        assert!(j > 1 << 36, "{j}");
        assert!(reached(&sim, j) && !reached(&sim, j + 1));
    }
}
