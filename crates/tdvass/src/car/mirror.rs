//! The car in mirror coordinates: each coordinate of a left corner and its
//! right twin's (a state, a coefficient of an input, an unknown end-node
//! wheel state) as their half-sum and half-difference,
//! `s = (x_l + x_r) / 2` in the left one's place and
//! `d = (x_l − x_r) / 2` in the right one's, so that `x_l = s + d` and
//! `x_r = s − d`. The chassis's coordinates, the W_k filter's and the
//! exosystem's stay as they are.
//!
//! **Why.** When the right half of the car mirrors the left (the same
//! corners, the same road on both tracks, the tracks centred) the
//! differences, the roll and its rate form a block that nothing else
//! drives: in these coordinates every matrix of the car has exact zeros
//! around it, which the exponential's products and sums keep, and the
//! inputs of that block are differences of equal numbers, exactly zero.
//! Started at rest, the block stays exactly zero and the left and right
//! corners are equal to the bit. In the corners' own coordinates the
//! rounding of a matrix product differs from a left row to its right
//! twin; a landing that grazes the road turns such a difference into a
//! lift-off on one side only, and the car rolls on a road that cannot
//! roll it.
//!
//! Layer: the car's system (beside `layout`, whose indices it pairs).

use super::layout::{
    CORNERS, CarSystem, DELAY_ORDER, INPUTS, ROAD_ORDER, STATES, delay_input, road_input, slot,
};
use crate::model::{V_T, X_H};
use nalgebra::{DMatrix, DVector, RowDVector};

/// The left corners and their right twins: (fl, fr) and (rl, rr).
const TWINS: [(usize, usize); 2] = [(0, 1), (2, 3)];
/// The unknown end-node wheel states of a corner (`x_t`, `v_t`).
const WHEEL_UNKNOWNS: usize = 2;

/// Corner `c`'s pair (left, right) and whether `c` is the left one.
fn twin(c: usize) -> (usize, usize, bool) {
    let (left, right) = TWINS[c / 2];
    (left, right, c == left)
}

/// Pairs of indices (left, right) of one space: the left one holds the
/// half-sum, the right one the half-difference.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Pairs(Vec<(usize, usize)>);

impl Pairs {
    /// The car's states: each corner's `[x_h, v_h, x_t, v_t]`.
    pub fn states() -> Pairs {
        Pairs(
            TWINS
                .iter()
                .flat_map(|&(l, r)| (X_H..=V_T).map(move |k| (slot(l, k), slot(r, k))))
                .collect(),
        )
    }

    /// The inputs' coefficients: each corner's road and delayed input.
    pub fn inputs() -> Pairs {
        Pairs(
            TWINS
                .iter()
                .flat_map(|&(l, r)| {
                    let road = (0..ROAD_ORDER).map(move |p| (road_input(l) + p, road_input(r) + p));
                    let delay =
                        (0..DELAY_ORDER).map(move |p| (delay_input(l) + p, delay_input(r) + p));
                    road.chain(delay)
                })
                .collect(),
        )
    }

    /// The unknown end-node wheel states (`2 c`, `2 c + 1` of corner c).
    pub fn unknowns() -> Pairs {
        Pairs(
            TWINS
                .iter()
                .flat_map(|&(l, r)| {
                    (0..WHEEL_UNKNOWNS)
                        .map(move |k| (WHEEL_UNKNOWNS * l + k, WHEEL_UNKNOWNS * r + k))
                })
                .collect(),
        )
    }

    /// The augmented space of the step maps: the states, then the inputs'
    /// coefficients.
    pub fn augmented() -> Pairs {
        let mut pairs = Pairs::states().0;
        pairs.extend(
            Pairs::inputs()
                .0
                .into_iter()
                .map(|(l, r)| (STATES + l, STATES + r)),
        );
        Pairs(pairs)
    }

    /// A vector into mirror coordinates: `(v_l, v_r) → ((v_l + v_r)/2,
    /// (v_l − v_r)/2)`.
    pub fn halve(&self, v: &mut [f64]) {
        for &(l, r) in &self.0 {
            let (a, b) = (v[l], v[r]);
            v[l] = (a + b) / 2.0;
            v[r] = (a - b) / 2.0;
        }
    }

    /// A vector back from mirror coordinates: `(s, d) → (s + d, s − d)`.
    pub fn restore(&self, v: &mut [f64]) {
        for &(l, r) in &self.0 {
            let (s, d) = (v[l], v[r]);
            v[l] = s + d;
            v[r] = s - d;
        }
    }

    /// A row that acts on this space's vectors, for mirror coordinates:
    /// `(r_l, r_r) → (r_l + r_r, r_l − r_r)`, so that `r' · v' = r · v`.
    pub fn pair_up(&self, r: &mut [f64]) {
        for &(l, r_) in &self.0 {
            let (a, b) = (r[l], r[r_]);
            r[l] = a + b;
            r[r_] = a - b;
        }
    }

