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
//!   method is fourth-order accurate in the step;
//! - the road is a sine (an exosystem) or a straight line (see
//!   [`crate::road`]).
//!
//! All the step matrices come from one exponential of an augmented matrix
//! (the plant plus the input generators), computed by the 2^N algorithm in
//! [`expm::precise_exp`].
//!
//! **Caller independence.** States are committed only on an internal grid
//! anchored at the start time (`t_k = t_0 + k h`); road breakpoints inside a
//! step split it internally. A time between grid nodes is reached by a dense
//! output from the last grid node that is not committed. So how a caller
//! splits an interval does not change any result: outputs agree bit for bit.
//! An external road input (`RoadSpec::Input`) is the exception: the state is
//! committed where the input changes.

pub mod expm;
mod persist;

use crate::error::{Error, Result};
use crate::metrics::{RmsValues, RunningRms, Weights};
use crate::model::{Params, Performance, Plant, State, V_T, Variant, X_T};
use crate::road::{Road, RoadPiece, RoadSpec};
use nalgebra::{Matrix6, SMatrix, Vector2, Vector4};
use std::collections::HashMap;

/// Default upper bound of the internal step (s).
pub const DEFAULT_MAX_INTERNAL_STEP: f64 = 1e-4;
/// Most grid nodes of delay history kept (8 M nodes, 64 MiB); a delay
/// needing more is refused.
pub const MAX_HISTORY_NODES: u64 = 1 << 23;
/// Delays below this (s) are folded into the plant as
/// `x_t(t − tau) ≈ x_t(t) − tau v_t(t)` (error ≤ tau²/2 |d²x_t/dt²|, below
/// 5e-15 |d²x_t/dt²|) instead of forcing a grid step of tau.
pub const MIN_RESOLVED_DELAY: f64 = 1e-7;
/// Displacement bound (m): beyond it the run is declared divergent.
pub const DIVERGENCE_DISPLACEMENT: f64 = 1e3;
/// Velocity bound (m/s): beyond it the run is declared divergent.
pub const DIVERGENCE_VELOCITY: f64 = 1e6;
/// Cached operators for partial steps (the cache is cleared when full).
const OPERATOR_CACHE_SIZE: usize = 512;
/// Resolution of partial step lengths: 2^-40 of the grid step.
const PARTIAL_STEP_RESOLUTION: f64 = 1099511627776.0;

/// Everything that defines a simulation.
#[derive(Debug, Clone, PartialEq)]
pub struct SimulationConfig {
    /// Physical and controller parameters.
    pub params: Params,
    /// CS, PVASS or TDVASS.
    pub variant: Variant,
    /// The road.
    pub road: RoadSpec,
    /// Upper bound of the internal step (s).
    pub max_internal_step: f64,
    /// Start time t_0 (s).
    pub start_time: f64,
    /// X(t_0) = [x_s, v_s, x_h, v_h, x_t, v_t]; also the history for t < t_0.
    pub initial_state: State,
    /// Weights of the objective J.
    pub weights: Weights,
}

impl Default for SimulationConfig {
    /// TDVASS, Table 1, (g1, tau1), the harmonic road 0.05 sin 5t, from rest.
    fn default() -> Self {
        SimulationConfig {
            params: Params::default(),
            variant: Variant::Tdvass,
            road: RoadSpec::paper_harmonic(),
            max_internal_step: DEFAULT_MAX_INTERNAL_STEP,
            start_time: 0.0,
            initial_state: State::zeros(),
            weights: Weights::default(),
        }
    }
}

/// How the delay is resolved on the grid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DelayGrid {
    /// Internal step h (s).
    pub step: f64,
    /// tau = m h; 0 when the delay is folded into the plant.
    pub delay_steps: u64,
}

