//! The exact step maps of partial steps, applied to vectors: the state at
//! a point inside an internal step (a communication point, a switch of the
//! tire contact, a road breakpoint, `t_k + tau`), at about the cost of a
//! whole step instead of a fresh matrix exponential per offset.
//!
//! **What is needed.** A partial step of length σ maps the augmented vector
//! `z = [X; p; q; z_h]` (the state, the delayed input's cubic
//! `[u, u', u'', u''']`, the linear road `[x_g, x_g']`, the harmonic road
//! `A [sin ω a, cos ω a]`; with the W_k filter also `w`) to `e^{Mσ} z`, and
//! every caller needs that product only for one vector or a few (the
//! state, and with the delay inside the step the two columns of its 6×2
//! sensitivity), and only its first 6 rows (the state) or the filter rows.
//!
//! **Method.** σ is quantized as before to `κ 2^-40 h` (κ the nearest
//! integer; the time error is at most `2^-41 h`, 4.5e-16 s at h = 1 ms,
//! which moves the state by at most that times `|dX/dt|`). κ splits into
//! its high bits `j = ⌊κ 2^{n−40}⌋` (the length in units of `h 2^-n`,
//! `0 ≤ j ≤ 2^n`) and the rest `σ_f = (κ mod 2^{40−n}) 2^-40 h < h 2^-n`,
//! and `σ = j h 2^-n + σ_f` exactly. Then
//!
//! ```text
//! e^{Mσ} z = (I + T_j) y,   y = Σ_{k=0}^{K} (M σ_f)^k z / k!  (+ the truncation)
//! ```
//!
//! where `T_j = e^{M j h 2^-n} − I` comes from a table built once per mode
//! (lazily, at the first point inside a step, so a simulator that never
//! stops inside a step, as in the PSO, never builds it) and `y` is the
//! Taylor polynomial of order K, by Horner's rule on the vector
//! (`y ← z + (σ_f/k) M y`, k = K … 1) with the structure of M (the plant's
//! 6×6 block and two columns, the shifts of the cubic, the road's
//! generator: about 60 multiplications a term for the 14 dimensions). A
//! point costs those K terms and the product of the kept 6×14 rows of
//! `T_j` with `y` (8×22 for the filter's rows, only when a getter asks for
//! the comfort outputs).
//!
//! **The table.** The ladder `L_i = e^{M h 2^{i−n}} − I`, `i = 0 … n`,
//! starts from [`expm::precise_exp_increment`] at `h 2^-n` and doubles by
//! `L_{i+1} = 2 L_i + L_i L_i` (the 2^N algorithm's squaring: the
//! increments are kept apart from the identity, so a short step keeps its
//! relative accuracy); it costs about one exponential of the whole step.
//! An entry `T_j` is composed from the ladder entries of j's bits, lowest
//! first (`T ← T + L_i + T L_i`, the kept rows of T only), and each prefix
//! is kept: a new j costs one row-block product (at most `2^n + 1` entries,
//! 65 × 6×14 numbers for the plant at n = 6). The operations that give
//! `T_j` depend on j alone, never on which entries were built before, so
//! the result is the same to the bit whatever the order of the calls, on
//! every platform (IEEE +, −, ×, ÷ only). The table is a cache of a
//! function of the operators: it is not saved with the state and is
//! dropped when they change (`set_gain`).
//!
//! **Bound.** Let `D` be a diagonal of powers of two that balances M
//! (Osborne's iteration, radix 2: [`balanced_norm`]) and
//! `ν = ‖D⁻¹ M D‖_∞`. The truncated series satisfies, in exact arithmetic,
//!
//! ```text
//! ‖D⁻¹ (e^{Mσ_f} z − y)‖_∞ ≤ θ^{K+1} / (K+1)! / (1 − θ/(K+2)) ‖D⁻¹ z‖_∞,
//! θ = ν h 2^-n ≥ ν σ_f,
//! ```
//!
//! K is the least order that brings the factor to [`TRUNCATION`] = 2^-56
//! or below, and n the least of 6 … 12 with `θ ≤ 1/16`. The table's factor
//! `‖D⁻¹ (I + T_j) D‖_∞ ≤ e^{ν j h 2^-n} ≤ e^{ν h}` carries it to the
//! result: the truncation error is at most `e^{νh} 2^-56 ‖D⁻¹ z‖_∞` in the
//! balanced norm. For the default TDVASS plant (ν ≈ 700 1/s, its fastest
//! mode 450 rad/s) at the FMU's h = 1 ms: n = 6, θ = 0.011, K = 6, and the
//! factor is 3.6e-18 (7e-18 with e^{νh} = 2); the filter's 22 dimensions
//! take K = 7 to 8. What remains is the rounding of the products, of the
//! order of that of a full exponential: for random offsets the plant's
//! rows agree with the full exponential of the quantized length to 8e-16
//! and the filter's to 3e-15 relative, and through the simulator states
//! and outputs agree to 1.5e-14 of their largest values in every delay
//! regime, with the filter and with the unilateral tire (unit tests
//! below), against tolerances of 1e-8 and more.
//!
//! **Pieces of fixed length.** With the delay inside the step every step
//! has the pieces `[t_k, t_k + tau)` and `[t_k + tau, t_{k+1})`; their
//! offsets are kept as 6×14 matrices (the map above applied to the
//! identity's columns, the same matrix whenever it is built), one product
//! each.
//!
//! **Caller independence.** A point inside a step is reached from the last
//! committed point and is not committed itself, so a master's
//! communication points never feed back into the grid nodes (unit test
//! `in_step_points_leave_the_nodes_unchanged`); what is committed inside a
//! step (a road breakpoint, a switch of the tire contact, a change of an
//! external road input) is located from committed values alone, as before.

