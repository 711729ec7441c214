//! Road displacement inputs `x_g(t)`.
//!
//! Every road is a function of absolute time (and, for random roads, of the
//! seed) only: it never depends on the solver's internal step or on the
//! communication steps a master chooses. The solver reads a road as a
//! sequence of [`RoadPiece`]s, each exactly representable over its interval
//! (a sine, or a straight line), so the step integral of Eq. (23) is exact.
//!
//! - [`RoadSpec::Harmonic`]: `x_g = A sin(ω t)` (section 5.1).
//! - [`RoadSpec::Iso8608`]: the ISO 8608 filtered white noise road
//!   `dx_g/dt = −2π f0 x_g + 2π n0 sqrt(Gq(n0) u) w(t)` (notes.md item 6,
//!   the corrected Eq. (27)), with `w` scaled so that the road's one-sided
//!   spatial PSD is `Gq(n0) (n/n0)^-2` above the cut-off. It is sampled
//!   exactly (Ornstein–Uhlenbeck transition) at nodes [`ISO_NODE_INTERVAL`]
//!   apart and linearly interpolated.
//! - [`RoadSpec::PaperCompatible`]: the band-limited road that reproduces
//!   the paper's Table 3 (notes.md section 3): N(0, 1) samples held for `D`
//!   without 1/√D scaling, forward Euler at step `D`, linear interpolation.
//!   It is about ten times weaker than a true class-C road; results obtained
//!   with it must say so.
//! - [`RoadSpec::Samples`]: a measured profile (t, x_g), linearly interpolated.
//! - [`RoadSpec::Input`]: a signal given from outside (the FMU input `x_g`),
//!   as a value plus a slope from the time it is set.
//!
//! The module's parts: [`spec`] (what road to apply), [`piece`] (a piece
//! with a closed form), `nodes` (the random roads' generator), `saved`
//! (the byte forms of the specification and the dynamic state, which both
//! engines save) and here the [`Road`] the solvers consume, with its saved
//! state.

mod nodes;
pub mod piece;
mod saved;
pub mod spec;

use crate::error::{Error, Result};
use nodes::{MAX_NODE, MAX_RESERVED_NODES, NODE_MARGIN, NODE_WINDOW, NodeSequence};
use piece::sample_piece;
use spec::finite;
use std::f64::consts::PI;
use std::sync::Arc;

pub use piece::RoadPiece;
pub(crate) use saved::RoadState;
pub use spec::{
    ISO_NODE_INTERVAL, REFERENCE_SPATIAL_FREQUENCY, RandomRoad, RoadClass, RoadShift, RoadSpec,
    RoadType,
};

/// The road as the simulator consumes it.
#[derive(Debug, Clone)]
pub struct Road {
    spec: RoadSpec,
    kind: RoadKind,
    /// The last linear piece handed out by a random or sampled road. Such a
    /// road's piece at t is the one whose `[start, end)` holds t, so a
    /// query inside the cached piece returns it unchanged (the cache never
    /// changes a result; it is not part of the saved state).
    cache: Option<RoadPiece>,
    /// A delayed random road's piece before its profile starts: `x_g = 0`
    /// from the start time to the profile's start ([`RoadShift`]); `None`
    /// for the other roads.
    lead: Option<RoadPiece>,
}

#[derive(Debug, Clone)]
enum RoadKind {
    Harmonic(RoadPiece),
    Nodes(Box<NodeSequence>),
    Samples(Arc<Vec<(f64, f64)>>),
    Input(RoadPiece),
}

impl Road {
    /// Builds the road for a simulation starting at `start_time` (random
    /// roads start at `x_g = 0` there, like the vehicle at rest).
    pub fn new(spec: &RoadSpec, start_time: f64) -> Result<Road> {
        Road::with_shift(spec, start_time, RoadShift::NONE)
    }

