//! Model Exchange: the model as an ordinary differential equation with
//! events, for a master whose own solver integrates it.
//!
//! **The continuous states** ([`CONTINUOUS_STATES`], the layout of
//! [`crate::solver::CONTINUOUS_STATES`]): the plant X of Eq. (2), the W_k
//! filter w, and the integrals from the start time behind every time
//! average: `∫BA²`, `∫SDD²`, `∫TDD²`, `∫a_w²`, `∫a_w⁴` and the time without
//! tire contact. Their derivatives are
//!
//! ```text
//! dX/dt = A X + b x_t(t − tau) + e x_g(t)            (contact, Eq. (2))
//! dX/dt = (A + e c_tᵀ) X + b x_t(t − tau) − e W/k_t  (flight, unilateral tire)
//! dw/dt = A_w w + b_w BA,  a_w = c_w w               (ISO 2631-1 W_k)
//! d/dt ∫y² = y²,  d/dt ∫a_w⁴ = a_w⁴,  d/dt t_lost = [no contact]
//! ```
//!
//! (CS: `x_h`, `v_h` follow the wheel's derivatives, so they mirror it as
//! the co-simulation reports them.) A corner of a vehicle
//! ([`crate::model::Body::Attached`]) takes the body's coordinates `x_s`,
//! `v_s` from its input ([`ModelExchange::set_body_input`]) wherever the
//! rates, the partials and the outputs read them; its states `x_s`, `v_s`
//! integrate the velocity given and nothing reads them. The outputs are
//! computed from these states: RMS values `sqrt(∫y²/(t − t_0))`, J of Eq. (6), `RMS(a_w)`,
//! `VDV = (∫a_w⁴)^{1/4}`, the dynamic tire load ratio `k_t RMS(TDD)/W`.
//!
//! **The delayed input** `x_t(t − tau)` comes from a [`DelayHistory`] of
//! the evaluated and accepted points (see there). Delays below
//! [`MIN_RESOLVED_DELAY`] are folded as in the co-simulation:
//! `x_t(t − tau) ≈ x_t − tau v_t`.
//!
//! **Going back.** [`ModelExchange::set_time`] takes any time from the
//! floor ([`ModelExchange::earliest_time`]) on: the last accepted point
//! (start, completed integrator step, event) or, while the master has never
//! completed a step, [`TRIAL_REACH`] before the latest time it set,
//! whichever is later. The history and the random road keep what the
//! times from the floor on need (at most [`MAX_HISTORY_POINTS`] points and
//! [`crate::limits::MAX_WORK_PER_CALL`] road nodes); an earlier time is refused with an
//! error naming both times.
//!
//! **Bounded work.** A time whose random road would need more than
//! [`crate::limits::MAX_WORK_PER_CALL`] nodes generated or kept is refused, and so is a
//! time beyond `2^42` times the finest time the model resolves (the delay,
//! the road's node interval, at most [`crate::solver::accuracy::LARGEST_STEP`]), as the
//! co-simulation refuses times its grid cannot resolve. No derivative or
//! event indicator that is not finite is handed out.
//!
//! **Events.** One event indicator per switching element of the model's
//! list ([`crate::model::dynamics::SWITCHES`]): its level
//! ([`Switching::level`]), moved away from zero by a hysteresis after each
//! event. Today that is the tire's margin `W/k_t − (x_t − x_g)` (m) to the
//! loss of contact: in contact `z = margin + ε_c`, out of contact
//! `z = margin − ε_f`, with the ε set at each event to `1e-12 W/k_t` (the
//! element's [`Switching::scale`]) plus whatever margin of the wrong sign
//! the located event left, so that z ≠ 0 after every event. At an event
//! each element's side follows the sign of its level, and the mode the
//! sides ([`Switching::mode_of`]); for the tire:
//! a fall through 0 is a lift-off (counted in `lift_off_count`; with the
//! unilateral tire the wheel then flies), a rise a touch-down. With the
//! bilateral tire its side only counts and times the losses of contact.
//! Outputs that are extrema or counts (the largest |SDD|, the lift-offs)
//! are updated at completed integrator steps and events.
//!
//! **One model.** The plant's right-hand side in each tire mode, the
//! tire's laws, the fold of a short delay, the delayed input's
//! interpolant and the rates of the continuous states are those of
//! [`crate::model::dynamics`], and the time averages
//! [`crate::metrics::time_averages`]: the functions the co-simulation
//! builds its operators and outputs from ([`ModelExchange::mode_rates`]
//! equals [`Simulator::mode_rates`] to the bit).
//!
//! Layer: exchange (docs/architecture.md); it imports the crate's `comfort`,
//! `error`, `limits`, `metrics`, `model`, `road` and the solver's public
//! configuration and report types.