use super::expm;
use super::linalg::{Scaling, balanced_norm};
use super::system::{
    AUGMENTED, DELAY_INPUT, Filter, FilterCoupling, HARMONIC_ROAD, LINEAR_ROAD, WITH_FILTER,
    augmented_matrix, with_filter_matrix,
};
use crate::comfort::WK_STATES;
use crate::model::State;
use crate::road::RoadPiece;
use nalgebra::{Matrix6, SMatrix, SVector, Vector4};

/// Partial step lengths are quantized to `2^-OFFSET_BITS` of the step.
pub(super) const OFFSET_BITS: u32 = 40;
/// The least and the most bits of the table (`2^n` entries at most).
const TABLE_BITS: (u32, u32) = (6, 12);
/// The table's bits are the least that bring θ = ν h 2^-n to at most
/// this.
const MAX_THETA: f64 = 1.0 / 16.0;
/// The truncation bound of the Taylor polynomial (relative, in the
/// balanced norm): 2^-56.
pub(super) const TRUNCATION: f64 = 1.0 / 72_057_594_037_927_936.0;
/// The highest order of the Taylor polynomial.
const MAX_ORDER: usize = 30;

/// The augmented vector of the plant (see the module docs).
pub(super) type Augmented<const C: usize> = SMatrix<f64, AUGMENTED, C>;

/// The quantized offset κ of a partial step of length `length` in a grid
/// step `h` (a negative or NaN length gives 0).
#[inline]
pub(super) fn offset_key(length: f64, h: f64) -> u64 {
    // Rounded to the nearest integer (ties to even) by adding and taking
    // away 2^52, exact below 2^52 (κ ≤ 2^41 here); `as` maps a negative
    // or NaN value to 0.
    const SHIFT: f64 = 4_503_599_627_370_496.0;
    let scaled = length / h * (1u64 << OFFSET_BITS) as f64;
    ((scaled + SHIFT) - SHIFT) as u64
}

/// `m z` for small static matrices, column by column (the loops unroll).
#[inline(always)]
fn product<const R: usize, const D: usize, const C: usize>(
    m: &SMatrix<f64, R, D>,
    z: &SMatrix<f64, D, C>,
) -> SMatrix<f64, R, C> {
    let mut out = SMatrix::<f64, R, C>::zeros();
    for c in 0..C {
        let mut column = [0.0; R];
        for d in 0..D {
            let v = z[(d, c)];
            for (i, o) in column.iter_mut().enumerate() {
                *o += m[(i, d)] * v;
            }
        }
        out.column_mut(c).copy_from_slice(&column);
    }
    out
}

/// The table of one augmented matrix (D dimensions), giving the R rows
/// from `first_row` of `e^{M j h 2^-n} − I`.
#[derive(Debug, Clone)]
struct Table<const D: usize, const R: usize> {
    first_row: usize,
    /// n: the table resolves `h 2^-n`.
    bits: u32,
    /// K: the order of the Taylor polynomial over the rest.
    order: usize,
    /// `h 2^-40` (s): the unit of κ.
    unit: f64,
    /// `L_i = e^{M h 2^{i−n}} − I`, i = 0 … n.
    ladder: Vec<SMatrix<f64, D, D>>,
    /// The kept rows of `T_j`, j = 0 … 2^n, as built (`T_0 = 0` is never
    /// stored).
    entries: Vec<Option<Box<SMatrix<f64, R, D>>>>,
}

impl<const D: usize, const R: usize> Table<D, R> {
    fn new(m: &SMatrix<f64, D, D>, h: f64, first_row: usize) -> Self {
        let nu = balanced_norm(m);
        let mut bits = TABLE_BITS.0;
        while bits < TABLE_BITS.1 && nu * h * 0.5f64.powi(bits as i32) > MAX_THETA {
            bits += 1;
        }
        let theta = nu * h * 0.5f64.powi(bits as i32);
        let mut increment = expm::precise_exp_increment(&(m * (h * 0.5f64.powi(bits as i32))));
        let mut ladder = Vec::with_capacity(bits as usize + 1);
        for _ in 0..bits {
            let next = increment * 2.0 + increment * increment;
            ladder.push(increment);
            increment = next;
        }
        ladder.push(increment);
        Table {
            first_row,
            bits,
            order: taylor_order(theta),
            unit: h * 0.5f64.powi(OFFSET_BITS as i32),
            ladder,
            entries: vec![None; (1 << bits) + 1],
        }
    }

