//! How a [`Simulator`] is built from its configuration: the checks, the
//! plant, the grid the delay lies on, the parts at the start time and the
//! tire's mode there.
//!
//! Layer: driver (docs/architecture.md); it imports the solver's `config`,
//! `driver`, `grid`, `holding`, `inputs`, `modes`, `observers`, `stepping`,
//! `system`, `trajectory` and the crate's `error`, `model`, `road`.

use super::config::{
    SimulationConfig, StepChoice, check_communication_step, check_max_internal_step,
    check_tolerance,
};
use super::driver::Simulator;
use super::grid::DelayGrid;
use super::holding::Holding;
use super::inputs::Inputs;
use super::modes::Modes;
use super::observers::Observers;
use super::stepping::stepping;
use super::system::Filter;
use super::trajectory::Trajectory;
use crate::error::{Error, Result};
use crate::model::dynamics::Mode;
use crate::model::{Plant, V_T, Variant, X_T};
use crate::road::Road;

impl Simulator {
    /// Largest |start time| in internal steps (2^42). Node times
    /// `t_0 + k h` then resolve every step to 2^-10 h near the start; from
    /// 2^53 steps on, `t_0 + h` can round to `t_0` and a step would no
    /// longer advance time.
    pub const MAX_START_TIME_IN_STEPS: f64 = 4_398_046_511_104.0;

    /// As [`Self::new`], with the internal step bound given (a restored
    /// state keeps the step it was saved with).
    pub(crate) fn with_step_bound(config: SimulationConfig, step_bound: f64) -> Result<Simulator> {
        let plant = Self::validate(&config)?;
        check_tolerance(config.tolerance)?;
        check_max_internal_step(config.max_internal_step)?;
        check_communication_step(config.communication_step)?;
        let grid = DelayGrid::new(Self::resolved_delay(&config), step_bound)?;
        let mut sim = Self::with_grid(config, plant, grid)?;
        sim.step_choice.step_bound = step_bound;
        Ok(sim)
    }

    /// The delay the grid resolves: tau with the controller, else 0.
    pub(super) fn resolved_delay(config: &SimulationConfig) -> f64 {
        if config.variant.has_control() {
            config.params.tau
        } else {
            0.0
        }
    }

    /// The plant of a configuration whose every value is checked.
    pub(super) fn validate(config: &SimulationConfig) -> Result<Plant> {
        let plant = Plant::new(config.params, config.variant)?.with_body(config.body);
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
        crate::limits::check_config(
            &config.params,
            config.variant,
            &config.road,
            &config.initial_state,
            &config.weights,
        )?;
        Ok(plant)
    }

    /// The simulator of a checked configuration on the given grid.
    pub(crate) fn with_grid(
        config: SimulationConfig,
        plant: Plant,
        grid: DelayGrid,
    ) -> Result<Simulator> {
        if config.start_time.abs() > grid.step * Self::MAX_START_TIME_IN_STEPS {
            return Err(Error::InvalidTime {
                name: "start_time",
                value: config.start_time,
                reason: "|start_time| must be at most 2^42 internal steps (the step the tolerance sets, max_internal_step, or less to divide tau) so that node times resolve the step",
            });
        }
        let road = Road::with_shift(&config.road, config.start_time, config.road_shift)?;
        let mut initial = config.initial_state;
        if config.variant == Variant::Cs {
            initial[crate::model::X_H] = 0.0;
            initial[crate::model::V_H] = 0.0;
        }
        let inputs = Inputs::new(road, grid, config.start_time, [initial[X_T], initial[V_T]]);
        let modes = Modes::new(&plant, &config, &grid, inputs.angular_frequency())?;
        let start_time = config.start_time;
        let mut sim = Simulator {
            plant,
            grid,
            step_choice: StepChoice {
                step_bound: grid.step,
                model_step: f64::NAN,
                probe_error: f64::NAN,
                probe_rounds: 0,
            },
            modes,
            inputs,
            trajectory: Trajectory {
                grid_index: 0,
                committed_time: config.start_time,
                committed_state: initial,
                committed_filter: Filter::zeros(),
                current_time: config.start_time,
                current_state: initial,
                deferred: None,
                mode: Mode::CONTACT,
                flight_start: None,
            },
            observers: Observers::new(start_time),
            outputs_cache: None,
            config,
        };
        let piece = sim.inputs.piece_from(start_time);
        let rest = Filter::zeros();
        sim.observers.integral.anchor = stepping!(sim).squares_at(
            0,
            start_time,
            &initial,
            &rest,
            (start_time, initial),
            &piece,
        );
        let margin = stepping!(sim).margin_at(start_time, &initial, &piece);
        sim.observers.holding = Holding::new(
            initial[crate::model::X_S] - initial[X_T],
            margin[0],
            start_time,
        );
        sim.observers.start_load = sim.config.params.k_t * (piece.value(start_time) - initial[X_T]);
        if sim.config.tire_contact.is_unilateral() {
            // A start without contact is a lift-off at the start, made by
            // the first step's switch search.
            sim.observers.holding.first_loss = None;
            sim.observers.holding.lift_offs = 0;
        }
        sim.enter_recorded_mode();
        Ok(sim)
    }
}