mod history;
mod instance;
mod jacobian;
mod persist;
mod reach;

pub use history::{DelayHistory, Delayed, HistoryPoint, MAX_HISTORY_POINTS, STAGE_POINTS};
use instance::{CONTACT_LOSS_TIME, Delay, Discrete, HYSTERESIS, Matrices};
pub use instance::{ContactEvent, EVENT_INDICATORS, ModelExchange, TRIAL_REACH};
pub use jacobian::{Gradient, Jacobian, OutputPartials};
pub use persist::EXCHANGE_FORMAT_VERSION;

use crate::comfort::wk_state_space;
use crate::error::{Error, Result};
use crate::limits::DIVERGENCE_BOUNDS;
use crate::metrics::time_averages;
use crate::model::dynamics::{
    CONTINUOUS_STATES, FILTER_STATES_AT, INTEGRAL_NAMES, INTEGRALS_AT, Instant, Mode, SWITCHES,
    Switch, Switching, continuous_rates, flight_input, plant_rates, tire_load,
};
use crate::model::inputs::{BODY_ATTACHMENT, prescribed_from};
use crate::model::{Performance, Plant, STATE_NAMES, State, V_T, X_S, X_T};
use crate::road::Road;
use crate::solver::{
    ComfortValues, ContactLoss, MIN_RESOLVED_DELAY, Metrics, Outputs, RoadHolding,
    SimulationConfig, Simulator,
};

/// The names of the continuous states, in order.
pub fn state_names() -> [String; CONTINUOUS_STATES] {
    std::array::from_fn(|i| match i {
        0..6 => STATE_NAMES[i].to_string(),
        _ if i < INTEGRALS_AT => format!("wk_filter_{}", i - FILTER_STATES_AT + 1),
        _ => INTEGRAL_NAMES[i - INTEGRALS_AT].to_string(),
    })
}

/// The nominal values of the continuous states (their typical magnitudes
/// on the paper's roads; a master scales its absolute tolerances by them):
/// displacements 1e-3 m, velocities 1e-2 m/s, the W_k filter 1e-2 m/s²,
/// `∫BA²` and the a_w integrals 1e-3, `∫SDD²`, `∫TDD²` 1e-9 m²·s, the time
/// without contact 1e-4 s.
pub fn nominals() -> [f64; CONTINUOUS_STATES] {
    std::array::from_fn(|i| match i {
        0..6 if i % 2 == 0 => 1e-3,
        0..6 => 1e-2,
        _ if i < INTEGRALS_AT => 1e-2,
        _ => [1e-3, 1e-9, 1e-9, 1e-3, 1e-3, 1e-4][i - INTEGRALS_AT],
    })
}

