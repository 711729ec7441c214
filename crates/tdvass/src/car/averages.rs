//! The full car's time averages: the integrals of the squared outputs
//! by the quarter car's corrected trapezoid over each piece,
//! `∫_a^b f = (b − a)/2 (f_a + f_b) − (b − a)²/12 (f'_b − f'_a)`, the
//! largest |SDD| on each piece's cubic Hermite interpolant, and each
//! tire's contact: its flight time, or with the bilateral tire the time
//! below zero and the downward crossings of its contact margin.
//!
//! The groups of averages (each corner's, the chassis's) end their pieces
//! apart: a corner's at its own road breakpoints and switches, the
//! chassis's at every corner's, all at the step's end.
//!
//! Layer: the car's maps (beside `crossings`, whose `below_zero` it uses);
//! it imports the car's `layout` and the solver's `largest_magnitude`.

use super::crossings::below_zero;
use super::layout::CORNERS;
use crate::solver::largest_magnitude;

/// The integrals kept: `SDD²` and `TDD²` of each corner, the squares of
/// `z''`, `θ''`, `φ''`, and `a_w²`, `a_w⁴`.
pub(super) const INTEGRALS: usize = 2 * CORNERS + 3 + 2;
/// Index of `∫ SDD²` of corner 0 (then `TDD²` at `CORNERS`, the
/// accelerations at `2 CORNERS`).
pub(super) const DEFLECTION: usize = 0;
pub(super) const TIRE: usize = CORNERS;
pub(super) const ACCELERATION: usize = 2 * CORNERS;
pub(super) const WEIGHTED_SQUARE: usize = 2 * CORNERS + 3;
const WEIGHTED_FOURTH: usize = 2 * CORNERS + 4;
/// The groups of time averages: each corner's, then the chassis's.
pub(super) const GROUPS: usize = CORNERS + 1;
/// The chassis's group.
pub(super) const CHASSIS_GROUP: usize = CORNERS;
/// Every group's bit.
pub(super) const ALL_GROUPS: u8 = (1 << GROUPS) - 1;

/// What a run accumulates.
#[derive(Debug, Clone, Default)]
pub(super) struct Accumulated {
    /// The integrals ([`INTEGRALS`]).
    pub integrals: [f64; INTEGRALS],
    /// The largest |SDD| of each corner (m).
    pub max_deflection: [f64; CORNERS],
    /// The time each tire had no contact (s).
    pub loss_time: [f64; CORNERS],
    /// Each tire's lift-offs.
    pub lift_offs: [u64; CORNERS],
}

impl Accumulated {
    /// `∫ SDD²` of corner c.
    pub fn deflection(&self, c: usize) -> f64 {
        self.integrals[DEFLECTION + c]
    }
    /// `∫ TDD²` of corner c.
    pub fn tire(&self, c: usize) -> f64 {
        self.integrals[TIRE + c]
    }
    /// `∫` of the square of the chassis's acceleration i (heave, pitch, roll).
    pub fn acceleration(&self, i: usize) -> f64 {
        self.integrals[ACCELERATION + i]
    }
    /// `∫ a_w²` and `∫ a_w⁴`.
    pub fn weighted(&self) -> (f64, f64) {
        (
            self.integrals[WEIGHTED_SQUARE],
            self.integrals[WEIGHTED_FOURTH],
        )
    }

    /// Adds a piece of `length` between the points `a` and `b` to the
    /// time averages of `group` (a corner's SDD², TDD², largest |SDD| and
    /// contact, the tire meeting the road as `contact` says; the
    /// chassis's accelerations and a_w).
    pub fn add(&mut self, group: usize, length: f64, a: &Point, b: &Point, contact: Contact) {
        let acc = self;
        let trapezoid = |f: [f64; 2], g: [f64; 2]| {
            length / 2.0 * (f[0] + g[0]) - length * length / 12.0 * (g[1] - f[1])
        };
        let square = |p: &Point, i: usize| [p.value[i] * p.value[i], 2.0 * p.value[i] * p.rate[i]];
        if group == CHASSIS_GROUP {
            for i in ACCELERATION..WEIGHTED_SQUARE + 1 {
                acc.integrals[i] += trapezoid(square(a, i), square(b, i));
            }
            let fourth = |p: &Point| {
                let y = p.value[WEIGHTED_SQUARE];
                [y * y * y * y, 4.0 * y * y * y * p.rate[WEIGHTED_SQUARE]]
            };
            acc.integrals[WEIGHTED_FOURTH] += trapezoid(fourth(a), fourth(b));
            return;
        }
        let c = group;
        for i in [DEFLECTION + c, TIRE + c] {
            acc.integrals[i] += trapezoid(square(a, i), square(b, i));
        }
        let i = DEFLECTION + c;
        let largest = largest_magnitude(length, [a.value[i], a.rate[i]], [b.value[i], b.rate[i]]);
        acc.max_deflection[c] = acc.max_deflection[c].max(largest);
        match contact {
            Contact::Flight => acc.loss_time[c] += length,
            Contact::Bilateral => {
                let (below, downs) = below_zero(length, a.margin[c], b.margin[c]);
                acc.loss_time[c] += below;
                acc.lift_offs[c] += downs;
            }
            Contact::Ground | Contact::None => {}
        }
    }
}

/// The outputs the integrals need at an instant, with their rates.
#[derive(Debug, Clone, Copy)]
pub(super) struct Point {
    /// The integrands' outputs y: SDD, TDD of each corner, the three
    /// accelerations, a_w.
    pub value: [f64; INTEGRALS - 1],
    pub rate: [f64; INTEGRALS - 1],
    /// Each corner's contact margin and its rate.
    pub margin: [[f64; 2]; CORNERS],
}

/// How a corner's tire meets the road over a piece.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Contact {
    /// The unilateral tire on the road.
    Ground,
    /// The unilateral tire in flight: the piece is flight time.
    Flight,
    /// The bilateral tire: its margin's time below zero is measured.
    Bilateral,
    /// Not a corner (the chassis's group).
    None,
}