    /// [`Road::new`] as a wheel sees it with `shift`: the profile delayed
    /// by `shift.delay` (a random road then starts at `x_g = 0` at
    /// `start_time + delay`, 0 before), the harmonic road also moved by
    /// `shift.phase`.
    pub fn with_shift(spec: &RoadSpec, start_time: f64, shift: RoadShift) -> Result<Road> {
        spec.validate()?;
        shift.validate(spec)?;
        let delayed = shift.delay != 0.0;
        let profile_start = if delayed {
            start_time + shift.delay
        } else {
            start_time
        };
        let kind = match spec {
            RoadSpec::Input => RoadKind::Input(RoadPiece::Linear {
                start: start_time,
                end: f64::INFINITY,
                value: 0.0,
                slope: 0.0,
            }),
            RoadSpec::Harmonic {
                amplitude,
                angular_frequency,
            } => RoadKind::Harmonic(RoadPiece::Harmonic {
                amplitude: *amplitude,
                angular_frequency: *angular_frequency,
                phase: shift.phase - angular_frequency * shift.delay,
            }),
            RoadSpec::Iso8608(road) => {
                // Exact Ornstein–Uhlenbeck transition over one node interval.
                // The white noise of Eq. (27) is taken with one-sided unit
                // spectral density, i.e. intensity 1/2: this is what makes the
                // spatial PSD equal Gq(n0) (n/n0)^-2.
                let rate = 2.0 * PI * road.cutoff_frequency;
                let decay = crate::math::exp(-rate * ISO_NODE_INTERVAL);
                let diffusion = road.noise_gain() / std::f64::consts::SQRT_2;
                let gain = diffusion
                    * (-crate::math::exp_m1(-2.0 * rate * ISO_NODE_INTERVAL) / (2.0 * rate)).sqrt();
                RoadKind::Nodes(Box::new(NodeSequence::new(
                    profile_start,
                    ISO_NODE_INTERVAL,
                    decay,
                    gain,
                    road.seed,
                )))
            }
            RoadSpec::PaperCompatible {
                road,
                sample_interval,
            } => {
                let d = *sample_interval;
                let decay = 1.0 - 2.0 * PI * road.cutoff_frequency * d;
                RoadKind::Nodes(Box::new(NodeSequence::new(
                    profile_start,
                    d,
                    decay,
                    d * road.noise_gain(),
                    road.seed,
                )))
            }
            RoadSpec::Samples(samples) if delayed => RoadKind::Samples(Arc::new(
                samples.iter().map(|&(t, x)| (t + shift.delay, x)).collect(),
            )),
            RoadSpec::Samples(samples) => RoadKind::Samples(samples.clone()),
        };
        let random = matches!(kind, RoadKind::Nodes(_));
        Ok(Road {
            spec: spec.clone(),
            kind,
            cache: None,
            lead: (random && delayed).then_some(RoadPiece::Linear {
                start: start_time,
                end: profile_start,
                value: 0.0,
                slope: 0.0,
            }),
        })
    }

    /// The specification this road was built from.
    pub fn spec(&self) -> &RoadSpec {
        &self.spec
    }

    /// The piece valid at `t` (a right-continuous choice at breakpoints).
    /// The one piece of the harmonic and external roads, and the cached
    /// piece, are returned inline (every call of a step asks); a new piece
    /// of a random or sampled road is `Road::new_piece`'s.
    #[inline(always)]
    pub fn piece(&mut self, t: f64) -> RoadPiece {
        match &self.kind {
            RoadKind::Harmonic(piece) | RoadKind::Input(piece) => *piece,
            _ => match self.cache {
                Some(cached @ RoadPiece::Linear { start, end, .. }) if start <= t && t < end => {
                    cached
                }
                _ => self.new_piece(t),
            },
        }
    }

    /// [`Road::piece`] of a random or sampled road at a `t` outside the
    /// cached piece: found, and cached.
    #[inline(never)]
    fn new_piece(&mut self, t: f64) -> RoadPiece {
        let piece = match (&mut self.kind, self.lead) {
            // A delayed random road before its profile starts.
            (RoadKind::Nodes(_), Some(lead)) if t < lead.end() => lead,
            (RoadKind::Nodes(nodes), _) => nodes.piece(t),
            (RoadKind::Samples(samples), _) => sample_piece(samples, t),
            (RoadKind::Harmonic(piece) | RoadKind::Input(piece), _) => *piece,
        };
        self.cache = Some(piece);
        piece
    }

