//! Byte encoding of a whole [`Simulator`]: configuration and dynamic state
//! (time, committed and current state, the delay history, the road
//! generator, the RMS accumulators). Little-endian, position independent.
//! Framing (magic, version, checksum) is the caller's business; this layer
//! refuses truncated or inconsistent input with an error, never a panic.

use super::{SimulationConfig, Simulator};
use crate::error::{Error, Result};
use crate::metrics::{RunningRms, Weights};
use crate::model::{Params, State, Variant};
use crate::road::{RandomRoad, RoadClass, RoadSpec, RoadState};
use std::sync::Arc;

/// Appends little-endian values to a byte vector.
#[derive(Default)]
pub struct ByteWriter {
    /// The bytes written so far.
    pub bytes: Vec<u8>,
}

impl ByteWriter {
    /// Appends a u64.
    pub fn u64(&mut self, v: u64) {
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }
    /// Appends a u128.
    pub fn u128(&mut self, v: u128) {
        self.bytes.extend_from_slice(&v.to_le_bytes());
    }
    /// Appends an f64 (bit pattern).
    pub fn f64(&mut self, v: f64) {
        self.u64(v.to_bits());
    }
    /// Appends a slice of f64 with its length.
    pub fn f64s(&mut self, v: &[f64]) {
        self.u64(v.len() as u64);
        v.iter().for_each(|&x| self.f64(x));
    }
}

/// Reads what [`ByteWriter`] wrote; every read checks the remaining length.
pub struct ByteReader<'a> {
    bytes: &'a [u8],
}

impl<'a> ByteReader<'a> {
    /// Reads from `bytes`.
    pub fn new(bytes: &'a [u8]) -> Self {
        ByteReader { bytes }
    }
    fn take(&mut self, n: usize) -> Result<&'a [u8]> {
        if self.bytes.len() < n {
            return Err(Error::InvalidState(format!(
                "truncated: needed {n} more bytes, {} left",
                self.bytes.len()
            )));
        }
        let (head, tail) = self.bytes.split_at(n);
        self.bytes = tail;
        Ok(head)
    }
    /// Reads a u64.
    pub fn u64(&mut self) -> Result<u64> {
        let mut b = [0u8; 8];
        b.copy_from_slice(self.take(8)?);
        Ok(u64::from_le_bytes(b))
    }
    /// Reads a u128.
    pub fn u128(&mut self) -> Result<u128> {
        let mut b = [0u8; 16];
        b.copy_from_slice(self.take(16)?);
        Ok(u128::from_le_bytes(b))
    }
    /// Reads an f64.
    pub fn f64(&mut self) -> Result<f64> {
        Ok(f64::from_bits(self.u64()?))
    }
    /// Reads a length-prefixed slice of f64 (at most `max` values).
    pub fn f64s(&mut self, max: u64) -> Result<Vec<f64>> {
        let n = self.u64()?;
        if n > max || n.saturating_mul(8) > self.bytes.len() as u64 {
            return Err(Error::InvalidState(format!("implausible length {n}")));
        }
        (0..n).map(|_| self.f64()).collect()
    }
    /// Whether every byte was consumed.
    pub fn is_empty(&self) -> bool {
        self.bytes.is_empty()
    }
}

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
    match &c.road {
        RoadSpec::Input => w.u64(0),
        RoadSpec::Harmonic {
            amplitude,
            angular_frequency,
        } => {
            w.u64(1);
            w.f64(*amplitude);
            w.f64(*angular_frequency);
        }
        RoadSpec::Iso8608(road) => {
            w.u64(2);
            write_random_road(w, road);
        }
        RoadSpec::PaperCompatible {
            road,
            sample_interval,
        } => {
            w.u64(3);
            write_random_road(w, road);
            w.f64(*sample_interval);
        }
        RoadSpec::Samples(samples) => {
            w.u64(4);
            let flat: Vec<f64> = samples.iter().flat_map(|&(t, x)| [t, x]).collect();
            w.f64s(&flat);
        }
    }
    w.f64(c.max_internal_step);
    w.f64(c.start_time);
    c.initial_state.iter().for_each(|&v| w.f64(v));
    w.f64(c.weights.body_acceleration);
    w.f64(c.weights.suspension_deflection);
    w.f64(c.weights.tire_deflection);
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
    let road = match r.u64()? {
        0 => RoadSpec::Input,
        1 => RoadSpec::Harmonic {
            amplitude: r.f64()?,
            angular_frequency: r.f64()?,
        },
        2 => RoadSpec::Iso8608(read_random_road(r)?),
        3 => RoadSpec::PaperCompatible {
            road: read_random_road(r)?,
            sample_interval: r.f64()?,
        },
        4 => {
            let flat = r.f64s(1 << 28)?;
            if flat.len() % 2 != 0 {
                return Err(Error::InvalidState("odd road sample count".into()));
            }
            RoadSpec::Samples(Arc::new(flat.chunks(2).map(|c| (c[0], c[1])).collect()))
        }
        other => return Err(Error::InvalidState(format!("unknown road kind {other}"))),
    };
    let max_internal_step = r.f64()?;
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
    Ok(SimulationConfig {
        params,
        variant,
        road,
        max_internal_step,
        start_time,
        initial_state,
        weights,
    })
}

