//! The unilateral tire ([`crate::model::TireContact::Unilateral`]): contact and flight,
//! each exact, with the switches between them located inside the steps.
//!
//! **The two modes.** In contact the plant is Eq. (2). In flight the tire
//! force is the constant −W, so the wheel row loses the tire spring: with
//! `e = [0, …, k_t/m_t]` the road column, the flight plant is
//! `dX/dt = (A + e c_tᵀ) X + b u + e (−W/k_t)`, `c_t` picking x_t. That is
//! the same form as contact, with the road replaced by the constant
//! `−W/k_t` ([`Stepping::forcing`](super::stepping::Stepping::forcing)), so every exact step map of the solver
//! applies to flight unchanged: the mode's plant matrix and its operators
//! are put in force at a switch ([`Modes::enter`](super::modes::Modes::enter)).
//!
//! **The switches.** With the margin `g = W/k_t − (x_t − x_g)` (m) of
//! `solver::holding`, the wheel lifts off where g falls through 0 in
//! contact, and touches down where it rises through 0 in flight. The
//! tire force `max(−W, k_t (x_g − x_t))` is continuous there, so the state
//! and its first two derivatives are: the delay history, the RMS
//! integrals, the W_k filter and the running extrema continue across a
//! switch.
//!
//! From the committed point the step is integrated to its end node in the
//! current mode; the cubic Hermite interpolant of the switch function
//! (g in contact, −g in flight) through the exact values and rates at the
//! ends of each road piece brackets its first fall through 0 (the root
//! test of `solver::holding`). The bracket is then checked and narrowed on
//! the exact dense output (the state from the committed point by the exact
//! partial step of `solver::dense`), by Newton's method on `φ' = ±(x_g' − v_t)`, a state,
//! kept inside the bracket by bisection, to [`LOCATION_TOLERANCE`](super::events::LOCATION_TOLERANCE). The
//! switch time is committed like a change of an external road input (the
//! RMS run closes there), the mode flips, and the step goes on from there.
//! A bracket that the exact output does not confirm is a graze (the
//! margin touches 0 within the interpolant's error, some 1e-14 m) and
//! switches nothing.
//!
//! The search always runs to the step's end node, whatever time the
//! caller asked for, so the switch times do not depend on how a run is
//! split. A step may hold at most [`MAX_SWITCHES_PER_STEP`] switches;
//! more is refused with an error naming the cause (the margin then
//! oscillates about 0 faster than the step resolves), never looped on.
//!
//! **Accuracy.** Each mode keeps the exact step. The Hermite interpolant of
//! the delayed `x_t` over a grid interval with a switch in it interpolates
//! a function whose third derivative jumps there (the tire force has a
//! kink), an error of order `h³ |Δx_t'''|` over that interval only; with a
//! delay inside the step (`0 < tau < h`) the step's end node is predicted
//! in the mode at the step's start. Both are within the tolerance's step
//! choice, which probes the unilateral run itself.
//!
//! Layer: system (docs/architecture.md); it imports nothing of the crate.

/// Most switches between contact and flight inside one internal step.
pub const MAX_SWITCHES_PER_STEP: u32 = 16;

/// Lift-offs kept for the front-ends' event log between two takes (a
/// fixed array: logging a lift-off allocates nothing; later ones are
/// counted in [`LiftOffLog::dropped`]).
pub const LIFT_OFF_LOG: usize = 64;

/// A lift-off, as logged.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct LiftOff {
    /// When (s).
    pub time: f64,
    /// TDD = x_t − x_g then (m): W/k_t up to the location tolerance.
    pub tire_deflection: f64,
    /// W/k_t (m): the TDD at which the tire load reaches 0.
    pub limit: f64,
}

/// Lift-offs since the front-end last took them: the first
/// [`LIFT_OFF_LOG`] in a fixed array, and the count of those that did not
/// fit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LiftOffLog {
    events: [LiftOff; LIFT_OFF_LOG],
    len: usize,
    /// Lift-offs that did not fit.
    pub dropped: u64,
}

impl Default for LiftOffLog {
    fn default() -> Self {
        LiftOffLog {
            events: [LiftOff::default(); LIFT_OFF_LOG],
            len: 0,
            dropped: 0,
        }
    }
}

impl LiftOffLog {
    /// The lift-offs kept, oldest first.
    pub fn events(&self) -> &[LiftOff] {
        &self.events[..self.len]
    }

    /// Whether no lift-off was logged or dropped.
    pub fn is_empty(&self) -> bool {
        self.len == 0 && self.dropped == 0
    }

    /// Forgets the lift-offs logged.
    pub(super) fn clear(&mut self) {
        self.len = 0;
        self.dropped = 0;
    }

    /// Keeps `event`, or counts it as dropped when the log is full.
    pub(super) fn record(&mut self, event: LiftOff) {
        if self.len < LIFT_OFF_LOG {
            self.events[self.len] = event;
            self.len += 1;
        } else {
            self.dropped += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{State, TireContact, V_T, X_T};
    use crate::solver::SimulationConfig;
    use crate::solver::Simulator;

    #[test]
    fn more_switches_in_one_step_than_the_limit_are_refused_with_the_cause() {
        // A wheel leaving the road at the start: the first step switches.
        let mut initial = State::zeros();
        initial[X_T] = 0.1;
        initial[V_T] = 1.0;
        let mut sim = Simulator::new(SimulationConfig {
            tire_contact: TireContact::Unilateral,
            initial_state: initial,
            ..SimulationConfig::default()
        })
        .unwrap();
        let node = sim.grid_time(1);
        let mut switches = MAX_SWITCHES_PER_STEP;
        let message = sim
            .switch_by(0, node, &mut switches)
            .unwrap_err()
            .to_string();
        assert!(message.contains("tire_contact = 1"), "{message}");
        assert!(message.contains("more than 16 switches"), "{message}");
        // Below the limit the same switch is made.
        let mut switches = 0;
        assert!(sim.switch_by(0, node, &mut switches).unwrap());
        assert!(sim.in_flight());
        assert_eq!(switches, 1);
    }
}
