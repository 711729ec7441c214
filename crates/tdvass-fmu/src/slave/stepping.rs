//! Communication steps: `do_step`, the input over a step (held, given
//! slope or extrapolated) and the output derivatives.

use super::{HOLD_WARNING_STEP, Slave};
use crate::defaults::{Model, TIME_TOLERANCE};
use crate::error::{FmiError, Status};
use crate::guards;
use crate::phase::Phase;
use crate::variables::{Access, Causality, VarType, by_vr};

/// The slope of the straight line that continues the input over a step of
/// length `h` from its last value `(t_k, x_k)` (the last of `values`, in
/// time order, at most three):
/// - one value: 0 (held);
/// - two values: the line through both, `(x_k − x_{k−1}) / (t_k − t_{k−1})`
///   (it lags a curved input by about `(5/12) h² ẍ` on average over a step);
/// - three values: the parabola q through them, and of the lines through
///   `(t_k, x_k)` the one closest to q over the step in the mean square,
///   slope `q'(t_k) + 3 q'' h / 8` (mean lag `q'' h² / 48`, twenty times
///   less).
///
/// Times that do not increase give 0.
pub fn extrapolation_slope(values: &[(f64, f64)], h: f64) -> f64 {
    match *values {
        [.., (t1, x1), (t2, x2)] if t2 > t1 => {
            let last = (x2 - x1) / (t2 - t1);
            match *values {
                [(t0, x0), _, _] if t1 > t0 => {
                    let before = (x1 - x0) / (t1 - t0);
                    let curvature = 2.0 * (last - before) / (t2 - t0);
                    last + 0.5 * curvature * (t2 - t1) + 0.375 * curvature * h
                }
                _ => last,
            }
        }
        _ => 0.0,
    }
}

impl Slave {
    /// `DoStep` from `t` (must equal the FMU time to a relative 1e-9)
    /// over `h` (> 0, finite, not past a defined stop time): [`Self::begin_step`]
    /// then [`Self::advance_within_step`] to its end. A divergence returns
    /// `Discard`: the instance stays at the last good grid node
    /// (`LastSuccessfulTime`), asks for termination (`Terminated`) and
    /// goes to `stepFailed`.
    pub fn do_step(&mut self, t: f64, h: f64) -> Result<Status, FmiError> {
        let target = self.begin_step(t, h)?;
        self.advance_within_step(target, h)
    }

    /// Checks a communication step from `t` over `h` (the arguments, the
    /// stop time, the work it needs) and returns its end.
    pub fn begin_step(&mut self, t: f64, h: f64) -> Result<f64, FmiError> {
        let now = self.time();
        if !(h.is_finite() && h > 0.0) {
            return Err(FmiError::error(format!(
                "invalid communicationStepSize {h}: must be finite and > 0"
            )));
        }
        if !t.is_finite() || (t - now).abs() > TIME_TOLERANCE * now.abs().max(t.abs()).max(h) {
            return Err(FmiError::error(format!(
                "currentCommunicationPoint {t} does not match the FMU time {now}"
            )));
        }
        let target = (t + h).max(now);
        if !target.is_finite() {
            return Err(FmiError::error(format!(
                "a step of {h} s from {t} s does not end at a finite time"
            )));
        }
        if let Some(stop) = self.state.stop_time
            && target > stop + TIME_TOLERANCE * stop.abs().max(h)
        {
            return Err(FmiError::error(format!(
                "a step of {h} s from {t} s ends at {target} s, past the stop time {stop} s"
            )));
        }
        if self.state.engine.chassis().is_some() {
            // The chassis's step is a closed form: the same work however long.
            return Ok(target);
        }
        let Some(sim) = self.state.engine.simulator() else {
            return Err(no_simulator());
        };
        let (settings, step) = (&self.state.settings, sim.grid().step);
        // The function's name is formatted only for the message.
        if guards::step_work(settings, step, target - now) > guards::MAX_WORK_PER_STEP {
            guards::check_step_work(settings, step, target - now, self.call("DoStep"))?;
        }
        guards::check_time_resolution("the step end", target, step)?;
        Ok(target)
    }

