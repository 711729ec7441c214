//! The exact step maps of Eq. (23): one exponential of an augmented matrix
//! (the plant plus the generators of the delayed input and the roads) gives
//! every matrix of a step ([`StepOperator`]), and [`GridStep`] holds a whole
//! grid step in the column form the whole-step loop uses.

use super::expm;
use super::filter::{FilterCoupling, FilterGridStep, FilterRows};
use super::holding::ContactCheck;
use crate::metrics::RunningRms;
use crate::model::{State, V_T, X_S, X_T};
use crate::road::RoadPiece;
use nalgebra::{Matrix4, Matrix6, SMatrix, Vector2, Vector4};

/// Dimension of the augmented system: plant (6), cubic delayed input (4),
/// linear road (2), harmonic road (2).
pub(super) const AUGMENTED: usize = 14;
pub(super) const DELAY_INPUT: usize = 6;
pub(super) const LINEAR_ROAD: usize = 10;
pub(super) const HARMONIC_ROAD: usize = 12;

/// The exact map of one step of length δ:
/// `X(a+δ) = Φ X(a) + Γ_u p + Γ_l q + Γ_h z`, where
/// `p = [u, u', u'', u'''](a)` (delayed tire displacement and derivatives),
/// `q = [x_g, x_g'](a)` (linear road), `z = A_r [sin ω a, cos ω a]` (harmonic).
#[derive(Debug, Clone, PartialEq)]
pub(super) struct StepOperator {
    pub(super) transition: Matrix6<f64>,
    pub(super) delayed_input: SMatrix<f64, 6, 4>,
    pub(super) linear_road: SMatrix<f64, 6, 2>,
    pub(super) harmonic_road: SMatrix<f64, 6, 2>,
    /// The rows of the W_k filter states over the same step, when the
    /// comfort outputs are on ([`FilterRows`]).
    pub(super) filter: Option<FilterRows>,
}

impl StepOperator {
    /// The step of length `length` (s); with `coupling`, the W_k filter
    /// rows too ([`FilterRows::new`]). The plant's matrices come from the
    /// plant's own 14-dimensional exponential either way, so turning the
    /// filter on does not change a bit of the plant's step.
    pub(super) fn new(
        a: &Matrix6<f64>,
        b: &State,
        e: &State,
        angular_frequency: f64,
        length: f64,
        coupling: Option<&FilterCoupling>,
    ) -> Self {
        let m = augmented_matrix(a, b, e, angular_frequency);
        let exp = expm::precise_exp(&(m * length));
        StepOperator {
            transition: exp.fixed_view::<6, 6>(0, 0).into_owned(),
            delayed_input: exp.fixed_view::<6, 4>(0, DELAY_INPUT).into_owned(),
            linear_road: exp.fixed_view::<6, 2>(0, LINEAR_ROAD).into_owned(),
            harmonic_road: exp.fixed_view::<6, 2>(0, HARMONIC_ROAD).into_owned(),
            filter: coupling.map(|c| FilterRows::new(&m, c, length)),
        }
    }

    #[inline]
    pub(super) fn apply(
        &self,
        x: &State,
        delayed: Option<&Vector4<f64>>,
        road: &RoadPiece,
        at: f64,
    ) -> State {
        let mut next = self.transition * x;
        if let Some(p) = delayed {
            next += self.delayed_input * p;
        }
        next += road_input(&self.linear_road, &self.harmonic_road, road, at);
        next
    }
}

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

/// The road's part of an exact step map starting at time `at`, for the
/// rows `linear` (`Γ_l`, acting on `[x_g, x_g']` of a linear piece) and
/// `harmonic` (`Γ_h`, acting on `A [sin ω at, cos ω at]`) of any state.
#[inline]
pub(super) fn road_input<const R: usize>(
    linear: &SMatrix<f64, R, 2>,
    harmonic: &SMatrix<f64, R, 2>,
    road: &RoadPiece,
    at: f64,
) -> SMatrix<f64, R, 1> {
    match *road {
        RoadPiece::Linear { .. } => linear * Vector2::new(road.value(at), road.slope(at)),
        RoadPiece::Harmonic {
            amplitude,
            angular_frequency,
        } => {
            let (sin, cos) = crate::math::sin_cos(angular_frequency * at);
            harmonic * Vector2::new(amplitude * sin, amplitude * cos)
        }
    }
}

