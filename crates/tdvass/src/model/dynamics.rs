//! The model's dynamics, written once for both engines: the precise
//! integration of the co-simulation (`crate::solver`) builds its operators
//! and reads its outputs from these, and Model Exchange (`crate::exchange`)
//! evaluates them at the master's points.
//!
//! - **The continuous states** ([`CONTINUOUS_STATES`]): the plant X of
//!   Eq. (2), the 8 states w of the ISO 2631-1 W_k filter, and the
//!   integrals from the start time behind every time average
//!   ([`INTEGRAL_NAMES`]).
//! - **The plant in a mode** ([`plant_rates`]): `Ẋ = A_m X + b u + e r_m`,
//!   Eq. (2) in contact, and in flight the tire's force held at −W.
//! - **The modes** ([`Mode`], [`Switching::mode_matrix`]): one bit per switching
//!   element of the list [`SWITCHES`] (today the unilateral tire).
//! - **The tire** ([`contact_margin`], [`tire_load`], [`flight_matrix`]):
//!   the margin `W/k_t − (x_t − x_g)` whose sign is the contact, the load
//!   the tire law gives, and the plant in flight, `A + e c_tᵀ` with the
//!   constant input `−W/k_t` on the road column `e` (the tire's force held
//!   at −W).
//! - **The delayed input's interpolant** ([`hermite`]): the cubic through
//!   positions and velocities at two points.
//! - **A short delay** folded into the current state ([`folded_delay`]):
//!   `x_t(t − tau) ≈ x_t − tau v_t`, below what the grid resolves.
//! - **The rates of the continuous states** ([`continuous_rates`]): the
//!   plant's, the filter's `ẇ = A_w w + b_w BA`, and the integrands `BA²`,
//!   `SDD²`, `TDD²`, `a_w²`, `a_w⁴` and the loss of contact.
//!
//! The time averages the outputs report from the integrals are the
//! metrics' ([`crate::metrics::time_averages`]).
//!
//! Layer: data (docs/architecture.md), with the model; it imports the
//! model and the crate's `comfort`.

use super::params::{Params, State, V_T, Variant, X_T};
use super::plant::Plant;
use super::tire::TireContact;
use crate::comfort::{WK_STATES, WkStateSpace};
use nalgebra::{Matrix6, SVector};

impl Plant {
    /// Time derivative of the state, Eq. (2):
    /// `A X + b x_t(t - tau) + e x_g` ([`plant_rates`]).
    #[inline]
    pub fn derivative(&self, x: &State, delayed_tire: f64, road: f64) -> State {
        plant_rates(&self.a, &self.b, &self.e, x, delayed_tire, road)
    }
}

/// The continuous states of the model as one vector, the layout of Model
/// Exchange and of the co-simulation's continuous states: the plant
/// `[x_s, v_s, x_h, v_h, x_t, v_t]` (CS: `x_h`, `v_h` mirror the wheel),
/// the 8 states of the W_k filter, then the integrals [`INTEGRAL_NAMES`]
/// from the start time.
pub const CONTINUOUS_STATES: usize = 6 + WK_STATES + INTEGRAL_STATES;
/// Index of the first W_k filter state in the continuous states.
pub const FILTER_STATES_AT: usize = 6;
/// Index of the first integral in the continuous states.
pub const INTEGRALS_AT: usize = 6 + WK_STATES;
/// Number of integrals among the continuous states.
pub const INTEGRAL_STATES: usize = 6;
/// The integrals among the continuous states, in order: `∫ BA² dt`
/// (m²/s³), `∫ SDD² dt` (m²·s), `∫ TDD² dt` (m²·s), `∫ a_w² dt` (m²/s³),
/// `∫ a_w⁴ dt` (m⁴/s⁷) and the time without tire contact (s).
pub const INTEGRAL_NAMES: [&str; INTEGRAL_STATES] = [
    "integral_body_acceleration_squared",
    "integral_suspension_deflection_squared",
    "integral_tire_deflection_squared",
    "integral_weighted_acceleration_squared",
    "integral_weighted_acceleration_fourth",
    "contact_loss_time",
];