    /// The next time, after `from` by at least `intermediate_update_interval`,
    /// at which an intermediate update is due inside the step that ends at
    /// `target`: an internal grid node strictly between the current time
    /// and `target` (beyond the snap tolerance of each), if there is one.
    pub fn next_intermediate_time(&self, from: f64, target: f64) -> Option<f64> {
        let sim = self.state.engine.simulator()?;
        let now = sim.time();
        let interval = self.state.settings.intermediate_update_interval;
        let node = sim.node_at_or_after((from + interval).max(now));
        let tolerance = sim.snap_tolerance(node);
        (node > now + tolerance && node < target - tolerance).then_some(node)
    }

    /// Advances to `until` (the end of the step begun by
    /// [`Self::begin_step`], or a time inside it): a new input value is
    /// applied from the current time with the slope fitted over `span`
    /// (s); then the outputs must be finite. A divergence is a `Discard`
    /// as described at [`Self::do_step`].
    pub fn advance_within_step(&mut self, until: f64, span: f64) -> Result<Status, FmiError> {
        if self.state.engine.chassis().is_some() {
            return self.advance_chassis(until);
        }
        let now = self.time();
        // The settings are read where needed, not copied: they hold every
        // model's values (the chassis's too), and a copy a step is a
        // `memcpy` of all of them.
        let road_is_input = self.state.settings.road_is_input();
        let pending = self.state.input_pending;
        let slope = if road_is_input {
            self.input_slope_for_step(now, span)?
        } else {
            0.0
        };
        let body_acceleration = self.body_acceleration_from(now);
        let Some(sim) = self.state.engine.simulator_mut() else {
            return Err(no_simulator());
        };
        if pending && road_is_input {
            let x_g = self.state.settings.x_g;
            sim.set_road_input(x_g, slope)?;
            self.state.earlier_input = self.state.previous_input;
            self.state.previous_input = Some((now, x_g));
        }
        self.state.input_pending = false;
        let advanced = Self::advance_extrapolated(sim, until, body_acceleration);
        // The lift-offs up to where the simulation stopped, whatever the
        // outcome.
        self.log_lift_offs();
        let Some(sim) = self.state.engine.simulator_mut() else {
            return Err(no_simulator());
        };
        match advanced {
            // `advance_to` bounds every state (its divergence check, or
            // for a state it defers, a bound that passes it); the outputs,
            // computed only when a getter asks, follow from them.
            Ok(()) => match sim
                .computed_state()
                .and_then(|x| guards::non_finite_state(&x))
            {
                None => {
                    self.state.last_successful_time = sim.time();
                    // The bilateral tire warns once where the linear model
                    // stops holding; the unilateral one has logged its
                    // lift-offs as events.
                    let loss =
                        if self.state.contact_warned || sim.config().tire_contact.is_unilateral() {
                            None
                        } else {
                            sim.first_contact_loss()
                        };
                    if let Some(loss) = loss {
                        self.state.contact_warned = true;
                        self.warning(format_args!(
                            "{}: the tire leaves the road at t = {} s: `dynamic_tire_load` = {} N is below minus the static load {} N, so the linear model no longer holds from there (the simulation goes on; `contact_loss_time` accumulates the time without contact)",
                            self.call("DoStep"),
                            loss.time,
                            loss.dynamic_tire_load,
                            loss.static_load
                        ));
                    }
                    Ok(Status::Ok)
                }
                Some((name, value)) => {
                    self.state.terminate_requested = true;
                    self.state.phase = Phase::StepFailed;
                    Err(FmiError::discard(format!(
                        "state `{name}` = {value} is not finite at t = {until} s; the outputs are not available, {} is {} s, the FMU asks to terminate ({})",
                        self.dialect.last_successful_time,
                        self.state.last_successful_time,
                        self.dialect.terminate_flag
                    )))
                }
            },
            Err(e @ tdvass::Error::Diverged { .. }) => {
                let stopped = sim.time();
                self.state.last_successful_time = stopped;
                self.state.terminate_requested = true;
                self.state.phase = Phase::StepFailed;
                Err(FmiError::discard(format!(
                    "{e}; the FMU stays at t = {stopped} s ({}) and asks to terminate ({}); g = {} N/m, tau = {} s",
                    self.dialect.last_successful_time,
                    self.dialect.terminate_flag,
                    self.state.settings.params.g,
                    self.state.settings.params.tau
                )))
            }
            Err(e) => {
                self.state.phase = Phase::Error;
                Err(FmiError::error(format!("the simulation failed: {e}")))
            }
        }
    }