impl DelayGrid {
    /// `h = tau / m` with `m = ceil(tau / h_max)`, or `h = h_max` when the
    /// delay is zero or below [`MIN_RESOLVED_DELAY`].
    pub fn new(tau: f64, max_internal_step: f64) -> Result<DelayGrid> {
        if !(max_internal_step.is_finite() && max_internal_step > 0.0) {
            return Err(Error::InvalidParameter {
                name: "max_internal_step",
                value: max_internal_step,
                reason: "must be finite and > 0",
            });
        }
        if !(tau.is_finite() && tau >= 0.0) {
            return Err(Error::InvalidParameter {
                name: "tau",
                value: tau,
                reason: "the delay must be finite and >= 0",
            });
        }
        if tau < MIN_RESOLVED_DELAY {
            return Ok(DelayGrid {
                step: max_internal_step,
                delay_steps: 0,
            });
        }
        let ratio = (tau / max_internal_step * (1.0 - 1e-12)).ceil().max(1.0);
        if ratio > MAX_HISTORY_NODES as f64 {
            return Err(Error::InvalidParameter {
                name: "tau",
                value: tau,
                reason: "the delay needs more than 8388608 history nodes at this max_internal_step",
            });
        }
        let delay_steps = ratio as u64;
        Ok(DelayGrid {
            step: tau / delay_steps as f64,
            delay_steps,
        })
    }

    /// Whether the delay is resolved on the grid (not folded).
    pub fn resolves_delay(&self) -> bool {
        self.delay_steps > 0
    }
}

/// Dimension of the augmented system: plant (6), cubic delayed input (4),
/// linear road (2), harmonic road (2).
const AUGMENTED: usize = 14;
const DELAY_INPUT: usize = 6;
const LINEAR_ROAD: usize = 10;
const HARMONIC_ROAD: usize = 12;

/// The exact map of one step of length δ:
/// `X(a+δ) = Φ X(a) + Γ_u p + Γ_l q + Γ_h z`, where
/// `p = [u, u', u'', u'''](a)` (delayed tire displacement and derivatives),
/// `q = [x_g, x_g'](a)` (linear road), `z = A_r [sin ω a, cos ω a]` (harmonic).
#[derive(Debug, Clone, PartialEq)]
struct StepOperator {
    transition: Matrix6<f64>,
    delayed_input: SMatrix<f64, 6, 4>,
    linear_road: SMatrix<f64, 6, 2>,
    harmonic_road: SMatrix<f64, 6, 2>,
}

impl StepOperator {
    fn new(a: &Matrix6<f64>, b: &State, e: &State, angular_frequency: f64, length: f64) -> Self {
        let mut m = SMatrix::<f64, AUGMENTED, AUGMENTED>::zeros();
        m.fixed_view_mut::<6, 6>(0, 0).copy_from(a);
        m.fixed_view_mut::<6, 1>(0, DELAY_INPUT).copy_from(b);
        for i in 0..3 {
            m[(DELAY_INPUT + i, DELAY_INPUT + i + 1)] = 1.0;
        }
        m.fixed_view_mut::<6, 1>(0, LINEAR_ROAD).copy_from(e);
        m[(LINEAR_ROAD, LINEAR_ROAD + 1)] = 1.0;
        m.fixed_view_mut::<6, 1>(0, HARMONIC_ROAD).copy_from(e);
        m[(HARMONIC_ROAD, HARMONIC_ROAD + 1)] = angular_frequency;
        m[(HARMONIC_ROAD + 1, HARMONIC_ROAD)] = -angular_frequency;
        let exp = expm::precise_exp(&(m * length));
        StepOperator {
            transition: exp.fixed_view::<6, 6>(0, 0).into_owned(),
            delayed_input: exp.fixed_view::<6, 4>(0, DELAY_INPUT).into_owned(),
            linear_road: exp.fixed_view::<6, 2>(0, LINEAR_ROAD).into_owned(),
            harmonic_road: exp.fixed_view::<6, 2>(0, HARMONIC_ROAD).into_owned(),
        }
    }

