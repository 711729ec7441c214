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

use crate::error::{Error, Result};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use std::collections::VecDeque;
use std::f64::consts::PI;
use std::sync::Arc;

/// Reference spatial frequency n0 of ISO 8608 (1/m).
pub const REFERENCE_SPATIAL_FREQUENCY: f64 = 0.1;
/// Time between the nodes of the ISO 8608 road (s). At 20 m/s this is a
/// 2 cm spatial resolution, far above every resonance of the quarter car.
pub const ISO_NODE_INTERVAL: f64 = 1e-3;

/// ISO 8608 road class A..H.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RoadClass {
    A,
    B,
    C,
    D,
    E,
    F,
    G,
    H,
}

impl RoadClass {
    /// Classes in order, index 0 = A.
    pub const ALL: [RoadClass; 8] = [
        RoadClass::A,
        RoadClass::B,
        RoadClass::C,
        RoadClass::D,
        RoadClass::E,
        RoadClass::F,
        RoadClass::G,
        RoadClass::H,
    ];

    /// From the FMU's integer code 1..8 = A..H.
    pub fn from_code(code: i64) -> Result<RoadClass> {
        if (1..=8).contains(&code) {
            Ok(RoadClass::ALL[(code - 1) as usize])
        } else {
            Err(Error::InvalidSetting {
                name: "road_class",
                value: code,
                reason: "must be 1..8 (ISO 8608 class A..H)",
            })
        }
    }

    /// The FMU's integer code 1..8.
    pub fn code(self) -> i32 {
        RoadClass::ALL.iter().position(|&c| c == self).unwrap_or(0) as i32 + 1
    }

    /// Road roughness coefficient Gq(n0) in m³ (geometric mean of the
    /// class): A 16e-6, B 64e-6, C 256e-6 ... H 262144e-6.
    pub fn roughness(self) -> f64 {
        16e-6 * 4f64.powi(self.code() - 1)
    }
}

impl std::str::FromStr for RoadClass {
    type Err = Error;
    fn from_str(s: &str) -> Result<RoadClass> {
        let c = s.trim().to_ascii_uppercase();
        RoadClass::ALL
            .iter()
            .find(|k| format!("{k:?}") == c)
            .copied()
            .ok_or_else(|| Error::UnknownName {
                what: "road class",
                given: s.to_string(),
                expected: "an ISO 8608 class A..H (any case)",
            })
    }
}

/// Parameters shared by the two random roads.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RandomRoad {
    /// ISO 8608 class.
    pub class: RoadClass,
    /// Vehicle speed u (m/s).
    pub speed: f64,
    /// Lower cut-off frequency f0 (Hz).
    pub cutoff_frequency: f64,
    /// Seed: the same seed gives the same road.
    pub seed: u64,
}

impl Default for RandomRoad {
    /// Class C at 20 m/s, f0 = 0.1 Hz, seed 1 (section 5.2).
    fn default() -> Self {
        RandomRoad {
            class: RoadClass::C,
            speed: 20.0,
            cutoff_frequency: 0.1,
            seed: 1,
        }
    }
}

impl RandomRoad {
    fn validate(&self) -> Result<()> {
        positive("vehicle_speed", self.speed)?;
        positive("road_cutoff_frequency", self.cutoff_frequency)
    }

    /// Gain `2π n0 sqrt(Gq(n0) u)` of the white noise in Eq. (27).
    pub fn noise_gain(&self) -> f64 {
        2.0 * PI * REFERENCE_SPATIAL_FREQUENCY * (self.class.roughness() * self.speed).sqrt()
    }
}

/// What road to apply.
/// The integer code of each kind of road: the FMU's `road` parameter
/// (0 to 3) and the saved state (which also knows roads read from a file).
/// This is the one place the codes are declared.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RoadType {
    /// 0: the external input `x_g`.
    Input = 0,
    /// 1: the harmonic road.
    Harmonic = 1,
    /// 2: the ISO 8608 road.
    Iso8608 = 2,
    /// 3: the paper-compatible random road.
    PaperCompatible = 3,
    /// 4: samples read from a file (not an FMU setting).
    Samples = 4,
}

