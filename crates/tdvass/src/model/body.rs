//! What carries the suspension: the paper's sprung mass, or a body outside
//! the model whose attachment point's motion is given (the corner of a
//! vehicle).

use crate::error::{Error, Result};

/// What the suspension carries.
///
/// - [`Body::Mass`]: the quarter car of the paper, the body a mass m_s on
///   the suspension (Eq. (1)).
/// - [`Body::Attached`]: a corner of a vehicle whose body is outside the
///   model. The body's attachment point `(x_s, v_s)` is an input, set
///   when it changes ([`crate::solver::Simulator::set_body_input`]) and
///   moving at its given velocity in between (`dx_s/dt = v_s`,
///   `dv_s/dt = 0`: the plant's body row of A is zero,
///   [`super::Plant::with_body`]). The suspension's force on the body,
///   [`super::Plant::body_force`], is the corner's output, and
///   `m_s = W_c / g0` carries the corner's share W_c of the body's weight
///   (it sets the tire's static load W, and nothing else). Its BA (the
///   body row of A) is zero, so its comfort outputs are zero too: the
///   corner FMU runs it at [`crate::solver::Metrics::RoadHolding`], with
///   no W_k filter to integrate.
///
/// The quarter car is the corner under a body that is a point mass m_s
/// driven by that force.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Body {
    /// The paper's sprung mass (the default).
    #[default]
    Mass,
    /// A body outside the model, its attachment point's motion given.
    Attached,
}

impl Body {
    /// Both, in code order.
    pub const ALL: [Body; 2] = [Body::Mass, Body::Attached];

    /// The integer code, as saved: 0 = mass, 1 = attached.
    pub fn code(self) -> i32 {
        match self {
            Body::Mass => 0,
            Body::Attached => 1,
        }
    }

    /// Inverse of [`Body::code`].
    pub fn from_code(code: i64) -> Result<Body> {
        match code {
            0 => Ok(Body::Mass),
            1 => Ok(Body::Attached),
            _ => Err(Error::InvalidSetting {
                name: "body",
                value: code,
                reason: "must be 0 (the sprung mass) or 1 (a body outside the model, attached)",
            }),
        }
    }

    /// Whether the body is outside the model (a corner).
    pub fn is_attached(self) -> bool {
        self == Body::Attached
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_codes_round_trip_and_a_wrong_one_is_named() {
        for body in Body::ALL {
            assert_eq!(Body::from_code(body.code() as i64).unwrap(), body);
        }
        let e = Body::from_code(2).unwrap_err().to_string();
        assert!(e.contains("body") && e.contains('2'), "{e}");
    }
}
