//! What the simulator reports: the outputs at an instant, their time
//! derivatives, and the summary of a run.
//!
//! Layer: clients (docs/architecture.md); it imports the solver's `driver`,
//! `holding`, `integrals`, `reports`, `stepping` and the crate's `metrics`,
//! `model`, `road`.

use super::driver::Simulator;
use super::integrals::{Accumulated, WEIGHTED_FOURTH, WEIGHTED_SQUARE};
use super::reports::{
    CONTINUOUS_STATES, ComfortValues, ContactLoss, FILTER_STATES_AT, INTEGRAL_STATES, INTEGRALS_AT,
    Instantaneous, OutputDerivatives, Outputs, RoadHolding, TimeAverages,
};
use super::stepping::stepping;
use crate::metrics::RmsValues;
use crate::metrics::{rms_values, tire_load_ratio, weighted_averages};
use crate::model::dynamics::{Instant, continuous_rates, plant_rates};
use crate::model::{Performance, State, V_T, X_S, X_T};
use crate::road::RoadPiece;

fn road_piece_now(sim: &mut Simulator) -> RoadPiece {
    let t = sim.trajectory.current_time;
    let piece = sim.inputs.road.piece(t);
    if sim.coincide(piece.end(), t) {
        sim.inputs.road.piece(piece.end())
    } else {
        piece
    }
}

/// `[u, u']`: the delayed tire displacement and its rate now.
fn delayed_tire_now(sim: &mut Simulator) -> (f64, f64) {
    sim.settle();
    let (k, t, x) = (
        sim.trajectory.grid_index,
        sim.trajectory.current_time,
        sim.trajectory.current_state,
    );
    let from = (
        sim.trajectory.committed_time,
        sim.trajectory.committed_state,
    );
    let p = stepping!(sim).delayed_vector_at(k, t, from, &x);
    (p[0], p[1])
}

/// [`Simulator::instantaneous`].
pub(super) fn instantaneous(sim: &mut Simulator) -> Instantaneous {
    match &sim.outputs_cache {
        Some(outputs) => Instantaneous {
            time: outputs.time,
            state: outputs.state,
            performance: outputs.performance,
            road_displacement: outputs.road_displacement,
            control_force: outputs.control_force,
            body_force: outputs.body_force,
            dynamic_tire_load: outputs.dynamic_tire_load,
        },
        None => instantaneous_now(sim),
    }
}

/// [`Simulator::instantaneous`] computed (the state settled first).
fn instantaneous_now(sim: &mut Simulator) -> Instantaneous {
    sim.settle();
    let t = sim.trajectory.current_time;
    let x = sim.trajectory.current_state;
    let piece = road_piece_now(sim);
    let [road, _] = sim.inputs.road_at(&piece, t);
    let (delayed, _) = delayed_tire_now(sim);
    let k_t = sim.config.params.k_t;
    Instantaneous {
        time: t,
        state: sim.plant.reported_state(&x),
        performance: Performance::at(&sim.plant, &x, road),
        road_displacement: road,
        control_force: sim.config.params.effective_gain(sim.config.variant) * delayed,
        body_force: sim.plant.body_force(&x),
        dynamic_tire_load: sim.tire_load(k_t * (road - x[X_T])),
    }
}

/// [`Simulator::outputs`].
pub(super) fn outputs(sim: &mut Simulator) -> Outputs {
    if let Some(outputs) = sim.outputs_cache {
        return outputs;
    }
    let instant = instantaneous_now(sim);
    let t = instant.time;
    let now = sim.accumulated_now();
    let duration = t - sim.config.start_time;
    let averages = time_averages_of(sim, &now.integral, duration);
    let performance = instant.performance;
    let outputs = Outputs {
        time: t,
        state: instant.state,
        performance,
        road_displacement: instant.road_displacement,
        control_force: instant.control_force,
        body_force: instant.body_force,
        rms: averages.rms,
        objective: averages.objective,
        comfort: comfort_values(sim, &now, duration),
        dynamic_tire_load: instant.dynamic_tire_load,
        rms_dynamic_tire_load_ratio: averages.rms_dynamic_tire_load_ratio,
        road_holding: sim.config.metrics.road_holding().then(|| RoadHolding {
            contact_loss_time: now.holding.lost_steps as f64 * sim.grid.step
                + now.holding.lost_time
                + sim.trajectory.flight_start.map_or(0.0, |start| t - start),
            max_suspension_deflection: now
                .holding
                .max_deflection
                .max(performance.suspension_deflection.abs()),
            first_contact_loss: now
                .holding
                .first_loss
                .map(|time| contact_loss_at(sim, time)),
            lift_off_count: now.holding.lift_offs,
        }),
    };
    sim.outputs_cache = Some(outputs);
    outputs
}