impl RoadType {
    /// The integer code.
    pub fn code(self) -> i64 {
        self as i64
    }

    /// The road type of a code, if it is one.
    pub fn from_code(code: i64) -> Option<RoadType> {
        [
            RoadType::Input,
            RoadType::Harmonic,
            RoadType::Iso8608,
            RoadType::PaperCompatible,
            RoadType::Samples,
        ]
        .into_iter()
        .find(|t| t.code() == code)
    }
}

#[derive(Debug, Clone, PartialEq)]
pub enum RoadSpec {
    /// External signal set through [`Road::set_input`].
    Input,
    /// `x_g = amplitude · sin(angular_frequency · t)` (m, rad/s).
    Harmonic {
        amplitude: f64,
        angular_frequency: f64,
    },
    /// The ISO 8608 filtered-white-noise road.
    Iso8608(RandomRoad),
    /// The paper-compatible random road; `sample_interval` is D (s).
    PaperCompatible {
        road: RandomRoad,
        sample_interval: f64,
    },
    /// Samples (t in s, x_g in m), strictly increasing in t.
    Samples(Arc<Vec<(f64, f64)>>),
}

impl RoadSpec {
    /// The paper's harmonic road `x_g = 0.05 sin(5 t)`.
    pub fn paper_harmonic() -> RoadSpec {
        RoadSpec::Harmonic {
            amplitude: 0.05,
            angular_frequency: 5.0,
        }
    }

    /// The road's [`RoadType`] (its integer code).
    pub fn road_type(&self) -> RoadType {
        match self {
            RoadSpec::Input => RoadType::Input,
            RoadSpec::Harmonic { .. } => RoadType::Harmonic,
            RoadSpec::Iso8608(_) => RoadType::Iso8608,
            RoadSpec::PaperCompatible { .. } => RoadType::PaperCompatible,
            RoadSpec::Samples(_) => RoadType::Samples,
        }
    }

    /// Short name of the kind of road (`input`, `harmonic`, `iso8608`,
    /// `paper`, `file`).
    pub fn kind(&self) -> &'static str {
        match self {
            RoadSpec::Input => "input",
            RoadSpec::Harmonic { .. } => "harmonic",
            RoadSpec::Iso8608(_) => "iso8608",
            RoadSpec::PaperCompatible { .. } => "paper",
            RoadSpec::Samples(_) => "file",
        }
    }

    /// Checks every field; the error names the FMU variable.
    pub fn validate(&self) -> Result<()> {
        match self {
            RoadSpec::Input => Ok(()),
            RoadSpec::Harmonic {
                amplitude,
                angular_frequency,
            } => {
                finite("road_amplitude", *amplitude)?;
                finite("road_angular_frequency", *angular_frequency)
            }
            RoadSpec::Iso8608(r) => r.validate(),
            RoadSpec::PaperCompatible {
                road,
                sample_interval,
            } => {
                road.validate()?;
                positive("road_sample_interval", *sample_interval)
            }
            RoadSpec::Samples(samples) => validate_samples(samples),
        }
    }

    /// The last sample of a sampled road: (t in s, x_g in m). A sampled road
    /// holds this value after `t` (and its first value before its first
    /// sample). `None` for the other roads, which never end.
    pub fn last_sample(&self) -> Option<(f64, f64)> {
        match self {
            RoadSpec::Samples(samples) => samples.last().copied(),
            _ => None,
        }
    }

    /// Reads a CSV file of `t,x_g` rows (a header line is allowed).
    pub fn from_csv_file(path: &str) -> Result<RoadSpec> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::RoadFile {
            path: path.to_string(),
            reason: e.to_string(),
        })?;
        let mut samples = Vec::new();
        for (line_number, line) in text.lines().enumerate() {
            let line = line.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let fields: Vec<&str> = line.split([',', ';', '\t', ' ']).collect();
            let parsed: Option<Vec<f64>> = fields
                .iter()
                .filter(|f| !f.is_empty())
                .map(|f| f.parse::<f64>().ok())
                .collect();
            match parsed.as_deref() {
                Some([t, x, ..]) => samples.push((*t, *x)),
                _ if samples.is_empty() && line_number == 0 => continue,
                _ => {
                    return Err(Error::RoadFile {
                        path: path.to_string(),
                        reason: format!(
                            "line {}: expected `t,x_g`, found `{line}`",
                            line_number + 1
                        ),
                    });
                }
            }
        }
        validate_samples(&samples).map_err(|e| Error::RoadFile {
            path: path.to_string(),
            reason: e.to_string(),
        })?;
        Ok(RoadSpec::Samples(Arc::new(samples)))
    }
}