    /// `(j, σ_f)` of the offset κ; `None` beyond `h (1 + 2^-n)`.
    #[inline]
    fn split(&self, key: u64) -> Option<(usize, f64)> {
        let below = OFFSET_BITS - self.bits;
        let j = key >> below;
        if j > 1 << self.bits {
            return None;
        }
        let rest = key & ((1u64 << below) - 1);
        Some((j as usize, rest as f64 * self.unit))
    }

    /// The kept rows of `T_j` (1 ≤ j ≤ 2^n): from j's bits, lowest first,
    /// every prefix kept.
    fn entry(&mut self, j: usize) -> &SMatrix<f64, R, D> {
        if self.entries[j].is_none() {
            let mut prefix = 0usize;
            for bit in 0..=self.bits as usize {
                if (j >> bit) & 1 == 0 {
                    continue;
                }
                let next = prefix | (1 << bit);
                if self.entries[next].is_none() {
                    let ladder = &self.ladder[bit];
                    let rows = ladder.fixed_rows::<R>(self.first_row).into_owned();
                    let value = match self.entries[prefix].as_deref() {
                        Some(before) => before + rows + before * ladder,
                        None => rows,
                    };
                    self.entries[next] = Some(Box::new(value));
                }
                prefix = next;
            }
        }
        self.entries[j].as_deref().expect("built above")
    }

    /// `rows (I + T_j) y`.
    #[inline]
    fn finish<const C: usize>(&mut self, j: usize, y: &SMatrix<f64, D, C>) -> SMatrix<f64, R, C> {
        let first = self.first_row;
        let kept = y.fixed_rows::<R>(first).into_owned();
        if j == 0 {
            kept
        } else {
            kept + product(self.entry(j), y)
        }
    }
}

/// The least order K with `θ^{K+1}/(K+1)! / (1 − θ/(K+2)) ≤`
/// [`TRUNCATION`] (at most [`MAX_ORDER`]).
fn taylor_order(theta: f64) -> usize {
    let mut term = theta;
    for k in 1..=MAX_ORDER {
        term *= theta / (k + 1) as f64;
        let ratio = theta / (k + 2) as f64;
        if ratio < 1.0 && term / (1.0 - ratio) <= TRUNCATION {
            return k;
        }
    }
    MAX_ORDER
}

/// The dense output of one mode of the plant (see the module docs).
#[derive(Debug, Clone)]
pub(super) struct DenseOutput {
    /// The solver's state matrix, delayed-input and road columns.
    a: Matrix6<f64>,
    b: State,
    e: State,
    angular_frequency: f64,
    h: f64,
    plant: Table<AUGMENTED, 6>,
    /// The first 6 rows of `e^{Mσ}` for offsets every step has (κ and the
    /// rows, each the map below applied to the identity's columns).
    fixed: Vec<(u64, SMatrix<f64, 6, AUGMENTED>)>,
    /// With the W_k filter: its rows of the 22-dimensional matrix and
    /// their table (built at the first use).
    filter: Option<FilterTable>,
    /// The balance of the solver's matrix that bounds a deferred state
    /// inside a step ([`super::deferred`]).
    pub(super) scaling: Scaling,
}

#[derive(Debug, Clone)]
struct FilterTable {
    rows: SMatrix<f64, WK_STATES, WITH_FILTER>,
    table: Table<WITH_FILTER, WK_STATES>,
}

impl DenseOutput {
    /// For the solver's state matrix `a`, input column `b` (zero when the
    /// delay is folded), road column `e`, the harmonic road's ω and the
    /// grid step h.
    pub(super) fn new(
        a: &Matrix6<f64>,
        b: &State,
        e: &State,
        angular_frequency: f64,
        h: f64,
    ) -> DenseOutput {
        let m = augmented_matrix(a, b, e, angular_frequency);
        DenseOutput {
            a: *a,
            b: *b,
            e: *e,
            angular_frequency,
            h,
            plant: Table::new(&m, h, 0),
            fixed: Vec::new(),
            filter: None,
            scaling: Scaling::new(a, b, e),
        }
    }

    /// This dense output, the offsets `keys` (κ) taken as a 6×14 matrix
    /// applied to the vectors (the same matrix whenever it is built; an
    /// offset that every step has then costs one product).
    pub(super) fn with_fixed(mut self, keys: &[u64]) -> DenseOutput {
        for &key in keys {
            if self.fixed.iter().all(|(k, _)| *k != key) {
                let rows = self.plant(key, &Augmented::<AUGMENTED>::identity());
                self.fixed.push((key, rows));
            }
        }
        self
    }