/// The margin to the loss of tire contact (m): `limit − (x_t − x_g)`, with
/// `limit` = W/k_t; positive in contact.
#[inline(always)]
pub fn contact_margin(limit: f64, tire: f64, road: f64) -> f64 {
    limit - (tire - road)
}

/// The dynamic tire load the tire law gives (N) for the linear load `load`
/// = `k_t (x_g − x_t)`: the load itself (bilateral), at least −W
/// (`static_load`) for a unilateral tire, which cannot pull.
#[inline(always)]
pub fn tire_load(unilateral: bool, load: f64, static_load: f64) -> f64 {
    if unilateral {
        load.max(-static_load)
    } else {
        load
    }
}

/// The plant matrix in flight for the matrix `contact` of contact (the
/// plant's A, or the solver's with the feedback folded in): the tire's
/// column gains the road column `e`, whose input is then the constant
/// `−W/k_t` (the tire's force held at −W).
pub fn flight_matrix(contact: &Matrix6<f64>, e: &State) -> Matrix6<f64> {
    let mut a = *contact;
    for row in 0..6 {
        a[(row, X_T)] += e[row];
    }
    a
}

/// A switching element of the model: a piecewise-linear part whose law
/// changes where its switch function crosses zero. Each has a bit of the
/// [`Mode`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Switch {
    /// The unilateral tire: in contact (bit clear) while its margin
    /// ([`contact_margin`]) is not negative, in flight (bit set), with its
    /// force held at −W, after the margin fell through zero.
    Tire,
}

impl Switch {
    /// Whether the element switches at all with the parameters `params`
    /// of `variant` under the tire law `tire_contact`: the tire only when
    /// it is unilateral.
    pub fn applies(self, _params: &Params, _variant: Variant, tire_contact: TireContact) -> bool {
        match self {
            Switch::Tire => tire_contact.is_unilateral(),
        }
    }
}

/// Every switching element, in bit order: the list the engines' switch
/// searches go through.
pub const SWITCHES: [Switch; 1] = [Switch::Tire];

/// The switching elements of a configuration, for both engines: which of
/// [`SWITCHES`] switch, and the constants of their switch functions. A
/// new element adds its constants here and its arms to [`Switch::applies`],
/// [`Switching::side`] and [`Switching::rounding`]; the co-simulation's
/// whole-step test, its switch search and Model Exchange's event
/// indicators go through the list.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Switching {
    /// Whether each element of [`SWITCHES`] switches, in bit order.
    pub applies: [bool; SWITCHES.len()],
    /// W/k_t (m): the tire deflection `x_t − x_g` at which the tire's load
    /// reaches zero ([`contact_margin`]); +∞ when k_t = 0.
    pub tire_limit: f64,
}

impl Switching {
    /// No element switches (the tire never lifts off).
    pub const NONE: Switching = Switching {
        applies: [false; SWITCHES.len()],
        tire_limit: f64::INFINITY,
    };

    /// The elements of the configuration (`params` of `variant`, the tire
    /// law `tire_contact`).
    pub fn of(params: &Params, variant: Variant, tire_contact: TireContact) -> Switching {
        let tire_limit = if params.k_t > 0.0 {
            params.static_load(variant) / params.k_t
        } else {
            f64::INFINITY
        };
        Switching {
            applies: SWITCHES.map(|switch| switch.applies(params, variant, tire_contact)),
            tire_limit,
        }
    }

    /// Whether any element switches.
    #[inline(always)]
    pub fn any(&self) -> bool {
        self.applies.iter().any(|&applies| applies)
    }

