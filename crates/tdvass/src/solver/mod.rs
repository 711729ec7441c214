//! The fine (precise) integration method for the delay equation of Eq. (2),
//! `dX/dt = A X + b x_t(t − tau) + e x_g(t)`, section 4.1.
//!
//! Over a step of length δ starting at `a`, Eq. (23) gives
//! `X(a+δ) = e^{Aδ} X(a) + ∫_0^δ e^{A(δ−s)} [b u(a+s) + e x_g(a+s)] ds`.
//! The integral is exact here because both inputs have closed forms over
//! the step:
//! - the delayed tire displacement `u = x_t(t − tau)` is the cubic Hermite
//!   interpolant of `x_t` and its derivative `v_t` (a state) at the grid
//!   nodes one delay earlier (the grid step divides tau exactly), so the
//!   method is fourth-order accurate in the step; a delay shorter than the
//!   step bound keeps the step and splits it at tau, the end node of the
//!   step entering its own interpolant through a 2×2 solve
//!   ([`DelayRegime::InsideStep`]);
//! - the road is a sine (an exosystem) or a straight line (see
//!   [`crate::road`]).
//!
//! All the step matrices come from one exponential of an augmented matrix
//! (the plant plus the input generators), computed by the 2^N algorithm in
//! [`expm::precise_exp`]. A partial step (a point inside a step: a
//! communication point, a road breakpoint, a switch of the tire contact)
//! applies the same exponential at its length to the augmented vector
//! through a table of the step's binary fractions and a short Taylor
//! polynomial, with a stated bound (`dense`), at about the cost of a
//! whole step.
//!
//! **Caller independence.** States are committed only on an internal grid
//! anchored at the start time (`t_k = t_0 + k h`); road breakpoints inside a
//! step split it internally. A time between grid nodes is reached by a dense
//! output from the last grid node that is not committed. So how a caller
//! splits an interval does not change any result: outputs agree bit for bit.
//! An external road input (`RoadSpec::Input`) is the exception: the state is
//! committed where the input changes.
//!
//! **Hot path.** From a committed grid node, [`Simulator::advance_to`] runs
//! every whole step the call reaches in one loop (`whole_steps` around the
//! hot loop of `kernel`, see
//! BENCHMARKS.md): the delayed input acts on the two history nodes through
//! `Γ_u H` precomputed, the harmonic road phase is rotated from node to
//! node (exact every `PHASE_ANCHOR` = 1024 nodes), a linear road piece
//! gives `x_g` from the node index until the piece ends, and BA, SDD, TDD
//! go straight into the RMS sums. Each node's state, phase and sums are
//! functions of its index alone, so splits and `to_bytes`/`from_bytes`
//! stay bit-identical (the unit tests in `tests.rs`).
//!
//! **The step.** The internal step comes from the tolerance
//! ([`SimulationConfig::tolerance`]): an error model of what depends on it
//! (the Hermite interpolant of the delayed input, the time-average
//! quadrature, the located extrema) gives a first step, and a
//! step-doubling probe checks and refines it ([`accuracy`]).
//!
//! **Layers** (each module's documentation says what it owns and imports;
//! the test `crates/tdvass/tests/layers.rs` keeps every import pointing
//! down; docs/architecture.md draws them), from the ground up: the linear
//! algebra (`expm`, `linalg`); the system (`system`: the augmented layout
//! and the W_k filter's coupling; `grid`, `config`, `holding`, `contact`,
//! `reports`); the step maps (`operators`) and the inputs (`pieces`: the
//! breakpoint rule; `inputs`: road pieces, delay history, harmonic
//! phases); the whole and partial steps (`grid_step`, `dense`); the modes
//! of the tire (`modes`); stepping inside a step (`stepping`, `integrals`,
//! `events`, `deferred`), on a view of the simulator's parts
//! (`stepping!`); the observers (`observers`, `trajectory`); the whole-step
//! loop (`kernel`: the hot loop and its AVX2 build, and `whole_steps`:
//! its segments and commits; the solver's only `unsafe`, which the crate
//! denies elsewhere); the driver (`driver`: the [`Simulator`] and its step); the
//! clients (`accuracy`, `outputs`, `persist`); and this file, which
//! declares the simulator's public constructors and readers over the
//! clients and re-exports the public names.

pub mod accuracy;
mod config;
mod contact;
mod deferred;
mod dense;
mod driver;
mod events;
pub mod expm;
mod grid;
mod grid_step;
mod holding;
mod inputs;
mod integrals;
mod kernel;
mod linalg;
mod modes;
mod observers;
mod operators;
mod outputs;
mod persist;
mod pieces;
mod reports;
mod setup;
mod stepping;
mod switching;
mod system;
mod trajectory;
mod whole_steps;

