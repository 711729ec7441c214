//! The modes of the plant and their operators: the tire in contact (the
//! paper's plant, Eq. (2)) and, with the unilateral tire, in flight (the
//! tire force at its floor −W, see `contact`).
//!
//! [`Modes`] holds the operators of the mode in force (the solver's state
//! matrix with any folded feedback, the whole step, its grid form, the
//! partial steps' table) and those of the other mode, which it swaps at a
//! switch; a new piecewise-linear element adds its mode's matrices here.
//! It imports the configuration, the system and the step maps; nothing of
//! the trajectory or the accumulators.

use super::config::SimulationConfig;
use super::dense::{self, DenseOutput};
use super::grid::DelayGrid;
use super::grid_step::{FilterGridStep, GridStep};
use super::linalg::infinity_norm;
use super::operators::StepOperator;
use super::system::FilterCoupling;
use crate::error::{Error, Result};
use crate::model::dynamics::{flight_matrix, folded_feedback};
use crate::model::{Plant, State};
use nalgebra::Matrix6;

/// Node k + 1 (its state and `(x_t, v_t)`) reached from `(from, state)`
/// in step k, with the delay inside the step.
#[derive(Debug, Clone, Copy)]
pub(super) struct NextNode {
    pub(super) k: u64,
    pub(super) from: f64,
    pub(super) state: State,
    pub(super) flight: bool,
    pub(super) node: State,
    pub(super) end: [f64; 2],
}

/// The operators of the mode that is not in force.
#[derive(Debug, Clone)]
pub(super) struct ModeOperators {
    pub(super) solver_matrix: Matrix6<f64>,
    pub(super) solver_matrix_norm: f64,
    pub(super) full_step: StepOperator,
    pub(super) dense: Option<Box<DenseOutput>>,
}

/// The operators of the plant: those of the mode in force (contact, or
/// flight with the unilateral tire), the other mode's, and caches of
/// functions of them.
#[derive(Debug, Clone)]
pub(super) struct Modes {
    /// Plant matrix used by the solver (the plant's A, plus the folded
    /// feedback when the delay is not resolved on the grid).
    pub(super) solver_matrix: Matrix6<f64>,
    /// `‖solver_matrix‖_∞` (largest absolute row sum, 1/s): chooses the
    /// order of the Taylor series near a node.
    pub(super) solver_matrix_norm: f64,
    /// The delayed input's column of the solver: the plant's b, or zero
    /// when the feedback is folded into the matrix (either mode).
    pub(super) input_column: State,
    pub(super) full_step: StepOperator,
    /// `full_step` in the form of the whole-step loop (contact mode).
    pub(super) grid_step: GridStep,
    /// The partial steps' maps (`dense`), built at the first point
    /// inside a step: a cache of functions of the operators, not state.
    pub(super) dense: Option<Box<DenseOutput>>,
    /// The last node k + 1 solved for with the delay inside the step (a
    /// cache of a function of its arguments, the mode and the operators,
    /// cleared when an operator or the road input changes).
    pub(super) next_node: Option<NextNode>,
    /// How BA drives the W_k filter (only with the comfort metrics).
    pub(super) coupling: Option<FilterCoupling>,
    /// Unilateral tire: the operators of the mode not in force; `None`
    /// with the bilateral tire, and until the first lift-off or
    /// [`Self::reserve`].
    pub(super) other_mode: Option<Box<ModeOperators>>,
    /// The road's angular frequency ω (0 but on the harmonic road).
    angular_frequency: f64,
}

impl Modes {
    /// The contact mode's operators in force: the solver's state matrix,
    /// the whole step, its grid form (with the contact-loss test with the
    /// road-holding metrics and the filter with the comfort metrics) and
    /// the filter coupling; `angular_frequency`: the road's ω.
    pub(super) fn new(
        plant: &Plant,
        config: &SimulationConfig,
        grid: &DelayGrid,
        angular_frequency: f64,
    ) -> Result<Modes> {
        let (a, b) = if grid.resolves_delay() {
            (plant.a, plant.b)
        } else {
            // u = g (x_t − tau v_t): fold the feedback into the plant.
            let tau = if config.variant.has_control() {
                config.params.tau
            } else {
                0.0
            };
            folded_feedback(plant, tau)
        };
        let omega = angular_frequency;
        let (h, tau) = (grid.step, grid.inner_delay());
        let coupling = config
            .metrics
            .comfort()
            .then(|| FilterCoupling::new(&a, &b, plant));
        let filter = coupling.as_ref();
        let step = StepOperator::new(&a, &b, &plant.e, omega, h, filter);
        let mut grid_step = if grid.delay_inside_step() {
            let first = StepOperator::new(&a, &b, &plant.e, omega, tau, filter);
            let rest = StepOperator::new(&a, &b, &plant.e, omega, h - tau, filter);
            let mut grid_step = GridStep::inner_delay(&step, [&first, &rest], &a, omega, h, tau)
                .ok_or(Error::InvalidParameter {
                    name: "g",
                    value: config.params.g,
                    reason: "the step with the delay inside it is singular at this gain",
                })?;
            grid_step.filter =
                filter.and_then(|c| FilterGridStep::inner_delay(&step, [&first, &rest], c, h, tau));
            grid_step
        } else {
            let mut grid_step = GridStep::new(&step, &a, omega, h);
            grid_step.filter = filter.and_then(|c| FilterGridStep::new(&step, c, h));
            grid_step
        };
        let params = &config.params;
        grid_step.contact.limit = if params.k_t > 0.0 {
            params.static_load(config.variant) / params.k_t
        } else {
            f64::INFINITY
        };
        grid_step.contact.start_time = config.start_time;
        grid_step.contact.unilateral = config.tire_contact.is_unilateral();
        grid_step.holding = config.metrics.road_holding();
        Ok(Modes {
            solver_matrix_norm: infinity_norm(&a),
            solver_matrix: a,
            input_column: b,
            full_step: step,
            grid_step,
            dense: None,
            next_node: None,
            coupling,
            other_mode: None,
            angular_frequency,
        })
    }

