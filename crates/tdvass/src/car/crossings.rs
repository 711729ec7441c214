//! Where a switch function crosses zero inside a stretch, from its cubic
//! Hermite interpolant through the values and rates at the stretch's ends
//! (`model::dynamics::hermite`): the first crossing in a direction (which
//! brackets a unilateral tire's switch before Newton's method refines it
//! on the exact partial step) and the time below zero with the number of
//! downward crossings (the bilateral tire's loss of contact).
//!
//! Layer: the car's maps (beside `maps`); it imports the model's
//! `dynamics`.

use crate::model::dynamics::hermite;

/// The first offset in `(0, length]` where the cubic Hermite interpolant
/// through `a = [p, p']` at 0 and `b` at `length` crosses zero downwards
/// (`falling`: from `>= 0` to `< 0`) or upwards.
pub(super) fn first_crossing(length: f64, a: [f64; 2], b: [f64; 2], falling: bool) -> Option<f64> {
    let sign = if falling { 1.0 } else { -1.0 };
    let (a, b) = ([sign * a[0] + 0.0, sign * a[1]], [sign * b[0], sign * b[1]]);
    // Now a crossing is from >= 0 to < 0.
    pieces(length, a, b).windows(2).find_map(|w| {
        let (u0, u1) = (w[0], w[1]);
        let (p0, p1) = (cubic(length, a, b, u0), cubic(length, a, b, u1));
        (u1 > 1e-9 * length && p0 >= 0.0 && p1 < 0.0)
            .then(|| bisect(length, a, b, u0.max(1e-9 * length), u1))
    })
}

/// The time below zero in `[0, length]` of the cubic Hermite interpolant
/// through `a`, `b`, and the number of downward crossings.
pub(super) fn below_zero(length: f64, a: [f64; 2], b: [f64; 2]) -> (f64, u64) {
    let cuts = pieces(length, a, b);
    let mut roots = vec![0.0];
    let mut downs = 0;
    for w in cuts.windows(2) {
        let (p0, p1) = (cubic(length, a, b, w[0]), cubic(length, a, b, w[1]));
        if (p0 >= 0.0) != (p1 >= 0.0) {
            roots.push(bisect(length, a, b, w[0], w[1]));
            downs += u64::from(p0 >= 0.0);
        }
    }
    roots.push(length);
    let below = roots
        .windows(2)
        .filter(|w| cubic(length, a, b, 0.5 * (w[0] + w[1])) < 0.0)
        .map(|w| w[1] - w[0])
        .sum();
    (below, downs)
}

/// The interpolant's monotone pieces: 0, its critical points inside, length.
fn pieces(length: f64, a: [f64; 2], b: [f64; 2]) -> Vec<f64> {
    let (p0, d0, p1, d1) = (a[0], a[1] * length, b[0], b[1] * length);
    let c2 = 3.0 * (p1 - p0) - 2.0 * d0 - d1;
    let c3 = 2.0 * (p0 - p1) + d0 + d1;
    // p'(u) = d0 + 2 c2 u + 3 c3 u² on [0, 1].
    let (qa, qb, qc) = (3.0 * c3, 2.0 * c2, d0);
    let mut points = vec![0.0, length];
    if qa.abs() > 0.0 {
        let disc = qb * qb - 4.0 * qa * qc;
        if disc >= 0.0 {
            let root = disc.sqrt();
            for u in [(-qb - root) / (2.0 * qa), (-qb + root) / (2.0 * qa)] {
                if u > 0.0 && u < 1.0 {
                    points.push(u * length);
                }
            }
        }
    } else if qb.abs() > 0.0 {
        let u = -qc / qb;
        if u > 0.0 && u < 1.0 {
            points.push(u * length);
        }
    }
    points.sort_by(f64::total_cmp);
    points
}

/// The interpolant at `s` in `[0, length]`.
fn cubic(length: f64, a: [f64; 2], b: [f64; 2], s: f64) -> f64 {
    hermite([a[0], a[1], b[0], b[1]], length, s)[0]
}

/// The root of the interpolant between `lo` (`>= 0`) and `hi` (`< 0`),
/// or the other way round, by bisection.
fn bisect(length: f64, a: [f64; 2], b: [f64; 2], mut lo: f64, mut hi: f64) -> f64 {
    let lo_sign = cubic(length, a, b, lo) >= 0.0;
    for _ in 0..80 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if (cubic(length, a, b, mid) >= 0.0) == lo_sign {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
}
