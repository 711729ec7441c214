//! The exact step maps of Eq. (23): one exponential of an augmented matrix
//! (the plant plus the generators of the delayed input and the roads) gives
//! every matrix of a step of the plant ([`StepOperator`]), and one of the
//! 22-dimensional matrix the W_k filter's rows ([`FilterRows`]). They know
//! nothing of accumulators, contact checks or the simulator.
//!
//! Layer: step maps and inputs (docs/architecture.md); it imports the
//! solver's `expm`, `system` and the crate's `comfort`, `math`, `model`,
//! `road`.

use super::expm;
use super::system::{
    AUGMENTED, DELAY_INPUT, Filter, FilterCoupling, HARMONIC_ROAD, LINEAR_ROAD, augmented_matrix,
    with_filter_matrix,
};
use crate::comfort::WK_STATES;
use crate::model::State;
use crate::road::RoadPiece;
use nalgebra::{Matrix6, SMatrix, Vector2, Vector4};

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
            phase,
        } => {
            let angle = crate::road::piece::harmonic_angle(angular_frequency, phase, at);
            let (sin, cos) = crate::math::sin_cos(angle);
            harmonic * Vector2::new(amplitude * sin, amplitude * cos)
        }
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
        next += road_input(&self.linear_road, &self.harmonic_road, road, at);
        next
    }
}
