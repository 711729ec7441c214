//! The switches of the model's switching elements (today the unilateral
//! tire's, between contact and flight), as the driver commits them: the
//! next switch in a step located among the elements and committed, its
//! bit of the mode flipped and the operators of the new mode put in
//! force, what the element's switch means recorded (the tire's lift-offs
//! logged, its flights timed); the tire law and the mode a restored
//! simulator is in.
//!
//! Layer: driver (docs/architecture.md); it imports the solver's `contact`,
//! `driver`, `stepping` and the crate's `error`, `model`, `road`.

#[cfg(doc)]
use super::contact::LIFT_OFF_LOG;
use super::contact::{LiftOff, LiftOffLog, MAX_SWITCHES_PER_STEP};
use super::driver::Simulator;
use super::stepping::stepping;
use crate::error::{Error, Result};
use crate::model::dynamics::{Mode, Switch, tire_load};
use crate::model::{State, X_T};
use crate::road::RoadPiece;

impl Simulator {
    /// With a unilateral tire: to the end node of the current step,
    /// through the switches of the tire contact inside it.
    pub(super) fn step_to_node_switching(&mut self, switches: &mut u32) -> Result<()> {
        let k = self.trajectory.grid_index;
        let next_node = self.grid_time(k + 1);
        while self.switch_by(k, next_node, switches)? {
            if self.snaps(next_node, self.trajectory.committed_time) {
                break;
            }
        }
        self.step_to_node()
    }

    /// Whether the wheel is in flight now (unilateral tire only).
    pub fn in_flight(&self) -> bool {
        self.trajectory.mode.is(Switch::Tire)
    }

    /// The lift-offs since the log was last cleared (at most
    /// [`LIFT_OFF_LOG`], and the count of those left out), for an event
    /// log; a fixed array, so keeping them allocates nothing.
    pub fn lift_offs(&self) -> &LiftOffLog {
        &self.observers.lift_off_log
    }

    /// Empties the lift-off log ([`Self::lift_offs`]).
    pub fn clear_lift_offs(&mut self) {
        self.observers.lift_off_log.clear();
    }

    /// The tire load as the tire law gives it (N): `load` =
    /// `k_t (x_g − x_t)`, at least −W with the unilateral tire.
    pub(super) fn tire_load(&self, load: f64) -> f64 {
        tire_load(
            self.config.tire_contact.is_unilateral(),
            load,
            self.config.params.static_load(self.config.variant),
        )
    }

    /// Puts the operators of the recorded mode in force, the contact
    /// operators being in force (after a restore or a rebuild of them).
    pub(super) fn enter_recorded_mode(&mut self) {
        self.modes.forget_stored();
        let mode = self.trajectory.mode;
        self.modes
            .enter(Mode::CONTACT, mode, &self.plant, self.grid.step);
    }

    /// The first switch of an element of the list
    /// ([`SWITCHES`](crate::model::dynamics::SWITCHES)) in grid
    /// step k after the committed point, if it comes at or before `until`,
    /// is committed and its bit of the mode flipped (`Ok(true)`);
    /// `Ok(false)` if none comes by then.
    /// `switches`: the switches made in this step so far (refused beyond
    /// [`MAX_SWITCHES_PER_STEP`]).
    pub(super) fn switch_by(&mut self, k: u64, until: f64, switches: &mut u32) -> Result<bool> {
        let from = (
            self.trajectory.committed_time,
            self.trajectory.committed_state,
        );
        let Some((time, switch)) = stepping!(self).next_switch(k, from) else {
            return Ok(false);
        };
        if time > until && !self.snaps(until, time) {
            return Ok(false);
        }
        *switches += 1;
        if *switches > MAX_SWITCHES_PER_STEP {
            return Err(self.too_many_switches(k, switch));
        }
        self.commit_switch(k, time, switch)
    }

    /// The error of more than [`MAX_SWITCHES_PER_STEP`] switches in grid
    /// step k, the last one of `switch`: the element and why.
    fn too_many_switches(&self, k: u64, switch: Switch) -> Error {
        let (from, step) = (self.grid_time(k), self.grid.step);
        match switch {
            Switch::Tire => Error::Numerical {
                what: "the unilateral tire (tire_contact = 1)",
                reason: format!(
                    "more than {MAX_SWITCHES_PER_STEP} switches between contact and flight in the internal step from {from} s: the margin to W/k_t = {} m changes sign faster than a step of {step} s resolves; use a tighter tolerance or a smaller max_internal_step, or the bilateral tire",
                    self.modes.grid_step.switching.tire_limit,
                ),
            },
        }
    }

    /// The tire's switch at `time` with state x: the end of the flight in
    /// progress (its time joins the lost time), or a lift-off (counted,
    /// logged, the flight starts).
    fn record_tire_switch(&mut self, time: f64, x: &State, piece: &RoadPiece) {
        if self.in_flight() {
            let start = self.trajectory.flight_start.take().unwrap_or(time);
            self.observers.holding.lost_time += time - start;
            return;
        }
        let limit = self.modes.grid_step.switching.tire_limit;
        self.trajectory.flight_start = Some(time);
        self.observers.holding.lift_offs += 1;
        self.observers.holding.first_loss.get_or_insert(time);
        let event = LiftOff {
            time,
            tire_deflection: x[X_T] - piece.value(time),
            limit,
        };
        self.observers.lift_off_log.record(event);
    }

    /// Commits the state at the switch time `time` of `switch` in step k,
    /// records what the element's switch means (the tire: a lift-off or
    /// the end of a flight) and flips its bit of the mode.
    pub(super) fn commit_switch(&mut self, k: u64, time: f64, switch: Switch) -> Result<bool> {
        let (tc, xc) = (
            self.trajectory.committed_time,
            self.trajectory.committed_state,
        );
        let x = if time == tc {
            xc
        } else {
            stepping!(self).integrate_within_step(k, tc, xc, time)
        };
        crate::limits::check_divergence(time, &x)?;
        self.outputs_cache = None;
        self.trajectory.set_current(time, x);
        self.close_run_here();
        let piece = self.inputs.piece_from(time);
        let from = self.trajectory.mode;
        match switch {
            Switch::Tire => self.record_tire_switch(time, &x, &piece),
        }
        self.trajectory.mode = from.toggled(switch);
        self.modes
            .enter(from, self.trajectory.mode, &self.plant, self.grid.step);
        self.observers
            .reanchor(&mut stepping!(self), &self.trajectory.committed());
        Ok(true)
    }
}