    /// The chassis to `until` under the forces on their course (each from
    /// where it was last set, along its input derivative); then its
    /// outputs must be finite.
    fn advance_chassis(&mut self, until: f64) -> Result<Status, FmiError> {
        self.extrapolate_forces(self.time())?;
        let Some(chassis) = self.state.engine.chassis_mut() else {
            return Err(no_simulator());
        };
        chassis.advance_to(until)?;
        if let Some((name, value)) = guards::non_finite_chassis_output(chassis) {
            self.state.terminate_requested = true;
            self.state.phase = Phase::StepFailed;
            return Err(FmiError::discard(format!(
                "`{name}` = {value} is not finite at t = {until} s; the forces are too large for the chassis, {} is {} s, the FMU asks to terminate ({})",
                self.dialect.last_successful_time,
                self.state.last_successful_time,
                self.dialect.terminate_flag
            )));
        }
        self.state.last_successful_time = until;
        Ok(Status::Ok)
    }

    /// Logs (under `logEvents`) each lift-off of the unilateral tire since
    /// the last call: its time, the TDD then and the limit W/k_t it
    /// reached; those the simulator did not keep are counted in one more
    /// message.
    fn log_lift_offs(&mut self) {
        let Some(sim) = self.state.engine.simulator() else {
            return;
        };
        let log = sim.lift_offs();
        if log.is_empty() {
            return;
        }
        let (lift_offs, dropped) = (log.events(), log.dropped);
        let now = sim.time();
        let function = self.call("DoStep");
        for l in lift_offs {
            self.event(format_args!(
                "{function}: lift-off at t = {} s: the wheel leaves the road (TDD = {} m reaches W/k_t = {} m, where the tire load falls to 0; tire_contact = 1)",
                l.time, l.tire_deflection, l.limit
            ));
        }
        if dropped > 0 {
            self.event(format_args!(
                "{function}: ... and {dropped} more lift-offs up to t = {now} s, not listed one by one (`lift_off_count` counts every one)"
            ));
        }
        if let Some(sim) = self.state.engine.simulator_mut() {
            sim.clear_lift_offs();
        }
    }

    /// The slope of `x_g` over the step of length `h` that starts at `now`
    /// (road = 0): the input derivative when the master set one; else, when
    /// a new value was set, the slope [`extrapolation_slope`] gives for
    /// `input_extrapolation` 1 or 2 (fewer values than it needs: the
    /// values there are; the first step holds); else 0 (held). Logs one
    /// warning per instance when a held input with a changing value meets
    /// communication steps longer than [`HOLD_WARNING_STEP`].
    fn input_slope_for_step(&mut self, now: f64, h: f64) -> Result<f64, FmiError> {
        let m = &self.state;
        let x_g = m.settings.x_g;
        let rate = match m.previous_input {
            Some((t, value)) if now > t && m.input_pending => (x_g - value) / (now - t),
            _ => 0.0,
        };
        if m.input_slope_given {
            return Ok(m.input_slope);
        }
        let mode = m.settings.input_extrapolation;
        if mode >= 1 {
            if !m.input_pending {
                return Ok(m.input_slope);
            }
            let earlier = if mode == 2 { m.earlier_input } else { None };
            // The values there are, in time order, without allocating.
            let mut values = [(0.0, 0.0); 3];
            let mut count = 0;
            for value in [earlier, m.previous_input, Some((now, x_g))]
                .into_iter()
                .flatten()
            {
                values[count] = value;
                count += 1;
            }
            let slope = extrapolation_slope(&values[..count], h);
            guards::check_input_slope(slope).map_err(|e| {
                FmiError::error(format!(
                    "input_extrapolation = {mode}: the slope {slope} m/s through x_g = {x_g} m at {now} s and the values before it is refused: {}",
                    e.message
                ))
            })?;
            self.state.input_slope = slope;
            return Ok(slope);
        }
        if h > HOLD_WARNING_STEP && rate != 0.0 && !m.hold_warned {
            self.state.hold_warned = true;
            self.warning(format_args!(
                "{}: x_g is held over communication steps of {h} s (no input derivative, input_extrapolation = 0); at its current rate of change {rate:.4e} m/s the held value lags by about {:.3e} m on average ({:.3e} m at the step end). Set input_extrapolation = 2 (or 1), {}, or use steps of at most 1 ms.",
                self.call("DoStep"),
                0.5 * rate.abs() * h,
                rate.abs() * h,
                self.dialect.input_slope_remedy
            ));
        }
        Ok(0.0)
    }

