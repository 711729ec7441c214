//! The exact whole grid step in the column form of the whole-step loop
//! ([`super::kernel`]): the plant's ([`GridStep`]) and the W_k filter's
//! ([`FilterGridStep`]), built from the step maps of
//! [`super::operators`].
//!
//! Layer: grid and dense steps (docs/architecture.md); it imports the
//! solver's `holding`, `linalg`, `operators`, `system` and the crate's
//! `comfort`, `metrics`, `model`.

use super::holding::ContactCheck;
use super::linalg::{Columns, columns, hermite_matrix};
use super::operators::{FilterRows, StepOperator};
use super::system::{FilterCoupling, phase_rotation, rotate, tire_pick};
use crate::comfort::WK_STATES;
use crate::metrics::RunningRms;
use crate::model::dynamics::Switching;
use crate::model::{X_S, X_T};
use nalgebra::{Matrix6, SMatrix};

/// The exact map of one whole grid step from a grid node, in the form the
/// hot loop uses. At offset 0 over a whole step the Hermite vector is linear
/// in the two history nodes, `p = H [x_0, v_0, x_1, v_1]`, so the delayed
/// input acts through `Γ_u H` directly on the nodes (no division per step).
#[derive(Debug, Clone, PartialEq)]
pub(super) struct GridStep {
    /// Columns of Φ.
    pub(super) transition: Columns<6>,
    /// Columns of `Γ_u H`, acting on `[x_t, v_t](k − m)`, `[x_t, v_t](k − m + 1)`.
    pub(super) nodes: Columns<4>,
    /// Columns of `Γ_h`, acting on `A [sin ω t_k, cos ω t_k]`.
    pub(super) harmonic: Columns<2>,
    /// Columns of `Γ_l`, acting on `[x_g, x_g'](t_k)`.
    pub(super) linear: Columns<2>,
    /// The road phase rotation over one step
    /// ([`super::system::phase_rotation`]).
    pub(super) rotation: [[f64; 2]; 2],
    /// Columns of the 2×6 map from X to `[BA, SDD]` (row V_S of A, and
    /// `x_s − x_t`).
    pub(super) outputs: [[f64; 2]; 6],
    /// The W_k filter's step, when the comfort outputs are on.
    pub(super) filter: Option<FilterGridStep>,
    /// What the road-holding counts of every step need.
    pub(super) contact: ContactCheck,
    /// The switching elements whose switch every step is tested for (set
    /// by the simulator; none until then): the loop stops before a step
    /// in which one may switch.
    pub(super) switching: Switching,
    /// Whether the whole-step loop runs the road-holding test and the
    /// largest |SDD| (the road-holding metrics level and above).
    pub(super) holding: bool,
}

impl GridStep {
    pub(super) fn new(
        op: &StepOperator,
        a: &Matrix6<f64>,
        angular_frequency: f64,
        h: f64,
    ) -> GridStep {
        // [u, u', u'', u'''] at the start of the Hermite interpolant of
        // (x0, v0) and (x1, v1) over [0, h].
        let (h2, h3) = (h * h, h * h * h);
        #[rustfmt::skip]
        let hermite = nalgebra::Matrix4::new(
            1.0, 0.0, 0.0, 0.0,
            0.0, 1.0, 0.0, 0.0,
            -6.0 / h2, -4.0 / h, 6.0 / h2, -2.0 / h,
            12.0 / h3, 6.0 / h2, -12.0 / h3, 6.0 / h2,
        );
        Self::from_matrices(
            &op.transition,
            &(op.delayed_input * hermite),
            op,
            a,
            angular_frequency,
            h,
        )
    }

    /// The whole step when the delay `tau` is shorter than the step h
    /// ([`DelayRegime::InsideStep`](super::grid::DelayRegime::InsideStep)). Over `[t_k, t_k + tau)` the delayed
    /// argument lies in step k − 1 (Hermite offsets from `h − tau`), over
    /// `[t_k + tau, t_{k+1})` in step k itself (offsets from 0), so
    /// `X_{k+1} = Φ X_k + D_1 n_{k−1,k} + D_2 n_{k,k+1} + road` with
    /// `D_1 = Φ(h − tau) Γ_u(tau) H(h − tau)` and `D_2 = Γ_u(h − tau) H(0)`.
    /// Node k + 1 appears on both sides through its `(x_t, v_t) = C X_{k+1}`;
    /// with `S = (I − D_2'' C)^{-1}` (`D_2''` the columns acting on node
    /// k + 1, `D_2'` those on node k) the explicit step is
    /// `X_{k+1} = S (Φ + D_2' C) X_k + S D_1 n_{k−1,k} + S road`.
    /// `None` when `I − D_2'' C` is singular.
    pub(super) fn inner_delay(
        whole: &StepOperator,
        parts: [&StepOperator; 2],
        a: &Matrix6<f64>,
        angular_frequency: f64,
        h: f64,
        tau: f64,
    ) -> Option<GridStep> {
        let [first, rest] = parts;
        let earlier = rest.transition * first.delayed_input * hermite_matrix(h, h - tau);
        let current = rest.delayed_input * hermite_matrix(h, 0.0);
        let pick = tire_pick();
        let implicit = Matrix6::identity() - current.fixed_view::<6, 2>(0, 2) * pick;
        let solve = implicit.try_inverse()?;
        let scaled = StepOperator {
            transition: solve * (whole.transition + current.fixed_view::<6, 2>(0, 0) * pick),
            delayed_input: solve * earlier,
            linear_road: solve * whole.linear_road,
            harmonic_road: solve * whole.harmonic_road,
            filter: None,
        };
        Some(Self::from_matrices(
            &scaled.transition,
            &scaled.delayed_input,
            &scaled,
            a,
            angular_frequency,
            h,
        ))
    }