fn finite(name: &'static str, value: f64) -> Result<()> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(Error::InvalidParameter {
            name,
            value,
            reason: "must be finite",
        })
    }
}

fn positive(name: &'static str, value: f64) -> Result<()> {
    finite(name, value)?;
    if value > 0.0 {
        Ok(())
    } else {
        Err(Error::InvalidParameter {
            name,
            value,
            reason: "must be > 0",
        })
    }
}

fn validate_samples(samples: &[(f64, f64)]) -> Result<()> {
    if samples.is_empty() {
        return Err(Error::InvalidSetting {
            name: "road",
            value: 0,
            reason: "a sampled road needs at least one (t, x_g) sample",
        });
    }
    for (i, &(t, x)) in samples.iter().enumerate() {
        finite("road sample time", t)?;
        finite("road sample displacement", x)?;
        if i > 0 && t <= samples[i - 1].0 {
            return Err(Error::InvalidParameter {
                name: "road sample time",
                value: t,
                reason: "sample times must be strictly increasing",
            });
        }
    }
    Ok(())
}

/// A piece of road over which `x_g` has a closed form.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RoadPiece {
    /// `x_g(t) = amplitude sin(angular_frequency t)` for every t.
    Harmonic {
        amplitude: f64,
        angular_frequency: f64,
    },
    /// `x_g(t) = value + slope (t − start)` on `[start, end)`.
    Linear {
        start: f64,
        end: f64,
        value: f64,
        slope: f64,
    },
}

impl RoadPiece {
    /// `x_g(t)` (m).
    #[inline]
    pub fn value(&self, t: f64) -> f64 {
        match *self {
            RoadPiece::Harmonic {
                amplitude,
                angular_frequency,
            } => amplitude * crate::math::sin(angular_frequency * t),
            RoadPiece::Linear {
                start,
                value,
                slope,
                ..
            } => value + slope * (t - start),
        }
    }

    /// `dx_g/dt` (m/s).
    #[inline]
    pub fn slope(&self, t: f64) -> f64 {
        match *self {
            RoadPiece::Harmonic {
                amplitude,
                angular_frequency,
            } => amplitude * angular_frequency * crate::math::cos(angular_frequency * t),
            RoadPiece::Linear { slope, .. } => slope,
        }
    }

    /// `[x_g, x_g', x_g'', x_g''']` at t (m, m/s, m/s², m/s³): of the
    /// harmonic piece `A sin ω t` (`sin ω t` and `cos ω t` from one
    /// [`crate::math::sin_cos`]), of a linear piece its value and slope.
    #[inline]
    pub fn derivatives(&self, t: f64) -> [f64; 4] {
        match *self {
            RoadPiece::Harmonic {
                amplitude: a,
                angular_frequency: w,
            } => {
                let (sin, cos) = crate::math::sin_cos(w * t);
                [a * sin, a * w * cos, -a * w * w * sin, -a * w * w * w * cos]
            }
            RoadPiece::Linear { .. } => [self.value(t), self.slope(t), 0.0, 0.0],
        }
    }

