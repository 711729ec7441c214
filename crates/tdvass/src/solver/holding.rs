//! Road holding and working space, kept for every run: the time without
//! tire contact and the largest suspension deflection.
//!
//! **Contact loss.** The dynamic tire load is `F = k_t (x_g − x_t) =
//! −k_t TDD` (N; there is no tire damping). The tire would leave the road
//! where `F < −W`, W the static load ([`crate::model::Params::static_load`]),
//! that is where the margin `g = W/k_t − TDD` (m) is negative. Over each
//! step (or piece of a step between road breakpoints) of length L, g is
//! represented by its cubic Hermite interpolant through the exact values
//! and rates `g' = x_g' − v_t` at both ends (the interpolant the solver
//! itself uses for the delayed `x_t`); its error is below
//! `L⁴ max|g''''| / 384`, some 1e-14 m at L = 1e-4 s for a 20 Hz wheel hop
//! of 0.1 m. The time with `g < 0` is the measure of the set where that
//! cubic is negative, its roots found by bisection on its monotone pieces:
//! crossings are located inside the steps, not counted at the nodes.
//!
//! For the cubic p on `[0, L]`,
//! `min(g_0, g_1) − 4/27 L (|g'_0| + |g'_1|) <= p <= max(g_0, g_1) + 4/27 L (|g'_0| + |g'_1|)`,
//! so the whole-step loop decides most steps from the node values alone
//! ([`check_step`]): in contact, or without contact for the whole step;
//! only a step near a crossing goes to [`below_zero`].
//!
//! **Working space.** The largest |SDD| = |x_s − x_t|, located inside the
//! steps as the crossings are: over each step (or piece) SDD is represented
//! by its cubic Hermite interpolant through the exact values and rates
//! `SDD' = v_s − v_t` at both ends, whose error is below
//! `L⁴ max|SDD⁗| / 384` (within the tolerance that set the step; see
//! `accuracy`). The same bound as for the margin,
//! `|p| <= max(|s_0|, |s_1|) + 4/27 L (|s'_0| + |s'_1|)`, lets the
//! whole-step loop skip every step that cannot raise the maximum; the
//! others go to [`largest_magnitude`], which evaluates the cubic at its
//! critical points. The committed points and the current time enter
//! exactly.
//!
//! The accumulators are functions of the node index alone (a whole step's
//! lost time is counted as one step, its length added at read-out), so
//! they do not depend on how a run is split.
//!
//! Layer: system (docs/architecture.md); it imports the crate's `bytes`,
//! `error`, `model`.

use crate::bytes::{ByteReader, ByteWriter};
use crate::error::Result;
use crate::model::{V_S, V_T, X_S, X_T};

/// The bound factor 4/27 of the module documentation, rounded up.
const HERMITE_BOUND: f64 = 0.15;

/// Bisection steps on a monotone piece of the cubic (2^-60 of a step).
const BISECTIONS: usize = 60;

/// What the run has accumulated for road holding and working space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Holding {
    /// Largest |SDD| over the committed points (m).
    pub max_deflection: f64,
    /// Whole grid steps without contact (each lasts h).
    pub lost_steps: u64,
    /// Time without contact in the other steps and pieces (s).
    pub lost_time: f64,
    /// Time at which the contact was first lost (s).
    pub first_loss: Option<f64>,
    /// Lift-offs so far: with the bilateral tire the down-crossings of the
    /// margin through 0 (located on its cubic), with the unilateral tire
    /// the switches to flight (see `solver::contact`).
    pub lift_offs: u64,
}

impl Holding {
    /// Writes the accumulators.
    pub(super) fn write(&self, w: &mut ByteWriter) {
        w.f64(self.max_deflection);
        w.u64(self.lost_steps);
        w.f64(self.lost_time);
        w.optional_f64(self.first_loss);
        w.u64(self.lift_offs);
    }

    /// Reads what [`Holding::write`] wrote (checked against the run by
    /// the caller).
    pub(super) fn read(r: &mut ByteReader) -> Result<Holding> {
        Ok(Holding {
            max_deflection: r.f64()?,
            lost_steps: r.u64()?,
            lost_time: r.f64()?,
            first_loss: r.optional_f64("first contact loss")?,
            lift_offs: r.u64()?,
        })
    }