/// Cubic Hermite interpolant of `x_t` over one grid interval of length h:
/// `[u, u', u'', u''']` at offset σ.
#[inline]
pub(super) fn hermite(nodes: [f64; 4], h: f64, offset: f64) -> Vector4<f64> {
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

/// The 4×4 matrix of [`hermite`]: `[u, u', u'', u''']` at offset σ is
/// `hermite_matrix(h, σ) [x_0, v_0, x_1, v_1]`.
pub(super) fn hermite_matrix(h: f64, offset: f64) -> Matrix4<f64> {
    Matrix4::from_columns(&[
        hermite([1.0, 0.0, 0.0, 0.0], h, offset),
        hermite([0.0, 1.0, 0.0, 0.0], h, offset),
        hermite([0.0, 0.0, 1.0, 0.0], h, offset),
        hermite([0.0, 0.0, 0.0, 1.0], h, offset),
    ])
}

/// `C`: the 2×6 map from X to a history node `(x_t, v_t)`.
pub(super) fn tire_pick() -> SMatrix<f64, 2, 6> {
    let mut pick = SMatrix::<f64, 2, 6>::zeros();
    pick[(0, X_T)] = 1.0;
    pick[(1, V_T)] = 1.0;
    pick
}

/// Columns of a 6-row matrix, stored as plain arrays for the hot loop.
pub(super) type Columns<const N: usize> = [[f64; 6]; N];

pub(super) fn columns<const C: usize>(m: &SMatrix<f64, 6, C>) -> Columns<C> {
    std::array::from_fn(|j| std::array::from_fn(|i| m[(i, j)]))
}

/// `Σ_j cols[j] v[j]` for six columns, summed pairwise so that the
/// dependency chain is short.
#[inline(always)]
pub(super) fn combine6(c: &Columns<6>, v: &[f64; 6]) -> [f64; 6] {
    std::array::from_fn(|i| {
        ((c[0][i] * v[0] + c[1][i] * v[1]) + (c[2][i] * v[2] + c[3][i] * v[3]))
            + (c[4][i] * v[4] + c[5][i] * v[5])
    })
}

/// `Σ_j cols[j] v[j]` for four columns, summed pairwise.
#[inline(always)]
pub(super) fn combine4(c: &Columns<4>, v: &[f64; 4]) -> [f64; 6] {
    std::array::from_fn(|i| (c[0][i] * v[0] + c[1][i] * v[1]) + (c[2][i] * v[2] + c[3][i] * v[3]))
}

/// `cols[0] v[0] + cols[1] v[1]`.
#[inline(always)]
pub(super) fn combine2(c: &Columns<2>, v: &[f64; 2]) -> [f64; 6] {
    std::array::from_fn(|i| c[0][i] * v[0] + c[1][i] * v[1])
}

#[inline(always)]
pub(super) fn add6(a: [f64; 6], b: [f64; 6]) -> [f64; 6] {
    std::array::from_fn(|i| a[i] + b[i])
}

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
    /// The road phase rotation over one step, `z' = r_1 z + r_2 swap(z)` with
    /// `r_1 = [cos ω h, cos ω h]`, `r_2 = [sin ω h, −sin ω h]`.
    pub(super) rotation: [[f64; 2]; 2],
    /// Columns of the 2×6 map from X to `[BA, SDD]` (row V_S of A, and
    /// `x_s − x_t`).
    pub(super) outputs: [[f64; 2]; 6],
    /// The W_k filter's step, when the comfort outputs are on.
    pub(super) filter: Option<FilterGridStep>,
    /// The contact-loss test of every step (the limit is set by the
    /// simulator; +∞ until then).
    pub(super) contact: ContactCheck,
    /// Whether the whole-step loop runs the road-holding test and the
    /// largest |SDD| ([`super::Metrics::RoadHolding`]).
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
    /// ([`DelayRegime::InsideStep`](super::DelayRegime::InsideStep)). Over `[t_k, t_k + tau)` the delayed
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
        let (sin, cos) = crate::math::sin_cos(angular_frequency * h);
        GridStep {
            transition: columns(transition),
            nodes: columns(nodes),
            harmonic: columns(&road.harmonic_road),
            linear: columns(&road.linear_road),
            rotation: [[cos, cos], [sin, -sin]],
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
                limit: f64::INFINITY,
                angular_frequency,
                start_time: 0.0,
                step: h,
                unilateral: false,
            },
            holding: false,
        }
    }

    /// Road phase at the node after one with phase `z`.
    #[inline(always)]
    pub(super) fn rotate(&self, z: [f64; 2]) -> [f64; 2] {
        let [c, s] = self.rotation;
        [c[0] * z[0] + s[0] * z[1], c[1] * z[1] + s[1] * z[0]]
    }

    /// `[BA, SDD]` at state x, summed pairwise like [`combine6`] (in the
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

/// The largest absolute row sum of `m`.
pub(super) fn infinity_norm(m: &Matrix6<f64>) -> f64 {
    m.row_iter()
        .map(|row| row.iter().map(|v| v.abs()).sum::<f64>())
        .fold(0.0, f64::max)
}
