//! The modes of the plant and their operators: the tire in contact (the
//! paper's plant, Eq. (2)) and, with the unilateral tire, in flight (the
//! tire force at its floor −W, see `contact`).
//!
//! [`Modes`] holds the operators of the mode in force (the solver's state
//! matrix with any folded feedback, the whole step, its grid form, the
//! partial steps' table) and, by [`Mode`], those of the others, which it
//! puts in force at a switch ([`Modes::enter`]). A mode's matrix comes
//! from the contact matrix by [`Switching::mode_matrix`](crate::model::dynamics::Switching::mode_matrix): a new switching element
//! adds its law there, not here. It imports the configuration, the system
//! and the step maps; nothing of the trajectory or the accumulators.

use super::config::SimulationConfig;
use super::dense::{self, DenseOutput};
use super::grid::DelayGrid;
use super::grid_step::{FilterGridStep, GridStep};
use super::linalg::infinity_norm;
use super::operators::StepOperator;
use super::system::FilterCoupling;
use crate::error::{Error, Result};
use crate::model::dynamics::{Mode, Switching, folded_feedback};
use crate::model::{Plant, State};
use nalgebra::Matrix6;

/// Node k + 1 (its state and `(x_t, v_t)`) reached from `(from, state)`
/// in step k, with the delay inside the step.
#[derive(Debug, Clone, Copy)]
pub(super) struct NextNode {
    pub(super) k: u64,
    pub(super) from: f64,
    pub(super) state: State,
    pub(super) mode: Mode,
    pub(super) node: State,
    pub(super) end: [f64; 2],
}

/// The operators of a mode that is not in force.
#[derive(Debug, Clone)]
pub(super) struct ModeOperators {
    pub(super) solver_matrix: Matrix6<f64>,
    pub(super) solver_matrix_norm: f64,
    pub(super) full_step: StepOperator,
    pub(super) dense: Option<Box<DenseOutput>>,
}

/// The operators of the plant: those of the mode in force (contact, or
/// flight with the unilateral tire), those of the other modes by
/// [`Mode`], and caches of functions of them.
#[derive(Debug, Clone)]
pub(super) struct Modes {
    /// The solver's plant matrix with every element in its first law (the
    /// tire in contact), which every mode's matrix is made from.
    pub(super) contact_matrix: Matrix6<f64>,
    /// Plant matrix used by the solver in the mode in force (the plant's
    /// A, plus the folded feedback when the delay is not resolved on the
    /// grid).
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
    /// The operators of the modes not in force, by [`Mode::index`]:
    /// `None` for the mode in force, for a mode never entered (until
    /// [`Self::reserve`] builds those the configuration can reach) and
    /// for every mode of a bilateral tire.
    pub(super) stored: [Option<Box<ModeOperators>>; Mode::COUNT],
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
        grid_step.switching = Switching::of(params, config.variant, config.tire_contact);
        grid_step.contact.start_time = config.start_time;
        grid_step.holding = config.metrics.road_holding();
        Ok(Modes {
            solver_matrix_norm: infinity_norm(&a),
            contact_matrix: a,
            solver_matrix: a,
            input_column: b,
            full_step: step,
            grid_step,
            dense: None,
            next_node: None,
            coupling,
            stored: Default::default(),
            angular_frequency,
        })
    }

    /// The solver's plant matrix of `mode` (the feedback folded in as in
    /// force), `in_force` being the mode whose operators are in force: the
    /// matrix in force, a stored mode's, or one made from the contact
    /// matrix ([`Switching::mode_matrix`](crate::model::dynamics::Switching::mode_matrix)) while its operators are not.
    pub(super) fn mode_matrix(&self, mode: Mode, in_force: Mode, e: &State) -> Matrix6<f64> {
        if mode == in_force {
            return self.solver_matrix;
        }
        match &self.stored[mode.index()] {
            Some(stored) => stored.solver_matrix,
            None => self
                .grid_step
                .switching
                .mode_matrix(&self.contact_matrix, e, mode),
        }
    }

    /// The operators of `mode` ([`Switching::mode_matrix`](crate::model::dynamics::Switching::mode_matrix) of the contact matrix):
    /// in flight the tire's column of A gains the road column `e` of
    /// `plant`, whose input is then the constant −W/k_t.
    fn operators_of(&self, mode: Mode, plant: &Plant, h: f64) -> ModeOperators {
        let e = plant.e;
        let a = self
            .grid_step
            .switching
            .mode_matrix(&self.contact_matrix, &e, mode);
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
    /// the W_k filter: [`DenseOutput::reserve`]) and the operators of the
    /// other modes a run with its switching elements can reach
    /// ([`Mode::reachable`]) and their maps.
    /// Each is the same value whenever it is built (a cache of a function
    /// of the operators), so the results do not change.
    pub(super) fn reserve(&mut self, plant: &Plant, grid: &DelayGrid, in_force: Mode) {
        let coupling = self.coupling.clone();
        self.dense_output(plant, grid).reserve(coupling.as_ref());
        let switching = self.grid_step.switching;
        for mode in Mode::reachable(&switching) {
            if mode == in_force {
                continue;
            }
            if self.stored[mode.index()].is_none() {
                let operators = self.operators_of(mode, plant, grid.step);
                self.stored[mode.index()] = Some(Box::new(operators));
            }
            let Some(matrix) = self.stored[mode.index()]
                .as_deref()
                .filter(|stored| stored.dense.is_none())
                .map(|stored| stored.solver_matrix)
            else {
                continue;
            };
            let mut dense = self.dense_output_of(&matrix, plant, grid);
            dense.reserve(coupling.as_ref());
            if let Some(stored) = self.stored[mode.index()].as_deref_mut() {
                stored.dense = Some(Box::new(dense));
            }
        }
    }

    /// Puts the operators of `to` in force in place of those of `from`,
    /// which are stored. A mode's operators are made when it is first
    /// entered unless [`Self::reserve`] made them.
    pub(super) fn enter(&mut self, from: Mode, to: Mode, plant: &Plant, h: f64) {
        if from == to {
            return;
        }
        // The box of the incoming mode takes the outgoing one's operators:
        // no allocation once every mode was entered or reserved.
        let mut boxed = match self.stored[to.index()].take() {
            Some(stored) => stored,
            None => Box::new(self.operators_of(to, plant, h)),
        };
        std::mem::swap(&mut self.solver_matrix, &mut boxed.solver_matrix);
        std::mem::swap(&mut self.solver_matrix_norm, &mut boxed.solver_matrix_norm);
        std::mem::swap(&mut self.full_step, &mut boxed.full_step);
        std::mem::swap(&mut self.dense, &mut boxed.dense);
        self.stored[from.index()] = Some(boxed);
    }

    /// Forgets the stored operators (after a restore or a rebuild of the
    /// operators in force, which are then contact's).
    pub(super) fn forget_stored(&mut self) {
        self.stored = Default::default();
    }
}