    /// `nodes`: the 6×4 map from the two history nodes to the state; the
    /// road columns come from `road`.
    pub(super) fn from_matrices(
        transition: &Matrix6<f64>,
        nodes: &SMatrix<f64, 6, 4>,
        road: &StepOperator,
        a: &Matrix6<f64>,
        angular_frequency: f64,
        h: f64,
    ) -> GridStep {
        GridStep {
            transition: columns(transition),
            nodes: columns(nodes),
            harmonic: columns(&road.harmonic_road),
            linear: columns(&road.linear_road),
            rotation: phase_rotation(angular_frequency, h),
            outputs: std::array::from_fn(|j| {
                let sdd = match j {
                    X_S => 1.0,
                    X_T => -1.0,
                    _ => 0.0,
                };
                [a[(crate::model::V_S, j)], sdd]
            }),
            filter: None,
            contact: ContactCheck {
                angular_frequency,
                start_time: 0.0,
                step: h,
            },
            switching: Switching::NONE,
            holding: false,
        }
    }

    /// Road phase at the node after one with phase `z`.
    #[inline(always)]
    pub(super) fn rotate(&self, z: [f64; 2]) -> [f64; 2] {
        rotate(&self.rotation, z)
    }

    /// `[BA, SDD]` at state x, summed pairwise like [`super::linalg::combine6`] (in the
    /// hot loop the products share their broadcasts of x with `Φ x`).
    #[inline(always)]
    pub(super) fn ba_sdd(&self, x: &[f64; 6]) -> [f64; 2] {
        let c = &self.outputs;
        std::array::from_fn(|i| {
            ((c[0][i] * x[0] + c[1][i] * x[1]) + (c[2][i] * x[2] + c[3][i] * x[3]))
                + (c[4][i] * x[4] + c[5][i] * x[5])
        })
    }

    /// Adds node X's BA, SDD and TDD (road displacement `road`) to `rms`.
    #[inline(always)]
    pub(super) fn count(&self, rms: &mut RunningRms, x: &[f64; 6], road: f64) {
        let [ba, sdd] = self.ba_sdd(x);
        rms.add_values(ba, sdd, x[X_T] - road);
    }

    /// Adds `a_w²` and `a_w⁴` of the node with filter state w to `sums`
    /// (nothing without the filter).
    #[inline(always)]
    pub(super) fn count_weighted(&self, w: &[f64; 8], sums: &mut [f64; 2]) {
        if let Some(filter) = &self.filter {
            filter.count(w, sums);
        }
    }
}

/// Columns of an 8-row matrix, as plain arrays for the whole-step loop.
pub(super) type FilterColumns<const N: usize> = [[f64; WK_STATES]; N];

fn filter_columns<const C: usize>(m: &SMatrix<f64, WK_STATES, C>) -> FilterColumns<C> {
    std::array::from_fn(|j| std::array::from_fn(|i| m[(i, j)]))
}

/// The filter's whole grid step from a grid node in the whole-step loop's
/// column form:
/// `w_{k+1} = Φ_ww w_k + F_x X_k + F_n n + F_e C X_{k+1} + road`, where n
/// holds the two history nodes of the plant's step and `C X_{k+1}` the
/// `(x_t, v_t)` of the node just computed (non-zero only when the delay
/// lies inside the step).
#[derive(Debug, Clone, PartialEq)]
pub(super) struct FilterGridStep {
    /// Columns of Φ_ww.
    pub(super) transition: FilterColumns<WK_STATES>,
    /// Columns of F_x.
    pub(super) plant: FilterColumns<6>,
    /// Columns of F_n.
    pub(super) nodes: FilterColumns<4>,
    /// Columns of F_e.
    pub(super) next_node: FilterColumns<2>,
    /// Columns of Γ_wh.
    pub(super) harmonic: FilterColumns<2>,
    /// Columns of Γ_wl.
    pub(super) linear: FilterColumns<2>,
    /// c_w: `a_w = c_w · w`.
    pub(super) output: [f64; WK_STATES],
}

