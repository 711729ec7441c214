//! A Model Exchange instance's parts: the delayed input's form, the
//! plant's matrices as the co-simulation has them, the discrete state that
//! events change, the [`ModelExchange`] that holds them, and the readers of
//! its continuous states that its derivatives, partials and saved state
//! share.
//!
//! Layer: exchange (docs/architecture.md), the ground of its folder; it
//! imports the folder's `history` and the crate's `comfort`, `model`,
//! `road` and the solver's public configuration and layout.

use super::history::{DelayHistory, Delayed};
use crate::comfort::{WK_STATES, WkStateSpace};
use crate::model::dynamics::{
    CONTINUOUS_STATES, FILTER_STATES_AT, INTEGRALS_AT, Mode, SWITCHES, Switch, Switching,
    folded_delay, folded_feedback,
};
use crate::model::inputs::{PrescribedValues, with_prescribed};
use crate::model::{Plant, State, V_T, X_T};
use crate::road::Road;
use crate::solver::SimulationConfig;
use nalgebra::{Matrix6, SVector};

/// Number of event indicators: one per switching element of [`SWITCHES`]
/// (today the margin to the loss of tire contact, which marks the loss of
/// contact of the bilateral tire too).
pub const EVENT_INDICATORS: usize = SWITCHES.len();

/// Index of the time without tire contact among the continuous states.
pub(super) const CONTACT_LOSS_TIME: usize = CONTINUOUS_STATES - 1;

/// The hysteresis of an event indicator, relative to its element's scale
/// ([`Switching::scale`]: the tire's W/k_t).
pub(super) const HYSTERESIS: f64 = 1e-12;

/// How far back (s) a master that has never completed a step may set the
/// time, from the latest time it set.
pub const TRIAL_REACH: f64 = 1.0;

/// How the delayed input is formed.
#[derive(Debug, Clone, PartialEq)]
pub(super) enum Delay {
    /// No control force (CS, PVASS).
    None,
    /// `x_t − tau v_t` (tau below [`crate::solver::MIN_RESOLVED_DELAY`]).
    Folded(f64),
    /// From the history of evaluated points.
    History(DelayHistory),
}

/// The plant's matrices as the co-simulation's operators have them.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Matrices {
    /// By [`Mode::index`], each mode's matrix ([`Switching::mode_matrix`]) of the
    /// contact matrix: A, with the feedback `g (x_t − tau v_t)` folded in
    /// where the delay is folded or there is no controller (as the
    /// co-simulation folds it).
    pub(super) modes: [Matrix6<f64>; Mode::COUNT],
    /// The delayed input's column: b, or zero where folded.
    pub(super) feedback: State,
}

impl Matrices {
    /// The matrices of `plant` for the delay `delay`.
    pub(super) fn of(plant: &Plant, delay: &Delay, switching: &Switching) -> Matrices {
        let (contact, feedback) = match delay {
            Delay::History(_) => (plant.a, plant.b),
            Delay::Folded(tau) => folded_feedback(plant, *tau),
            Delay::None => folded_feedback(plant, 0.0),
        };
        Matrices {
            modes: std::array::from_fn(|i| {
                switching.mode_matrix(&contact, &plant.e, Mode::from_index(i))
            }),
            feedback,
        }
    }
}

/// The discrete state: the elements' sides and what events update.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Discrete {
    /// The side of each element at the last event, a bit set for the side
    /// of its second law (the tire: out of contact, its margin < 0); the
    /// mode in force is [`Switching::mode_of`] it.
    pub(super) sides: Mode,
    /// ε of each event indicator (> 0; the tire's in m), in bit order.
    pub(super) hysteresis: [f64; EVENT_INDICATORS],
    /// Lift-offs since the start (a start without contact counts one).
    pub(super) lift_off_count: u64,
    /// The largest |SDD| at the accepted points (m).
    pub(super) max_suspension_deflection: f64,
    /// The first loss of contact: time (s) and dynamic tire load (N).
    pub(super) first_contact_loss: Option<(f64, f64)>,
}

/// What an event changed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ContactEvent {
    /// The margin fell through 0 at this time (s): TDD (m) then.
    LiftOff { time: f64, tire_deflection: f64 },
    /// The margin rose through 0 at this time (s).
    TouchDown { time: f64 },
}

/// One Model Exchange instance of the model; see the module documentation.
#[derive(Debug, Clone)]
pub struct ModelExchange {
    pub(super) config: SimulationConfig,
    pub(super) plant: Plant,
    /// The plant's matrices as the co-simulation's operators have them.
    pub(super) matrices: Matrices,
    pub(super) wk: WkStateSpace,
    pub(super) road: Road,
    /// The switching elements and their switch functions' constants.
    pub(super) switching: Switching,
    /// The values of the inputs that prescribe coordinates
    /// ([`crate::model::inputs::PRESCRIBED`]; a corner's body attachment
    /// `[x_s (m), v_s (m/s)]`), which the rates and outputs take those
    /// coordinates from; `None` for an input the configuration does not
    /// have (the sprung mass's).
    pub(super) prescribed: PrescribedValues,
    /// W (N).
    pub(super) static_load: f64,
    pub(super) time: f64,
    pub(super) states: [f64; CONTINUOUS_STATES],
    pub(super) delay: Delay,
    pub(super) discrete: Discrete,
    /// The time of the last accepted point (s).
    pub(super) accepted: f64,
    /// The earliest time [`Self::set_time`] takes (s): see the module
    /// documentation. Never decreases.
    pub(super) floor: f64,
    /// The latest time set (s).
    pub(super) latest: f64,
    /// The master has called `CompletedIntegratorStep`: the floor is its
    /// last accepted point.
    pub(super) completes: bool,
    /// The largest |time| (s) the model resolves.
    pub(super) max_time: f64,
}

impl ModelExchange {
    /// The plant's state X: the first six continuous states, with the
    /// coordinates that inputs prescribe (a corner's body attachment) from
    /// those inputs.
    pub(super) fn plant_state(&self) -> State {
        with_prescribed(
            State::from_column_slice(&self.states[..6]),
            &self.prescribed,
        )
    }

    /// The W_k filter's state w.
    pub(super) fn filter_state(&self) -> SVector<f64, WK_STATES> {
        SVector::from_column_slice(&self.states[FILTER_STATES_AT..INTEGRALS_AT])
    }

    /// `x_t(t − tau)` now, with its partials with respect to the current
    /// `x_t` and `v_t`, without recording the point.
    pub(super) fn delayed_now(&self) -> Delayed {
        let x = &self.states;
        match &self.delay {
            Delay::None => Delayed {
                value: 0.0,
                by_position: 0.0,
                by_velocity: 0.0,
            },
            Delay::Folded(tau) => Delayed {
                value: folded_delay(&self.plant_state(), *tau),
                by_position: 1.0,
                by_velocity: -tau,
            },
            Delay::History(h) => h.delayed((self.time, x[X_T], x[V_T])),
        }
    }

    /// The mode in force ([`Switching::mode_of`] the sides): the tire's
    /// bit set while it flies (a unilateral tire out of contact).
    pub(super) fn mode(&self) -> Mode {
        self.switching.mode_of(self.discrete.sides)
    }

    /// Whether the tire is out of contact (its margin was < 0 at the last
    /// event), whatever its law.
    pub(super) fn contact_lost(&self) -> bool {
        self.discrete.sides.is(Switch::Tire)
    }
}