    /// At the start of a run, state with suspension deflection `sdd` and
    /// margin `margin` (negative: no contact from the start, at `start`).
    pub fn new(sdd: f64, margin: f64, start: f64) -> Holding {
        Holding {
            max_deflection: sdd.abs(),
            lost_steps: 0,
            lost_time: 0.0,
            first_loss: (margin < 0.0).then_some(start),
            lift_offs: u64::from(margin < 0.0),
        }
    }

    /// Adds the node (or committed point) with state x.
    #[inline(always)]
    pub fn add_node(&mut self, x: &[f64; 6]) {
        self.max_deflection = self.max_deflection.max((x[X_S] - x[X_T]).abs());
    }

    /// Adds a step or piece of length `length` (s) with the deflections
    /// `[SDD, SDD']` at its ends ([`deflection`]) to the largest |SDD|.
    #[inline(always)]
    pub fn add_deflection(&mut self, length: f64, a: [f64; 2], b: [f64; 2]) {
        let bound = a[0].abs().max(b[0].abs()) + HERMITE_BOUND * length * (a[1].abs() + b[1].abs());
        if bound > self.max_deflection {
            self.max_deflection = self.max_deflection.max(largest_magnitude(length, a, b));
        }
    }

    /// Adds an interval starting at `start` (s), of length `length` (s),
    /// with the margins `[g, g']` at its ends.
    pub fn add_interval(&mut self, start: f64, length: f64, a: [f64; 2], b: [f64; 2]) {
        if a[0].min(b[0]) >= HERMITE_BOUND * length.abs() * (a[1].abs() + b[1].abs()) {
            // In contact throughout (the test of [`check_step`]).
            return;
        }
        let below = below_zero(length, a, b);
        self.lost_time += below.time;
        self.lift_offs += below.entries;
        if let (None, Some(offset)) = (self.first_loss, below.first) {
            self.first_loss = Some(start + offset);
        }
    }
}

/// Whether the cubic through the margins `a` and `b` (`[g, g']` at the
/// ends of an interval of length `length`) may be negative somewhere: the
/// test of [`check_step`].
#[inline]
pub(crate) fn may_lose_contact(length: f64, a: [f64; 2], b: [f64; 2]) -> bool {
    a[0].min(b[0]) < HERMITE_BOUND * length * (a[1].abs() + b[1].abs())
}

/// A sufficient condition for `!may_lose_contact(length, a, b)` from a
/// lower bound `lower` of `min(a[0], b[0])` and an upper bound `rates` of
/// `|a[1]| + |b[1]|` (the factor `1 + 1e-9` covers the rounding of the
/// test itself).
#[inline]
pub(crate) fn keeps_contact(length: f64, lower: f64, rates: f64) -> bool {
    lower > HERMITE_BOUND * length * rates * (1.0 + 1e-9)
}

/// `[SDD, SDD']` = `[x_s − x_t, v_s − v_t]` (m, m/s) at state x.
#[inline(always)]
pub(crate) fn deflection(x: &[f64; 6]) -> [f64; 2] {
    [x[X_S] - x[X_T], x[V_S] - x[V_T]]
}

/// The largest |p| over `[0, length]` for the cubic Hermite interpolant p
/// through `a = [p_0, p'_0]` at 0 and `b = [p_1, p'_1]` at `length`: the
/// ends and the critical points inside (0 for a length that is not
/// positive, besides the ends).
#[cold]
#[inline(never)]
pub(crate) fn largest_magnitude(length: f64, a: [f64; 2], b: [f64; 2]) -> f64 {
    let ends = a[0].abs().max(b[0].abs());
    if length.is_nan() || length <= 0.0 {
        return ends;
    }
    let (p0, d0, p1, d1) = (a[0], a[1] * length, b[0], b[1] * length);
    let c2 = 3.0 * (p1 - p0) - 2.0 * d0 - d1;
    let c3 = 2.0 * (p0 - p1) + d0 + d1;
    let p = |s: f64| {
        let r = 1.0 - s;
        p0 * ((1.0 + 2.0 * s) * r * r) + p1 * (s * s * (3.0 - 2.0 * s)) + d0 * (s * r * r)
            - d1 * (s * s * r)
    };
    quadratic_roots(3.0 * c3, 2.0 * c2, d0)
        .as_slice()
        .iter()
        .copied()
        .filter(|s| *s > 0.0 && *s < 1.0)
        .map(|s| p(s).abs())
        .fold(ends, f64::max)
}