use crate::error::Result;
pub use crate::limits::{DIVERGENCE_DISPLACEMENT, DIVERGENCE_VELOCITY};
use crate::metrics::RmsValues;
use crate::model::dynamics::{Mode, plant_rates};
use crate::model::{Plant, State};
pub use config::{DEFAULT_TOLERANCE, Metrics, SimulationConfig, StepChoice};
pub use contact::{LIFT_OFF_LOG, LiftOff, LiftOffLog, MAX_SWITCHES_PER_STEP};
pub use driver::Simulator;
pub use events::LOCATION_TOLERANCE;
pub use grid::{DelayGrid, DelayRegime, MAX_HISTORY_NODES, MIN_RESOLVED_DELAY};
pub(crate) use holding::largest_magnitude;
pub use persist::STATE_FORMAT_VERSION;
pub use reports::{
    CONTINUOUS_STATES, ComfortValues, ContactLoss, FILTER_STATES_AT, INTEGRAL_NAMES,
    INTEGRAL_STATES, INTEGRALS_AT, Instantaneous, OutputDerivatives, Outputs, RoadHolding,
    RunSummary, TimeAverages,
};

/// The constructors that choose the internal step (`accuracy`), and the
/// readers of the outputs (`outputs`) and of the byte form (`persist`):
/// the simulator's public interface over its clients; the rest is the
/// driver's (`driver`).
impl Simulator {
    /// Validates the configuration and places the system at its initial
    /// state. Besides each value and the numerical limits of
    /// [`crate::limits::check_config`], it checks the tolerance and
    /// chooses the internal step from it ([`accuracy::choose_step`]), and
    /// checks that the internal step `h` resolves times near the start:
    /// `|start_time| <= 2^42 h` ([`Self::MAX_START_TIME_IN_STEPS`]).
    pub fn new(config: SimulationConfig) -> Result<Simulator> {
        let plant = Self::validate(&config)?;
        match accuracy::choose(&plant, &config)? {
            // The probe's coarse simulator, before it ran, is this one.
            (choice, Some(mut sim)) => {
                sim.step_choice = choice;
                Ok(*sim)
            }
            (choice, None) => Self::with_choice(config, choice),
        }
    }

    /// The one check of a configuration, whatever integrates it (this
    /// simulator, Model Exchange): every value finite and in range, the
    /// numerical limits of [`crate::limits::check_config`]; the plant it
    /// describes. The tolerance and the internal step are the
    /// simulator's own ([`Self::new`]).
    pub fn check_config(config: &SimulationConfig) -> Result<Plant> {
        Self::validate(config)
    }

    /// The right-hand side the operators of `mode`
    /// integrate: `Ẋ = A_m X + b u + e r_m`
    /// ([`crate::model::dynamics::plant_rates`]) at the state `x`, the
    /// delayed input `delayed` (m) and the road column's input
    /// `road_input` (m: the road in contact, `−W/k_t` in flight), with the
    /// solver's matrices (the feedback folded in below the grid's
    /// resolution). Model Exchange evaluates the same
    /// ([`crate::exchange::ModelExchange::mode_rates`]).
    pub fn mode_rates(&self, mode: Mode, x: &State, delayed: f64, road_input: f64) -> State {
        let e = &self.plant.e;
        let a = self.modes.mode_matrix(mode, self.trajectory.mode, e);
        plant_rates(&a, &self.modes.input_column, e, x, delayed, road_input)
    }

    /// Checks `config` as [`Self::new`] does and chooses its internal step
    /// from the tolerance ([`accuracy::choose_step`]).
    pub fn choose_step(config: &SimulationConfig) -> Result<StepChoice> {
        let plant = Self::validate(config)?;
        accuracy::choose_step(&plant, config)
    }

    /// [`Self::new`] with the step already chosen by [`Self::choose_step`]
    /// for the same configuration.
    pub fn with_choice(config: SimulationConfig, choice: StepChoice) -> Result<Simulator> {
        let mut sim = Self::with_step_bound(config, choice.step_bound)?;
        sim.step_choice = choice;
        Ok(sim)
    }

    /// The instantaneous outputs at the current time, the same values as
    /// [`Self::outputs`] gives, at less cost when the others are not
    /// needed: the integrals from the start are not closed.
    pub fn instantaneous(&mut self) -> Instantaneous {
        outputs::instantaneous(self)
    }

    /// Runs from the current time for `duration` seconds and summarises.
    pub fn run_for(&mut self, duration: f64) -> Result<RunSummary> {
        self.advance_to(self.trajectory.current_time + duration)?;
        let outputs = self.outputs();
        Ok(RunSummary {
            rms: outputs.rms,
            objective: outputs.objective,
            comfort: outputs.comfort,
            rms_dynamic_tire_load_ratio: outputs.rms_dynamic_tire_load_ratio,
            road_holding: outputs.road_holding,
        })
    }

    /// All outputs at the current time.
    pub fn outputs(&mut self) -> Outputs {
        outputs::outputs(self)
    }