    /// `M z` for the plant's augmented vectors (the columns of z), from
    /// the structure of M: `X' = A X + b u + e (x_g)` and the generators
    /// of the cubic and of the roads.
    #[inline]
    fn derivative<const C: usize>(&self, z: &Augmented<C>) -> Augmented<C> {
        let mut out = Augmented::<C>::zeros();
        let w = self.angular_frequency;
        for c in 0..C {
            let z: [f64; AUGMENTED] = std::array::from_fn(|i| z[(i, c)]);
            let (u, road) = (z[DELAY_INPUT], z[LINEAR_ROAD] + z[HARMONIC_ROAD]);
            let mut dx: [f64; 6] = std::array::from_fn(|i| self.b[i] * u + self.e[i] * road);
            for (j, &v) in z.iter().take(6).enumerate() {
                for (i, d) in dx.iter_mut().enumerate() {
                    *d += self.a[(i, j)] * v;
                }
            }
            let mut column = [0.0; AUGMENTED];
            column[..6].copy_from_slice(&dx);
            column[DELAY_INPUT..DELAY_INPUT + 3]
                .copy_from_slice(&z[DELAY_INPUT + 1..DELAY_INPUT + 4]);
            column[LINEAR_ROAD] = z[LINEAR_ROAD + 1];
            column[HARMONIC_ROAD] = w * z[HARMONIC_ROAD + 1];
            column[HARMONIC_ROAD + 1] = -w * z[HARMONIC_ROAD];
            out.column_mut(c).copy_from_slice(&column);
        }
        out
    }

    /// The Taylor polynomial of order `order` of `e^{Mσ} z` by Horner's
    /// rule, `y ← z + (σ/k) M y` for k = K … 1, column by column, with
    /// the structure of M ([`Self::derivative`]).
    #[inline]
    fn taylor<const C: usize>(&self, z: &Augmented<C>, sigma: f64, order: usize) -> Augmented<C> {
        let mut y = *z;
        if sigma == 0.0 {
            return y;
        }
        let a: [[f64; 6]; 6] = std::array::from_fn(|j| std::array::from_fn(|i| self.a[(i, j)]));
        let (b, e, w) = (&self.b, &self.e, self.angular_frequency);
        for c in 0..C {
            let z: [f64; AUGMENTED] = std::array::from_fn(|i| z[(i, c)]);
            let mut v = z;
            for k in (1..=order).rev() {
                let s = sigma / k as f64;
                let (u, road) = (v[DELAY_INPUT], v[LINEAR_ROAD] + v[HARMONIC_ROAD]);
                let x: [f64; 6] = std::array::from_fn(|i| v[i]);
                let ax = super::linalg::combine6(&a, &x);
                let mut next = z;
                for i in 0..6 {
                    next[i] += s * (ax[i] + (b[i] * u + e[i] * road));
                }
                for i in 0..3 {
                    next[DELAY_INPUT + i] += s * v[DELAY_INPUT + i + 1];
                }
                next[LINEAR_ROAD] += s * v[LINEAR_ROAD + 1];
                next[HARMONIC_ROAD] += s * (w * v[HARMONIC_ROAD + 1]);
                next[HARMONIC_ROAD + 1] += s * (-w * v[HARMONIC_ROAD]);
                v = next;
            }
            y.column_mut(c).copy_from_slice(&v);
        }
        y
    }

    /// The first 6 rows of `e^{Mσ} z` for the columns of z, σ the offset
    /// `key` ([`offset_key`]).
    pub(super) fn plant<const C: usize>(
        &mut self,
        key: u64,
        z: &Augmented<C>,
    ) -> SMatrix<f64, 6, C> {
        #[cfg(test)]
        if tests::EXACT.get() {
            return self.exact(key).fixed_rows::<6>(0) * z;
        }
        if let Some((_, rows)) = self.fixed.iter().find(|(k, _)| *k == key) {
            return product(rows, z);
        }
        let Some((j, sigma)) = self.plant.split(key) else {
            return self.exact(key).fixed_rows::<6>(0) * z;
        };
        let y = self.taylor(z, sigma, self.plant.order);
        self.plant.finish(j, &y)
    }