    /// The elements that switch, in bit order.
    pub fn elements(&self) -> impl Iterator<Item = Switch> + '_ {
        SWITCHES
            .into_iter()
            .zip(self.applies)
            .filter_map(|(switch, applies)| applies.then_some(switch))
    }

    /// The side `[s, s']` of `switch` at the plant state `x`
    /// (`[x_s, v_s, x_h, v_h, x_t, v_t]`) with the road `road` (m) and its
    /// rate `road_rate` (m/s): the element's first law holds where
    /// `s ≥ 0`. The tire's is its contact margin `W/k_t − (x_t − x_g)`
    /// ([`contact_margin`], m) with the rate `x_g' − v_t`.
    #[inline(always)]
    pub fn side(&self, switch: Switch, x: &[f64], road: f64, road_rate: f64) -> [f64; 2] {
        let level = self.level(switch, x, road);
        match switch {
            Switch::Tire => [level, road_rate - x[V_T]],
        }
    }

    /// The side's value `s` alone ([`Self::side`]); Model Exchange's event
    /// indicators are made of it.
    #[inline(always)]
    pub fn level(&self, switch: Switch, x: &[f64], road: f64) -> f64 {
        match switch {
            Switch::Tire => contact_margin(self.tire_limit, x[X_T], road),
        }
    }

    /// The length that the side of `switch` is measured against (the
    /// tire: W/k_t, m); Model Exchange's hysteresis is relative to it.
    pub fn scale(&self, switch: Switch) -> f64 {
        match switch {
            Switch::Tire => self.tire_limit,
        }
    }

    /// The plant matrix in `mode` for the matrix `contact` of every
    /// element's first law (the plant's A, or the solver's with the
    /// feedback folded in) and the road column `e`: each element in its
    /// second law changes it by its law, with its constants (the tire in
    /// flight: [`flight_matrix`]).
    pub fn mode_matrix(&self, contact: &Matrix6<f64>, e: &State, mode: Mode) -> Matrix6<f64> {
        let mut a = *contact;
        for switch in SWITCHES {
            if mode.is(switch) {
                a = match switch {
                    Switch::Tire => flight_matrix(&a, e),
                };
            }
        }
        a
    }

    /// The mode in force when the elements are on the sides `sides` (a bit
    /// set for an element on the side of its second law): an element that
    /// does not switch keeps its first law.
    pub fn mode_of(&self, sides: Mode) -> Mode {
        self.elements().fold(Mode::CONTACT, |mode, switch| {
            mode.with(switch, sides.is(switch))
        })
    }

    /// The sides of every element of [`SWITCHES`] (those that do not
    /// switch too), in bit order.
    #[inline(always)]
    pub fn sides(&self, x: &[f64], road: f64, road_rate: f64) -> [[f64; 2]; SWITCHES.len()] {
        SWITCHES.map(|switch| self.side(switch, x, road, road_rate))
    }

    /// The switch function `[φ, φ']` of `switch` in `mode`: its side in
    /// its first law, the side's negative in its second; the element
    /// switches where φ falls through 0 (the tire: the margin in contact,
    /// its negative in flight).
    #[inline(always)]
    pub fn function(
        &self,
        switch: Switch,
        mode: Mode,
        x: &[f64],
        road: f64,
        road_rate: f64,
    ) -> [f64; 2] {
        let [side, rate] = self.side(switch, x, road, road_rate);
        if mode.is(switch) {
            [-side, -rate]
        } else {
            [side, rate]
        }
    }

    /// The rounding level of the side of `switch` at the plant state `x`
    /// with the road `road` (m): below it a side of the other sign is
    /// taken for 0. The tire's (m): `64 ε (|W/k_t| + |x_t| + |x_g|)`.
    pub fn rounding(&self, switch: Switch, x: &[f64], road: f64) -> f64 {
        match switch {
            Switch::Tire => {
                let scale = self.tire_limit.abs() + x[X_T].abs() + road.abs();
                64.0 * f64::EPSILON * scale
            }
        }
    }
}

/// The mode in force: one bit per switching element ([`SWITCHES`]), clear
/// for its first law (the tire in contact). One value that the engines
/// keep, compare and save.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
pub struct Mode(u8);