    #[inline]
    fn apply(&self, x: &State, delayed: Option<&Vector4<f64>>, road: &RoadPiece, at: f64) -> State {
        let mut next = self.transition * x;
        if let Some(p) = delayed {
            next += self.delayed_input * p;
        }
        match *road {
            RoadPiece::Linear { .. } => {
                next += self.linear_road * Vector2::new(road.value(at), road.slope(at));
            }
            RoadPiece::Harmonic {
                amplitude,
                angular_frequency,
            } => {
                let (sin, cos) = (angular_frequency * at).sin_cos();
                next += self.harmonic_road * Vector2::new(amplitude * sin, amplitude * cos);
            }
        }
        next
    }
}

/// Cubic Hermite interpolant of `x_t` over one grid interval of length h:
/// `[u, u', u'', u''']` at offset σ.
#[inline]
fn hermite(nodes: [f64; 4], h: f64, offset: f64) -> Vector4<f64> {
    let [x0, v0, x1, v1] = nodes;
    let slope = (x1 - x0) / h;
    let c2 = (3.0 * slope - 2.0 * v0 - v1) / h;
    let c3 = (v0 + v1 - 2.0 * slope) / (h * h);
    let s = offset;
    Vector4::new(
        x0 + s * (v0 + s * (c2 + s * c3)),
        v0 + s * (2.0 * c2 + 3.0 * c3 * s),
        2.0 * c2 + 6.0 * c3 * s,
        6.0 * c3,
    )
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
    /// Running RMS values from the start to now, sampled on the grid.
    pub rms: RmsValues,
    /// J of Eq. (6) from the running RMS values.
    pub objective: f64,
}

/// First time derivatives of the instantaneous outputs.
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
}

/// Summary of a finished run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunSummary {
    /// RMS values over the run.
    pub rms: RmsValues,
    /// J of Eq. (6).
    pub objective: f64,
}

/// The simulator: a quarter car on a road, advanced in time by the precise
/// integration method. `Clone` is a complete snapshot of it.
#[derive(Debug, Clone)]
pub struct Simulator {
    config: SimulationConfig,
    plant: Plant,
    /// Plant matrix used by the solver (the plant's A, plus the folded
    /// feedback when the delay is not resolved on the grid).
    solver_matrix: Matrix6<f64>,
    grid: DelayGrid,
    full_step: StepOperator,
    partial_steps: HashMap<u64, StepOperator>,
    road: Road,
    /// Index k of the grid node at or before the committed time.
    grid_index: u64,
    committed_time: f64,
    committed_state: State,
    current_time: f64,
    current_state: State,
    /// (x_t, v_t) at grid nodes `grid_index − m ..= grid_index`, by `index % (m + 1)`.
    history: Vec<[f64; 2]>,
    rms: RunningRms,
}

impl Simulator {
    /// Validates the configuration and places the system at its initial state.
    pub fn new(config: SimulationConfig) -> Result<Simulator> {
        let plant = Plant::new(config.params, config.variant)?;
        if !config.start_time.is_finite() {
            return Err(Error::InvalidTime {
                name: "start_time",
                value: config.start_time,
                reason: "must be finite",
            });
        }
        for (i, value) in config.initial_state.iter().enumerate() {
            if !value.is_finite() {
                return Err(Error::InvalidParameter {
                    name: crate::model::STATE_NAMES[i],
                    value: *value,
                    reason: "the initial state must be finite",
                });
            }
        }
        let w = config.weights;
        for (name, value) in [
            ("w_ba", w.body_acceleration),
            ("w_sdd", w.suspension_deflection),
            ("w_tdd", w.tire_deflection),
        ] {
            if !value.is_finite() {
                return Err(Error::InvalidParameter {
                    name,
                    value,
                    reason: "a weight must be finite",
                });
            }
        }
        let tau = if config.variant.has_control() {
            config.params.tau
        } else {
            0.0
        };
        let grid = DelayGrid::new(tau, config.max_internal_step)?;
        let road = Road::new(&config.road, config.start_time)?;
        let mut initial = config.initial_state;
        if config.variant == Variant::Cs {
            initial[crate::model::X_H] = 0.0;
            initial[crate::model::V_H] = 0.0;
        }
        let (solver_matrix, full_step) = Self::operators(&plant, &config, &grid);
        let history = vec![[initial[X_T], initial[V_T]]; grid.delay_steps as usize + 1];
        Ok(Simulator {
            plant,
            solver_matrix,
            grid,
            full_step,
            partial_steps: HashMap::new(),
            road,
            grid_index: 0,
            committed_time: config.start_time,
            committed_state: initial,
            current_time: config.start_time,
            current_state: initial,
            history,
            rms: RunningRms::default(),
            config,
        })
    }