/// What the whole-step loop needs to count its steps' loss of contact
/// (the tire's side, [`crate::model::dynamics::Switching::side`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ContactCheck {
    /// ω of the harmonic road (rad/s; 0 for the other roads).
    pub angular_frequency: f64,
    /// t_0 (s): node k lies at `t_0 + k h`.
    pub start_time: f64,
    /// h (s).
    pub step: f64,
}

/// Whether a switch function `φ` may fall through 0 in a step of length
/// `h` from `a = [φ, φ']` to `b`: the whole-step loop's test of every
/// switching element, which stops the loop before such a step
/// ([`super::kernel::SegmentEnd::Switch`]). Its cubic cannot be negative
/// (the common case, decided inline), or it is negative nowhere inside by
/// [`below_zero`]: no; else yes. For the tire in contact it is the
/// step's loss of contact by [`check_step`].
#[inline(always)]
pub(crate) fn may_fall_through_zero(h: f64, a: [f64; 2], b: [f64; 2]) -> bool {
    let slack = HERMITE_BOUND * h * (a[1].abs() + b[1].abs());
    a[0].min(b[0]) < slack && negative_in_step(h, a, b, slack)
}

/// Whether the cubic of [`may_fall_through_zero`] is negative in the step:
/// throughout (both ends below `−slack`), or somewhere by [`below_zero`].
#[cold]
#[inline(never)]
fn negative_in_step(h: f64, a: [f64; 2], b: [f64; 2], slack: f64) -> bool {
    a[0].max(b[0]) < -slack || below_zero(h, a, b).first.is_some()
}

/// The whole-step loop's test of the step from node k (margins a) to node
/// k + 1 (margins b): `None` when the cubic cannot be negative (the common
/// case, decided inline), else what the step adds, from
/// [`step_without_contact`].
#[inline(always)]
pub(crate) fn check_step(
    check: ContactCheck,
    k: u64,
    a: [f64; 2],
    b: [f64; 2],
) -> Option<StepLoss> {
    let slack = HERMITE_BOUND * check.step * (a[1].abs() + b[1].abs());
    if a[0].min(b[0]) < slack {
        Some(step_without_contact(check, k, a, b, slack))
    } else {
        None
    }
}

/// What one step adds to the time without contact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct StepLoss {
    /// The whole step (one lost step), or a part of it.
    pub whole: bool,
    /// The part's length (s) when not the whole step.
    pub time: f64,
    /// When the contact is lost first in the step (s).
    pub first: Option<f64>,
    /// How often it is lost in the step ([`BelowZero::entries`]).
    pub entries: u64,
}

impl Holding {
    /// Adds what a step without contact (in part) contributes.
    #[inline]
    pub fn add_step(&mut self, loss: StepLoss) {
        if loss.whole {
            self.lost_steps += 1;
        } else {
            self.lost_time += loss.time;
        }
        self.lift_offs += loss.entries;
        if let (None, Some(first)) = (self.first_loss, loss.first) {
            self.first_loss = Some(first);
        }
    }
}

/// A step near a crossing, or without contact throughout: one lost step
/// when the cubic cannot be positive, else the measure of
/// [`below_zero`].
#[cold]
#[inline(never)]
fn step_without_contact(
    check: ContactCheck,
    k: u64,
    a: [f64; 2],
    b: [f64; 2],
    slack: f64,
) -> StepLoss {
    let (h, t_k) = (check.step, check.start_time + k as f64 * check.step);
    if a[0].max(b[0]) < -slack {
        StepLoss {
            whole: true,
            time: 0.0,
            first: Some(t_k),
            entries: 0,
        }
    } else {
        let below = below_zero(h, a, b);
        StepLoss {
            whole: false,
            time: below.time,
            first: below.first.map(|offset| t_k + offset),
            entries: below.entries,
        }
    }
}

/// The time and the first offset of [`below_zero`]; `(0, None)` for a
/// length that is not positive.
#[cfg(test)]
pub(crate) fn time_below_zero(length: f64, a: [f64; 2], b: [f64; 2]) -> (f64, Option<f64>) {
    let below = below_zero(length, a, b);
    (below.time, below.first)
}