    /// A vector into mirror coordinates, as a new vector.
    pub fn halved(&self, v: &DVector<f64>) -> DVector<f64> {
        let mut out = v.clone();
        self.halve(out.as_mut_slice());
        out
    }

    /// A vector back from mirror coordinates, as a new vector.
    pub fn restored(&self, v: &DVector<f64>) -> DVector<f64> {
        let mut out = v.clone();
        self.restore(out.as_mut_slice());
        out
    }

    /// A row for mirror coordinates, as a new row.
    pub fn paired(&self, r: &RowDVector<f64>) -> RowDVector<f64> {
        let mut out = r.clone();
        self.pair_up(out.as_mut_slice());
        out
    }
}

/// `m` from `from`'s space into `to`'s, in mirror coordinates: its
/// columns halved by `to`'s pairs, its rows paired up by `from`'s.
pub(super) fn mirror_matrix(m: &DMatrix<f64>, to: &Pairs, from: &Pairs) -> DMatrix<f64> {
    let mut out = m.clone();
    for mut column in out.column_iter_mut() {
        to.halve(column.as_mut_slice());
    }
    for &(l, r) in &from.0 {
        for i in 0..out.nrows() {
            let (a, b) = (out[(i, l)], out[(i, r)]);
            out[(i, l)] = a + b;
            out[(i, r)] = a - b;
        }
    }
    out
}

/// The car's rows and input columns in mirror coordinates.
#[derive(Debug, Clone)]
pub(super) struct Mirrored {
    /// The pairs of the states.
    pub states: Pairs,
    /// The pairs of the inputs' coefficients.
    pub inputs: Pairs,
    /// The pairs of the unknown end-node wheel states.
    pub unknowns: Pairs,
    /// The road and delayed-input columns, one per input coefficient
    /// (the value's; the higher coefficients' are zero).
    pub input_columns: DMatrix<f64>,
    /// SDD of each corner.
    pub deflection_rows: [RowDVector<f64>; CORNERS],
    /// `[z'', θ'', φ'']`.
    pub acceleration_rows: [RowDVector<f64>; 3],
    /// The seat's vertical acceleration.
    pub seat_row: RowDVector<f64>,
    /// a_w at the seat.
    pub weighted_row: RowDVector<f64>,
}

impl Mirrored {
    /// The rows and columns of `system`.
    pub fn new(system: &CarSystem) -> Mirrored {
        let states = Pairs::states();
        let inputs = Pairs::inputs();
        let mut columns = DMatrix::<f64>::zeros(STATES, INPUTS);
        for c in 0..CORNERS {
            columns.set_column(road_input(c), &system.road_columns[c]);
            columns.set_column(delay_input(c), &system.delay_columns[c]);
        }
        Mirrored {
            input_columns: mirror_matrix(&columns, &states, &inputs),
            deflection_rows: std::array::from_fn(|c| states.paired(&system.deflection_rows[c])),
            acceleration_rows: std::array::from_fn(|i| states.paired(&system.acceleration_rows[i])),
            seat_row: states.paired(&system.seat_row),
            weighted_row: states.paired(&system.weighted_row),
            states,
            inputs,
            unknowns: Pairs::unknowns(),
        }
    }
}

/// Corner c's local coordinate `local` (`X_H` … `V_T`) in its own terms,
/// from the car's state `y` in mirror coordinates.
pub(super) fn corner_value(y: &DVector<f64>, c: usize, local: usize) -> f64 {
    let (left, right, is_left) = twin(c);
    let (s, d) = (y[slot(left, local)], y[slot(right, local)]);
    if is_left { s + d } else { s - d }
}

/// The car's state in the corners' own coordinates.
pub(super) fn corner_coordinates(y: &DVector<f64>) -> DVector<f64> {
    let mut x = y.clone();
    for c in 0..CORNERS {
        for local in X_H..=V_T {
            x[slot(c, local)] = corner_value(y, c, local);
        }
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn halving_and_pairing_keep_a_row_times_a_vector() {
        let pairs = Pairs::states();
        let v = DVector::from_fn(STATES, |i, _| (i as f64).sin());
        let r = RowDVector::from_fn(STATES, |_, j| (j as f64 * 0.7).cos());
        let before = (&r * &v)[0];
        let after = (pairs.paired(&r) * pairs.halved(&v))[0];
        assert!((before - after).abs() <= 1e-14 * before.abs());
        let back = corner_coordinates(&pairs.halved(&v));
        assert!((back - v).amax() <= 1e-15);
    }

    #[test]
    fn equal_twins_leave_exact_zeros() {
        let pairs = Pairs::states();
        let mut v = DVector::from_fn(STATES, |i, _| (i as f64).sqrt());
        for &(l, r) in &pairs.0 {
            v[r] = v[l];
        }
        let y = pairs.halved(&v);
        assert!(pairs.0.iter().all(|&(_, r)| y[r] == 0.0));
        for c in 0..CORNERS {
            assert_eq!(corner_value(&y, c, V_T), v[slot(c, V_T)]);
        }
    }
}