    fn operators(
        plant: &Plant,
        config: &SimulationConfig,
        grid: &DelayGrid,
    ) -> (Matrix6<f64>, StepOperator) {
        let mut a = plant.a;
        let mut b = plant.b;
        if !grid.resolves_delay() {
            // u = g (x_t − tau v_t): fold the feedback into the plant.
            let tau = if config.variant.has_control() {
                config.params.tau
            } else {
                0.0
            };
            for row in 0..6 {
                a[(row, X_T)] += b[row];
                a[(row, V_T)] -= tau * b[row];
            }
            b = State::zeros();
        }
        let omega = match config.road {
            RoadSpec::Harmonic {
                angular_frequency, ..
            } => angular_frequency,
            _ => 0.0,
        };
        let step = StepOperator::new(&a, &b, &plant.e, omega, grid.step);
        (a, step)
    }

    /// The configuration.
    pub fn config(&self) -> &SimulationConfig {
        &self.config
    }

    /// The plant (A, b, e of Eq. (2)).
    pub fn plant(&self) -> &Plant {
        &self.plant
    }

    /// The internal grid (step and delay in steps).
    pub fn grid(&self) -> DelayGrid {
        self.grid
    }

    /// Current time (s).
    pub fn time(&self) -> f64 {
        self.current_time
    }

    /// Time of the last committed state (s): the last grid node reached, or
    /// the last change of an external road input.
    pub fn committed_time(&self) -> f64 {
        self.committed_time
    }

    /// Current state `X` (solver coordinates).
    pub fn state(&self) -> State {
        self.current_state
    }

    fn grid_time(&self, k: u64) -> f64 {
        self.config.start_time + k as f64 * self.grid.step
    }

    fn coincide(&self, a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-9 * self.grid.step + 8.0 * f64::EPSILON * a.abs().max(b.abs())
    }

    /// Delayed-input vector `[u, u', u'', u''']` at offset σ into grid step k.
    #[inline]
    fn delayed_input(&self, k: u64, offset: f64) -> Vector4<f64> {
        let m = self.grid.delay_steps;
        let nodes = if k < m {
            let x = self.config.initial_state[X_T];
            [x, 0.0, x, 0.0]
        } else {
            let len = self.history.len() as u64;
            let [x0, v0] = self.history[((k - m) % len) as usize];
            let [x1, v1] = self.history[((k - m + 1) % len) as usize];
            [x0, v0, x1, v1]
        };
        hermite(nodes, self.grid.step, offset)
    }

    fn partial_operator(&mut self, length: f64) -> &StepOperator {
        let key = (length / self.grid.step * PARTIAL_STEP_RESOLUTION).round() as u64;
        if self.partial_steps.len() >= OPERATOR_CACHE_SIZE && !self.partial_steps.contains_key(&key)
        {
            self.partial_steps.clear();
        }
        let (a, b, e) = (self.solver_matrix, self.solver_input_column(), self.plant.e);
        let omega = match self.config.road {
            RoadSpec::Harmonic {
                angular_frequency, ..
            } => angular_frequency,
            _ => 0.0,
        };
        let quantized = key as f64 / PARTIAL_STEP_RESOLUTION * self.grid.step;
        self.partial_steps
            .entry(key)
            .or_insert_with(|| StepOperator::new(&a, &b, &e, omega, quantized))
    }

