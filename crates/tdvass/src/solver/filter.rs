//! The ISO 2631-1 W_k weighting of the body acceleration inside the precise
//! integration (only when [`super::Metrics::comfort`] is on).
//!
//! The realization of [`crate::comfort::wk_state_space`],
//! `ẇ = A_w w + b_w BA`, `a_w = c_w w` (8 states, m/s²), is driven by
//! `BA = c X + β_u u + β_g x_g` (row V_S of the solver's A, and the V_S
//! entries of b and e, which are zero in every variant). The plant and the
//! filter together form the block lower-triangular system
//!
//! ```text
//! d/dt [X]   [ A        0  ] [X]   [ b      ]       [ e      ]
//!      [w] = [ b_w c    A_w] [w] + [ b_w β_u] u  +  [ b_w β_g] x_g
//! ```
//!
//! with the same inputs as the plant alone (the delayed tire displacement
//! as a cubic, the road as a line or a sine), so one exponential of the
//! 22-dimensional augmented matrix (plant 6, delayed input 4, linear road
//! 2, harmonic road 2, filter 8) gives the filter's exact step
//! `w(a+δ) = Φ_ww w(a) + Φ_wx X(a) + Γ_wu p + Γ_wl q + Γ_wh z`
//! ([`FilterRows`]). The plant keeps the matrices of its own
//! 14-dimensional exponential: turning the filter on changes no bit of the
//! plant's states or of the BA, SDD, TDD values.
//!
//! The filter starts from rest (`w(t_0) = 0`).

use super::operators::{
    AUGMENTED, DELAY_INPUT, HARMONIC_ROAD, LINEAR_ROAD, StepOperator, hermite_matrix, tire_pick,
};
use super::{Simulator, expm};
use crate::comfort::{WK_STATES, WkStateSpace, wk_state_space};
use crate::model::{Plant, State, V_S};
use crate::road::RoadPiece;
use nalgebra::{Matrix6, RowSVector, SMatrix, SVector, Vector4};

/// The W_k filter state w (m/s², see [`WkStateSpace`]).
pub(crate) type Filter = SVector<f64, WK_STATES>;

/// Dimension of the plant's augmented system plus the filter.
pub(super) const WITH_FILTER: usize = AUGMENTED + WK_STATES;

/// Columns of an 8-row matrix, as plain arrays for the whole-step loop.
pub(super) type FilterColumns<const N: usize> = [[f64; WK_STATES]; N];

fn filter_columns<const C: usize>(m: &SMatrix<f64, WK_STATES, C>) -> FilterColumns<C> {
    std::array::from_fn(|j| std::array::from_fn(|i| m[(i, j)]))
}

/// How BA drives the filter: the realization and
/// `BA = c X + β_u u + β_g x_g`.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct FilterCoupling {
    /// The W_k realization (A_w in 1/s, b_w in 1/s, c_w, d_w = 0).
    pub(super) wk: WkStateSpace,
    /// c: row V_S of the solver's state matrix (1/s², 1/s).
    pub(super) acceleration_row: RowSVector<f64, 6>,
    /// β_u: BA per unit delayed input (1/s²; zero in every variant).
    pub(super) acceleration_delayed: f64,
    /// β_g: BA per unit road displacement (1/s²; zero in every variant).
    pub(super) acceleration_road: f64,
}

impl FilterCoupling {
    /// For the solver's state matrix `a`, input column `b` and the plant's
    /// road column.
    pub(super) fn new(a: &Matrix6<f64>, b: &State, plant: &Plant) -> FilterCoupling {
        FilterCoupling {
            wk: wk_state_space(),
            acceleration_row: a.row(V_S).into_owned(),
            acceleration_delayed: b[V_S],
            acceleration_road: plant.e[V_S],
        }
    }

    /// `a_w = c_w w` (m/s²; `d_w = 0`).
    #[inline]
    pub(super) fn weighted(&self, w: &Filter) -> f64 {
        (self.wk.output_vector * w)[0]
    }

    /// `ȧ_w = c_w (A_w w + b_w BA)` (m/s³) for the filter state w and BA.
    #[inline]
    pub(super) fn weighted_rate(&self, w: &Filter, body_acceleration: f64) -> f64 {
        (self.wk.output_vector * self.wk.derivative(w, body_acceleration))[0]
    }
}