impl Mode {
    /// Every element in its first law (the tire in contact).
    pub const CONTACT: Mode = Mode(0);
    /// How many modes there are: `2^SWITCHES.len()`.
    pub const COUNT: usize = 1 << SWITCHES.len();

    /// This mode with `switch` in its second law (`on`) or its first.
    pub const fn with(self, switch: Switch, on: bool) -> Mode {
        let bit = 1 << switch as u8;
        Mode(if on { self.0 | bit } else { self.0 & !bit })
    }

    /// Whether `switch` is in its second law (the tire in flight).
    #[inline(always)]
    pub const fn is(self, switch: Switch) -> bool {
        self.0 & (1 << switch as u8) != 0
    }

    /// This mode with `switch` in its other law.
    pub const fn toggled(self, switch: Switch) -> Mode {
        Mode(self.0 ^ (1 << switch as u8))
    }

    /// The mode's index in `0..Mode::COUNT`.
    pub const fn index(self) -> usize {
        self.0 as usize
    }

    /// The mode of index `index` (in `0..Mode::COUNT`).
    pub const fn from_index(index: usize) -> Mode {
        Mode(index as u8)
    }

    /// Every mode, by index.
    pub fn all() -> impl Iterator<Item = Mode> {
        (0..Mode::COUNT).map(Mode::from_index)
    }

    /// The modes a run with the elements `switching` can reach: those
    /// whose every element in its second law switches
    /// ([`Switching::applies`]).
    pub fn reachable(switching: &Switching) -> impl Iterator<Item = Mode> + '_ {
        Mode::all().filter(move |mode| {
            SWITCHES
                .iter()
                .zip(switching.applies)
                .all(|(&switch, applies)| !mode.is(switch) || applies)
        })
    }
}

/// `Ẋ = A_m X + b u + e r_m`: the plant's rates in a mode m of matrix
/// `a` (A in contact, [`flight_matrix`] in flight; either with the
/// feedback folded in, [`folded_feedback`]), with the delayed input u
/// (`delayed`, m) through the feedback column `b` and the road column
/// `e`'s input `road_input` (the road x_g in contact, [`flight_input`] in
/// flight). The operators of the co-simulation's exact step are those of
/// this system.
#[inline(always)]
pub fn plant_rates(
    a: &Matrix6<f64>,
    b: &State,
    e: &State,
    x: &State,
    delayed: f64,
    road_input: f64,
) -> State {
    // By value, as the solver's products are (nalgebra's product of
    // references takes a slower, general path).
    *a * *x + *b * delayed + *e * road_input
}

/// The road column's input in flight (m): `−W/k_t`, with `limit` = W/k_t.
#[inline(always)]
pub fn flight_input(limit: f64) -> f64 {
    -limit
}

/// The cubic Hermite interpolant of the delayed input through
/// `nodes = [x_0, v_0, x_1, v_1]` (positions and velocities at the two
/// ends of an interval of length `h`): `[u, u', u'', u''']` at `offset`
/// from the left end. Fourth order; both engines' delayed input is it
/// (the co-simulation's between grid nodes, Model Exchange's between the
/// points of its history).
#[inline(always)]
pub fn hermite(nodes: [f64; 4], h: f64, offset: f64) -> [f64; 4] {
    let [x0, v0, x1, v1] = nodes;
    let slope = (x1 - x0) / h;
    let c2 = (3.0 * slope - 2.0 * v0 - v1) / h;
    let c3 = (v0 + v1 - 2.0 * slope) / (h * h);
    let s = offset;
    [
        x0 + s * (v0 + s * (c2 + s * c3)),
        v0 + s * (2.0 * c2 + 3.0 * c3 * s),
        2.0 * c2 + 6.0 * c3 * s,
        6.0 * c3,
    ]
}

