//! The external inputs that prescribe coordinates of the plant, as data.
//!
//! Each sets one of the plant's positions and its velocity from outside,
//! at its changes; between changes the position moves at the velocity (the
//! velocity's rows of A, b and e are zero where the input applies:
//! [`super::Plant::with_body`]). Both engines, their saved states, their
//! partials and the FMU's setters read this list:
//!
//! - the co-simulation writes the values into the plant's state at a
//!   change and commits the point there, as at a change of the road input
//!   (`Simulator::set_prescribed`);
//! - Model Exchange keeps the values and reads the coordinates from them
//!   wherever it reads the state (`ModelExchange::set_prescribed`), and
//!   its partials with respect to those coordinates are the partials with
//!   respect to the input ([`crate::exchange::Gradient::prescribed`]).
//!
//! A new input of this kind is an entry of [`PRESCRIBED`] (with the
//! configuration it applies to), and its two variables in the FMU's table
//! and settings: docs/architecture.md, "The recipe, counted".

use super::body::Body;
use super::params::{V_S, X_S};

/// An input that prescribes a position of the plant and its velocity.
#[derive(Debug, Clone, Copy)]
pub struct Prescribed {
    /// What the input is, for messages.
    pub what: &'static str,
    /// The state indices it sets: the position, then its velocity.
    pub coordinates: [usize; 2],
    /// The names of its two values (the FMU's variables, m and m/s).
    pub names: [&'static str; 2],
    /// Whether a configuration with this body has the input.
    pub applies: fn(Body) -> bool,
    /// Why a configuration without it refuses it.
    pub absent: &'static str,
}

/// A corner's body attachment ([`Body::Attached`]): `x_s`, `v_s`.
pub const BODY_ATTACHMENT: usize = 0;

/// Every input that prescribes coordinates, by index.
pub const PRESCRIBED: [Prescribed; 1] = [Prescribed {
    what: "the body attachment",
    coordinates: [X_S, V_S],
    names: ["body_displacement", "body_velocity"],
    applies: Body::is_attached,
    absent: "the body's attachment point is an input only of a corner (a body outside the model, body = 1)",
}];

/// The values of the inputs in force, by index into [`PRESCRIBED`]:
/// `[position (m), velocity (m/s)]`, `None` for an input the
/// configuration does not have.
pub type PrescribedValues = [Option<[f64; 2]>; PRESCRIBED.len()];

/// The inputs a configuration with `body` has, their values taken from
/// the state `x`.
pub fn prescribed_from(body: Body, x: &super::State) -> PrescribedValues {
    std::array::from_fn(|i| {
        let p = &PRESCRIBED[i];
        (p.applies)(body).then(|| p.coordinates.map(|c| x[c]))
    })
}

/// `x` with the coordinates of every input in `values` set from it.
#[inline]
pub fn with_prescribed(mut x: super::State, values: &PrescribedValues) -> super::State {
    for (p, value) in PRESCRIBED.iter().zip(values) {
        if let Some(v) = value {
            x[p.coordinates[0]] = v[0];
            x[p.coordinates[1]] = v[1];
        }
    }
    x
}

/// The input whose value is named `name`, and which of its two values
/// (0: the position, 1: the velocity). Inlined: an FMU's setter asks it
/// of every variable it sets.
#[inline]
pub fn prescribed_by_name(name: &str) -> Option<(usize, usize)> {
    for (i, p) in PRESCRIBED.iter().enumerate() {
        for (k, n) in p.names.iter().enumerate() {
            if *n == name {
                return Some((i, k));
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_input_sets_a_position_and_its_velocity_and_is_found_by_name() {
        for (i, p) in PRESCRIBED.iter().enumerate() {
            let [position, velocity] = p.coordinates;
            assert_eq!(velocity, position + 1, "{}", p.what);
            for (k, name) in p.names.iter().enumerate() {
                assert_eq!(prescribed_by_name(name), Some((i, k)));
            }
        }
        assert_eq!(prescribed_by_name("x_g"), None);
        let x = super::super::State::from_fn(|i, _| i as f64);
        let values = prescribed_from(Body::Attached, &x);
        assert_eq!(values[BODY_ATTACHMENT], Some([x[X_S], x[V_S]]));
        assert_eq!(prescribed_from(Body::Mass, &x), [None]);
        let moved = with_prescribed(x, &[Some([7.0, 8.0])]);
        assert_eq!((moved[X_S], moved[V_S], moved[2]), (7.0, 8.0, x[2]));
    }
}