/// Where the cubic of [`below_zero`] is negative.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct BelowZero {
    /// The measure of the set where it is negative (s).
    pub time: f64,
    /// The first offset at which it is negative (s).
    pub first: Option<f64>,
    /// How often it goes negative: its down-crossings through 0, and its
    /// start when it starts at 0 and falls (a start below 0 is not one).
    pub entries: u64,
}

/// The cubic Hermite interpolant p on `[0, 1]` (σ = offset / length)
/// through `a = [p_0, p'_0]` at 0 and `b = [p_1, p'_1]` at `length`, and
/// the points cutting `[0, 1]` into sub-intervals on each of which p keeps
/// its sign: the ends, its critical points and its roots (by bisection on
/// its monotone pieces).
fn sign_pieces(
    length: f64,
    a: [f64; 2],
    b: [f64; 2],
) -> (impl Fn(f64) -> f64, Points<SIGN_POINTS>) {
    // p(σ) = c0 + c1 σ + c2 σ² + c3 σ³ on σ ∈ [0, 1].
    let (g0, d0, g1, d1) = (a[0], a[1] * length, b[0], b[1] * length);
    let c = [
        g0,
        d0,
        3.0 * (g1 - g0) - 2.0 * d0 - d1,
        2.0 * (g0 - g1) + d0 + d1,
    ];
    // Evaluated in the Hermite basis, whose terms keep their signs near the
    // ends (no cancellation where p touches zero at an end).
    let p = move |s: f64| {
        let r = 1.0 - s;
        g0 * ((1.0 + 2.0 * s) * r * r) + g1 * (s * s * (3.0 - 2.0 * s)) + d0 * (s * r * r)
            - d1 * (s * s * r)
    };
    // Monotone pieces: split at the roots of p' = c1 + 2 c2 σ + 3 c3 σ².
    let mut cuts = Points::<4>::starting_at(0.0);
    let mut critical = quadratic_roots(3.0 * c[3], 2.0 * c[2], c[1]);
    critical.values[..critical.len].sort_by(f64::total_cmp);
    for &s in critical.as_slice() {
        if s > 0.0 && s < 1.0 {
            cuts.push(s);
        }
    }
    cuts.push(1.0);
    // Every root of p inside a piece where it changes sign.
    let mut points = Points::<SIGN_POINTS>::starting_at(0.0);
    for pair in cuts.as_slice().windows(2) {
        let (mut lo, mut hi) = (pair[0], pair[1]);
        let (p_lo, p_hi) = (p(lo), p(hi));
        if (p_lo < 0.0) != (p_hi < 0.0) {
            let rising = p_lo < 0.0;
            for _ in 0..BISECTIONS {
                let mid = 0.5 * (lo + hi);
                if (p(mid) < 0.0) == rising {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            points.push(0.5 * (lo + hi));
        }
        points.push(pair[1]);
    }
    points.dedup();
    (p, points)
}

/// The most points [`sign_pieces`] gives: 0, then for each of the at most
/// three monotone pieces a root and the piece's end.
const SIGN_POINTS: usize = 7;

/// A list of at most `N` offsets kept on the stack (the sign pieces of a
/// cubic are computed inside a step, where nothing is allocated).
#[derive(Debug, Clone, Copy)]
struct Points<const N: usize> {
    values: [f64; N],
    len: usize,
}

impl<const N: usize> Points<N> {
    fn starting_at(first: f64) -> Self {
        let mut points = Points {
            values: [0.0; N],
            len: 0,
        };
        points.push(first);
        points
    }

    /// Appends `value`; the callers' counts never exceed `N`.
    fn push(&mut self, value: f64) {
        self.values[self.len] = value;
        self.len += 1;
    }

    fn as_slice(&self) -> &[f64] {
        &self.values[..self.len]
    }

    /// Removes consecutive repeats.
    fn dedup(&mut self) {
        let mut kept = 0;
        for i in 0..self.len {
            if kept == 0 || self.values[i] != self.values[kept - 1] {
                self.values[kept] = self.values[i];
                kept += 1;
            }
        }
        self.len = kept;
    }
}

/// [`BelowZero`] of the cubic Hermite interpolant through
/// `a = [g_0, g'_0]` at 0 and `b = [g_1, g'_1]` at `length`: the time (s)
/// during which it is negative and the first offset (s) at which it is;
/// nothing for a length that is not positive.
pub(crate) fn below_zero(length: f64, a: [f64; 2], b: [f64; 2]) -> BelowZero {
    let mut below = BelowZero {
        time: 0.0,
        first: None,
        entries: 0,
    };
    if length.is_nan() || length <= 0.0 {
        return below;
    }
    let (p, points) = sign_pieces(length, a, b);
    // Sum the sub-intervals on which p is negative (tested at the middle;
    // a sub-interval of zero length adds nothing).
    let mut negative_before = a[0] < 0.0;
    for pair in points.as_slice().windows(2) {
        let (lo, hi) = (pair[0], pair[1]);
        if hi <= lo {
            continue;
        }
        let negative = p(0.5 * (lo + hi)) < 0.0;
        if negative {
            below.time += (hi - lo) * length;
            below.first.get_or_insert(lo * length);
            if !negative_before {
                below.entries += 1;
            }
        }
        negative_before = negative;
    }
    below
}

/// The first place where the cubic of [`below_zero`] falls through
/// 0: offsets (s) `[lo, root, hi]`, the root and a bracket of it,
/// `p(lo) >= 0 > p(hi)`, `lo` the start of the sign piece before it and
/// `hi` the deepest sub-interval middle of the negative stretch after it
/// (so that a tiny first piece next to a root at an end does not make a
/// bracket that rounding can undo); or zeros when it is negative from the
/// start and `skip_start` is false. With `skip_start` a negative stretch at the start is passed
/// over (a state just switched, whose margin is 0 up to rounding and
/// rising).
pub(crate) fn first_fall(
    length: f64,
    a: [f64; 2],
    b: [f64; 2],
    skip_start: bool,
) -> Option<[f64; 3]> {
    if length.is_nan() || length <= 0.0 {
        return (a[0] < 0.0 && !skip_start).then_some([0.0; 3]);
    }
    let (p, points) = sign_pieces(length, a, b);
    let mut negative_before = a[0] < 0.0 && skip_start;
    let mut before = 0.0;
    // The fall found: (its lo, its root, the deepest middle so far, p there).
    let mut fall: Option<(f64, f64, f64, f64)> = None;
    for pair in points.as_slice().windows(2) {
        let (lo, hi) = (pair[0], pair[1]);
        if hi <= lo {
            continue;
        }
        let middle = 0.5 * (lo + hi);
        let value = p(middle);
        let negative = value < 0.0;
        match fall {
            Some((_, _, _, deepest)) if negative => {
                if value < deepest {
                    fall = fall.map(|(start, root, _, _)| (start, root, middle, value));
                }
            }
            Some(_) => break,
            None if negative && !negative_before => {
                if lo == 0.0 && a[0] < 0.0 {
                    return Some([0.0; 3]);
                }
                fall = Some((before, lo, middle, value));
            }
            None => {
                if !negative {
                    before = lo;
                }
                negative_before = negative;
            }
        }
    }
    fall.map(|(lo, root, hi, _)| [lo * length, root * length, hi * length])
}

/// Real roots of `a s² + b s + c` (none, one or two; a linear or constant
/// polynomial when a = 0).
fn quadratic_roots(a: f64, b: f64, c: f64) -> Points<2> {
    let mut roots = Points {
        values: [0.0; 2],
        len: 0,
    };
    if a == 0.0 {
        if b != 0.0 {
            roots.push(-c / b);
        }
        return roots;
    }
    let discriminant = b * b - 4.0 * a * c;
    if discriminant < 0.0 {
        return roots;
    }
    // The root of larger magnitude first, the other from the product
    // (no cancellation).
    let q = -0.5 * (b + b.signum() * discriminant.sqrt());
    if q == 0.0 {
        roots.push(0.0);
        return roots;
    }
    roots.push(q / a);
    roots.push(c / q);
    roots
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_measure_of_a_cubic_below_zero_is_exact() {
        // g = (s − 0.3)(s − 0.7)(s + 1) on [0, 1] (L = 1): negative on
        // (0.3, 0.7).
        let g = |s: f64| (s - 0.3) * (s - 0.7) * (s + 1.0);
        let dg = |s: f64| (s - 0.7) * (s + 1.0) + (s - 0.3) * (s + 1.0) + (s - 0.3) * (s - 0.7);
        let (lost, first) = time_below_zero(1.0, [g(0.0), dg(0.0)], [g(1.0), dg(1.0)]);
        assert!((lost - 0.4).abs() < 1e-15, "{lost}");
        assert!((first.unwrap() - 0.3).abs() < 1e-15);
        // Scaled to a step of 1e-4 s.
        let h = 1e-4;
        let (lost, first) = time_below_zero(h, [g(0.0), dg(0.0) / h], [g(1.0), dg(1.0) / h]);
        assert!((lost - 0.4 * h).abs() < 1e-19, "{lost}");
        assert!((first.unwrap() - 0.3 * h).abs() < 1e-19);
        // A line from −1 to 1: negative on the first half.
        let (lost, first) = time_below_zero(2.0, [-1.0, 1.0], [1.0, 1.0]);
        assert!((lost - 1.0).abs() < 1e-15 && first == Some(0.0));
        // Positive throughout, and negative throughout.
        assert_eq!(time_below_zero(1.0, [1.0, 0.0], [1.0, 0.0]), (0.0, None));
        assert_eq!(
            time_below_zero(1.0, [-1.0, 0.0], [-2.0, 0.0]),
            (1.0, Some(0.0))
        );
        assert_eq!(time_below_zero(0.0, [-1.0, 0.0], [-2.0, 0.0]), (0.0, None));
    }

    #[test]
    fn the_largest_deflection_is_found_inside_the_step() {
        // p = sin(π s) on [0, 1]: the cubic through its end values and
        // rates peaks at s = 1/2 with p = (0 + 0)/2 + (π − (−π))/8 = π/4.
        let pi = std::f64::consts::PI;
        let peak = largest_magnitude(1.0, [0.0, pi], [0.0, -pi]);
        assert!((peak - pi / 4.0).abs() < 1e-15, "{peak}");
        // Monotone: the larger end.
        assert_eq!(largest_magnitude(2.0, [-3.0, 1.0], [-1.0, 1.0]), 3.0);
        // The fast test skips a step that cannot raise the maximum, and
        // takes the inner peak of one that can.
        let mut holding = Holding::new(1.0, 1.0, 0.0);
        holding.add_deflection(1.0, [0.0, pi], [0.0, -pi]);
        assert_eq!(holding.max_deflection, 1.0);
        let mut holding = Holding::new(0.5, 1.0, 0.0);
        holding.add_deflection(1.0, [0.0, pi], [0.0, -pi]);
        assert!((holding.max_deflection - pi / 4.0).abs() < 1e-15);
        // A negative peak counts by its magnitude.
        let mut holding = Holding::new(0.0, 1.0, 0.0);
        holding.add_deflection(1.0, [0.0, -pi], [0.0, pi]);
        assert!((holding.max_deflection - pi / 4.0).abs() < 1e-15);
    }

    #[test]
    fn the_node_test_agrees_with_the_exact_measure() {
        // Margins on both sides of zero, rates of both signs: the fast
        // decisions of check_step equal the exact measure.
        let h = 1e-4;
        let values = [-2e-5, -1e-6, -1e-9, 0.0, 1e-9, 1e-6, 2e-5];
        let rates = [-0.3, -1e-3, 0.0, 1e-3, 0.3];
        for &g0 in &values {
            for &g1 in &values {
                for &d0 in &rates {
                    for &d1 in &rates {
                        let mut fast = Holding::new(0.0, 1.0, 0.0);
                        let check = ContactCheck {
                            angular_frequency: 0.0,
                            start_time: 0.0,
                            step: h,
                        };
                        let loss = check_step(check, 0, [g0, d0], [g1, d1]);
                        let falls = may_fall_through_zero(h, [g0, d0], [g1, d1]);
                        assert_eq!(
                            falls,
                            loss.is_some_and(|l| l.whole || l.first.is_some()),
                            "{g0} {d0} {g1} {d1}"
                        );
                        if let Some(loss) = loss {
                            fast.add_step(loss);
                        }
                        let fast_time = fast.lost_steps as f64 * h + fast.lost_time;
                        let (exact, _) = time_below_zero(h, [g0, d0], [g1, d1]);
                        assert!(
                            (fast_time - exact).abs() <= 1e-18,
                            "{g0} {d0} {g1} {d1}: {fast_time} against {exact}"
                        );
                    }
                }
            }
        }
    }
}