/// [`Simulator::time_averages`].
pub(super) fn time_averages(sim: &mut Simulator) -> TimeAverages {
    if let Some(outputs) = &sim.outputs_cache {
        return outputs.time_averages();
    }
    let integral = sim.rms_integral_now();
    let duration = sim.trajectory.current_time - sim.config.start_time;
    time_averages_of(sim, &integral, duration)
}

/// The time averages from the integrals `∫ y² dt` over `duration`.
fn time_averages_of(sim: &Simulator, integral: &[f64], duration: f64) -> TimeAverages {
    let rms = rms_values(integral, duration);
    TimeAverages {
        rms,
        objective: rms.objective(&sim.config.weights),
        rms_dynamic_tire_load_ratio: tire_load_ratio(
            sim.config.params.k_t,
            rms.tire_deflection,
            static_load(sim),
        ),
    }
}

/// [`Simulator::static_load`].
pub(super) fn static_load(sim: &Simulator) -> f64 {
    sim.config.params.static_load(sim.config.variant)
}

/// [`Simulator::first_contact_loss`].
pub(super) fn first_contact_loss(sim: &mut Simulator) -> Option<ContactLoss> {
    if !sim.config.metrics.road_holding() {
        return None;
    }
    if let Some(time) = sim.observers.holding.first_loss {
        return Some(contact_loss_at(sim, time));
    }
    let (tc, t) = (sim.trajectory.committed_time, sim.trajectory.current_time);
    if t <= tc {
        return None;
    }
    let piece = sim.inputs.piece_from(tc);
    if piece.end() >= t {
        let xc = sim.trajectory.committed_state;
        if let Some(drift) = sim.deferred_drift() {
            // A deferred state: the test below with bounds of its
            // `x_t` and `|v_t|` (each evaluation is
            // monotone in them, so passing it means the state passes
            // it too); where it does not pass, the state is computed.
            let end = StretchEnd {
                tire_high: xc[X_T] + drift[X_T],
                tire_magnitude: xc[X_T].abs() + drift[X_T],
                tire_speed: xc[V_T].abs() + drift[V_T],
            };
            if stretch_keeps_contact(sim, &piece, (tc, &xc), (t, end)) {
                return None;
            }
            sim.settle();
        }
        let x = sim.trajectory.current_state;
        if stretch_keeps_contact(sim, &piece, (tc, &xc), (t, StretchEnd::at(&x))) {
            return None;
        }
        let (a, b) = (
            stepping!(sim).margin_kept(tc, &xc, &piece),
            stepping!(sim).margin_kept(t, &x, &piece),
        );
        if !super::holding::may_lose_contact(t - tc, a, b) {
            return None;
        }
    }
    outputs(sim)
        .road_holding
        .and_then(|holding| holding.first_contact_loss)
}