    /// The W_k filter's rows of `e^{M_w σ} [z; w]` (M_w the 22-dimensional
    /// matrix of [`super::filter`]).
    pub(super) fn filter(
        &mut self,
        key: u64,
        z: &Augmented<1>,
        w: &Filter,
        coupling: &FilterCoupling,
    ) -> Filter {
        let mut big = SVector::<f64, WITH_FILTER>::zeros();
        big.fixed_rows_mut::<AUGMENTED>(0).copy_from(z);
        big.fixed_rows_mut::<WK_STATES>(AUGMENTED).copy_from(w);
        #[cfg(test)]
        if tests::EXACT.get() {
            let m = augmented_matrix(&self.a, &self.b, &self.e, self.angular_frequency);
            let full = with_filter_matrix(&m, coupling);
            let sigma = key as f64 * self.h * 0.5f64.powi(OFFSET_BITS as i32);
            return expm::precise_exp(&(full * sigma)).fixed_rows::<WK_STATES>(AUGMENTED) * big;
        }
        if self.filter.is_none() {
            let m = augmented_matrix(&self.a, &self.b, &self.e, self.angular_frequency);
            let full = with_filter_matrix(&m, coupling);
            self.filter = Some(FilterTable {
                rows: full.fixed_rows::<WK_STATES>(AUGMENTED).into_owned(),
                table: Table::new(&full, self.h, AUGMENTED),
            });
        }
        let Some((j, sigma)) = self.filter.as_ref().and_then(|f| f.table.split(key)) else {
            let m = augmented_matrix(&self.a, &self.b, &self.e, self.angular_frequency);
            let full = with_filter_matrix(&m, coupling);
            let sigma = key as f64 * self.h * 0.5f64.powi(OFFSET_BITS as i32);
            return expm::precise_exp(&(full * sigma)).fixed_rows::<WK_STATES>(AUGMENTED) * big;
        };
        let order = self.filter.as_ref().map_or(0, |f| f.table.order);
        let mut y = big;
        if sigma != 0.0 {
            for k in (1..=order).rev() {
                let plant = self.derivative(&y.fixed_rows::<AUGMENTED>(0).into_owned());
                let filter = self.filter.as_ref().map(|f| f.rows * y).unwrap_or_default();
                let mut derivative = SVector::<f64, WITH_FILTER>::zeros();
                derivative.fixed_rows_mut::<AUGMENTED>(0).copy_from(&plant);
                derivative
                    .fixed_rows_mut::<WK_STATES>(AUGMENTED)
                    .copy_from(&filter);
                y = big + derivative * (sigma / k as f64);
            }
        }
        match self.filter.as_mut() {
            Some(f) => f.table.finish(j, &y),
            None => Filter::zeros(),
        }
    }

    /// `e^{Mσ}` in full, for an offset beyond the table (never reached by
    /// the solver, whose partial steps are at most a step long).
    fn exact(&self, key: u64) -> SMatrix<f64, AUGMENTED, AUGMENTED> {
        let m = augmented_matrix(&self.a, &self.b, &self.e, self.angular_frequency);
        let sigma = key as f64 * self.h * 0.5f64.powi(OFFSET_BITS as i32);
        expm::precise_exp(&(m * sigma))
    }
}

/// The plant's augmented vector at time `at`: the state, the delayed
/// input (zero without one), the road piece's generator state; `phase`
/// gives the harmonic road's `A [sin ω at, cos ω at]`.
#[inline]
pub(super) fn augmented(
    x: &State,
    delayed: Option<&Vector4<f64>>,
    road: &RoadPiece,
    at: f64,
    phase: impl FnOnce() -> [f64; 2],
) -> Augmented<1> {
    let mut z = Augmented::<1>::zeros();
    z.fixed_rows_mut::<6>(0).copy_from(x);
    if let Some(p) = delayed {
        z.fixed_rows_mut::<4>(DELAY_INPUT).copy_from(p);
    }
    match *road {
        RoadPiece::Linear { .. } => {
            z[LINEAR_ROAD] = road.value(at);
            z[LINEAR_ROAD + 1] = road.slope(at);
        }
        RoadPiece::Harmonic { .. } => {
            let [sin, cos] = phase();
            z[HARMONIC_ROAD] = sin;
            z[HARMONIC_ROAD + 1] = cos;
        }
    }
    z
}

/// The last four `(sin, cos)` of [`crate::math::sin_cos`] by their
/// angle's bits: the points inside a step ask for the same few angles
/// again (`ω tau`, the committed time's).
#[derive(Debug, Clone, Copy)]
pub(super) struct Phases([(u64, (f64, f64)); 4]);

impl Default for Phases {
    fn default() -> Self {
        Phases([(f64::NAN.to_bits(), (f64::NAN, f64::NAN)); 4])
    }
}