    /// Bounds of `|x_g|, |x_g'|, |x_g''|, |x_g'''|` over the piece from t
    /// on (the harmonic piece's `|A| |ω|^j`; a linear piece's value at t
    /// and its slope).
    #[inline]
    pub fn derivative_bounds(&self, t: f64) -> [f64; 4] {
        match *self {
            RoadPiece::Harmonic {
                amplitude,
                angular_frequency,
            } => {
                let (a, w) = (amplitude.abs(), angular_frequency.abs());
                [a, a * w, a * w * w, a * w * w * w]
            }
            RoadPiece::Linear { .. } => [self.value(t).abs(), self.slope(t).abs(), 0.0, 0.0],
        }
    }

    /// End of the piece's validity (`+inf` for the harmonic road).
    #[inline]
    pub fn end(&self) -> f64 {
        match *self {
            RoadPiece::Harmonic { .. } => f64::INFINITY,
            RoadPiece::Linear { end, .. } => end,
        }
    }
}

/// Largest index of a random road node (2^53, where node indices stop
/// being exact in f64). The road holds the value of this node after its
/// time, so a piece lookup never needs node `n + 1` beyond it.
const MAX_NODE: u64 = 1 << 53;

/// Room for generated road nodes made with the road.
const NODE_WINDOW: usize = 64;
/// Nodes reserved beyond those of the span asked for
/// ([`Road::reserve_window`]).
const NODE_MARGIN: usize = 8;
/// Most nodes [`Road::reserve_window`] reserves (8 MB of nodes).
const MAX_RESERVED_NODES: usize = 1 << 20;

/// Random road node generator: node `n` is at `origin + n · interval`.
#[derive(Debug, Clone)]
struct NodeSequence {
    origin: f64,
    interval: f64,
    /// `x_{n+1} = decay x_n + gain ξ_n` with ξ_n ~ N(0, 1).
    decay: f64,
    gain: f64,
    seed: u64,
    rng: ChaCha8Rng,
    /// Index of `nodes[0]`.
    first: u64,
    nodes: VecDeque<f64>,
}

impl NodeSequence {
    fn new(origin: f64, interval: f64, decay: f64, gain: f64, seed: u64) -> NodeSequence {
        NodeSequence {
            origin,
            interval,
            decay,
            gain,
            seed,
            rng: ChaCha8Rng::seed_from_u64(seed),
            first: 0,
            nodes: Self::window(),
        }
    }

    /// The generated nodes at the start: node 0, with room for
    /// [`NODE_WINDOW`] (the solver releases the nodes behind its committed
    /// point as it goes, so a run keeps a few; generating them allocates
    /// nothing).
    fn window() -> VecDeque<f64> {
        let mut nodes = VecDeque::with_capacity(NODE_WINDOW);
        nodes.push_back(0.0);
        nodes
    }

    fn node_time(&self, n: u64) -> f64 {
        self.origin + n as f64 * self.interval
    }

    fn node(&mut self, n: u64) -> f64 {
        debug_assert!(n >= self.first, "road node {n} was released");
        while self.first + self.nodes.len() as u64 <= n {
            let last = *self.nodes.back().unwrap_or(&0.0);
            let xi: f64 = StandardNormal.sample(&mut self.rng);
            self.nodes.push_back(self.decay * last + self.gain * xi);
        }
        self.nodes[(n - self.first.min(n)) as usize]
    }

