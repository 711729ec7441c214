//! What the simulator reports: the outputs at an instant, their time
//! derivatives, and the summary of a run.

use super::Simulator;
use super::integrals::{Accumulated, WEIGHTED_FOURTH, WEIGHTED_SQUARE, rms_from_integral};
use super::stepping::stepping;
use crate::metrics::RmsValues;
use crate::model::{Performance, State, V_T, X_S, X_T};
use crate::road::RoadPiece;

/// Ride comfort by ISO 2631-1:1997 (vertical whole-body vibration, W_k
/// weighting of the body acceleration BA; see [`crate::comfort`]), present
/// when [`super::SimulationConfig::metrics`] is [`super::Metrics::Comfort`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ComfortValues {
    /// The frequency-weighted body acceleration a_w(t) (m/s²): BA through
    /// W_k, the filter starting from rest at t_0.
    pub weighted_body_acceleration: f64,
    /// Its running RMS, the time average
    /// `sqrt((1/(t − t_0)) ∫_{t_0}^{t} a_w² ds)` (m/s²; 0 at the start),
    /// the a_w of ISO 2631-1 section 6.1 and of its comfort scale
    /// ([`crate::comfort::comfort_reaction`]).
    pub rms_weighted_body_acceleration: f64,
    /// The vibration dose value `VDV = (∫_{t_0}^{t} a_w⁴ ds)^{1/4}`
    /// (m/s^1.75), ISO 2631-1 section 6.3.2.
    pub vibration_dose_value: f64,
}

/// Road holding and working space so far, kept with
/// [`super::Metrics::RoadHolding`] (and [`super::Metrics::Comfort`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RoadHolding {
    /// The time without tire contact so far (s): the measure of the times
    /// at which the dynamic tire load was below −W, crossings located
    /// inside the steps (see `solver::holding`); with the unilateral tire
    /// the flight time, between located switches (see `solver::contact`).
    pub contact_loss_time: f64,
    /// The largest |SDD| so far (m), located inside the steps (see
    /// `solver::holding`), and now: the suspension working space used.
    pub max_suspension_deflection: f64,
    /// The first loss of tire contact, if any so far.
    pub first_contact_loss: Option<ContactLoss>,
    /// The number of lift-offs so far: with the unilateral tire, the
    /// switches from contact to flight; with the bilateral tire, the
    /// number of times the dynamic tire load went below −W (a run that
    /// starts without contact counts one at the start).
    pub lift_off_count: u64,
}

/// The first loss of tire contact: the first time at which the dynamic
/// tire load `k_t (x_g − x_t)` fell below minus the static load
/// ([`crate::model::Params::static_load`]). With the bilateral tire the
/// linear model does not hold while the contact is lost; the simulation
/// goes on, and front-ends warn once. With the unilateral tire it is the
/// first lift-off.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactLoss {
    /// When (s).
    pub time: f64,
    /// The dynamic tire load then (N): minus the static load at a crossing
    /// inside the run, the initial value when the run starts without
    /// contact.
    pub dynamic_tire_load: f64,
    /// The static load W (N).
    pub static_load: f64,
}

/// Every output of the model at one instant (the FMU's outputs).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Outputs {
    /// Time (s).
    pub time: f64,
    /// Reported state `[x_s, v_s, x_h, v_h, x_t, v_t]` (CS: x_h, v_h mirror the wheel).
    pub state: State,
    /// BA, SDD, TDD.
    pub performance: Performance,
    /// The road displacement x_g actually applied (m).
    pub road_displacement: f64,
    /// Control force `u = g x_t(t − tau)` (N).
    pub control_force: f64,
    /// Running RMS values from the start to now, as time averages
    /// `sqrt((1/(t − t_0)) ∫_{t_0}^{t} y² ds)` (0 at the start).
    pub rms: RmsValues,
    /// J of Eq. (6) from the running RMS values.
    pub objective: f64,
    /// ISO 2631-1 ride comfort (`None` unless
    /// [`super::SimulationConfig::metrics`] is [`super::Metrics::Comfort`]).
    pub comfort: Option<ComfortValues>,
    /// The dynamic tire load `k_t (x_g − x_t)` (N; `−k_t TDD`, positive
    /// when the tire is compressed beyond its static load; there is no tire
    /// damping); with the unilateral tire at least −W (0 N of total load
    /// in flight).
    pub dynamic_tire_load: f64,
    /// `RMS(dynamic tire load) / W` (dimensionless): `k_t RMS(TDD) / W`
    /// with the static load W ([`crate::model::Params::static_load`]).
    /// At most 1/3 keeps the contact with 3σ confidence for a Gaussian
    /// load. It is the tire deflection's, also with the unilateral tire
    /// (whose load does not fall below −W in flight).
    pub rms_dynamic_tire_load_ratio: f64,
    /// Road holding and working space (`None` below
    /// [`super::Metrics::RoadHolding`]).
    pub road_holding: Option<RoadHolding>,
}

impl Outputs {
    /// The time averages among them.
    pub fn time_averages(&self) -> TimeAverages {
        TimeAverages {
            rms: self.rms,
            objective: self.objective,
            rms_dynamic_tire_load_ratio: self.rms_dynamic_tire_load_ratio,
        }
    }