/// The filter rows of one exact step of length δ (see the module
/// documentation): `w(a+δ) = Φ_ww w + Φ_wx X + Γ_wu p + Γ_wl q + Γ_wh z`,
/// with p, q, z as in [`StepOperator`].
#[derive(Debug, Clone, PartialEq)]
pub(super) struct FilterRows {
    /// Φ_ww (8×8).
    pub(super) transition: SMatrix<f64, WK_STATES, WK_STATES>,
    /// Φ_wx (8×6).
    pub(super) plant: SMatrix<f64, WK_STATES, 6>,
    /// Γ_wu (8×4), acting on `[u, u', u'', u''']`.
    pub(super) delayed_input: SMatrix<f64, WK_STATES, 4>,
    /// Γ_wl (8×2), acting on `[x_g, x_g']`.
    pub(super) linear_road: SMatrix<f64, WK_STATES, 2>,
    /// Γ_wh (8×2), acting on `A [sin ω a, cos ω a]`.
    pub(super) harmonic_road: SMatrix<f64, WK_STATES, 2>,
}

impl FilterRows {
    /// From the plant's unscaled 14×14 augmented matrix `m`
    /// ([`StepOperator::new`]), the coupling and the step length (s): the
    /// filter rows of `exp(M δ)` for the 22×22 matrix M of the module
    /// documentation.
    pub(super) fn new(
        m: &SMatrix<f64, AUGMENTED, AUGMENTED>,
        coupling: &FilterCoupling,
        length: f64,
    ) -> FilterRows {
        let big = with_filter_matrix(m, coupling);
        let exp = expm::precise_exp(&(big * length));
        let rows = |column: usize| {
            exp.fixed_view::<WK_STATES, 2>(AUGMENTED, column)
                .into_owned()
        };
        FilterRows {
            transition: exp
                .fixed_view::<WK_STATES, WK_STATES>(AUGMENTED, AUGMENTED)
                .into_owned(),
            plant: exp.fixed_view::<WK_STATES, 6>(AUGMENTED, 0).into_owned(),
            delayed_input: exp
                .fixed_view::<WK_STATES, 4>(AUGMENTED, DELAY_INPUT)
                .into_owned(),
            linear_road: rows(LINEAR_ROAD),
            harmonic_road: rows(HARMONIC_ROAD),
        }
    }

    /// The filter state after the step from `(x, w)` at time `at`, with the
    /// delayed input `delayed` (as [`StepOperator::apply`]).
    #[inline]
    pub(super) fn apply(
        &self,
        w: &Filter,
        x: &State,
        delayed: Option<&Vector4<f64>>,
        road: &RoadPiece,
        at: f64,
    ) -> Filter {
        let mut next = self.transition * w + self.plant * x;
        if let Some(p) = delayed {
            next += self.delayed_input * p;
        }
        next += super::operators::road_input(&self.linear_road, &self.harmonic_road, road, at);
        next
    }
}

