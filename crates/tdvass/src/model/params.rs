//! The model's data: the state vector and its indices, the three variants,
//! the parameters of Table 1 with their checks and their byte form.
//!
//! Layer: data (docs/architecture.md), the model's ground; it imports the
//! crate's `bytes`, `error`.

use crate::bytes::{ByteReader, ByteWriter};
use crate::error::{Error, Result};
use nalgebra::Vector6;

/// 6-vector of the state or of an input column.
pub type State = Vector6<f64>;

/// Index of the body displacement `x_s` in the state.
pub const X_S: usize = 0;
/// Index of the body velocity `v_s`.
pub const V_S: usize = 1;
/// Index of the absorber displacement `x_h`.
pub const X_H: usize = 2;
/// Index of the absorber velocity `v_h`.
pub const V_H: usize = 3;
/// Index of the tire (wheel) displacement `x_t`.
pub const X_T: usize = 4;
/// Index of the tire (wheel) velocity `v_t`.
pub const V_T: usize = 5;
/// Names of the state components, in state order.
pub const STATE_NAMES: [&str; 6] = ["x_s", "v_s", "x_h", "v_h", "x_t", "v_t"];

/// The three suspensions compared in the paper.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Variant {
    /// Conventional 2-DOF quarter car (body and wheel joined by k_s, c_s).
    Cs,
    /// 3-DOF suspension with the annular absorber, no control (g = 0).
    Pvass,
    /// PVASS plus tire-displacement time-delay feedback `u = g x_t(t - tau)`.
    Tdvass,
}

impl Variant {
    /// All variants in the paper's order.
    pub const ALL: [Variant; 3] = [Variant::Cs, Variant::Pvass, Variant::Tdvass];

    /// The FMU's integer code: 1 = CS, 2 = PVASS, 3 = TDVASS.
    pub fn code(self) -> i32 {
        match self {
            Variant::Cs => 1,
            Variant::Pvass => 2,
            Variant::Tdvass => 3,
        }
    }

    /// Inverse of [`Variant::code`].
    pub fn from_code(code: i64) -> Result<Variant> {
        match code {
            1 => Ok(Variant::Cs),
            2 => Ok(Variant::Pvass),
            3 => Ok(Variant::Tdvass),
            _ => Err(Error::InvalidSetting {
                name: "variant",
                value: code,
                reason: "must be 1 (CS), 2 (PVASS) or 3 (TDVASS)",
            }),
        }
    }

    /// Lower-case name as used on the command line (`cs`, `pvass`, `tdvass`).
    pub fn name(self) -> &'static str {
        match self {
            Variant::Cs => "cs",
            Variant::Pvass => "pvass",
            Variant::Tdvass => "tdvass",
        }
    }

    /// The paper's upper-case label.
    pub fn label(self) -> &'static str {
        match self {
            Variant::Cs => "CS",
            Variant::Pvass => "PVASS",
            Variant::Tdvass => "TDVASS",
        }
    }

    /// Whether the delayed feedback `u = g x_t(t - tau)` acts.
    pub fn has_control(self) -> bool {
        self == Variant::Tdvass
    }

    /// Whether the annular absorber (m_h, k_h, c_h) is present.
    pub fn has_absorber(self) -> bool {
        self != Variant::Cs
    }
}

impl std::str::FromStr for Variant {
    type Err = Error;
    fn from_str(s: &str) -> Result<Variant> {
        match s.to_ascii_lowercase().as_str() {
            "cs" | "1" => Ok(Variant::Cs),
            "pvass" | "2" => Ok(Variant::Pvass),
            "tdvass" | "3" => Ok(Variant::Tdvass),
            _ => Err(Error::UnknownName {
                what: "variant",
                given: s.to_string(),
                expected: "cs, pvass or tdvass (or their codes 1, 2, 3; any case)",
            }),
        }
    }
}

/// Physical parameters of the quarter car (Table 1) and of the controller.
///
/// Units: masses in kg, stiffnesses and the gain in N/m, dampings in N·s/m,
/// the delay in s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Params {
    /// Body (sprung) mass m_s.
    pub m_s: f64,
    /// Annular absorber mass m_h (0.1 m_t in the paper).
    pub m_h: f64,
    /// Wheel mass m_t.
    pub m_t: f64,
    /// Suspension stiffness k_s.
    pub k_s: f64,
    /// Absorber stiffness k_h.
    pub k_h: f64,
    /// Tire stiffness k_t.
    pub k_t: f64,
    /// Suspension damping c_s.
    pub c_s: f64,
    /// Absorber damping c_h.
    pub c_h: f64,
    /// Feedback gain g of `u = g x_t(t - tau)` (TDVASS only).
    pub g: f64,
    /// Feedback delay tau (TDVASS only).
    pub tau: f64,
}

/// Standard acceleration of gravity g0 (m/s²), ISO 80000-3 (and
/// ISO 2631-1's unit of acceleration).
pub const STANDARD_GRAVITY: f64 = 9.80665;

/// The paper's harmonic-road optimum `g1` (N/m), section 4.2.
pub const PAPER_G1: f64 = 5386.0;
/// The paper's harmonic-road optimum `tau1` (s), section 4.2.
pub const PAPER_TAU1: f64 = 2e-4;
/// The paper's random-road optimum `g2` (N/m), section 4.2.
pub const PAPER_G2: f64 = 2528.0;
/// The paper's random-road optimum `tau2` (s), section 4.2.
pub const PAPER_TAU2: f64 = 1.28e-4;