    /// The solver's plant matrix of the tire's mode `flight` (the feedback
    /// folded in as in force), `in_flight` saying which mode is in force:
    /// the matrix in force or the other mode's; flight's made from
    /// contact's ([`flight_matrix`]) while its operators are not.
    pub(super) fn mode_matrix(&self, flight: bool, in_flight: bool, e: &State) -> Matrix6<f64> {
        if flight == in_flight {
            return self.solver_matrix;
        }
        match &self.other_mode {
            Some(other) => other.solver_matrix,
            None => flight_matrix(&self.solver_matrix, e),
        }
    }

    /// The flight mode's operators for the contact plant matrix `contact`
    /// (the solver's, with any folded feedback): the tire's column of A
    /// gains the road column `e` of `plant`, whose input is then the
    /// constant −W/k_t.
    fn flight_operators(&self, plant: &Plant, contact: &Matrix6<f64>, h: f64) -> ModeOperators {
        let e = plant.e;
        let a = flight_matrix(contact, &e);
        let (omega, b) = (self.angular_frequency, self.input_column);
        ModeOperators {
            solver_matrix_norm: infinity_norm(&a),
            full_step: StepOperator::new(&a, &b, &e, omega, h, self.coupling.as_ref()),
            solver_matrix: a,
            dense: None,
        }
    }

    /// The partial steps' maps of a mode with solver matrix `a` (the
    /// input column and ω are the same in both modes), with the pieces
    /// every step has when the delay is inside the step
    /// ([`DenseOutput::with_fixed`]); the W_k filter's table is built by
    /// [`Self::reserve`] or at its first use.
    fn dense_output_of(&self, a: &Matrix6<f64>, plant: &Plant, grid: &DelayGrid) -> DenseOutput {
        let h = grid.step;
        let dense = DenseOutput::new(a, &self.input_column, &plant.e, self.angular_frequency, h);
        if grid.delay_inside_step() {
            let tau = grid.inner_delay();
            dense.with_fixed(&[dense::offset_key(tau, h), dense::offset_key(h - tau, h)])
        } else {
            dense
        }
    }

    /// The mode in force's partial steps' maps, built on first use.
    pub(super) fn dense_output(&mut self, plant: &Plant, grid: &DelayGrid) -> &mut DenseOutput {
        if self.dense.is_none() {
            self.dense = Some(Box::new(self.dense_output_of(
                &self.solver_matrix,
                plant,
                grid,
            )));
        }
        self.dense.as_deref_mut().expect("built above")
    }

    /// Builds now what stepping would otherwise build on first use, so
    /// that stepping allocates nothing: the partial steps' maps of the
    /// mode in force (their table's entries, and the filter's table with
    /// the W_k filter: [`DenseOutput::reserve`]) and, with `unilateral`,
    /// the flight operators and their maps. Each is
    /// the same value whenever it is built (a cache of a function of the
    /// operators), so the results do not change.
    pub(super) fn reserve(&mut self, plant: &Plant, grid: &DelayGrid, unilateral: bool) {
        let coupling = self.coupling.clone();
        self.dense_output(plant, grid).reserve(coupling.as_ref());
        if !unilateral {
            return;
        }
        if self.other_mode.is_none() {
            // Never swapped: contact is in force.
            let flight = self.flight_operators(plant, &self.solver_matrix, grid.step);
            self.other_mode = Some(Box::new(flight));
        }
        let Some(other) = self.other_mode.as_deref() else {
            return;
        };
        if other.dense.is_none() {
            let mut dense = self.dense_output_of(&other.solver_matrix, plant, grid);
            dense.reserve(coupling.as_ref());
            if let Some(other) = self.other_mode.as_deref_mut() {
                other.dense = Some(Box::new(dense));
            }
        }
    }

    /// Swaps the operators in force with those of the other mode. Those
    /// of flight are made at the first lift-off unless [`Self::reserve`]
    /// made them: until then (`other_mode` empty) the contact operators
    /// are in force.
    pub(super) fn swap(&mut self, plant: &Plant, h: f64) {
        if self.other_mode.is_none() {
            let flight = self.flight_operators(plant, &self.solver_matrix, h);
            self.other_mode = Some(Box::new(flight));
        }
        let Some(other) = self.other_mode.as_mut() else {
            return;
        };
        std::mem::swap(&mut self.solver_matrix, &mut other.solver_matrix);
        std::mem::swap(&mut self.solver_matrix_norm, &mut other.solver_matrix_norm);
        std::mem::swap(&mut self.full_step, &mut other.full_step);
        std::mem::swap(&mut self.dense, &mut other.dense);
    }
}