/// Whether the margins of [`Simulator::first_contact_loss`]'s test over the
/// stretch from the committed point `c` to the current point `now`
/// surely pass it, decided without a sine: on the harmonic road, from
/// a committed grid node and the phase the whole-step loop carries
/// there. `x_g` at the node is that phase's `A sin ω t_c` up to its
/// rounding drift (of the order of [`super::inputs::PHASE_ANCHOR`] ulp, and of
/// the rounding of `ω t_c`), both inside `slack`; `x_g` at `now` is
/// above it less `|A ω| (t − t_c)`; each `|g'|` is at most
/// `|A ω| + |v_t|`. `false` (the exact test decides) elsewhere.
fn stretch_keeps_contact(
    sim: &Simulator,
    piece: &RoadPiece,
    (tc, xc): (f64, &State),
    (t, end): (f64, StretchEnd),
) -> bool {
    let RoadPiece::Harmonic {
        amplitude,
        angular_frequency,
        phase,
    } = *piece
    else {
        return false;
    };
    let k = sim.trajectory.grid_index;
    let Some(z) = sim.inputs.kept_node_phase(k) else {
        return false;
    };
    if tc != sim.grid_time(k) {
        return false;
    }
    let length = t - tc;
    let limit = sim.modes.grid_step.switching.tire_limit;
    let amplitude = amplitude.abs();
    let sweep = (amplitude * angular_frequency).abs();
    let slack = 1e-9 * (limit.abs() + amplitude + xc[X_T].abs() + end.tire_magnitude)
        + 8.0 * f64::EPSILON * amplitude * ((angular_frequency * tc).abs() + phase.abs());
    let road = z[0] - slack;
    let lower = (limit - (xc[X_T] - road)).min(limit - (end.tire_high - (road - sweep * length)));
    let rates = 2.0 * sweep + xc[V_T].abs() + end.tire_speed;
    super::holding::keeps_contact(length, lower, rates)
}

fn contact_loss_at(sim: &Simulator, time: f64) -> ContactLoss {
    let static_load = static_load(sim);
    let dynamic_tire_load =
        if time == sim.config.start_time && sim.observers.start_load < -static_load {
            sim.observers.start_load
        } else {
            -static_load
        };
    ContactLoss {
        time,
        dynamic_tire_load,
        static_load,
    }
}

fn comfort_values(sim: &Simulator, now: &Accumulated, duration: f64) -> Option<ComfortValues> {
    let coupling = sim.modes.coupling.as_ref()?;
    let (rms, dose) = weighted_averages(
        now.integral[WEIGHTED_SQUARE],
        now.integral[WEIGHTED_FOURTH],
        duration,
    );
    Some(ComfortValues {
        weighted_body_acceleration: coupling.weighted(&now.filter),
        rms_weighted_body_acceleration: rms,
        vibration_dose_value: dose,
    })
}

/// [`Simulator::output_derivatives`].
pub(super) fn output_derivatives(sim: &mut Simulator) -> OutputDerivatives {
    sim.settle();
    let t = sim.trajectory.current_time;
    let x = sim.trajectory.current_state;
    let piece = road_piece_now(sim);
    let (road, road_rate) = (piece.value(t), piece.slope(t));
    let (delayed, delayed_rate) = delayed_tire_now(sim);
    let b = sim.modes.input_column;
    let drive = stepping!(sim).forcing(&piece);
    let dx = plant_rates(
        &sim.modes.solver_matrix,
        &b,
        &sim.plant.e,
        &x,
        delayed,
        drive.value(t),
    );
    let d2x = sim.modes.solver_matrix * dx + b * delayed_rate + sim.plant.e * drive.slope(t);
    let gain = sim.config.params.effective_gain(sim.config.variant);
    let now = Performance::at(&sim.plant, &x, road);
    let rms = outputs(sim).rms;
    let duration = t - sim.config.start_time;
    let rate = |y: f64, value: f64| {
        if duration > 0.0 && value > 0.0 {
            (y * y - value * value) / (2.0 * value * duration)
        } else {
            0.0
        }
    };
    let rms_rate = RmsValues {
        body_acceleration: rate(now.body_acceleration, rms.body_acceleration),
        suspension_deflection: rate(now.suspension_deflection, rms.suspension_deflection),
        tire_deflection: rate(now.tire_deflection, rms.tire_deflection),
    };
    let outputs = outputs(sim);
    let accumulated = sim.accumulated_now();
    let comfort = match (&sim.modes.coupling, outputs.comfort) {
        (Some(coupling), Some(values)) => {
            let filter = accumulated.filter;
            let a = values.weighted_body_acceleration;
            let vdv = values.vibration_dose_value;
            Some(ComfortValues {
                weighted_body_acceleration: coupling.weighted_rate(&filter, now.body_acceleration),
                rms_weighted_body_acceleration: rate(a, values.rms_weighted_body_acceleration),
                vibration_dose_value: if vdv > 0.0 {
                    a.powi(4) / (4.0 * vdv.powi(3))
                } else {
                    0.0
                },
            })
        }
        _ => None,
    };
    let k_t = sim.config.params.k_t;
    let sdd_rate = dx[X_S] - dx[X_T];
    let sdd = now.suspension_deflection;
    let growing = sdd.signum() * sdd_rate;
    let holding = accumulated.holding;
    let in_contact = if sim.config.tire_contact.is_unilateral() {
        !sim.in_flight()
    } else {
        stepping!(sim).margin_at(t, &x, &piece)[0] >= 0.0
    };
    OutputDerivatives {
        comfort,
        dynamic_tire_load: if in_contact {
            k_t * (road_rate - dx[X_T])
        } else if sim.config.tire_contact.is_unilateral() {
            0.0
        } else {
            k_t * (road_rate - dx[X_T])
        },
        rms_dynamic_tire_load_ratio: k_t * rms_rate.tire_deflection / static_load(sim),
        road_holding: sim.config.metrics.road_holding().then_some(RoadHolding {
            contact_loss_time: if in_contact { 0.0 } else { 1.0 },
            max_suspension_deflection: if sdd.abs() >= holding.max_deflection && growing > 0.0 {
                growing
            } else {
                0.0
            },
            first_contact_loss: None,
            lift_off_count: 0,
        }),
        rms: rms_rate,
        objective: rms_rate.objective(&sim.config.weights),
        state: sim.plant.reported_state(&dx),
        performance: Performance {
            body_acceleration: d2x[crate::model::V_S],
            suspension_deflection: dx[crate::model::X_S] - dx[X_T],
            tire_deflection: dx[X_T] - road_rate,
        },
        road_displacement: road_rate,
        control_force: gain * delayed_rate,
        body_force: sim.plant.body_force(&dx),
    }
}