impl Default for Params {
    /// Table 1 with the harmonic-road controller (g1, tau1).
    fn default() -> Self {
        Params {
            m_s: 345.0,
            m_h: 4.05,
            m_t: 40.5,
            k_s: 16000.0,
            k_h: 6444.0,
            k_t: 190000.0,
            c_s: 1500.0,
            c_h: 348.0,
            g: PAPER_G1,
            tau: PAPER_TAU1,
        }
    }
}

/// `Ok` when `value` is finite and `ok`; else the error naming `name` and
/// `value` ("must be finite", or `reason`).
pub(crate) fn check(name: &'static str, value: f64, ok: bool, reason: &'static str) -> Result<()> {
    if !value.is_finite() {
        return Err(Error::InvalidParameter {
            name,
            value,
            reason: "must be finite",
        });
    }
    if ok {
        Ok(())
    } else {
        Err(Error::InvalidParameter {
            name,
            value,
            reason,
        })
    }
}

impl Params {
    /// Table 1 with the given controller.
    pub fn with_controller(g: f64, tau: f64) -> Params {
        Params {
            g,
            tau,
            ..Params::default()
        }
    }

    /// Names and values of every parameter, in declaration order.
    pub fn named_values(&self) -> [(&'static str, f64); 10] {
        [
            ("m_s", self.m_s),
            ("m_h", self.m_h),
            ("m_t", self.m_t),
            ("k_s", self.k_s),
            ("k_h", self.k_h),
            ("k_t", self.k_t),
            ("c_s", self.c_s),
            ("c_h", self.c_h),
            ("g", self.g),
            ("tau", self.tau),
        ]
    }

    /// Writes every parameter, in the order of [`Params::named_values`].
    pub(crate) fn write(&self, w: &mut ByteWriter) {
        self.named_values().iter().for_each(|(_, v)| w.f64(*v));
    }

    /// Reads what [`Params::write`] wrote (checked by [`Params::validate`]
    /// where the configuration is) in the saved-state format `version`:
    /// a parameter added in a later format takes its default from the
    /// bytes of an earlier one (every parameter is in every format read
    /// today).
    pub(crate) fn read(r: &mut ByteReader, _version: u64) -> Result<Params> {
        // Field initialisers run in the order written: that of
        // `named_values`.
        Ok(Params {
            m_s: r.f64()?,
            m_h: r.f64()?,
            m_t: r.f64()?,
            k_s: r.f64()?,
            k_h: r.f64()?,
            k_t: r.f64()?,
            c_s: r.f64()?,
            c_h: r.f64()?,
            g: r.f64()?,
            tau: r.f64()?,
        })
    }

    /// Checks that masses are > 0, stiffnesses and dampings >= 0, tau >= 0
    /// and everything is finite. The error names the parameter and value.
    pub fn validate(&self) -> Result<()> {
        for (name, value) in [("m_s", self.m_s), ("m_h", self.m_h), ("m_t", self.m_t)] {
            check(name, value, value > 0.0, "a mass must be > 0")?;
        }
        for (name, value) in [
            ("k_s", self.k_s),
            ("k_h", self.k_h),
            ("k_t", self.k_t),
            ("c_s", self.c_s),
            ("c_h", self.c_h),
        ] {
            check(
                name,
                value,
                value >= 0.0,
                "a stiffness or damping must be >= 0",
            )?;
        }
        check("g", self.g, true, "")?;
        check("tau", self.tau, self.tau >= 0.0, "the delay must be >= 0")?;
        Ok(())
    }

    /// The gain that acts in `variant` (g for TDVASS, 0 otherwise).
    pub fn effective_gain(&self, variant: Variant) -> f64 {
        if variant.has_control() { self.g } else { 0.0 }
    }

    /// Static tire load W (N): the weight on the tire,
    /// `(m_s + m_h + m_t) g0` for PVASS and TDVASS, `(m_s + m_t) g0` for
    /// the CS (which has no absorber mass), with the standard gravity
    /// [`STANDARD_GRAVITY`]. The tire keeps contact while the dynamic tire
    /// load `k_t (x_g − x_t)` stays above `−W`.
    pub fn static_load(&self, variant: Variant) -> f64 {
        let masses = if variant.has_absorber() {
            self.m_s + self.m_h + self.m_t
        } else {
            self.m_s + self.m_t
        };
        masses * STANDARD_GRAVITY
    }

    /// Static deflection (m) of the springs between body and wheel under
    /// the weight above them: `m_s g0 / k_s + (m_s + m_h) g0 / k_h` for
    /// PVASS and TDVASS (k_s and k_h in series through the absorber mass),
    /// `m_s g0 / k_s` for the CS. A spring of zero stiffness gives +∞.
    ///
    /// The linear model around the static equilibrium does not see this
    /// sag; the comfort objective of `analysis::optimize` bounds it, so that
    /// a design cannot win comfort by being statically softer.
    pub fn static_deflection(&self, variant: Variant) -> f64 {
        let sag = |load: f64, stiffness: f64| {
            if stiffness > 0.0 {
                load / stiffness
            } else {
                f64::INFINITY
            }
        };
        let body = sag(self.m_s * STANDARD_GRAVITY, self.k_s);
        if variant.has_absorber() {
            body + sag((self.m_s + self.m_h) * STANDARD_GRAVITY, self.k_h)
        } else {
            body
        }
    }
}