impl ModelExchange {
    /// The model of `config` at its start time and initial state (the
    /// tolerance and the internal step of the co-simulation play no part).
    /// The configuration is checked by the one check
    /// ([`Simulator::check_config`]).
    pub fn new(config: SimulationConfig) -> Result<ModelExchange> {
        let plant = Simulator::check_config(&config)?;
        let max_time = Self::time_bound(&config);
        if config.start_time.abs() > max_time {
            return Err(Error::InvalidTime {
                name: "start_time",
                value: config.start_time,
                reason: "|start_time| must be at most 2^42 times the finest time the model resolves (the delay, the road's node interval, 0.01 s)",
            });
        }
        let k_t = config.params.k_t;
        let static_load = config.params.static_load(config.variant);
        let mut road = Road::with_shift(&config.road, config.start_time, config.road_shift)?;
        let t0 = config.start_time;
        let x = plant.reported_state(&config.initial_state);
        let tau = config.params.tau;
        let delay = if !config.variant.has_control() {
            Delay::None
        } else if tau < MIN_RESOLVED_DELAY {
            Delay::Folded(tau)
        } else {
            Delay::History(DelayHistory::new(t0, x[X_T], x[V_T], tau))
        };
        let switching = Switching::of(&config.params, config.variant, config.tire_contact);
        let road_now = road.value(t0);
        // Each element starts on the side its level gives (the tire: in
        // contact at a margin of 0).
        let sides = SWITCHES.into_iter().fold(Mode::CONTACT, |sides, switch| {
            sides.with(
                switch,
                switching.level(switch, x.as_slice(), road_now) < 0.0,
            )
        });
        let mut states = [0.0; CONTINUOUS_STATES];
        states[..6].copy_from_slice(x.as_slice());
        let mut model = ModelExchange {
            matrices: Matrices::of(&plant, &delay, &switching),
            plant,
            wk: wk_state_space(),
            road,
            switching,
            prescribed: prescribed_from(config.body, &x),
            static_load,
            time: t0,
            states,
            delay,
            accepted: t0,
            floor: t0,
            latest: t0,
            completes: false,
            max_time,
            discrete: Discrete {
                sides,
                hysteresis: [0.0; EVENT_INDICATORS],
                lift_off_count: u64::from(sides.is(Switch::Tire)),
                max_suspension_deflection: (x[X_S] - x[X_T]).abs(),
                first_contact_loss: None,
            },
            config: SimulationConfig {
                metrics: Metrics::Comfort,
                ..config
            },
        };
        for (i, switch) in SWITCHES.into_iter().enumerate() {
            let level = switching.level(switch, x.as_slice(), road_now);
            model.discrete.hysteresis[i] = model.hysteresis_for(switch, level, sides.is(switch));
        }
        if sides.is(Switch::Tire) {
            let margin = switching.level(Switch::Tire, x.as_slice(), road_now);
            let limit = switching.tire_limit;
            model.discrete.first_contact_loss = Some((t0, k_t * (-margin - limit)));
        }
        model.reserve();
        Ok(model)
    }

    /// Makes room for the random road's nodes a run keeps (from the floor
    /// to the latest time; [`TRIAL_REACH`] and a little more), also after a
    /// copied or restored state, whose nodes come without room, so that
    /// evaluating the derivatives allocates nothing. The delay history
    /// keeps its room through copies.
    pub fn reserve(&mut self) {
        let tau = self.config.params.tau.max(0.0);
        self.road.reserve_window(1.1 * TRIAL_REACH + tau);
    }

    /// The configuration.
    pub fn config(&self) -> &SimulationConfig {
        &self.config
    }

    /// The current time (s).
    pub fn time(&self) -> f64 {
        self.time
    }

    /// The continuous states.
    pub fn states(&self) -> &[f64; CONTINUOUS_STATES] {
        &self.states
    }

    /// The time of the last accepted point (start, completed step,
    /// event).
    pub fn accepted_time(&self) -> f64 {
        self.accepted
    }

