//! The quarter-car models of the paper: parameters (Table 1), the three
//! variants and the linear state-space form of Eq. (2).
//!
//! The state is `X = [x_s, v_s, x_h, v_h, x_t, v_t]` (m, m/s) for every
//! variant. For the two-degree-of-freedom conventional suspension the
//! absorber coordinates carry no dynamics (their rows and columns of A are
//! zero and they stay at zero); outputs report `x_h = x_t`, `v_h = v_t`.

pub mod dynamics;
mod equations;
mod tire;

pub use equations::{Element, MassSpringDamper};
pub use tire::TireContact;

use crate::bytes::{ByteReader, ByteWriter};
use crate::error::{Error, Result};
use nalgebra::{Matrix6, Vector6};

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
    /// where the configuration is).
    pub(crate) fn read(r: &mut ByteReader) -> Result<Params> {
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

/// The linear plant of Eq. (2) for one variant:
/// `dX/dt = A X + b x_t(t - tau) + e x_g(t)`.
///
/// `b` already contains the gain: `b = [0, 0, 0, -g/m_h, 0, g/m_t]`
/// (notes.md section 1; the paper's `g_t` in B means `g`).
/// `e = [0, 0, 0, 0, 0, k_t/m_t]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Plant {
    /// The variant this plant describes.
    pub variant: Variant,
    /// The parameters it was built from.
    pub params: Params,
    /// State matrix A of Eq. (2).
    pub a: Matrix6<f64>,
    /// Delayed-feedback column (B of Eq. (2) times g).
    pub b: State,
    /// Road column E of Eq. (2).
    pub e: State,
}

impl Plant {
    /// Builds A, b, e for `variant` after validating `params`, from Eq. (1)
    /// ([`MassSpringDamper`]): for each coordinate x_i with mass m_i,
    /// `dx_i/dt = v_i`, `dv_i/dt = −(K x + C v)_i / m_i + …`.
    pub fn new(params: Params, variant: Variant) -> Result<Plant> {
        let eq1 = MassSpringDamper::new(&params, variant)?;
        let mut a = Matrix6::zeros();
        let mut b = State::zeros();
        let mut e = State::zeros();
        for (i, &x_i) in eq1.coordinates.iter().enumerate() {
            let (v_i, mass) = (x_i + 1, eq1.masses[i]);
            a[(x_i, v_i)] = 1.0;
            for (j, &x_j) in eq1.coordinates.iter().enumerate() {
                if let Some(stiffness) = eq1.stiffness(i, j) {
                    a[(v_i, x_j)] = -stiffness / mass;
                }
                if let Some(damping) = eq1.damping(i, j) {
                    a[(v_i, x_j + 1)] = -damping / mass;
                }
            }
            if eq1.coordinates.len() == 3 {
                b[v_i] = eq1.feedback[i] / mass;
            }
            if i == eq1.wheel() {
                e[v_i] = eq1.road_stiffness(i) / mass;
            }
        }
        Ok(Plant {
            variant,
            params,
            a,
            b,
            e,
        })
    }

    /// Time derivative of the state, Eq. (2):
    /// `A X + b x_t(t - tau) + e x_g`.
    #[inline]
    pub fn derivative(&self, x: &State, delayed_tire: f64, road: f64) -> State {
        dynamics::plant_rates(&self.a, &self.b, &self.e, x, delayed_tire, road)
    }

    /// Body acceleration BA = d²x_s/dt² (m/s²), first row of Eq. (26).
    /// It does not depend on the road or the control force.
    #[inline]
    pub fn body_acceleration(&self, x: &State) -> f64 {
        self.a.row(V_S).dot(&x.transpose())
    }

    /// The state as reported: for CS the absorber coordinates mirror the wheel.
    pub fn reported_state(&self, x: &State) -> State {
        let mut y = *x;
        if self.variant == Variant::Cs {
            y[X_H] = x[X_T];
            y[V_H] = x[V_T];
        }
        y
    }
}

/// The three performance outputs of Eq. (2), `Y = [BA, SDD, TDD]`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Performance {
    /// Body acceleration BA = d²x_s/dt² (m/s²).
    pub body_acceleration: f64,
    /// Suspension dynamic deflection SDD = x_s − x_t (m).
    pub suspension_deflection: f64,
    /// Tire dynamic displacement TDD = x_t − x_g (m).
    pub tire_deflection: f64,
}

