//! What road to apply: the specification of every kind of road (harmonic,
//! ISO 8608, paper-compatible, samples, the external input), its integer
//! codes, the ISO 8608 classes and the random roads' parameters, each
//! checked.

use crate::error::{Error, Result};
use std::f64::consts::PI;
use std::sync::Arc;

/// How a wheel of a vehicle sees a built-in road: the profile delayed (a
/// rear wheel follows its front wheel by wheelbase / speed) and, on the
/// harmonic road, a phase (a right track out of step with the left, which
/// excites roll): `x_g(t) = profile(t − delay)`, the harmonic road
/// `A sin(ω (t − delay) + phase)`. A random road's profile starts at 0 at
/// `start_time + delay` and is 0 before.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RoadShift {
    /// The delay (s, ≥ 0).
    pub delay: f64,
    /// The harmonic road's phase (rad).
    pub phase: f64,
}

impl RoadShift {
    /// The road as it is.
    pub const NONE: RoadShift = RoadShift {
        delay: 0.0,
        phase: 0.0,
    };

    /// Checks the shift for the road `spec`; the error names the FMU
    /// variable (`road_delay`, `road_phase`).
    pub fn validate(&self, spec: &RoadSpec) -> Result<()> {
        finite("road_delay", self.delay)?;
        finite("road_phase", self.phase)?;
        if self.delay < 0.0 {
            return Err(Error::InvalidParameter {
                name: "road_delay",
                value: self.delay,
                reason: "must not be negative (a wheel sees the road after the wheel ahead of it)",
            });
        }
        if self.delay != 0.0 && matches!(spec, RoadSpec::Input) {
            return Err(Error::InvalidParameter {
                name: "road_delay",
                value: self.delay,
                reason: "applies to the built-in roads; the input x_g (road = 0) is the road as the wheel sees it",
            });
        }
        if self.phase != 0.0 && !matches!(spec, RoadSpec::Harmonic { .. }) {
            return Err(Error::InvalidParameter {
                name: "road_phase",
                value: self.phase,
                reason: "only the harmonic road (road = 1) has a phase",
            });
        }
        Ok(())
    }
}

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
    /// External signal set through [`super::Road::set_input`].
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

pub(super) fn finite(name: &'static str, value: f64) -> Result<()> {
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