    /// The node whose interval holds `t`: the largest `n <= MAX_NODE` with
    /// `node_time(n) <= t` (0 before the origin or for NaN). The floor of
    /// `(t − origin) / interval` is corrected against rounding by a bounded
    /// search, also where many nodes share one floating-point time (an
    /// interval below the spacing of floats at t).
    fn index_at(&self, t: f64) -> u64 {
        // `as` saturates and maps NaN to 0; the search clamps to MAX_NODE.
        let estimate = ((t - self.origin) / self.interval).floor() as u64;
        crate::monotone::last_index_where(0, MAX_NODE, estimate, |n| self.node_time(n) <= t)
    }

    /// The linear piece whose `[start, end)` holds `t` (the first piece
    /// before the origin; from node [`MAX_NODE`] on, its value held).
    fn piece(&mut self, t: f64) -> RoadPiece {
        let n = self.index_at(t).max(self.first);
        let (x0, start) = (self.node(n), self.node_time(n));
        if n >= MAX_NODE {
            return RoadPiece::Linear {
                start,
                end: f64::INFINITY,
                value: x0,
                slope: 0.0,
            };
        }
        let (x1, end) = (self.node(n + 1), self.node_time(n + 1));
        RoadPiece::Linear {
            start,
            end,
            value: x0,
            slope: (x1 - x0) / (end - start),
        }
    }

    /// Takes the generator's position and the nodes of `state`.
    fn restore(&mut self, state: &RoadState) {
        self.rng = ChaCha8Rng::seed_from_u64(self.seed);
        self.rng.set_word_pos(state.word_position);
        self.first = state.first_node;
        self.nodes = state.nodes.iter().copied().collect();
    }

    fn release_before(&mut self, t: f64) {
        while self.nodes.len() > 2 && self.node_time(self.first + 1) <= t {
            self.nodes.pop_front();
            self.first += 1;
        }
    }
}

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
        spec.validate()?;
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
                    start_time,
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
                    start_time,
                    d,
                    decay,
                    d * road.noise_gain(),
                    road.seed,
                )))
            }
            RoadSpec::Samples(samples) => RoadKind::Samples(samples.clone()),
        };
        Ok(Road {
            spec: spec.clone(),
            kind,
            cache: None,
        })
    }

    /// The specification this road was built from.
    pub fn spec(&self) -> &RoadSpec {
        &self.spec
    }

    /// The piece valid at `t` (a right-continuous choice at breakpoints).
    #[inline]
    pub fn piece(&mut self, t: f64) -> RoadPiece {
        match &mut self.kind {
            RoadKind::Harmonic(piece) | RoadKind::Input(piece) => *piece,
            kind => {
                if let Some(cached @ RoadPiece::Linear { start, end, .. }) = self.cache
                    && start <= t
                    && t < end
                {
                    return cached;
                }
                let piece = match kind {
                    RoadKind::Nodes(nodes) => nodes.piece(t),
                    RoadKind::Samples(samples) => sample_piece(samples, t),
                    RoadKind::Harmonic(piece) | RoadKind::Input(piece) => *piece,
                };
                self.cache = Some(piece);
                piece
            }
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

/// Saved dynamic state of a [`Road`].
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct RoadState {
    pub word_position: u128,
    pub first_node: u64,
    pub nodes: Vec<f64>,
    pub input: Option<(f64, f64, f64)>,
}

fn sample_piece(samples: &[(f64, f64)], t: f64) -> RoadPiece {
    let after = samples.partition_point(|&(ts, _)| ts <= t);
    if after == 0 {
        let (t0, x0) = samples[0];
        return RoadPiece::Linear {
            start: t0,
            end: t0,
            value: x0,
            slope: 0.0,
        };
    }
    let (t0, x0) = samples[after - 1];
    match samples.get(after) {
        Some(&(t1, x1)) => RoadPiece::Linear {
            start: t0,
            end: t1,
            value: x0,
            slope: (x1 - x0) / (t1 - t0),
        },
        None => RoadPiece::Linear {
            start: t0,
            end: f64::INFINITY,
            value: x0,
            slope: 0.0,
        },
    }
}

#[cfg(test)]
mod tests;