    /// The time averages among the outputs at the current time, the same
    /// values as [`Self::outputs`] gives, at less cost when the other
    /// outputs are not needed: the integrals from the start are closed at
    /// the current time, the instantaneous outputs are not computed.
    pub fn time_averages(&mut self) -> TimeAverages {
        outputs::time_averages(self)
    }

    /// The suspension's force on the body (N) now, positive up, zero at
    /// the static equilibrium ([`crate::model::Plant::body_force`]): a
    /// corner's output ([`crate::model::Body::Attached`]); with the sprung
    /// mass it is `m_s BA`.
    pub fn body_force(&mut self) -> f64 {
        let x = self.instantaneous().state;
        self.plant.body_force(&x)
    }

    /// The switching elements of the configuration and their switch
    /// functions' constants (the model's, which Model Exchange uses too).
    pub fn switching(&self) -> &crate::model::dynamics::Switching {
        &self.modes.grid_step.switching
    }

    /// The static tire load W (N) of the configured variant
    /// ([`crate::model::Params::static_load`]).
    pub fn static_load(&self) -> f64 {
        outputs::static_load(self)
    }

    /// The first loss of tire contact so far, if any (see [`ContactLoss`];
    /// always `None` below [`Metrics::RoadHolding`]).
    ///
    /// Cheap where nothing is lost: the committed accumulators answer up to
    /// the committed point, and the stretch from there to now is decided
    /// from its end margins (the bound of `solver::holding`; on the
    /// harmonic road first from bounds that need no sine, see
    /// `stretch_keeps_contact`); only a stretch that may lose contact
    /// computes the outputs.
    pub fn first_contact_loss(&mut self) -> Option<ContactLoss> {
        outputs::first_contact_loss(self)
    }

    /// Exact first time derivatives of the instantaneous outputs.
    pub fn output_derivatives(&mut self) -> OutputDerivatives {
        outputs::output_derivatives(self)
    }

    /// RMS values so far (time averages from the start to now).
    pub fn rms(&mut self) -> RmsValues {
        outputs::rms(self)
    }

    /// The continuous states now, in the layout of Model Exchange
    /// ([`CONTINUOUS_STATES`]): the reported plant state, the W_k filter
    /// (zero below [`Metrics::Comfort`]) and the integrals from the start.
    pub fn continuous_states(&mut self) -> [f64; CONTINUOUS_STATES] {
        outputs::continuous_states(self)
    }

    /// The time derivatives of [`Self::continuous_states`].
    pub fn continuous_state_derivatives(&mut self) -> [f64; CONTINUOUS_STATES] {
        outputs::continuous_state_derivatives(self)
    }

    /// Encodes the whole simulator.
    pub fn to_bytes(&self) -> Vec<u8> {
        persist::to_bytes(self)
    }

    /// Rebuilds a simulator from [`Simulator::to_bytes`]; the result continues
    /// bit-identically.
    ///
    /// Besides the layout, the configuration (as [`Simulator::new`]) and
    /// finite times and states, it checks what bounds the work of the next
    /// [`Simulator::advance_to`] by the length of the interval it is asked
    /// to cover, with the tolerance at which the solver takes two times as
    /// the same (so that every state the simulator saves is accepted):
    /// - `grid_index` k is below `u64::MAX` and step k has a positive
    ///   length: `t_k < t_{k+1}`, with `t_k = t_0 + k h`;
    /// - `committed_time` lies in step k: `t_k <= committed_time < t_{k+1}`,
    ///   or it coincides with `t_k` (after an external road input changes,
    ///   it may lie strictly inside the step);
    /// - `current_time` is reachable from `committed_time` inside step k:
    ///   `committed_time <= current_time <= t_{k+1}`, each bound up to the
    ///   snap tolerance ([`Simulator::snap_tolerance`]);
    /// - the road generator is consistent with `committed_time` (see
    ///   `Road::restore_dynamic_state`, with the horizon `t_{k+2}`).
    ///
    /// The comfort and road-holding accumulators must be consistent too:
    /// finite; the filter state and the a_w integrals zero without the
    /// filter; the largest |SDD| not below the committed point's; the time
    /// without contact within the time run, with a first loss recorded
    /// whenever there is such time, at a time between the start and the
    /// committed point.
    pub fn from_bytes(bytes: &[u8]) -> Result<Simulator> {
        persist::from_bytes(bytes)
    }
}

/// Simulates `config` from its start for `duration` seconds.
pub fn simulate(config: SimulationConfig, duration: f64) -> Result<RunSummary> {
    Simulator::new(config)?.run_for(duration)
}

#[cfg(test)]
impl SimulationConfig {
    /// This configuration at the fixed internal step of 1e-4 s that some
    /// unit tests count in (the tolerance at its loosest, so the bound sets
    /// the step).
    pub(crate) fn at_fixed_step(self) -> SimulationConfig {
        SimulationConfig {
            tolerance: accuracy::MAX_TOLERANCE,
            max_internal_step: 1e-4,
            ..self
        }
    }
}

#[cfg(test)]
mod tests;