    fn solver_input_column(&self) -> State {
        if self.grid.resolves_delay() {
            self.plant.b
        } else {
            State::zeros()
        }
    }

    /// Integrates from (a, x) to b, all inside grid step k, splitting at road
    /// breakpoints.
    fn integrate_within_step(&mut self, k: u64, from: f64, x: State, to: f64) -> State {
        let step_start = self.grid_time(k);
        let mut start = from;
        let mut state = x;
        loop {
            let mut piece = self.road.piece(start);
            if piece.end() <= start || self.coincide(piece.end(), start) {
                piece = self.road.piece(piece.end().max(start));
            }
            let end = if piece.end() < to && !self.coincide(piece.end(), to) {
                piece.end()
            } else {
                to
            };
            let delayed = self
                .grid
                .resolves_delay()
                .then(|| self.delayed_input(k, start - step_start));
            let length = end - start;
            state = if self.coincide(length, self.grid.step) {
                self.full_step
                    .apply(&state, delayed.as_ref(), &piece, start)
            } else {
                self.partial_operator(length)
                    .apply(&state, delayed.as_ref(), &piece, start)
            };
            if end == to {
                return state;
            }
            start = end;
        }
    }

    fn check_divergence(&self, time: f64, x: &State) -> Result<()> {
        for (i, value) in x.iter().enumerate() {
            let bound = if i % 2 == 0 {
                DIVERGENCE_DISPLACEMENT
            } else {
                DIVERGENCE_VELOCITY
            };
            if value.is_nan() || value.abs() > bound {
                return Err(Error::Diverged {
                    time,
                    variable: crate::model::STATE_NAMES[i],
                    value: *value,
                    bound,
                });
            }
        }
        Ok(())
    }

    /// Advances to `t_end` (any length; any number of calls). On divergence
    /// the simulator stays at the last good grid node and returns
    /// [`Error::Diverged`].
    pub fn advance_to(&mut self, t_end: f64) -> Result<()> {
        if !t_end.is_finite()
            || (t_end < self.current_time && !self.coincide(t_end, self.current_time))
        {
            return Err(Error::InvalidTime {
                name: "t_end",
                value: t_end,
                reason: "must be finite and not before the current time",
            });
        }
        loop {
            let k = self.grid_index;
            let next_node = self.grid_time(k + 1);
            if next_node < t_end || self.coincide(next_node, t_end) {
                let x = self.integrate_within_step(
                    k,
                    self.committed_time,
                    self.committed_state,
                    next_node,
                );
                self.check_divergence(next_node, &x)?;
                self.commit_node(k + 1, next_node, x);
                if self.coincide(next_node, t_end) {
                    self.current_time = t_end;
                    return Ok(());
                }
            } else {
                if self.coincide(self.committed_time, t_end) {
                    self.current_state = self.committed_state;
                } else {
                    let x = self.integrate_within_step(
                        k,
                        self.committed_time,
                        self.committed_state,
                        t_end,
                    );
                    self.check_divergence(t_end, &x)?;
                    self.current_state = x;
                }
                self.current_time = t_end;
                return Ok(());
            }
        }
    }

    fn commit_node(&mut self, k: u64, time: f64, x: State) {
        let len = self.history.len() as u64;
        self.history[(k % len) as usize] = [x[X_T], x[V_T]];
        let road = self.road.value(time);
        self.rms.add(&Performance::at(&self.plant, &x, road));
        self.grid_index = k;
        self.committed_time = time;
        self.committed_state = x;
        self.current_time = time;
        self.current_state = x;
        self.road.release_before(time);
    }

    /// Sets the external road input from the current time on (only with
    /// `RoadSpec::Input`): `x_g(t) = value + slope (t − now)`.
    pub fn set_road_input(&mut self, value: f64, slope: f64) -> Result<()> {
        let now = self.current_time;
        if !self.road.is_input() {
            return Err(Error::InvalidSetting {
                name: "road",
                value: 0,
                reason: "the input x_g is only used when road = 0",
            });
        }
        self.road.set_input(now, value, slope)?;
        self.committed_time = now;
        self.committed_state = self.current_state;
        Ok(())
    }