    /// `SetRealInputDerivatives`: order 1 of `x_g` sets the slope used
    /// from the current communication point on (until `x_g` or the slope is
    /// set again); order 1 of a chassis's force, its rate from now on
    /// (`set_force_derivatives`). Higher orders, and the derivatives of the corner's body
    /// inputs, are ignored with `Warning`.
    pub fn set_real_input_derivatives(
        &mut self,
        vrs: &[u32],
        orders: &[i32],
        values: &[f64],
    ) -> Result<Status, FmiError> {
        if self.model() == Model::Chassis {
            return self.set_force_derivatives(vrs, orders, values);
        }
        let mut slope = None;
        // Whether orders above 1 of `x_g`, and derivatives of the body
        // inputs, were given: named in the warnings as the arguments list
        // them (without allocating: masters set these at every step).
        let (mut ignored, mut body_ignored) = (false, false);
        for ((&vr, &order), &value) in vrs.iter().zip(orders).zip(values) {
            let var = self.variable(vr, VarType::Real)?;
            if var.causality != Causality::Input {
                return Err(FmiError::error(format!(
                    "`{}` is not an input; only the derivative of `x_g` can be set",
                    var.name
                )));
            }
            if order < 1 {
                return Err(FmiError::error(format!(
                    "invalid derivative order {order} for `{}`: must be >= 1",
                    var.name
                )));
            }
            if !value.is_finite() {
                return Err(FmiError::error(format!(
                    "invalid value {value} for the order-{order} derivative of `{}`: must be finite",
                    var.name
                )));
            }
            if var.name != "x_g" {
                // The corner's attachment moves at `body_velocity` over a
                // step; a body input's derivative adds nothing to it.
                body_ignored = true;
            } else if order == 1 {
                guards::check_input_slope(value)?;
                slope = Some(value);
            } else {
                ignored = true;
            }
        }
        // Every reference is known here (checked above).
        let (model, version) = (self.model(), self.dialect.version);
        let name = |vr: u32| by_vr(model, version, vr).map_or("", |var| var.name);
        let body_names = DebugList(|| vrs.iter().map(|&vr| name(vr)).filter(|&name| name != "x_g"));
        let orders_ignored = DebugList(|| {
            vrs.iter()
                .zip(orders)
                .filter(|&(&vr, &order)| name(vr) == "x_g" && order != 1)
                .map(|(_, &order)| order)
        });
        if let Some(slope) = slope {
            self.state.input_slope = slope;
            self.state.input_slope_given = true;
            self.state.input_pending = true;
        }
        if body_ignored {
            self.warning(format_args!(
                "{}: the derivatives of {body_names:?} are ignored: the body's attachment point moves at body_velocity from body_displacement, from where they were set (or on the velocity extrapolated from their last values: input_extrapolation)",
                self.call(self.dialect.set_input_derivatives)
            ));
        }
        if !ignored && !body_ignored {
            Ok(Status::Ok)
        } else if !ignored {
            Ok(Status::Warning)
        } else {
            self.warning(format_args!(
                "{}: derivative orders {orders_ignored:?} of `x_g` ignored (the input is extrapolated linearly)",
                self.call(self.dialect.set_input_derivatives)
            ));
            Ok(Status::Warning)
        }
    }