/// `x_t(t − tau) ≈ x_t − tau v_t` for a delay `tau` below what the grid
/// resolves; the same of any vector's `x_t`, `v_t` components (the
/// derivatives of the folded input).
#[inline(always)]
pub fn folded_delay(x: &State, tau: f64) -> f64 {
    x[X_T] - tau * x[V_T]
}

/// The plant's `(A, b)` with the feedback `u = g (x_t − tau v_t)` folded
/// into A (the delay below what the grid resolves): `b` is then zero.
pub fn folded_feedback(plant: &Plant, tau: f64) -> (Matrix6<f64>, State) {
    let (mut a, b) = (plant.a, plant.b);
    for row in 0..6 {
        a[(row, X_T)] += b[row];
        a[(row, V_T)] -= tau * b[row];
    }
    (a, State::zeros())
}

/// What the integrands are made of at an instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Instant {
    /// BA (m/s²).
    pub body_acceleration: f64,
    /// SDD (m).
    pub suspension_deflection: f64,
    /// TDD (m).
    pub tire_deflection: f64,
    /// a_w (m/s²).
    pub weighted_acceleration: f64,
    /// 1 without tire contact, else 0 (the rate of the time without it).
    pub contact_lost: f64,
}

/// The rates of the continuous states ([`CONTINUOUS_STATES`]): the plant's
/// `plant` (as reported: CS mirrors the wheel), the W_k filter's
/// `A_w w + b_w BA` (when `wk` is given, else 0) and the integrands of the
/// integrals at `now`.
pub fn continuous_rates(
    plant: &State,
    filter: &SVector<f64, WK_STATES>,
    wk: Option<&WkStateSpace>,
    now: &Instant,
) -> [f64; CONTINUOUS_STATES] {
    let mut rates = [0.0; CONTINUOUS_STATES];
    rates[..6].copy_from_slice(plant.as_slice());
    if let Some(wk) = wk {
        let dw = wk.derivative(filter, now.body_acceleration);
        rates[FILTER_STATES_AT..INTEGRALS_AT].copy_from_slice(dw.as_slice());
    }
    let squared = now.weighted_acceleration * now.weighted_acceleration;
    rates[INTEGRALS_AT..].copy_from_slice(&[
        now.body_acceleration * now.body_acceleration,
        now.suspension_deflection * now.suspension_deflection,
        now.tire_deflection * now.tire_deflection,
        squared,
        squared * squared,
        now.contact_lost,
    ]);
    rates
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{Params, Variant};

    #[test]
    fn the_margin_and_the_load_agree_on_the_loss_of_contact() {
        let (k_t, weight) = (190_000.0, 3_820.0);
        let limit = weight / k_t;
        for tire in [0.0, 0.5 * limit, limit, 1.5 * limit] {
            let margin = contact_margin(limit, tire, 0.0);
            let load = tire_load(true, k_t * (0.0 - tire), weight);
            assert_eq!(margin >= 0.0, load > -weight || margin == 0.0);
            assert!(load >= -weight);
        }
        assert_eq!(tire_load(false, -2.0 * weight, weight), -2.0 * weight);
    }

    #[test]
    fn the_mode_is_one_bit_per_switching_element() {
        let flight = Mode::CONTACT.with(Switch::Tire, true);
        assert!(flight.is(Switch::Tire) && !Mode::CONTACT.is(Switch::Tire));
        assert_eq!(flight.toggled(Switch::Tire), Mode::CONTACT);
        assert_eq!(flight.with(Switch::Tire, false), Mode::CONTACT);
        let every: Vec<Mode> = Mode::all().collect();
        assert_eq!(every, [Mode::CONTACT, flight]);
        assert!(every.iter().all(|m| Mode::from_index(m.index()) == *m));
        // A bilateral tire never flies; a unilateral one reaches both.
        let of = |tire| Switching::of(&Params::default(), Variant::Tdvass, tire);
        let (bilateral, unilateral) = (of(TireContact::Bilateral), of(TireContact::Unilateral));
        let reached = |s: &Switching| Mode::reachable(s).collect::<Vec<Mode>>();
        assert_eq!(reached(&bilateral), [Mode::CONTACT]);
        assert_eq!(reached(&unilateral), [Mode::CONTACT, flight]);
        let plant = Plant::new(Params::default(), Variant::Tdvass).unwrap();
        let law = |mode| unilateral.mode_matrix(&plant.a, &plant.e, mode);
        assert_eq!(law(Mode::CONTACT), plant.a);
        assert_eq!(law(flight), flight_matrix(&plant.a, &plant.e));
    }

    #[test]
    fn the_switch_functions_come_from_the_list() {
        let params = Params::default();
        let variant = Variant::Tdvass;
        let bilateral = Switching::of(&params, variant, TireContact::Bilateral);
        let unilateral = Switching::of(&params, variant, TireContact::Unilateral);
        let limit = params.static_load(variant) / params.k_t;
        assert_eq!(unilateral.tire_limit, limit);
        assert!(!bilateral.any() && bilateral.elements().next().is_none());
        assert!(unilateral.any());
        assert_eq!(unilateral.elements().collect::<Vec<_>>(), [Switch::Tire]);
        // An element that does not switch keeps its first law whatever its
        // side; one that does follows its side.
        let out = Mode::CONTACT.with(Switch::Tire, true);
        assert_eq!(bilateral.mode_of(out), Mode::CONTACT);
        assert_eq!(unilateral.mode_of(out), out);
        // The tire's side is its margin and rate; its switch function is
        // the side in contact and its negative in flight.
        let x = [0.01, 0.2, 0.0, 0.0, 0.004, -0.3];
        let (road, road_rate) = (0.001, 0.5);
        let side = unilateral.side(Switch::Tire, &x, road, road_rate);
        assert_eq!(
            side,
            [contact_margin(limit, x[X_T], road), road_rate - x[V_T]]
        );
        assert_eq!(unilateral.level(Switch::Tire, &x, road), side[0]);
        assert_eq!(unilateral.sides(&x, road, road_rate), [side]);
        let f = |mode| unilateral.function(Switch::Tire, mode, &x, road, road_rate);
        assert_eq!(f(Mode::CONTACT), side);
        assert_eq!(f(out), [-side[0], -side[1]]);
        assert_eq!(unilateral.scale(Switch::Tire), limit);
        let rounding = unilateral.rounding(Switch::Tire, &x, road);
        assert!(rounding > 0.0 && rounding < 1e-12 * limit.max(1.0) * 1e3);
        // Without a tire spring the wheel never lifts off.
        let soft = Params { k_t: 0.0, ..params };
        let never = Switching::of(&soft, variant, TireContact::Unilateral);
        assert_eq!(never.tire_limit, f64::INFINITY);
        assert!(never.level(Switch::Tire, &x, road) > 0.0);
    }

    #[test]
    fn flight_adds_the_road_column_to_the_tire_column() {
        let plant = Plant::new(Params::default(), Variant::Tdvass).unwrap();
        let flight = flight_matrix(&plant.a, &plant.e);
        // In flight the tire's stiffness no longer acts on x_t.
        let x = State::from_column_slice(&[0.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
        let contact = plant.a * x + plant.e * 0.0;
        let flying = flight * x;
        assert!((flying[V_T] - (contact[V_T] + plant.e[V_T])).abs() < 1e-9);
    }

    #[test]
    fn folding_the_feedback_is_the_folded_delay_through_b() {
        let plant = Plant::new(Params::default(), Variant::Tdvass).unwrap();
        let tau = 1e-8;
        let (a, b) = folded_feedback(&plant, tau);
        assert_eq!(b, State::zeros());
        let x = State::from_column_slice(&[0.1, -0.2, 0.3, 0.4, -0.5, 0.6]);
        let direct = plant.a * x + plant.b * folded_delay(&x, tau);
        for (p, q) in (a * x).iter().zip(direct.iter()) {
            assert!((p - q).abs() <= 1e-12 * q.abs().max(1.0));
        }
    }
}