    /// Changes the feedback gain g (tunable); the history is kept.
    pub fn set_gain(&mut self, g: f64) -> Result<()> {
        let params = Params {
            g,
            ..self.config.params
        };
        let plant = Plant::new(params, self.config.variant)?;
        self.config.params = params;
        let (matrix, step) = Self::operators(&plant, &self.config, &self.grid);
        self.plant = plant;
        self.solver_matrix = matrix;
        self.full_step = step;
        self.partial_steps.clear();
        Ok(())
    }

    /// Changes the weights of J (tunable).
    pub fn set_weights(&mut self, weights: Weights) {
        self.config.weights = weights;
    }

    fn step_offset(&self) -> (u64, f64) {
        (
            self.grid_index,
            self.current_time - self.grid_time(self.grid_index),
        )
    }

    fn road_piece_now(&mut self) -> RoadPiece {
        let t = self.current_time;
        let piece = self.road.piece(t);
        if self.coincide(piece.end(), t) {
            self.road.piece(piece.end())
        } else {
            piece
        }
    }

    /// `[u, u']`: the delayed tire displacement and its rate now.
    fn delayed_tire_now(&self) -> (f64, f64) {
        if self.grid.resolves_delay() {
            let (k, offset) = self.step_offset();
            let p = self.delayed_input(k, offset);
            (p[0], p[1])
        } else {
            let tau = if self.config.variant.has_control() {
                self.config.params.tau
            } else {
                0.0
            };
            let x = self.current_state;
            let dx = self.solver_matrix * x;
            (x[X_T] - tau * x[V_T], dx[X_T] - tau * dx[V_T])
        }
    }

    /// All outputs at the current time.
    pub fn outputs(&mut self) -> Outputs {
        let t = self.current_time;
        let x = self.current_state;
        let road = self.road_piece_now().value(t);
        let (delayed, _) = self.delayed_tire_now();
        let rms = self.rms.values();
        Outputs {
            time: t,
            state: self.plant.reported_state(&x),
            performance: Performance::at(&self.plant, &x, road),
            road_displacement: road,
            control_force: self.config.params.effective_gain(self.config.variant) * delayed,
            rms,
            objective: rms.objective(&self.config.weights),
        }
    }

    /// Exact first time derivatives of the instantaneous outputs.
    pub fn output_derivatives(&mut self) -> OutputDerivatives {
        let t = self.current_time;
        let x = self.current_state;
        let piece = self.road_piece_now();
        let (road, road_rate) = (piece.value(t), piece.slope(t));
        let (delayed, delayed_rate) = self.delayed_tire_now();
        let b = self.solver_input_column();
        let dx = self.solver_matrix * x + b * delayed + self.plant.e * road;
        let d2x = self.solver_matrix * dx + b * delayed_rate + self.plant.e * road_rate;
        let gain = self.config.params.effective_gain(self.config.variant);
        OutputDerivatives {
            state: self.plant.reported_state(&dx),
            performance: Performance {
                body_acceleration: d2x[crate::model::V_S],
                suspension_deflection: dx[crate::model::X_S] - dx[X_T],
                tire_deflection: dx[X_T] - road_rate,
            },
            road_displacement: road_rate,
            control_force: gain * delayed_rate,
        }
    }

    /// RMS values so far.
    pub fn rms(&self) -> RmsValues {
        self.rms.values()
    }

    /// Runs from the current time for `duration` seconds and summarises.
    pub fn run_for(&mut self, duration: f64) -> Result<RunSummary> {
        self.advance_to(self.current_time + duration)?;
        let rms = self.rms.values();
        Ok(RunSummary {
            rms,
            objective: rms.objective(&self.config.weights),
        })
    }
}

/// Simulates `config` from its start for `duration` seconds.
pub fn simulate(config: SimulationConfig, duration: f64) -> Result<RunSummary> {
    Simulator::new(config)?.run_for(duration)
}