/// The 22-dimensional augmented matrix of the module documentation, from
/// the plant's 14-dimensional one `m` ([`super::operators::augmented_matrix`])
/// and the coupling.
pub(super) fn with_filter_matrix(
    m: &SMatrix<f64, AUGMENTED, AUGMENTED>,
    coupling: &FilterCoupling,
) -> SMatrix<f64, WITH_FILTER, WITH_FILTER> {
    let mut big = SMatrix::<f64, WITH_FILTER, WITH_FILTER>::zeros();
    big.fixed_view_mut::<AUGMENTED, AUGMENTED>(0, 0)
        .copy_from(m);
    let b_w = &coupling.wk.input_vector;
    for i in 0..WK_STATES {
        let row = AUGMENTED + i;
        for j in 0..6 {
            big[(row, j)] = b_w[i] * coupling.acceleration_row[j];
        }
        big[(row, DELAY_INPUT)] = b_w[i] * coupling.acceleration_delayed;
        // x_g is the first state of either road generator.
        big[(row, LINEAR_ROAD)] = b_w[i] * coupling.acceleration_road;
        big[(row, HARMONIC_ROAD)] = b_w[i] * coupling.acceleration_road;
    }
    big.fixed_view_mut::<WK_STATES, WK_STATES>(AUGMENTED, AUGMENTED)
        .copy_from(&coupling.wk.state_matrix);
    big
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
    /// [`super::operators::GridStep::new`].
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
    /// ([`super::operators::GridStep::inner_delay`]): with
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

impl Simulator {
    /// The W_k filter state at `to` inside grid step k, from the point
    /// `from` (time and plant state) of step k with filter state `w`:
    /// the exact filter step of each piece (split at road breakpoints and,
    /// when the delay lies inside the step, at `t_k + tau`), with the plant
    /// state carried along the same pieces. Zero without the filter.
    pub(super) fn filter_within_step(
        &mut self,
        k: u64,
        from: (f64, State),
        w: &Filter,
        to: f64,
    ) -> Filter {
        if self.coupling.is_none() {
            return Filter::zeros();
        }
        let switch = self
            .grid
            .delay_inside_step()
            .then(|| self.grid_time(k) + self.grid.inner_delay());
        let (mut start, mut x, mut w) = (from.0, from.1, *w);
        loop {
            let piece = self.piece_from(start);
            let mut end = if piece.end() < to && !self.coincide(piece.end(), to) {
                piece.end()
            } else {
                to
            };
            if let Some(switch) = switch
                && start < switch
                && !self.coincide(start, switch)
                && end > switch
                && !self.coincide(end, switch)
            {
                end = switch;
            }
            let delayed = self
                .grid
                .resolves_delay()
                .then(|| self.delayed_vector_at(k, start, from, &x));
            let length = end - start;
            let drive = self.forcing(&piece);
            if self.coincide(length, self.grid.step) {
                let op = &self.full_step;
                let rows = op.filter.as_ref().expect("the filter is on");
                w = rows.apply(&w, &x, delayed.as_ref(), &drive, start);
                x = op.apply(&x, delayed.as_ref(), &drive, start);
            } else {
                // The plant's state by the same operations as
                // `integrate_within_step`, the filter's from its own rows.
                let z = self.augmented(&x, delayed.as_ref(), &drive, start);
                w = self.partial_filter_step(length, &z, &w);
                x = self.partial_step(length, &z);
            }
            if end == to {
                return w;
            }
            start = end;
        }
    }

    /// The W_k filter state after a partial step of length `length` from
    /// the plant's augmented vector `z` and the filter state `w`
    /// ([`super::dense`]).
    fn partial_filter_step(
        &mut self,
        length: f64,
        z: &super::dense::Augmented<1>,
        w: &Filter,
    ) -> Filter {
        let key = super::dense::offset_key(length, self.grid.step);
        self.dense_output();
        match (self.dense.as_mut(), self.coupling.as_ref()) {
            (Some(dense), Some(coupling)) => dense.filter(key, z, w, coupling),
            _ => Filter::zeros(),
        }
    }

    /// The filter state at `committed_time + delta` for a `delta` within
    /// the snap tolerance: the fourth-order Taylor series of
    /// `ẇ = A_w w + b_w c X` with the plant's derivatives from
    /// [`Self::committed_derivatives`] (truncation below
    /// `(ν |delta|)^5 / 120` relative, ν the larger norm of A and A_w).
    pub(super) fn filter_near_committed(&mut self, delta: f64) -> Filter {
        let w = self.committed_filter;
        let Some(coupling) = self.coupling.clone() else {
            return Filter::zeros();
        };
        if delta == 0.0 {
            return w;
        }
        let plant = self.committed_derivatives(delta);
        let (a_w, b_w) = (&coupling.wk.state_matrix, &coupling.wk.input_vector);
        let acceleration = |x: &State| (coupling.acceleration_row * x)[0];
        let mut derivative = a_w * w + b_w * acceleration(&plant[0]);
        let mut result = w + derivative * delta;
        let mut factor = delta;
        for (j, x) in plant.iter().enumerate().skip(1) {
            derivative = a_w * derivative + b_w * acceleration(x);
            factor *= delta / (j + 1) as f64;
            result += derivative * factor;
        }
        result
    }

    /// `X, X', X'', X'''` at the committed point (the recursion of
    /// [`Self::state_near_committed`] at its highest order), for the
    /// filter's Taylor series; the road derivatives are those of the piece
    /// in force at `committed_time + delta`.
    fn committed_derivatives(&mut self, delta: f64) -> [State; 4] {
        let (k, t, x) = (self.grid_index, self.committed_time, self.committed_state);
        let p = self.delayed_vector_at(k, t, (t, x), &x);
        let road_piece = self.piece_from(t + delta);
        let piece = self.forcing(&road_piece);
        let road = match piece {
            RoadPiece::Harmonic {
                amplitude,
                angular_frequency: w,
            } => {
                let (sin, cos) = crate::math::sin_cos(w * t);
                let a = amplitude;
                [a * sin, a * w * cos, -a * w * w * sin, -a * w * w * w * cos]
            }
            RoadPiece::Linear { .. } => [piece.value(t), piece.slope(t), 0.0, 0.0],
        };
        let b = self.solver_input_column();
        let (m, e) = (self.solver_matrix, self.plant.e);
        let mut out = [x; 4];
        for j in 1..4 {
            out[j] = m * out[j - 1] + b * p[j - 1] + e * road[j - 1];
        }
        out
    }
}
