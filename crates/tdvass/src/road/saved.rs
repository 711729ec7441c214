//! The road's byte forms, the one encoding both engines save: the
//! specification ([`RoadSpec`], part of a simulator's configuration) and
//! the dynamic state ([`RoadState`]: a random road's generator position and
//! nodes, an external input's current piece). Written and read with the
//! crate's one codec ([`crate::bytes`]); a read checks lengths and codes.

use super::spec::{RandomRoad, RoadClass, RoadSpec, RoadType};
use crate::bytes::{ByteReader, ByteWriter};
use crate::error::{Error, Result};
use std::sync::Arc;

/// Most values a saved list may hold (road samples, road nodes): a bound on
/// what a read allocates; the engines check their own, tighter windows.
const MAX_SAVED_VALUES: u64 = 1 << 28;

/// Saved dynamic state of a [`super::Road`]: a random road's generator
/// position (its random word), the index of its first kept node and the
/// nodes (m), and an external input's piece (start s, value m, slope m/s).
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct RoadState {
    pub word_position: u128,
    pub first_node: u64,
    pub nodes: Vec<f64>,
    pub input: Option<(f64, f64, f64)>,
}

impl RandomRoad {
    fn write(&self, w: &mut ByteWriter) {
        w.u64(self.class.code() as u64);
        w.f64(self.speed);
        w.f64(self.cutoff_frequency);
        w.u64(self.seed);
    }

    fn read(r: &mut ByteReader) -> Result<RandomRoad> {
        Ok(RandomRoad {
            class: RoadClass::from_code(r.u64()? as i64)?,
            speed: r.f64()?,
            cutoff_frequency: r.f64()?,
            seed: r.u64()?,
        })
    }
}

impl RoadSpec {
    /// Writes the road's type code and its parameters.
    pub(crate) fn write(&self, w: &mut ByteWriter) {
        w.u64(self.road_type().code() as u64);
        match self {
            RoadSpec::Input => {}
            RoadSpec::Harmonic {
                amplitude,
                angular_frequency,
            } => {
                w.f64(*amplitude);
                w.f64(*angular_frequency);
            }
            RoadSpec::Iso8608(road) => road.write(w),
            RoadSpec::PaperCompatible {
                road,
                sample_interval,
            } => {
                road.write(w);
                w.f64(*sample_interval);
            }
            RoadSpec::Samples(samples) => {
                let flat: Vec<f64> = samples.iter().flat_map(|&(t, x)| [t, x]).collect();
                w.f64s(&flat);
            }
        }
    }

    /// Reads what [`RoadSpec::write`] wrote (the values are checked where
    /// the configuration is).
    pub(crate) fn read(r: &mut ByteReader) -> Result<RoadSpec> {
        let code = r.u64()?;
        let road_type = i64::try_from(code).ok().and_then(RoadType::from_code);
        Ok(match road_type {
            Some(RoadType::Input) => RoadSpec::Input,
            Some(RoadType::Harmonic) => RoadSpec::Harmonic {
                amplitude: r.f64()?,
                angular_frequency: r.f64()?,
            },
            Some(RoadType::Iso8608) => RoadSpec::Iso8608(RandomRoad::read(r)?),
            Some(RoadType::PaperCompatible) => RoadSpec::PaperCompatible {
                road: RandomRoad::read(r)?,
                sample_interval: r.f64()?,
            },
            Some(RoadType::Samples) => {
                let flat = r.f64s(MAX_SAVED_VALUES)?;
                if flat.len() % 2 != 0 {
                    return Err(Error::InvalidState("odd road sample count".into()));
                }
                RoadSpec::Samples(Arc::new(flat.chunks(2).map(|c| (c[0], c[1])).collect()))
            }
            None => return Err(Error::InvalidState(format!("unknown road kind {code}"))),
        })
    }
}

impl RoadState {
    /// Writes a random road's generator position and nodes.
    pub(crate) fn write_nodes(&self, w: &mut ByteWriter) {
        w.u128(self.word_position);
        w.u64(self.first_node);
        w.f64s(&self.nodes);
    }

    /// Reads what [`RoadState::write_nodes`] wrote (no input piece).
    pub(crate) fn read_nodes(r: &mut ByteReader) -> Result<RoadState> {
        Ok(RoadState {
            word_position: r.u128()?,
            first_node: r.u64()?,
            nodes: r.f64s(MAX_SAVED_VALUES)?,
            input: None,
        })
    }

    /// Writes the whole dynamic state: the nodes ([`RoadState::write_nodes`])
    /// and the external input's piece (tag 0, or 1 with its start, value
    /// and slope).
    pub(crate) fn write(&self, w: &mut ByteWriter) {
        self.write_nodes(w);
        match self.input {
            Some((start, value, slope)) => {
                w.u64(1);
                w.f64(start);
                w.f64(value);
                w.f64(slope);
            }
            None => w.u64(0),
        }
    }

    /// Reads what [`RoadState::write`] wrote.
    pub(crate) fn read(r: &mut ByteReader) -> Result<RoadState> {
        let mut state = RoadState::read_nodes(r)?;
        if r.u64()? == 1 {
            state.input = Some((r.f64()?, r.f64()?, r.f64()?));
        }
        Ok(state)
    }
}
