//! The system the solver integrates, above the linear algebra: the
//! augmented layout of Eq. (23)'s step maps (the plant, the generators of
//! the delayed input and of the roads), the selection of the history's
//! `(x_t, v_t)`, and the ISO 2631-1 W_k filter's coupling to the body
//! acceleration (below). It knows no step, no accumulator and no simulator.
//!
//! **The W_k filter** weights the body acceleration inside the precise
//! integration (only with the comfort metrics). The realization of [`crate::comfort::wk_state_space`],
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
//! (`operators::FilterRows`). The plant keeps the matrices of its own
//! 14-dimensional exponential: turning the filter on changes no bit of the
//! plant's states or of the BA, SDD, TDD values.
//!
//! The filter starts from rest (`w(t_0) = 0`).
//!
//! Layer: system (docs/architecture.md); it imports the crate's `comfort`,
//! `math`, `model`.

use crate::comfort::{WK_STATES, WkStateSpace, wk_state_space};
use crate::model::{Plant, State, V_S, V_T, X_T};
use nalgebra::{Matrix6, RowSVector, SMatrix, SVector};

/// Dimension of the augmented system: plant (6), cubic delayed input (4),
/// linear road (2), harmonic road (2).
pub(super) const AUGMENTED: usize = 14;
pub(super) const DELAY_INPUT: usize = 6;
pub(super) const LINEAR_ROAD: usize = 10;
pub(super) const HARMONIC_ROAD: usize = 12;

/// The augmented matrix M of the step maps (unscaled): the plant `a`,
/// the delayed input's column `b` and the cubic's generator, the road
/// column `e` for either road's generator (a line, a sine of angular
/// frequency `angular_frequency`).
pub(super) fn augmented_matrix(
    a: &Matrix6<f64>,
    b: &State,
    e: &State,
    angular_frequency: f64,
) -> SMatrix<f64, AUGMENTED, AUGMENTED> {
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
    m
}

/// `C`: the 2×6 map from X to a history node `(x_t, v_t)`.
pub(super) fn tire_pick() -> SMatrix<f64, 2, 6> {
    let mut pick = SMatrix::<f64, 2, 6>::zeros();
    pick[(0, X_T)] = 1.0;
    pick[(1, V_T)] = 1.0;
    pick
}

/// The W_k filter state w (m/s², see [`WkStateSpace`]).
pub(crate) type Filter = SVector<f64, WK_STATES>;

/// Dimension of the plant's augmented system plus the filter.
pub(super) const WITH_FILTER: usize = AUGMENTED + WK_STATES;

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

/// The 22-dimensional augmented matrix of the module documentation, from
/// the plant's 14-dimensional one `m` ([`augmented_matrix`])
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

/// The rotation of the harmonic road generator's phase
/// `A [sin ω t, cos ω t]` over one step h at angular frequency ω:
/// `z' = r_1 z + r_2 swap(z)` with `r_1 = [cos ω h, cos ω h]`,
/// `r_2 = [sin ω h, −sin ω h]` ([`rotate`]).
pub(super) fn phase_rotation(angular_frequency: f64, h: f64) -> [[f64; 2]; 2] {
    let (sin, cos) = crate::math::sin_cos(angular_frequency * h);
    [[cos, cos], [sin, -sin]]
}

/// The phase one step after `z` ([`phase_rotation`]).
#[inline(always)]
pub(super) fn rotate(rotation: &[[f64; 2]; 2], z: [f64; 2]) -> [f64; 2] {
    let [c, s] = rotation;
    [c[0] * z[0] + s[0] * z[1], c[1] * z[1] + s[1] * z[0]]
}
