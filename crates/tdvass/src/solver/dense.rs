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
//! (at the first point inside a step, so a simulator that never stops
//! inside a step, as in the PSO, never builds it; or, for the FMUs, when
//! the run starts: `Simulator::reserve`, so that stepping allocates
//! nothing) and `y` is the
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
//!
//! Layer: grid and dense steps (docs/architecture.md); it imports the
//! solver's `expm`, `linalg`, `system` and the crate's `comfort`, `model`,
//! `road`.

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

/// A table entry not built yet.
const NOT_BUILT: u32 = u32::MAX;
/// Tables of at most this many entries are filled when reserved
/// ([`DenseOutput::reserve`]); 257 is n = 8.
const FILLED_ENTRIES: usize = 257;

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
    /// Where `T_j`'s kept rows are in `built` (j = 0 … 2^n; `NOT_BUILT`
    /// until built; `T_0 = 0` is never stored).
    slots: Vec<u32>,
    /// The kept rows of the entries built, in the order built. Room for
    /// every entry is reserved with the table (not written), so building
    /// one later allocates nothing.
    built: Vec<SMatrix<f64, R, D>>,
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
            slots: vec![NOT_BUILT; (1 << bits) + 1],
            built: Vec::with_capacity((1 << bits) + 1),
        }
    }

    /// The kept rows of `T_j` if built.
    #[inline]
    fn built_entry(&self, j: usize) -> Option<&SMatrix<f64, R, D>> {
        match self.slots[j] {
            NOT_BUILT => None,
            slot => Some(&self.built[slot as usize]),
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
        if self.slots[j] == NOT_BUILT {
            let mut prefix = 0usize;
            for bit in 0..=self.bits as usize {
                if (j >> bit) & 1 == 0 {
                    continue;
                }
                let next = prefix | (1 << bit);
                if self.slots[next] == NOT_BUILT {
                    let ladder = &self.ladder[bit];
                    let rows = ladder.fixed_rows::<R>(self.first_row).into_owned();
                    let value = match self.built_entry(prefix) {
                        Some(before) => before + rows + before * ladder,
                        None => rows,
                    };
                    // At most 2^n + 1 entries: within the reserved room.
                    self.slots[next] = self.built.len() as u32;
                    self.built.push(value);
                }
                prefix = next;
            }
        }
        self.built_entry(j).expect("built above")
    }

    /// Builds every entry now when the table has at most
    /// [`FILLED_ENTRIES`] (n ≤ 8), so that no later point pays for one;
    /// larger tables keep building theirs at first use.
    fn fill(&mut self) {
        let count = (1usize << self.bits) + 1;
        if count <= FILLED_ENTRIES {
            for j in 1..count {
                self.entry(j);
            }
        }
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

    /// Builds now what a point inside a step would build at first use:
    /// every entry of the plant's table and, with `coupling` (the W_k
    /// filter), the filter's table and its entries (for tables of at most
    /// [`FILLED_ENTRIES`] entries). The entries depend on j alone, so the
    /// results are the same to the bit.
    pub(super) fn reserve(&mut self, coupling: Option<&FilterCoupling>) {
        self.plant.fill();
        if let Some(c) = coupling {
            self.reserve_filter(c);
            if let Some(f) = self.filter.as_mut() {
                f.table.fill();
            }
        }
    }

    /// Builds the filter's table now (once), for the coupling `coupling`.
    fn reserve_filter(&mut self, coupling: &FilterCoupling) {
        if self.filter.is_none() {
            let m = augmented_matrix(&self.a, &self.b, &self.e, self.angular_frequency);
            let full = with_filter_matrix(&m, coupling);
            self.filter = Some(FilterTable {
                rows: full.fixed_rows::<WK_STATES>(AUGMENTED).into_owned(),
                table: Table::new(&full, self.h, AUGMENTED),
            });
        }
    }

    /// The W_k filter's rows of `e^{M_w σ} [z; w]` (M_w the 22-dimensional
    /// matrix of [`super::system`]).
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
        self.reserve_filter(coupling);
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

#[cfg(test)]
pub(super) mod tests;