impl Phases {
    /// `sin_cos(angle)`, the same to the bit.
    #[inline]
    pub(super) fn sin_cos(&mut self, angle: f64) -> (f64, f64) {
        let bits = angle.to_bits();
        if let Some((_, value)) = self.0.iter().find(|(b, _)| *b == bits) {
            return *value;
        }
        let value = crate::math::sin_cos(angle);
        self.0 = [self.0[1], self.0[2], self.0[3], (bits, value)];
        value
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::model::{Params, Plant, Variant, X_T};
    use crate::solver::system::FilterCoupling;
    use std::cell::Cell;

    thread_local! {
        /// When set, partial steps take the full exponential of the
        /// quantized length (the method this module replaced), as the
        /// reference of the tests.
        pub(in crate::solver) static EXACT: Cell<bool> = const { Cell::new(false) };
    }

    /// `f` with partial steps by the full exponential.
    pub(in crate::solver) fn exactly<T>(f: impl FnOnce() -> T) -> T {
        EXACT.set(true);
        let out = f();
        EXACT.set(false);
        out
    }

    /// A reproducible stream of numbers in [0, 1).
    pub(in crate::solver) struct Lcg(pub(in crate::solver) u64);

    impl Lcg {
        pub(in crate::solver) fn next(&mut self) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// The plant matrices of the solver for a variant (with the delayed
    /// input), and in flight (the road column moved into X_T's).
    fn modes(variant: Variant, params: Params) -> Vec<(Matrix6<f64>, State, State, Plant)> {
        let plant = Plant::new(params, variant).unwrap();
        let mut flight = plant.a;
        for row in 0..6 {
            flight[(row, X_T)] += plant.e[row];
        }
        vec![
            (plant.a, plant.b, plant.e, plant.clone()),
            (flight, plant.b, plant.e, plant.clone()),
        ]
    }

    /// Largest |entry|, at least `floor`.
    fn scale<const R: usize, const C: usize>(m: &SMatrix<f64, R, C>, floor: f64) -> f64 {
        m.abs().max().max(floor)
    }

    #[test]
    fn agrees_with_the_full_exponential_for_random_offsets() {
        let mut random = Lcg(7);
        let cases = [
            (Variant::Tdvass, Params::default(), 5.0, 1e-3),
            (
                Variant::Tdvass,
                Params::with_controller(40000.0, 0.03),
                60.0,
                3.3e-3,
            ),
            (Variant::Pvass, Params::default(), 0.0, 1e-2),
            (Variant::Cs, Params::default(), 20.0, 2e-4),
        ];
        let mut worst: [f64; 2] = [0.0; 2];
        for (variant, params, omega, h) in cases {
            for (a, b, e, plant) in modes(variant, params) {
                let coupling = FilterCoupling::new(&a, &b, &plant);
                let mut dense = DenseOutput::new(&a, &b, &e, omega, h);
                let m = augmented_matrix(&a, &b, &e, omega);
                let full = with_filter_matrix(&m, &coupling);
                for i in 0..400 {
                    // Offsets over the whole step, near its ends, and tiny.
                    let fraction = match i % 4 {
                        0 => random.next(),
                        1 => 1.0 - random.next() * 1e-6,
                        2 => random.next() * 1e-6,
                        _ => (random.next() * 64.0).floor() / 64.0,
                    };
                    let key = offset_key(fraction * h, h);
                    let z = Augmented::<1>::from_fn(|_, _| 2.0 * random.next() - 1.0);
                    let w = Filter::from_fn(|_, _| 2.0 * random.next() - 1.0);
                    let sigma = key as f64 / (1u64 << OFFSET_BITS) as f64 * h;
                    let exp = expm::precise_exp(&(m * sigma));
                    let reference = exp.fixed_rows::<6>(0) * z;
                    let got = dense.plant(key, &z);
                    // Relative to the size of the terms summed.
                    let size = scale(&(exp.fixed_rows::<6>(0).abs() * z.abs()), 1e-300);
                    worst[0] = worst[0].max((got - reference).abs().max() / size);
                    let mut big = SVector::<f64, WITH_FILTER>::zeros();
                    big.fixed_rows_mut::<AUGMENTED>(0).copy_from(&z);
                    big.fixed_rows_mut::<WK_STATES>(AUGMENTED).copy_from(&w);
                    let exp = expm::precise_exp(&(full * sigma));
                    let rows = exp.fixed_rows::<WK_STATES>(AUGMENTED);
                    let reference = rows * big;
                    let got = dense.filter(key, &z, &w, &coupling);
                    let size = scale(&(rows.abs() * big.abs()), 1e-300);
                    worst[1] = worst[1].max((got - reference).abs().max() / size);
                }
                eprintln!(
                    "{variant:?} ω = {omega} h = {h}: plant n = {} K = {}, filter n = {} K = {}",
                    dense.plant.bits,
                    dense.plant.order,
                    dense.filter.as_ref().unwrap().table.bits,
                    dense.filter.as_ref().unwrap().table.order
                );
            }
        }
        eprintln!(
            "largest relative difference: plant {:e}, filter {:e}",
            worst[0], worst[1]
        );
        assert!(worst[0] < 1e-13, "plant: {worst:?}");
        assert!(worst[1] < 1e-13, "filter: {worst:?}");
    }

    /// Configurations in every delay regime (whole steps, inside the
    /// step, folded; none), on a smooth road, a road with breakpoints
    /// inside the steps and a sampled one, with the W_k filter, and with
    /// the unilateral tire (lifting off on the harmonic road of 70 rad/s).
    fn regimes() -> Vec<(&'static str, crate::solver::SimulationConfig)> {
        use crate::model::TireContact;
        use crate::road::{RandomRoad, RoadClass, RoadSpec};
        use crate::solver::{Metrics, SimulationConfig};
        let base = SimulationConfig {
            metrics: Metrics::Comfort,
            initial_state: State::new(0.01, 0.0, 0.0, 0.0, 0.002, 0.1),
            ..SimulationConfig::default()
        };
        let iso = RoadSpec::Iso8608(RandomRoad {
            class: RoadClass::D,
            ..RandomRoad::default()
        });
        let lifting = RoadSpec::Harmonic {
            amplitude: 0.01,
            angular_frequency: 70.0,
        };
        let with = |g: f64, tau: f64, bound: f64, road: &RoadSpec| SimulationConfig {
            params: Params::with_controller(g, tau),
            max_internal_step: bound,
            road: road.clone(),
            ..base.clone()
        };
        let harmonic = RoadSpec::paper_harmonic();
        let unilateral = |config: SimulationConfig| SimulationConfig {
            tire_contact: TireContact::Unilateral,
            ..config
        };
        vec![
            ("whole steps, harmonic", with(5386.0, 2e-4, 1e-4, &harmonic)),
            ("whole steps, ISO D", with(2528.0, 0.02, 0.0, &iso)),
            (
                "inside the step, harmonic",
                with(5386.0, 2e-4, 1e-3, &harmonic),
            ),
            ("inside the step, ISO D", with(2528.0, 1.28e-4, 0.0, &iso)),
            ("folded, harmonic", with(5386.0, 5e-8, 0.0, &harmonic)),
            (
                "CS, paper road",
                SimulationConfig {
                    variant: Variant::Cs,
                    road: RoadSpec::PaperCompatible {
                        road: RandomRoad::default(),
                        sample_interval: 0.1,
                    },
                    ..base.clone()
                },
            ),
            (
                "unilateral, inside the step",
                unilateral(with(5386.0, 2e-4, 1e-3, &lifting)),
            ),
            (
                "unilateral, whole steps",
                unilateral(with(20000.0, 0.02, 0.0, &lifting)),
            ),
            (
                "unilateral, folded, ISO D",
                unilateral(with(5386.0, 5e-8, 0.0, &iso)),
            ),
        ]
    }

    /// Strictly increasing times over `duration`, most of them inside
    /// internal steps (random offsets), some a hair off a node.
    fn times(random: &mut Lcg, duration: f64) -> Vec<f64> {
        let mut t = 0.0;
        let mut out = Vec::new();
        while t < duration {
            t += match out.len() % 3 {
                0 => random.next() * 7e-3,
                1 => random.next() * 1e-4,
                _ => random.next() * 2e-6,
            } + 1e-9;
            out.push(t);
        }
        out
    }

    #[test]
    fn in_step_points_agree_with_the_full_exponential_in_every_regime() {
        use crate::solver::Simulator;
        let mut random = Lcg(21);
        for (label, config) in regimes() {
            let mut dense = Simulator::new(config.clone()).unwrap();
            let mut exact = exactly(|| Simulator::new(config.clone()).unwrap());
            let stops = times(&mut random, 0.4);
            let (mut states, mut outputs) = (Vec::new(), Vec::new());
            for &t in &stops {
                dense.advance_to(t).unwrap();
                let values = dense.outputs().core_values();
                let (x, reference) = exactly(|| {
                    exact.advance_to(t).unwrap();
                    (exact.state(), exact.outputs().core_values())
                });
                states.push((dense.state(), x));
                outputs.push((values, reference));
            }
            // Each component against the largest it reaches.
            let worst = |pairs: &[(Vec<f64>, Vec<f64>)]| {
                let n = pairs[0].0.len();
                (0..n)
                    .map(|i| {
                        let size = pairs.iter().map(|(_, r)| r[i].abs()).fold(1e-300, f64::max);
                        pairs
                            .iter()
                            .map(|(a, r)| (a[i] - r[i]).abs() / size)
                            .fold(0.0, f64::max)
                    })
                    .fold(0.0, f64::max)
            };
            let states: Vec<_> = states
                .iter()
                .map(|(a, r)| (a.as_slice().to_vec(), r.as_slice().to_vec()))
                .collect();
            let outputs: Vec<_> = outputs
                .iter()
                .map(|(a, r)| (a.to_vec(), r.to_vec()))
                .collect();
            let (state_error, output_error) = (worst(&states), worst(&outputs));
            let lift_offs = dense.outputs().road_holding.map_or(0, |h| h.lift_off_count);
            eprintln!(
                "{label}: h = {:e}, {} points, lift-offs {lift_offs}: states {state_error:e}, outputs {output_error:e}",
                dense.grid().step,
                stops.len()
            );
            if label.starts_with("unilateral") && !label.contains("ISO") {
                assert!(lift_offs > 0, "{label}: no lift-off");
            }
            assert!(state_error < 1e-12, "{label}: states {state_error:e}");
            assert!(output_error < 1e-12, "{label}: outputs {output_error:e}");
        }
    }

    #[test]
    fn in_step_points_leave_the_nodes_unchanged() {
        use crate::solver::Simulator;
        let mut random = Lcg(5);
        for (label, config) in regimes() {
            let end = 0.4 + 0.37 * random.next() * 1e-3;
            // Straight to the end, and through many points inside steps.
            let mut straight = Simulator::new(config.clone()).unwrap();
            straight.advance_to(end).unwrap();
            let mut stopping = Simulator::new(config.clone()).unwrap();
            for t in times(&mut random, end) {
                if t < end {
                    stopping.advance_to(t).unwrap();
                    stopping.outputs();
                }
            }
            stopping.advance_to(end).unwrap();
            let bits = |sim: &mut Simulator| {
                let mut v: Vec<f64> = sim.outputs().core_values().to_vec();
                v.extend(sim.committed_state.iter());
                v.push(sim.committed_time);
                v.push(sim.grid_index as f64);
                v.extend(sim.state().iter());
                v.extend(sim.rms.sums_of_squares);
                v.extend(sim.committed_filter.iter());
                v.into_iter().map(f64::to_bits).collect::<Vec<_>>()
            };
            assert_eq!(bits(&mut straight), bits(&mut stopping), "{label}");
        }
    }

    #[test]
    fn sin_cos_is_sin_and_cos_to_the_bit() {
        // The contact-loss test takes a road's value and slope from the
        // kept `sin_cos` instead of `sin` and `cos`: the same bits.
        let mut random = Lcg(3);
        for i in 0..100_000 {
            let angle = (random.next() - 0.5) * 10f64.powi(i % 12 - 3);
            let (sin, cos) = crate::math::sin_cos(angle);
            assert_eq!(sin.to_bits(), crate::math::sin(angle).to_bits(), "{angle}");
            assert_eq!(cos.to_bits(), crate::math::cos(angle).to_bits(), "{angle}");
        }
    }

    #[test]
    fn the_order_meets_the_truncation_bound() {
        for theta in [1e-6, 1e-3, 1.0 / 64.0, 1.0 / 16.0, 0.5, 2.0] {
            let k = taylor_order(theta);
            let mut term = 1.0;
            for i in 1..=k + 1 {
                term *= theta / i as f64;
            }
            assert!(
                term / (1.0 - theta / (k + 2) as f64) <= TRUNCATION,
                "{theta}"
            );
            // And the order below does not.
            if k > 1 {
                let lower = term * (k + 1) as f64 / theta;
                assert!(
                    lower / (1.0 - theta / (k + 1) as f64) > TRUNCATION,
                    "{theta}"
                );
            }
        }
    }

    #[test]
    fn balancing_bounds_the_norm_from_below_and_from_the_plain_norm() {
        let plant = Plant::new(Params::default(), Variant::Tdvass).unwrap();
        let m = augmented_matrix(&plant.a, &plant.b, &plant.e, 5.0);
        let plain = m.abs().row_sum().max();
        let balanced = balanced_norm(&m);
        // ‖D⁻¹MD‖ is at least the spectral radius and at most the plain norm.
        let radius = m
            .complex_eigenvalues()
            .iter()
            .map(|l| l.norm())
            .fold(0.0, f64::max);
        eprintln!("plain {plain:e}, balanced {balanced:e}, spectral radius {radius:e}");
        assert!(balanced <= plain && balanced >= radius * (1.0 - 1e-12));
    }

    #[test]
    fn an_entry_is_the_same_whatever_was_built_before() {
        let plant = Plant::new(Params::default(), Variant::Tdvass).unwrap();
        let (a, b, e) = (plant.a, plant.b, plant.e);
        let mut first = DenseOutput::new(&a, &b, &e, 5.0, 1e-3);
        let mut second = first.clone();
        let z = Augmented::<1>::from_fn(|i, _| (i as f64 + 1.0).sqrt());
        let keys: Vec<u64> = (0..64)
            .map(|i| (i * 0x002f_5a1c_3b9d) % (1u64 << 40))
            .collect();
        let forward: Vec<_> = keys.iter().map(|&k| first.plant(k, &z)).collect();
        let backward: Vec<_> = keys.iter().rev().map(|&k| second.plant(k, &z)).collect();
        for (f, b) in forward.iter().zip(backward.iter().rev()) {
            assert_eq!(f.map(f64::to_bits), b.map(f64::to_bits));
        }
    }
}
