//! The full car's exact step maps (Eq. (23) for the whole car): over a
//! stretch of length L in a tire mode, with every input a polynomial given
//! by its Taylor coefficients at the stretch's start,
//! `X(L) = Φ X(0) + Γ w`, both blocks from one exponential of the
//! augmented matrix (the plant, and for each input a chain
//! `w_0' = w_1, w_1' = w_2, …` whose first state drives its column),
//! computed by the 2^N algorithm of `solver::expm`, in the mirror
//! coordinates of `mirror` (states, and the inputs' coefficients: `w` is
//! given per corner and halved here).
//!
//! The maps of the lengths a run meets again (the step, the pieces of a
//! step split at the delay or at a rear wheel's road breakpoints) are kept;
//! a stretch that ends at a located switch takes its own exponential.
//!
//! Layer: the car's maps; it imports the car's `layout` and `mirror` and
//! the solver's `expm`.

use super::layout::{
    CORNERS, CarSystem, DELAY_ORDER, INPUTS, ROAD_ORDER, STATES, delay_input, road_input,
};
use super::mirror::{Pairs, mirror_matrix};
use crate::solver::expm::precise_exp_dynamic;
use nalgebra::{DMatrix, DVector};

/// Most maps kept; the oldest is replaced first.
const KEPT: usize = 64;

/// The map of a stretch: `[Φ Γ]`, `STATES × (STATES + INPUTS)`, in mirror
/// coordinates.
#[derive(Debug, Clone)]
pub(super) struct StretchMap {
    map: DMatrix<f64>,
    inputs: Pairs,
    unknowns: Pairs,
}

impl StretchMap {
    /// `[Φ Γ]` of `mode` over `length` (s).
    pub fn new(system: &CarSystem, mode: u8, length: f64) -> StretchMap {
        let size = STATES + INPUTS;
        let mut augmented = DMatrix::<f64>::zeros(size, size);
        augmented
            .view_mut((0, 0), (STATES, STATES))
            .copy_from(&system.mode_matrix(mode));
        for c in 0..CORNERS {
            let road = STATES + road_input(c);
            augmented
                .view_mut((0, road), (STATES, 1))
                .copy_from(&system.road_columns[c]);
            let delay = STATES + delay_input(c);
            augmented
                .view_mut((0, delay), (STATES, 1))
                .copy_from(&system.delay_columns[c]);
            for p in 0..ROAD_ORDER - 1 {
                augmented[(road + p, road + p + 1)] = 1.0;
            }
            for p in 0..DELAY_ORDER - 1 {
                augmented[(delay + p, delay + p + 1)] = 1.0;
            }
        }
        let pairs = Pairs::augmented();
        let mirrored = mirror_matrix(&augmented, &pairs, &pairs);
        let exponential = precise_exp_dynamic(&(mirrored * length));
        StretchMap {
            map: exponential.rows(0, STATES).into_owned(),
            inputs: Pairs::inputs(),
            unknowns: Pairs::unknowns(),
        }
    }

    /// `Φ y + Γ w`: `y` in mirror coordinates, `w` per corner.
    pub fn apply(&self, y: &DVector<f64>, w: &DVector<f64>) -> DVector<f64> {
        self.map.columns(0, STATES) * y + self.map.columns(STATES, INPUTS) * self.inputs.halved(w)
    }

    /// `Φ m + Γ n` for the columns of `m` (states, in mirror coordinates,
    /// per mirrored unknown) and `n` (inputs per corner, per unknown
    /// end-node wheel state).
    pub fn apply_columns(&self, m: &DMatrix<f64>, n: &DMatrix<f64>) -> DMatrix<f64> {
        self.map.columns(0, STATES) * m
            + self.map.columns(STATES, INPUTS) * mirror_matrix(n, &self.inputs, &self.unknowns)
    }
}

/// The maps kept, by mode and length.
#[derive(Debug, Clone, Default)]
pub(super) struct Maps {
    kept: Vec<(u8, i64, StretchMap)>,
    next: usize,
}

impl Maps {
    /// The map of `mode` over `length`, with `step` the grid's step: one
    /// kept for a length within 1e-12 h of it, else made and kept.
    pub fn get(&mut self, system: &CarSystem, mode: u8, length: f64, step: f64) -> &StretchMap {
        let key = (length / step * 1e12).round() as i64;
        let found = self
            .kept
            .iter()
            .position(|(m, k, _)| *m == mode && *k == key);
        let index = match found {
            Some(index) => index,
            None => {
                let map = StretchMap::new(system, mode, length);
                if self.kept.len() < KEPT {
                    self.kept.push((mode, key, map));
                    self.kept.len() - 1
                } else {
                    let index = self.next;
                    self.kept[index] = (mode, key, map);
                    self.next = (self.next + 1) % KEPT;
                    index
                }
            }
        };
        &self.kept[index].2
    }
}