impl Simulator {
    /// Encodes the whole simulator.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut w = ByteWriter::default();
        write_config(&mut w, &self.config);
        w.u64(self.grid_index);
        w.f64(self.committed_time);
        self.committed_state.iter().for_each(|&v| w.f64(v));
        w.f64(self.current_time);
        self.current_state.iter().for_each(|&v| w.f64(v));
        let flat: Vec<f64> = self.history.iter().flatten().copied().collect();
        w.f64s(&flat);
        self.rms.sums_of_squares.iter().for_each(|&v| w.f64(v));
        w.u64(self.rms.samples);
        let road = self.road.dynamic_state();
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

    /// Rebuilds a simulator from [`Simulator::to_bytes`]; the result continues
    /// bit-identically.
    pub fn from_bytes(bytes: &[u8]) -> Result<Simulator> {
        let mut r = ByteReader::new(bytes);
        let config = read_config(&mut r)?;
        let mut sim = Simulator::new(config)?;
        sim.grid_index = r.u64()?;
        sim.committed_time = r.f64()?;
        for v in sim.committed_state.iter_mut() {
            *v = r.f64()?;
        }
        sim.current_time = r.f64()?;
        for v in sim.current_state.iter_mut() {
            *v = r.f64()?;
        }
        let flat = r.f64s(2 * super::MAX_HISTORY_NODES + 2)?;
        if flat.len() != 2 * sim.history.len() {
            return Err(Error::InvalidState(format!(
                "history of {} values where {} were expected",
                flat.len(),
                2 * sim.history.len()
            )));
        }
        for (slot, pair) in sim.history.iter_mut().zip(flat.chunks(2)) {
            *slot = [pair[0], pair[1]];
        }
        let mut rms = RunningRms::default();
        for v in rms.sums_of_squares.iter_mut() {
            *v = r.f64()?;
        }
        rms.samples = r.u64()?;
        sim.rms = rms;
        let mut road = RoadState {
            word_position: r.u128()?,
            first_node: r.u64()?,
            nodes: r.f64s(1 << 28)?,
            input: None,
        };
        if r.u64()? == 1 {
            road.input = Some((r.f64()?, r.f64()?, r.f64()?));
        }
        sim.road.restore_dynamic_state(&road)?;
        if !r.is_empty() {
            return Err(Error::InvalidState("trailing bytes".into()));
        }
        let times = [sim.committed_time, sim.current_time];
        let values_finite = sim
            .committed_state
            .iter()
            .chain(sim.current_state.iter())
            .all(|v| v.is_finite());
        if !values_finite
            || times.iter().any(|t| !t.is_finite())
            || sim.current_time < sim.committed_time
        {
            return Err(Error::InvalidState(
                "non-finite or inconsistent time or state".into(),
            ));
        }
        Ok(sim)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn last_node_until_is_bounded_where_node_times_do_not_resolve_steps() {
        // States no simulator reaches (`Simulator::new` refuses such start
        // times), built field by field: the search for the last node reached
        // returns without scanning the nodes that share one floating-point
        // time, and without overflowing the node index.
        let mut sim = Simulator::new(SimulationConfig::default()).unwrap();
        let k = u64::MAX - 10;
        sim.grid_index = k;
        sim.committed_time = sim.grid_time(k);
        sim.current_time = sim.committed_time;
        for t_end in [sim.committed_time, sim.committed_time * 1.5, f64::MAX] {
            let j = sim.last_node_until(t_end);
            assert!(j >= k && j < u64::MAX, "{j}");
        }
        let mut sim = Simulator::new(SimulationConfig::default()).unwrap();
        sim.config.start_time = 1e22;
        sim.committed_time = 1e22;
        sim.current_time = 1e22;
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