impl FilterGridStep {
    /// The whole step h of `whole` (which must carry filter rows), the
    /// delayed input acting on the nodes through `Γ_wu H` as in
    /// [`GridStep::new`].
    pub(super) fn new(
        whole: &StepOperator,
        coupling: &FilterCoupling,
        h: f64,
    ) -> Option<FilterGridStep> {
        let rows = whole.filter.as_ref()?;
        let nodes = rows.delayed_input * hermite_matrix(h, 0.0);
        Some(Self::from_parts(
            rows,
            &rows.plant,
            &nodes,
            &SMatrix::zeros(),
            coupling,
        ))
    }

    /// The whole step when the delay `tau` lies inside it
    /// ([`GridStep::inner_delay`]): with
    /// `Z = [X; w]`, the filter rows of
    /// `Z_{k+1} = Φ_Z(h) Z_k + Φ_Z(h − tau) Γ_Z(tau) H(h − tau) n_{k−1,k}
    /// + Γ_Z(h − tau) H(0) n_{k,k+1} + road`, where node k's part of
    /// `n_{k,k+1}` is `C X_k` and node k + 1's is `C X_{k+1}`.
    pub(super) fn inner_delay(
        whole: &StepOperator,
        parts: [&StepOperator; 2],
        coupling: &FilterCoupling,
        h: f64,
        tau: f64,
    ) -> Option<FilterGridStep> {
        let [first, rest] = parts;
        let (whole_rows, first_rows, rest_rows) = (
            whole.filter.as_ref()?,
            first.filter.as_ref()?,
            rest.filter.as_ref()?,
        );
        let earlier = (rest_rows.plant * first.delayed_input
            + rest_rows.transition * first_rows.delayed_input)
            * hermite_matrix(h, h - tau);
        let current = rest_rows.delayed_input * hermite_matrix(h, 0.0);
        let pick = tire_pick();
        let plant = whole_rows.plant + current.fixed_view::<WK_STATES, 2>(0, 0) * pick;
        let next = current.fixed_view::<WK_STATES, 2>(0, 2).into_owned();
        Some(Self::from_parts(
            whole_rows, &plant, &earlier, &next, coupling,
        ))
    }

    fn from_parts(
        road: &FilterRows,
        plant: &SMatrix<f64, WK_STATES, 6>,
        nodes: &SMatrix<f64, WK_STATES, 4>,
        next: &SMatrix<f64, WK_STATES, 2>,
        coupling: &FilterCoupling,
    ) -> FilterGridStep {
        FilterGridStep {
            transition: filter_columns(&road.transition),
            plant: filter_columns(plant),
            nodes: filter_columns(nodes),
            next_node: filter_columns(next),
            harmonic: filter_columns(&road.harmonic_road),
            linear: filter_columns(&road.linear_road),
            output: std::array::from_fn(|i| coupling.wk.output_vector[i]),
        }
    }

    /// `a_w = c_w · w` (m/s²), summed pairwise.
    #[inline(always)]
    pub(super) fn weighted(&self, w: &[f64; WK_STATES]) -> f64 {
        let c = &self.output;
        ((c[0] * w[0] + c[1] * w[1]) + (c[2] * w[2] + c[3] * w[3]))
            + ((c[4] * w[4] + c[5] * w[5]) + (c[6] * w[6] + c[7] * w[7]))
    }

    /// `Φ_ww w`, summed pairwise.
    #[inline(always)]
    pub(super) fn transition_times(&self, w: &[f64; WK_STATES]) -> [f64; WK_STATES] {
        let c = &self.transition;
        std::array::from_fn(|i| {
            ((c[0][i] * w[0] + c[1][i] * w[1]) + (c[2][i] * w[2] + c[3][i] * w[3]))
                + ((c[4][i] * w[4] + c[5][i] * w[5]) + (c[6][i] * w[6] + c[7][i] * w[7]))
        })
    }

    /// Adds `a_w²` and `a_w⁴` at filter state w to `sums`.
    #[inline(always)]
    pub(super) fn count(&self, w: &[f64; WK_STATES], sums: &mut [f64; 2]) {
        let a = self.weighted(w);
        let square = a * a;
        sums[0] += square;
        sums[1] += square * square;
    }
}

/// `Σ_j cols[j] v[j]` for N columns of 8 rows, in column order.
#[inline(always)]
pub(super) fn filter_combine<const N: usize>(
    c: &FilterColumns<N>,
    v: &[f64; N],
) -> [f64; WK_STATES] {
    std::array::from_fn(|i| {
        let mut sum = 0.0;
        for j in 0..N {
            sum += c[j][i] * v[j];
        }
        sum
    })
}
