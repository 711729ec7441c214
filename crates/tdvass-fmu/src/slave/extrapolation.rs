//! `input_extrapolation` of the vehicle's bonds in Co-Simulation: a
//! corner continues its body attachment, and the chassis its forces, over
//! a communication step from the values set at the last two
//! communication points, instead of holding them.
//!
//! - **The corner.** The attachment's velocity is extrapolated linearly,
//!   `v(t) = v_k + a (t − t_k)` with `a = (v_k − v_{k−1}) / (t_k − t_{k−1})`.
//!   Over a stretch of length d the attachment moves at that line's mean
//!   velocity `v_k + a d / 2` (the precise integration takes a body that
//!   moves at a constant velocity, [`tdvass::model::Body::Attached`]), so
//!   that it reaches the extrapolated displacement `x_k + v_k d + a d²/2`,
//!   and it ends at the extrapolated velocity `v_k + a d`: `body_force`
//!   at the step's end is the force of the extrapolated attachment.
//! - **The chassis.** Each force set at the communication point ramps
//!   along the line through its last two values (the same as an input
//!   derivative of that slope, which, when given, takes precedence).
//!
//! In a Jacobi co-simulation of corners and chassis, holding both inputs
//! makes the coupling first order in the step; extrapolating both makes it
//! second order (docs/full-car.md). The first step holds (one value).

use super::Slave;
use crate::defaults::Model;
use crate::error::FmiError;
use crate::state::BondHistory;

/// The slope `(x_k − x_{k−1}) / (t_k − t_{k−1})` through the last value
/// `(t_k, x_k)` and the one before, or 0 (held) without an earlier value
/// or when the times do not increase.
fn slope_through(previous: Option<(f64, f64)>, now: f64, value: f64) -> f64 {
    match previous {
        Some((t, x)) if now > t => (value - x) / (now - t),
        _ => 0.0,
    }
}

impl Slave {
    /// Whether the body inputs and forces are extrapolated
    /// (`input_extrapolation` >= 1).
    fn extrapolates(&self) -> bool {
        self.state.settings.input_extrapolation >= 1
    }

    /// Marks a corner's body inputs as set at the current time.
    pub(super) fn body_input_set(&mut self) {
        self.state.bonds.body_pending = true;
    }

    /// Marks the chassis's force `i` as set (`derivative_given`: its input
    /// derivative was given, which takes precedence over extrapolation).
    pub(super) fn force_set(&mut self, i: usize, derivative_given: bool) {
        if derivative_given {
            self.state.bonds.forces_pending &= !(1 << i);
        } else {
            self.state.bonds.forces_pending |= 1 << i;
        }
    }

    /// The values in force at the start of the simulation are the first
    /// of each input's history.
    pub(super) fn start_input_history(&mut self) {
        let (start, settings) = (self.state.start_time, &self.state.settings);
        self.state.bonds = BondHistory {
            previous_body: settings.body_input().map(|(_, velocity)| (start, velocity)),
            previous_forces: settings.forces.map(|force| Some((start, force))),
            ..BondHistory::default()
        };
    }

    /// A corner's attachment acceleration for a stretch from `now`: with
    /// new body inputs, the slope of the velocity through them and the
    /// values before (which they then become); without, the one in force.
    /// Always 0 without extrapolation or for another model.
    pub(super) fn body_acceleration_from(&mut self, now: f64) -> f64 {
        if self.model() != Model::Corner || !self.extrapolates() {
            return 0.0;
        }
        let velocity = self.state.settings.body_velocity;
        let bonds = &mut self.state.bonds;
        if bonds.body_pending {
            bonds.body_acceleration = slope_through(bonds.previous_body, now, velocity);
            bonds.previous_body = Some((now, velocity));
            bonds.body_pending = false;
        }
        bonds.body_acceleration
    }

    /// Advances a corner's simulation over `[now, until]` with its
    /// attachment on the extrapolated course of acceleration `a` (see the
    /// module documentation); with `a = 0` it moves at its velocity.
    pub(super) fn advance_extrapolated(
        sim: &mut tdvass::solver::Simulator,
        until: f64,
        a: f64,
    ) -> tdvass::Result<()> {
        if a == 0.0 {
            return sim.advance_to(until);
        }
        let span = until - sim.time();
        let (displacement, velocity) = sim.body_attachment();
        sim.set_body_input(displacement, velocity + 0.5 * a * span)?;
        sim.advance_to(until)?;
        let (displacement, _) = sim.body_attachment();
        sim.set_body_input(displacement, velocity + a * span)
    }

    /// The chassis's forces from `now`: each set since the last step
    /// (without its derivative) ramps along the line through its last two
    /// values, which it then becomes the later of. Holding
    /// (`input_extrapolation = 0`), nothing is kept.
    pub(super) fn extrapolate_forces(&mut self, now: f64) -> Result<(), FmiError> {
        let pending = std::mem::take(&mut self.state.bonds.forces_pending);
        if pending == 0 || !self.extrapolates() {
            return Ok(());
        }
        let m = &mut self.state;
        let Some(chassis) = m.engine.chassis_mut() else {
            return Ok(());
        };
        let (forces, mut rates) = chassis.forces();
        for (i, previous) in m.bonds.previous_forces.iter_mut().enumerate() {
            if pending & (1 << i) != 0 {
                let force = m.settings.forces[i];
                rates[i] = slope_through(*previous, now, force);
                *previous = Some((now, force));
            }
        }
        chassis.set_forces(forces, rates)?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::slope_through;

    #[test]
    fn the_slope_goes_through_the_last_two_values_or_holds() {
        assert_eq!(slope_through(Some((1.0, 2.0)), 1.5, 3.0), 2.0);
        assert_eq!(slope_through(None, 1.5, 3.0), 0.0);
        assert_eq!(slope_through(Some((1.5, 2.0)), 1.5, 3.0), 0.0);
        assert_eq!(slope_through(Some((2.0, 2.0)), 1.5, 3.0), 0.0);
    }
}