/// [`Simulator::continuous_states`].
pub(super) fn continuous_states(sim: &mut Simulator) -> [f64; CONTINUOUS_STATES] {
    let now = sim.accumulated_now();
    let reported = sim.plant.reported_state(&sim.trajectory.current_state);
    let mut states = [0.0; CONTINUOUS_STATES];
    states[..6].copy_from_slice(reported.as_slice());
    states[FILTER_STATES_AT..INTEGRALS_AT].copy_from_slice(now.filter.as_slice());
    states[INTEGRALS_AT..INTEGRALS_AT + INTEGRAL_STATES - 1].copy_from_slice(&now.integral);
    states[CONTINUOUS_STATES - 1] = outputs(sim)
        .road_holding
        .map_or(0.0, |r| r.contact_loss_time);
    states
}

/// [`Simulator::continuous_state_derivatives`].
pub(super) fn continuous_state_derivatives(sim: &mut Simulator) -> [f64; CONTINUOUS_STATES] {
    let d = output_derivatives(sim);
    let o = outputs(sim);
    let filter = sim.accumulated_now().filter;
    let now = Instant {
        body_acceleration: o.performance.body_acceleration,
        suspension_deflection: o.performance.suspension_deflection,
        tire_deflection: o.performance.tire_deflection,
        weighted_acceleration: o.comfort.map_or(0.0, |c| c.weighted_body_acceleration),
        contact_lost: d.road_holding.map_or(0.0, |r| r.contact_loss_time),
    };
    let wk = sim.modes.coupling.as_ref().map(|c| &c.wk);
    continuous_rates(&d.state, &filter, wk, &now)
}

/// [`Simulator::rms`].
pub(super) fn rms(sim: &mut Simulator) -> RmsValues {
    sim.rms_now()
}

/// The end point of a stretch in [`stretch_keeps_contact`]:
/// `x_t` there (or a bound above it), and bounds of `|x_t|` and `|v_t|`.
#[derive(Debug, Clone, Copy)]
struct StretchEnd {
    tire_high: f64,
    tire_magnitude: f64,
    tire_speed: f64,
}

impl StretchEnd {
    /// The end point at state x (the values themselves).
    fn at(x: &State) -> StretchEnd {
        StretchEnd {
            tire_high: x[X_T],
            tire_magnitude: x[X_T].abs(),
            tire_speed: x[V_T].abs(),
        }
    }
}
