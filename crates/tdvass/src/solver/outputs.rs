//! What the simulator reports: the outputs at an instant, their time
//! derivatives, and the summary of a run.

use super::Simulator;
use crate::metrics::RmsValues;
use crate::model::{Performance, State, X_T};
use crate::road::RoadPiece;

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
}

/// Summary of a finished run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunSummary {
    /// RMS values over the run.
    pub rms: RmsValues,
    /// J of Eq. (6).
    pub objective: f64,
}

impl Simulator {
    pub(super) fn road_piece_now(&mut self) -> RoadPiece {
        let t = self.current_time;
        let piece = self.road.piece(t);
        if self.coincide(piece.end(), t) {
            self.road.piece(piece.end())
        } else {
            piece
        }
    }

    /// `[u, u']`: the delayed tire displacement and its rate now.
    pub(super) fn delayed_tire_now(&mut self) -> (f64, f64) {
        let (k, t, x) = (self.grid_index, self.current_time, self.current_state);
        let from = (self.committed_time, self.committed_state);
        let p = self.delayed_vector_at(k, t, from, &x);
        (p[0], p[1])
    }

    /// All outputs at the current time.
    pub fn outputs(&mut self) -> Outputs {
        if let Some(outputs) = self.outputs_cache {
            return outputs;
        }
        let t = self.current_time;
        let x = self.current_state;
        let road = self.road_piece_now().value(t);
        let (delayed, _) = self.delayed_tire_now();
        let rms = self.rms_now();
        let outputs = Outputs {
            time: t,
            state: self.plant.reported_state(&x),
            performance: Performance::at(&self.plant, &x, road),
            road_displacement: road,
            control_force: self.config.params.effective_gain(self.config.variant) * delayed,
            rms,
            objective: rms.objective(&self.config.weights),
        };
        self.outputs_cache = Some(outputs);
        outputs
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
        let now = Performance::at(&self.plant, &x, road);
        let rms = self.outputs().rms;
        let duration = t - self.config.start_time;
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
        OutputDerivatives {
            rms: rms_rate,
            objective: rms_rate.objective(&self.config.weights),
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

    /// RMS values so far (time averages from the start to now).
    pub fn rms(&mut self) -> RmsValues {
        self.rms_now()
    }
}