    /// `SetRealInputDerivatives` of the chassis: order 1 of a force is its
    /// rate (N/s) from now on (until the force or its rate is set again);
    /// every value is checked before any is applied; higher orders are
    /// ignored with `Warning`.
    fn set_force_derivatives(
        &mut self,
        vrs: &[u32],
        orders: &[i32],
        values: &[f64],
    ) -> Result<Status, FmiError> {
        let mut rates = self.state.settings.force_rates;
        let mut given = [false; 4];
        let mut ignored = false;
        for ((&vr, &order), &value) in vrs.iter().zip(orders).zip(values) {
            let var = self.variable(vr, VarType::Real)?;
            let Some(i) = force_index(var.name) else {
                return Err(FmiError::error(format!(
                    "`{}` is not an input; only the derivatives of the forces can be set",
                    var.name
                )));
            };
            if order < 1 || !value.is_finite() {
                return Err(FmiError::error(format!(
                    "invalid order-{order} derivative {value} of `{}`: the order must be >= 1 and the value finite",
                    var.name
                )));
            }
            if order == 1 {
                rates[i] = value;
                given[i] = true;
            } else {
                ignored = true;
            }
        }
        self.state.settings.force_rates = rates;
        for i in (0..4).filter(|&i| given[i]) {
            self.force_set(i, true);
        }
        // The running chassis ramps each force from where it is now.
        if let Some(chassis) = self.state.engine.chassis_mut() {
            let (forces, _) = chassis.forces();
            chassis.set_forces(forces, rates)?;
        }
        if !ignored {
            return Ok(Status::Ok);
        }
        // The forces' references are known here (checked above).
        let (model, version) = (self.model(), self.dialect.version);
        let ignored = DebugList(|| {
            vrs.iter()
                .zip(orders)
                .filter(|&(_, &order)| order != 1)
                .map(|(&vr, &order)| (by_vr(model, version, vr).map_or("", |var| var.name), order))
        });
        self.warning(format_args!(
            "{}: derivatives {ignored:?} ignored (a force is linear over a step)",
            self.call(self.dialect.set_input_derivatives)
        ));
        Ok(Status::Warning)
    }

    /// `GetRealOutputDerivatives` (order 1 only).
    pub fn get_real_output_derivatives(
        &mut self,
        vrs: &[u32],
        orders: &[i32],
        values: &mut [f64],
    ) -> Result<Status, FmiError> {
        if self.model() == Model::Chassis {
            return Err(FmiError::error(
                "the chassis declares no output derivatives (maxOutputDerivativeOrder = 0)",
            ));
        }
        let Some(sim) = self.state.engine.simulator_mut() else {
            return Err(no_simulator());
        };
        let derivatives = sim.output_derivatives();
        for ((&vr, &order), value) in vrs.iter().zip(orders).zip(values.iter_mut()) {
            let var = by_vr(self.model(), self.dialect.version, vr)
                .ok_or_else(|| FmiError::error(format!("unknown value reference {vr}")))?;
            let id = match var.access {
                Access::Output(id) => id,
                Access::IntegerOutput(_) => {
                    return Err(FmiError::error(format!(
                        "`{}` is an Integer output (a count); derivatives exist for Real outputs only",
                        var.name
                    )));
                }
                _ => {
                    return Err(FmiError::error(format!(
                        "`{}` is not an output; derivatives exist for outputs only",
                        var.name
                    )));
                }
            };
            if order != 1 {
                return Err(FmiError::error(format!(
                    "derivative order {order} of `{}` not available (maxOutputDerivativeOrder = 1)",
                    var.name
                )));
            }
            *value = id.derivative(&derivatives);
            if !value.is_finite() {
                let bad = std::mem::replace(value, 0.0);
                return Err(FmiError::error(format!(
                    "the derivative of `{}` = {bad} is not finite; no value returned",
                    var.name
                )));
            }
        }
        Ok(Status::Ok)
    }
}

/// The index among the chassis's forces ([`tdvass::chassis::Corner::ALL`])
/// of the input `name`, if it is one.
/// Formats as `{:?}` of a `Vec` of the items `.0` yields, made while
/// formatting: a warning lists them without collecting them.
struct DebugList<F>(F);

impl<I, F> std::fmt::Debug for DebugList<F>
where
    F: Fn() -> I,
    I: Iterator,
    I::Item: std::fmt::Debug,
{
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list().entries((self.0)()).finish()
    }
}

pub(super) fn force_index(name: &str) -> Option<usize> {
    tdvass::chassis::Corner::ALL
        .iter()
        .position(|corner| corner.force_name() == name)
}

/// The refusal of a co-simulation call without a simulator: a Model
/// Exchange instance (whose master integrates), or one not initialized.
fn no_simulator() -> FmiError {
    FmiError::error(
        "no co-simulation: the instance is a Model Exchange instance (or not initialized); this call is a Co-Simulation capability",
    )
}