    /// The harmonic road's one piece (`None` for the other roads).
    pub fn harmonic(&self) -> Option<RoadPiece> {
        match self.kind {
            RoadKind::Harmonic(piece) => Some(piece),
            _ => None,
        }
    }

    /// `x_g(t)` (m).
    pub fn value(&mut self, t: f64) -> f64 {
        self.piece(t).value(t)
    }

    /// Checks an external input value and slope (finite).
    pub fn check_input(value: f64, slope: f64) -> Result<()> {
        finite("x_g", value)?;
        finite("slope of x_g", slope)
    }

    /// Sets the external input (only for [`RoadSpec::Input`]): from time
    /// `t` on, `x_g = value + slope (t' − t)`.
    pub fn set_input(&mut self, t: f64, value: f64, slope: f64) -> Result<()> {
        Road::check_input(value, slope)?;
        match &mut self.kind {
            RoadKind::Input(piece) => {
                *piece = RoadPiece::Linear {
                    start: t,
                    end: f64::INFINITY,
                    value,
                    slope,
                };
                Ok(())
            }
            _ => Err(Error::InvalidSetting {
                name: "road",
                value: 0,
                reason: "the input x_g is only used when road = 0",
            }),
        }
    }

    /// Whether the road comes from outside.
    pub fn is_input(&self) -> bool {
        matches!(self.kind, RoadKind::Input(_))
    }

    /// Makes room for the generated nodes of `span` seconds (at least 64),
    /// so that generating them allocates nothing: the solver keeps the
    /// nodes from the step before its committed point to the end of the
    /// next step (`span` = a few internal steps).
    pub fn reserve_window(&mut self, span: f64) {
        if let RoadKind::Nodes(nodes) = &mut self.kind {
            let wanted = (span / nodes.interval).ceil();
            let wanted = if wanted.is_finite() && wanted > 0.0 {
                (wanted as usize).min(MAX_RESERVED_NODES)
            } else {
                0
            };
            let room = (wanted + NODE_MARGIN).max(NODE_WINDOW);
            let length = nodes.nodes.len();
            if nodes.nodes.capacity() < room {
                nodes.nodes.reserve(room.saturating_sub(length));
            }
        }
    }

    /// Frees generated nodes that lie wholly before `t`.
    pub fn release_before(&mut self, t: f64) {
        if let RoadKind::Nodes(nodes) = &mut self.kind {
            nodes.release_before(t);
        }
    }

    /// The interval (s) between a random road's nodes, `None` for the
    /// other roads.
    pub fn node_interval(&self) -> Option<f64> {
        match &self.kind {
            RoadKind::Nodes(nodes) => Some(nodes.interval),
            _ => None,
        }
    }

    /// The time (s) of a random road's oldest node kept: the road is known
    /// from there on (−∞ for the other roads).
    pub fn earliest_time(&self) -> f64 {
        match &self.kind {
            // A delayed road is 0 before its first node.
            RoadKind::Nodes(nodes) if nodes.first == 0 && self.lead.is_some() => f64::NEG_INFINITY,
            RoadKind::Nodes(nodes) => nodes.node_time(nodes.first),
            _ => f64::NEG_INFINITY,
        }
    }

    /// A random road's node work of a query at `t` after the nodes before
    /// `from` are released: the nodes it generates and the nodes then kept
    /// (`(0, 0)` for the other roads), counted in f64 so that no time
    /// overflows them.
    pub fn node_work(&self, from: f64, t: f64) -> (f64, f64) {
        match &self.kind {
            RoadKind::Nodes(nodes) => {
                let last = nodes.node_time(nodes.first + nodes.nodes.len() as u64 - 1);
                let oldest = nodes.node_time(nodes.first).max(from);
                let generated = ((t - last) / nodes.interval + 1.0).max(0.0);
                let kept = (t.max(last) - oldest) / nodes.interval + 2.0;
                (generated, kept)
            }
            _ => (0.0, 0.0),
        }
    }

