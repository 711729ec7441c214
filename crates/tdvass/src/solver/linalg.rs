//! Linear algebra of the solver, the bottom layer: the cubic Hermite
//! interpolant of the delayed input, matrices in the column form of the
//! whole-step loop, norms and the balancing that bounds them. Pure
//! functions of numbers; it imports nothing of the solver (the exponential
//! itself is [`super::expm`]).

use crate::model::State;
use nalgebra::{Matrix4, Matrix6, SMatrix, Vector4};

/// The delayed input's cubic Hermite interpolant over one grid interval
/// of length h ([`crate::model::dynamics::hermite`]), as a column:
/// `[u, u', u'', u''']` at offset σ.
#[inline]
pub(super) fn hermite(nodes: [f64; 4], h: f64, offset: f64) -> Vector4<f64> {
    Vector4::from(crate::model::dynamics::hermite(nodes, h, offset))
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

/// The balance of the solver's matrix for the bounds of a deferred state inside a step (`super::deferred`):
/// `D` (powers of two), `ν = ‖D⁻¹ A D‖_∞`, `‖D⁻¹ b‖_∞`, `‖D⁻¹ e‖_∞`.
#[derive(Debug, Clone, Copy)]
pub(super) struct Scaling {
    pub(super) diagonal: [f64; 6],
    pub(super) norm: f64,
    pub(super) input: f64,
    pub(super) road: f64,
}

impl Scaling {
    /// For the solver's matrix `a`, input column `b` and road column `e`.
    pub(super) fn new(a: &nalgebra::Matrix6<f64>, b: &State, e: &State) -> Scaling {
        let (diagonal, norm) = balancing(a);
        Scaling {
            diagonal,
            norm,
            input: scaled_norm(&diagonal, b),
            road: scaled_norm(&diagonal, e),
        }
    }
}

/// `‖D⁻¹ c‖_∞` for the diagonal D.
pub(super) fn scaled_norm(diagonal: &[f64; 6], c: &State) -> f64 {
    (0..6).fold(0.0f64, |m, i| m.max(c[i].abs() / diagonal[i]))
}

/// A bound of `|p|` over `[0, h]` for the cubic Hermite interpolant `p`
/// of `[x_0, v_0, x_1, v_1]`: its basis functions of the values are
/// nonnegative and sum to 1, those of the slopes stay within `4/27 h`.
pub(super) fn hermite_bound([x0, v0, x1, v1]: [f64; 4], h: f64) -> f64 {
    x0.abs().max(x1.abs()) + 4.0 / 27.0 * h * (v0.abs() + v1.abs())
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

/// The largest absolute row sum of `m`.
pub(super) fn infinity_norm(m: &Matrix6<f64>) -> f64 {
    m.row_iter()
        .map(|row| row.iter().map(|v| v.abs()).sum::<f64>())
        .fold(0.0, f64::max)
}

/// `‖D⁻¹ M D‖_∞` for a diagonal D of powers of two that balances M
/// (Osborne's iteration in radix 2, as LAPACK's `gebal`: a state's row and
/// column sums off the diagonal are brought within a factor 2 of each
/// other while that lowers their sum by 5 %). Any D gives a valid bound;
/// balancing makes it tight. Powers of two scale exactly, and only +, ×
/// and comparisons are used.
pub(super) fn balanced_norm<const D: usize>(m: &SMatrix<f64, D, D>) -> f64 {
    balancing(m).1
}

/// The diagonal D of [`balanced_norm`] (powers of two) and the norm
/// `‖D⁻¹ M D‖_∞`.
pub(super) fn balancing<const D: usize>(m: &SMatrix<f64, D, D>) -> ([f64; D], f64) {
    let mut diagonal = [1.0; D];
    let mut b = m.abs();
    for _ in 0..64 {
        let mut changed = false;
        for i in 0..D {
            let (mut column, mut row) = (0.0, 0.0);
            for j in 0..D {
                if j != i {
                    column += b[(j, i)];
                    row += b[(i, j)];
                }
            }
            if column == 0.0 || row == 0.0 {
                continue;
            }
            let sum = column + row;
            let (mut c, mut r, mut f) = (column, row, 1.0);
            while c < 0.5 * r && f < 1e30 {
                c *= 2.0;
                r *= 0.5;
                f *= 2.0;
            }
            while 0.5 * c >= r && f > 1e-30 {
                c *= 0.5;
                r *= 2.0;
                f *= 0.5;
            }
            if c + r < 0.95 * sum {
                changed = true;
                diagonal[i] *= f;
                for j in 0..D {
                    b[(j, i)] *= f;
                    b[(i, j)] /= f;
                }
            }
        }
        if !changed {
            break;
        }
    }
    let norm = b
        .row_iter()
        .map(|row| row.iter().sum::<f64>())
        .fold(0.0, f64::max);
    (diagonal, norm)
}
