//! Inputs: the road as pieces over the internal grid, and the one rule
//! that ends a stretch of integration inside a step.
//!
//! Every loop that advances inside a step (the plant, the W_k filter, the
//! time averages, the switch search) goes from its start to `to` through
//! the stretches of [`stretch`]: a stretch ends at the road piece's end
//! when that lies before `to` and does not coincide with it
//! ([`ends_before`]), and, when the delay lies inside the step, at the
//! switch `t_k + tau` of the delayed argument. Times that coincide within
//! `1e-9 h + 8 ε |t|` ([`coincide`]) are one time, so a breakpoint a
//! rounding away from a node never makes a stretch of zero length.
//!
//! It imports the road alone; the simulator asks it with its own road and
//! internal step.

use crate::road::{Road, RoadPiece};

/// Whether times `a` and `b` are the same within `1e-9 h + 8 ε |t|` for
/// the internal step `step` (h); an infinite time (the end of a road piece
/// that never ends) coincides only with itself.
#[inline]
pub(super) fn coincide(a: f64, b: f64, step: f64) -> bool {
    if a.is_infinite() || b.is_infinite() {
        return a == b;
    }
    (a - b).abs() <= 1e-9 * step + 8.0 * f64::EPSILON * a.abs().max(b.abs())
}

/// The road piece in force from `t` on: the piece after a breakpoint that
/// `t` coincides with.
#[inline(always)]
pub(super) fn piece_from(road: &mut Road, t: f64, step: f64) -> RoadPiece {
    let piece = road.piece(t);
    piece_after(road, piece, t, step)
}

/// [`piece_from`] with `road.piece(t)` already known (`piece`).
#[inline(always)]
pub(super) fn piece_after(road: &mut Road, piece: RoadPiece, t: f64, step: f64) -> RoadPiece {
    if let RoadPiece::Harmonic { .. } = piece {
        // One piece for all times (the test below would ask for it again
        // at its end, +∞).
        return piece;
    }
    if piece.end() <= t || coincide(piece.end(), t, step) {
        road.piece(piece.end().max(t))
    } else {
        piece
    }
}

/// The breakpoint rule: whether `piece` ends before `to`, so that a
/// breakpoint splits the stretch towards `to` (its end before `to` and
/// not coinciding with it).
#[inline(always)]
pub(super) fn ends_before(piece: &RoadPiece, to: f64, step: f64) -> bool {
    piece.end() < to && !coincide(piece.end(), to, step)
}

/// One stretch of integration inside a step (see the module docs).
#[derive(Debug, Clone, Copy)]
pub(super) struct Stretch {
    /// The road piece in force over it.
    pub(super) piece: RoadPiece,
    /// Where it ends (s).
    pub(super) end: f64,
    /// Whether it starts before the switch `t_k + tau` (false without
    /// one).
    pub(super) before_switch: bool,
}

/// The stretch from `start` towards `to`: it ends at the road piece's end
/// ([`ends_before`]) or at `to`, and not past `switch` (the switch
/// `t_k + tau` of the delayed argument, with the delay inside the step)
/// when it starts before it.
#[inline]
pub(super) fn stretch(
    road: &mut Road,
    start: f64,
    to: f64,
    switch: Option<f64>,
    step: f64,
) -> Stretch {
    let piece = piece_from(road, start, step);
    let mut end = if ends_before(&piece, to, step) {
        piece.end()
    } else {
        to
    };
    let before_switch = match switch {
        Some(switch) if start < switch && !coincide(start, switch, step) => {
            if end > switch && !coincide(end, switch, step) {
                end = switch;
            }
            true
        }
        _ => false,
    };
    Stretch {
        piece,
        end,
        before_switch,
    }
}