    /// Sets the continuous states: exactly [`CONTINUOUS_STATES`] finite
    /// values (the error names the first that is not).
    pub fn set_states(&mut self, values: &[f64]) -> Result<()> {
        if values.len() != CONTINUOUS_STATES {
            return Err(Error::Refused(format!(
                "{} continuous states given, the model has {CONTINUOUS_STATES}",
                values.len()
            )));
        }
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(Error::Refused(format!(
                "continuous state {i} (`{}`) = {} is not finite",
                state_names()[i],
                values[i]
            )));
        }
        self.states.copy_from_slice(values);
        Ok(())
    }

    /// Tunes the gain g (N/m) from now on; the states and the history stay.
    pub fn set_gain(&mut self, g: f64) -> Result<()> {
        let params = crate::model::Params {
            g,
            ..self.config.params
        };
        let plant = Plant::new(params, self.config.variant)?.with_body(self.config.body);
        self.matrices = Matrices::of(&plant, &self.delay, &self.switching);
        self.plant = plant;
        self.config.params = params;
        Ok(())
    }

    /// Sets the weights of J from now on.
    pub fn set_weights(&mut self, weights: crate::metrics::Weights) {
        self.config.weights = weights;
    }

    /// Sets a corner's body attachment (only with
    /// [`crate::model::Body::Attached`]): `x_s = displacement` (m),
    /// `v_s = velocity` (m/s) ([`Self::set_prescribed`]).
    pub fn set_body_input(&mut self, displacement: f64, velocity: f64) -> Result<()> {
        self.set_prescribed(BODY_ATTACHMENT, [displacement, velocity])
    }

    /// Sets the input `input` (an index into [`PRESCRIBED`](crate::model::inputs::PRESCRIBED)), `values` =
    /// `[position (m), velocity (m/s)]`, which the rates and outputs take
    /// as those coordinates from now on (the continuous states of them
    /// integrate the velocity given, and nothing reads them). Refused by
    /// name when not finite or beyond the divergence bounds, or where the
    /// configuration does not have the input; a refused value changes
    /// nothing.
    pub fn set_prescribed(&mut self, input: usize, values: [f64; 2]) -> Result<()> {
        crate::limits::check_prescribed(self.config.body, input, values)?;
        self.prescribed[input] = Some(values);
        Ok(())
    }

    /// The values of the input `input` (an index into [`PRESCRIBED`](crate::model::inputs::PRESCRIBED)), if
    /// the configuration has it.
    pub fn prescribed(&self, input: usize) -> Option<[f64; 2]> {
        self.prescribed[input]
    }

    /// The suspension's force on the body (N) now
    /// ([`crate::model::Plant::body_force`]): a corner's output.
    pub fn body_force(&self) -> f64 {
        self.plant.body_force(&self.plant_state())
    }

    /// Sets the external road input `x_g` (m; road = input only).
    pub fn set_road_input(&mut self, value: f64) -> Result<()> {
        self.road.set_input(self.time, value, 0.0)
    }

    /// The time derivatives of the continuous states at the current time
    /// and states. The point becomes a trial point of the delay history
    /// (see [`DelayHistory`]). A derivative that is not finite, or a time
    /// whose delayed value the history no longer holds, is an error
    /// naming it.
    pub fn derivatives(&mut self) -> Result<[f64; CONTINUOUS_STATES]> {
        if let Delay::History(h) = &self.delay
            && self.time < h.earliest_time()
        {
            return Err(Error::Refused(format!(
                "t = {} s needs the delayed x_t at {} s, before the oldest of the {MAX_HISTORY_POINTS} points the delay history holds ({} s); call CompletedIntegratorStep at the solver's accepted steps, or take longer steps",
                self.time,
                self.time - h.tau(),
                h.earliest_time() - h.tau()
            )));
        }
        let delayed = self.delayed_now().value;
        let now = (self.time, self.states[X_T], self.states[V_T]);
        if let Delay::History(h) = &mut self.delay {
            h.record(now);
        }
        self.follow_history_bound();
        let rates = self.rates(delayed);
        if let Some(i) = rates.iter().position(|v| !v.is_finite()) {
            return Err(Error::Refused(format!(
                "the derivative of `{}` is {} at t = {} s",
                state_names()[i],
                rates[i],
                self.time
            )));
        }
        Ok(rates)
    }

    /// The derivatives for the delayed input `delayed` (m).
    fn rates(&mut self, delayed: f64) -> [f64; CONTINUOUS_STATES] {
        let t = self.time;
        let x = self.plant_state();
        let road = self.road.value(t);
        let mode = self.mode();
        let road_input = if mode.is(Switch::Tire) {
            flight_input(self.switching.tire_limit)
        } else {
            road
        };
        let dx = self
            .plant
            .reported_state(&self.mode_rates(mode, &x, delayed, road_input));
        let body_acceleration = self.plant.body_acceleration(&x);
        let w = self.filter_state();
        let now = Instant {
            body_acceleration,
            suspension_deflection: x[X_S] - x[X_T],
            tire_deflection: x[X_T] - road,
            weighted_acceleration: self.wk.weighted_acceleration(&w, body_acceleration),
            contact_lost: if self.contact_lost() { 1.0 } else { 0.0 },
        };
        continuous_rates(&dx, &w, Some(&self.wk), &now)
    }

    /// The right-hand side of the plant in `mode`:
    /// `Ẋ = A_m X + b u + e r_m` ([`plant_rates`]) at the state `x`, the
    /// delayed input `delayed` (m) and the road column's input
    /// `road_input` (m: the road in contact, `−W/k_t` in flight), with the
    /// matrices of the co-simulation's operators (the feedback folded in
    /// below the delay it resolves): what
    /// [`Simulator::mode_rates`] evaluates too.
    #[inline]
    pub fn mode_rates(&self, mode: Mode, x: &State, delayed: f64, road_input: f64) -> State {
        let m = &self.matrices;
        plant_rates(
            &m.modes[mode.index()],
            &m.feedback,
            &self.plant.e,
            x,
            delayed,
            road_input,
        )
    }

    /// The levels of the elements of [`SWITCHES`] now
    /// ([`Switching::level`]: the tire's margin `W/k_t − (x_t − x_g)`, m).
    fn levels(&mut self) -> [f64; EVENT_INDICATORS] {
        let road = self.road.value(self.time);
        let x = &self.states[..6];
        SWITCHES.map(|switch| self.switching.level(switch, x, road))
    }

    /// The event indicators (module documentation), one per element of
    /// [`SWITCHES`]; one that is not finite is an error naming the time.
    pub fn event_indicators(&mut self) -> Result<[f64; EVENT_INDICATORS]> {
        let levels = self.levels();
        let mut z = [0.0; EVENT_INDICATORS];
        for (i, switch) in SWITCHES.into_iter().enumerate() {
            let hysteresis = self.discrete.hysteresis[i];
            z[i] = if self.discrete.sides.is(switch) {
                levels[i] - hysteresis
            } else {
                levels[i] + hysteresis
            };
            if !z[i].is_finite() {
                return Err(Error::Refused(format!(
                    "the event indicator is {} at t = {} s",
                    z[i], self.time
                )));
            }
        }
        Ok(z)
    }

    /// ε of `switch` on the side `second` (of its second law) at the level
    /// `level`: the base hysteresis and any level of the wrong sign for
    /// the side.
    fn hysteresis_for(&self, switch: Switch, level: f64, second: bool) -> f64 {
        let wrong_side = if second { level } else { -level };
        HYSTERESIS * self.switching.scale(switch) + wrong_side.max(0.0)
    }

    /// Accepts the current point as a completed integrator step: it joins
    /// the delay history for good ([`DelayHistory::accept`]), becomes the
    /// floor, and updates the largest |SDD|.
    pub fn complete_step(&mut self) {
        self.completes = true;
        self.accept(true);
    }

    /// Accepts the current point: a completed integrator step when
    /// `completed`, else an event.
    fn accept(&mut self, completed: bool) {
        let x = self.plant_state();
        let now = (self.time, x[X_T], x[V_T]);
        let sdd = (x[X_S] - x[X_T]).abs();
        self.discrete.max_suspension_deflection = self.discrete.max_suspension_deflection.max(sdd);
        self.accepted = self.time;
        if let Delay::History(h) = &mut self.delay {
            h.accept(now, completed);
        }
        self.move_floor(self.time);
        self.follow_history_bound();
    }

    /// Event Mode: accepts the current point and sets each element's side
    /// from the sign of its level (the mode follows); returns the tire's
    /// switch, if any.
    pub fn update_discrete_states(&mut self) -> Option<ContactEvent> {
        self.accept(false);
        let levels = self.levels();
        let mut tire_event = None;
        for (i, switch) in SWITCHES.into_iter().enumerate() {
            let (level, second) = (levels[i], self.discrete.sides.is(switch));
            if !(if second { level > 0.0 } else { level < 0.0 }) {
                continue;
            }
            self.discrete.sides = self.discrete.sides.toggled(switch);
            self.discrete.hysteresis[i] = self.hysteresis_for(switch, level, !second);
            match switch {
                Switch::Tire => tire_event = Some(self.record_tire_switch(level, !second)),
            }
        }
        tire_event
    }

    /// What the tire's switch at the margin `margin` (m) means: a lift-off
    /// (`lost`: counted, the first loss of contact kept) or a touch-down.
    fn record_tire_switch(&mut self, margin: f64, lost: bool) -> ContactEvent {
        let time = self.time;
        if !lost {
            return ContactEvent::TouchDown { time };
        }
        self.discrete.lift_off_count += 1;
        if self.discrete.first_contact_loss.is_none() {
            self.discrete.first_contact_loss = Some((time, -self.static_load));
        }
        ContactEvent::LiftOff {
            time,
            tire_deflection: self.switching.tire_limit - margin,
        }
    }

    /// Whether the tire is in contact (its margin was >= 0 at the last
    /// event).
    pub fn in_contact(&self) -> bool {
        !self.contact_lost()
    }

    /// Lift-offs since the start.
    pub fn lift_off_count(&self) -> u64 {
        self.discrete.lift_off_count
    }

    /// The first plant state beyond the divergence bounds of the
    /// co-simulation (`crate::limits`): its name and value.
    pub fn diverged(&self) -> Option<(&'static str, f64)> {
        (0..6)
            .find(|&i| self.states[i].is_nan() || self.states[i].abs() > DIVERGENCE_BOUNDS[i])
            .map(|i| (STATE_NAMES[i], self.states[i]))
    }

    /// The outputs at the current time and states, from the states (the
    /// same quantities as [`crate::solver::Simulator::outputs`]).
    pub fn outputs(&mut self) -> Outputs {
        let t = self.time;
        let x = self.plant_state();
        let road = self.road.value(t);
        let delayed = self.delayed_now().value;
        let performance = Performance::at(&self.plant, &x, road);
        let k_t = self.config.params.k_t;
        let static_load = self.static_load;
        let averages = time_averages(
            &self.states[INTEGRALS_AT..],
            t - self.config.start_time,
            &self.config.weights,
            k_t,
            static_load,
        );
        let w = self.filter_state();
        let unilateral = self.config.tire_contact.is_unilateral();
        Outputs {
            time: t,
            state: x,
            performance,
            road_displacement: road,
            control_force: self.config.params.effective_gain(self.config.variant) * delayed,
            body_force: self.plant.body_force(&x),
            rms: averages.rms,
            objective: averages.objective,
            comfort: Some(ComfortValues {
                weighted_body_acceleration: self
                    .wk
                    .weighted_acceleration(&w, performance.body_acceleration),
                rms_weighted_body_acceleration: averages.rms_weighted_acceleration,
                vibration_dose_value: averages.vibration_dose_value,
            }),
            dynamic_tire_load: tire_load(unilateral, k_t * (road - x[X_T]), static_load),
            rms_dynamic_tire_load_ratio: averages.dynamic_tire_load_ratio,
            road_holding: Some(RoadHolding {
                contact_loss_time: self.states[CONTACT_LOSS_TIME],
                max_suspension_deflection: self
                    .discrete
                    .max_suspension_deflection
                    .max(performance.suspension_deflection.abs()),
                first_contact_loss: self.discrete.first_contact_loss.map(
                    |(time, dynamic_tire_load)| ContactLoss {
                        time,
                        dynamic_tire_load,
                        static_load,
                    },
                ),
                lift_off_count: self.discrete.lift_off_count,
            }),
        }
    }
}

#[cfg(test)]
mod tests;