    /// The outputs every metrics level has, as numbers in a fixed order:
    /// the reported state `[x_s, v_s, x_h, v_h, x_t, v_t]`, BA, SDD, TDD,
    /// x_g, the control force, RMS of BA, SDD, TDD, and J.
    pub fn core_values(&self) -> [f64; 15] {
        let s = &self.state;
        [
            s[0],
            s[1],
            s[2],
            s[3],
            s[4],
            s[5],
            self.performance.body_acceleration,
            self.performance.suspension_deflection,
            self.performance.tire_deflection,
            self.road_displacement,
            self.control_force,
            self.rms.body_acceleration,
            self.rms.suspension_deflection,
            self.rms.tire_deflection,
            self.objective,
        ]
    }
}

/// The outputs that are time averages from the start (see [`Outputs`]),
/// for a reader that needs only them ([`Simulator::time_averages`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct TimeAverages {
    /// Running RMS values of BA, SDD and TDD.
    pub rms: RmsValues,
    /// J of Eq. (6) from the running RMS values.
    pub objective: f64,
    /// `RMS(dynamic tire load) / W`.
    pub rms_dynamic_tire_load_ratio: f64,
}

/// The outputs that are values at the current instant (see [`Outputs`]),
/// for a reader that needs only them ([`Simulator::instantaneous`]): no
/// integral from the start is closed for them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Instantaneous {
    /// Time (s).
    pub time: f64,
    /// Reported state `[x_s, v_s, x_h, v_h, x_t, v_t]` (CS: x_h, v_h mirror the wheel).
    pub state: State,
    /// BA, SDD, TDD.
    pub performance: Performance,
    /// The road displacement x_g actually applied (m).
    pub road_displacement: f64,
    /// Control force `u = g x_t(t − tau)` (N).
    pub control_force: f64,
    /// The dynamic tire load `k_t (x_g − x_t)` (N; at least −W with the
    /// unilateral tire).
    pub dynamic_tire_load: f64,
}

/// First time derivatives of the outputs.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct OutputDerivatives {
    /// dX/dt (reported state).
    pub state: State,
    /// d/dt of BA, SDD, TDD.
    pub performance: Performance,
    /// dx_g/dt.
    pub road_displacement: f64,
    /// du/dt.
    pub control_force: f64,
    /// d/dt of the running RMS values: `(y² − RMS²) / (2 RMS (t − t_0))`
    /// (0 at the start and where an RMS value is 0).
    pub rms: RmsValues,
    /// dJ/dt.
    pub objective: f64,
    /// d/dt of the comfort outputs: `da_w/dt = c_w (A_w w + b_w BA)`, the
    /// RMS rate as above, `dVDV/dt = a_w⁴ / (4 VDV³)` (0 where VDV = 0).
    pub comfort: Option<ComfortValues>,
    /// d/dt of the dynamic tire load, `k_t (dx_g/dt − v_t)` (N/s).
    pub dynamic_tire_load: f64,
    /// d/dt of the RMS dynamic tire load ratio (1/s).
    pub rms_dynamic_tire_load_ratio: f64,
    /// d/dt of road holding and working space: of the contact loss time 1
    /// while the contact is lost, else 0; of the largest |SDD| (m/s)
    /// `d|SDD|/dt` while |SDD| now is the largest and growing, else 0;
    /// `first_contact_loss` is `None`.
    pub road_holding: Option<RoadHolding>,
}

/// Summary of a finished run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunSummary {
    /// RMS values over the run.
    pub rms: RmsValues,
    /// J of Eq. (6).
    pub objective: f64,
    /// ISO 2631-1 ride comfort at the end (`None` unless
    /// [`super::SimulationConfig::metrics`] is [`super::Metrics::Comfort`]).
    pub comfort: Option<ComfortValues>,
    /// `RMS(dynamic tire load) / W` over the run (see [`Outputs`]).
    pub rms_dynamic_tire_load_ratio: f64,
    /// Road holding and working space over the run (`None` below
    /// [`super::Metrics::RoadHolding`]).
    pub road_holding: Option<RoadHolding>,
}

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
    let rms = rms_from_integral(integral, duration);
    TimeAverages {
        rms,
        objective: rms.objective(&sim.config.weights),
        rms_dynamic_tire_load_ratio: sim.config.params.k_t * rms.tire_deflection / static_load(sim),
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
    let limit = sim.modes.grid_step.contact.limit;
    let amplitude = amplitude.abs();
    let sweep = (amplitude * angular_frequency).abs();
    let slack = 1e-9 * (limit.abs() + amplitude + xc[X_T].abs() + end.tire_magnitude)
        + 8.0 * f64::EPSILON * amplitude * (angular_frequency * tc).abs();
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
    let rms = if duration > 0.0 {
        (now.integral[WEIGHTED_SQUARE].max(0.0) / duration).sqrt()
    } else {
        0.0
    };
    Some(ComfortValues {
        weighted_body_acceleration: coupling.weighted(&now.filter),
        rms_weighted_body_acceleration: rms,
        vibration_dose_value: now.integral[WEIGHTED_FOURTH].max(0.0).sqrt().sqrt(),
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
    let dx = sim.modes.solver_matrix * x + b * delayed + sim.plant.e * drive.value(t);
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
    }
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