    /// The generator's dynamic state, for saving: (random word position,
    /// first node index, node values, current input piece).
    pub(crate) fn dynamic_state(&self) -> RoadState {
        match &self.kind {
            RoadKind::Nodes(n) => RoadState {
                word_position: n.rng.get_word_pos(),
                first_node: n.first,
                nodes: n.nodes.iter().copied().collect(),
                input: None,
            },
            RoadKind::Input(RoadPiece::Linear {
                start,
                value,
                slope,
                ..
            }) => RoadState {
                input: Some((*start, *value, *slope)),
                ..RoadState::default()
            },
            _ => RoadState::default(),
        }
    }

    /// The generated nodes of a random road (its [`Road::dynamic_state`]),
    /// `None` for the other roads.
    pub(crate) fn node_state(&self) -> Option<RoadState> {
        matches!(self.kind, RoadKind::Nodes(_)).then(|| self.dynamic_state())
    }

    /// Restores the generator and nodes of a random road that
    /// [`Road::node_state`] returned, for a Model Exchange model: any window
    /// of nodes is taken (the model keeps those of the times a master may
    /// still go back to), up to node [`MAX_NODE`].
    pub(crate) fn restore_nodes(&mut self, state: &RoadState) -> Result<()> {
        let RoadKind::Nodes(n) = &mut self.kind else {
            return Err(Error::InvalidState(
                "road nodes for a road without them".into(),
            ));
        };
        let count = state.nodes.len() as u64;
        if count == 0 || state.first_node.saturating_add(count) > MAX_NODE {
            return Err(Error::InvalidState(format!(
                "road first_node {} with {count} nodes (at least one, up to node {MAX_NODE})",
                state.first_node
            )));
        }
        self.cache = None;
        n.restore(state);
        Ok(())
    }

    /// Restores what [`Road::dynamic_state`] returned, for a simulator whose
    /// committed state is at `committed_time` and which will query the road
    /// up to `horizon` before committing again. Checked against these
    /// times, so that a restored road never has to generate nodes it could
    /// not have generated by then:
    /// - a random road's nodes `first_node ..= first_node + count − 1` hold
    ///   the node whose interval holds `committed_time` (it was not
    ///   released, and the nodes from there on need not be generated again)
    ///   and end at most two nodes after the one holding `horizon`;
    /// - an external input is finite and was set at or before
    ///   `committed_time`.
    pub(crate) fn restore_dynamic_state(
        &mut self,
        state: &RoadState,
        committed_time: f64,
        horizon: f64,
    ) -> Result<()> {
        self.cache = None;
        match &mut self.kind {
            RoadKind::Nodes(n) => {
                let (first, count) = (state.first_node, state.nodes.len() as u64);
                let (held, last) = (n.index_at(committed_time), n.index_at(horizon) + 2);
                if count == 0 {
                    return Err(Error::InvalidState("random road without nodes".into()));
                }
                if first > held || first.saturating_add(count) <= held {
                    return Err(Error::InvalidState(format!(
                        "road first_node {first} with {count} nodes does not hold node {held}, \
                         where committed_time {committed_time} s lies"
                    )));
                }
                if first.saturating_add(count - 1) > last {
                    return Err(Error::InvalidState(format!(
                        "road first_node {first} with {count} nodes extends past node {last}, \
                         two after the one holding {horizon} s"
                    )));
                }
                n.restore(state);
                Ok(())
            }
            RoadKind::Input(piece) => {
                let (start, value, slope) = state
                    .input
                    .ok_or_else(|| Error::InvalidState("input road without its input".into()))?;
                if !(start <= committed_time && [start, value, slope].iter().all(|v| v.is_finite()))
                {
                    return Err(Error::InvalidState(format!(
                        "road input set at {start} s (x_g = {value} m, slope {slope} m/s) \
                         is not finite or after committed_time {committed_time} s"
                    )));
                }
                *piece = RoadPiece::Linear {
                    start,
                    end: f64::INFINITY,
                    value,
                    slope,
                };
                Ok(())
            }
            _ => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests;