impl Performance {
    /// Evaluates Y of Eq. (2) at state `x` and road displacement `road`.
    #[inline]
    pub fn at(plant: &Plant, x: &State, road: f64) -> Performance {
        Performance {
            body_acceleration: plant.body_acceleration(x),
            suspension_deflection: x[X_S] - x[X_T],
            tire_deflection: x[X_T] - road,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table1_defaults_are_valid() {
        Params::default().validate().unwrap();
    }

    #[test]
    fn invalid_parameters_name_the_parameter_and_value() {
        let p = Params {
            m_h: -1.0,
            ..Params::default()
        };
        let err = p.validate().unwrap_err();
        assert_eq!(
            err,
            Error::InvalidParameter {
                name: "m_h",
                value: -1.0,
                reason: "a mass must be > 0"
            }
        );
        assert!(err.to_string().contains("m_h") && err.to_string().contains("-1"));
        let p = Params {
            tau: f64::NAN,
            ..Params::default()
        };
        assert!(matches!(
            p.validate(),
            Err(Error::InvalidParameter { name: "tau", .. })
        ));
        let p = Params {
            c_s: f64::INFINITY,
            ..Params::default()
        };
        assert!(matches!(
            p.validate(),
            Err(Error::InvalidParameter { name: "c_s", .. })
        ));
        assert!(Plant::new(p, Variant::Cs).is_err());
    }

    #[test]
    fn matrices_match_eq2() {
        let p = Params::default();
        let plant = Plant::new(p, Variant::Tdvass).unwrap();
        assert_eq!(plant.a[(V_H, V_H)], -(p.c_s + p.c_h) / p.m_h);
        assert_eq!(plant.a[(V_T, X_T)], -(p.k_h + p.k_t) / p.m_t);
        assert_eq!(plant.b[V_H], -p.g / p.m_h);
        assert_eq!(plant.b[V_T], p.g / p.m_t);
        assert_eq!(plant.e[V_T], p.k_t / p.m_t);
        let pv = Plant::new(p, Variant::Pvass).unwrap();
        assert_eq!(pv.b, State::zeros());
        assert_eq!(pv.a, plant.a);
    }

    #[test]
    fn static_load_and_deflection_follow_the_weights_on_the_springs() {
        let p = Params::default();
        let g0 = STANDARD_GRAVITY;
        assert_eq!(p.static_load(Variant::Tdvass), (345.0 + 4.05 + 40.5) * g0);
        assert_eq!(
            p.static_load(Variant::Pvass),
            p.static_load(Variant::Tdvass)
        );
        assert_eq!(p.static_load(Variant::Cs), (345.0 + 40.5) * g0);
        let absorber = 345.0 * g0 / 16000.0 + (345.0 + 4.05) * g0 / 6444.0;
        assert!((p.static_deflection(Variant::Pvass) - absorber).abs() < 1e-15);
        assert!((absorber - 0.742_649).abs() < 1e-6);
        assert_eq!(p.static_deflection(Variant::Cs), 345.0 * g0 / 16000.0);
        let loose = Params { k_h: 0.0, ..p };
        assert_eq!(loose.static_deflection(Variant::Pvass), f64::INFINITY);
    }

    #[test]
    fn cs_is_the_two_dof_quarter_car() {
        let p = Params::default();
        let cs = Plant::new(p, Variant::Cs).unwrap();
        // Static equilibrium under a unit road displacement: everything at 1.
        let x = State::new(1.0, 0.0, 0.0, 0.0, 1.0, 0.0);
        let dx = cs.derivative(&x, 0.0, 1.0);
        assert!(dx.norm() < 1e-12, "{dx}");
        assert_eq!(cs.a.row(X_H).norm() + cs.a.row(V_H).norm(), 0.0);
        assert_eq!(cs.a.column(X_H).norm() + cs.a.column(V_H).norm(), 0.0);
        let y = cs.reported_state(&x);
        assert_eq!(y[X_H], 1.0);
    }

    #[test]
    fn variant_codes_round_trip() {
        for v in Variant::ALL {
            assert_eq!(Variant::from_code(v.code() as i64).unwrap(), v);
            assert_eq!(v.name().parse::<Variant>().unwrap(), v);
        }
        assert!(Variant::from_code(4).is_err());
    }
}
