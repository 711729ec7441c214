//! Numerical limits beyond the admissible ranges of [`Params::validate`]:
//! what keeps every output finite and every call bounded. They belong to
//! the configuration, so every front-end (the FMU, the command line, a
//! library user) refuses the same runaway inputs with the same messages.
//!
//! - **Values** ([`check_value`]): initial displacements and the road
//!   amplitude (and an external road input) within the divergence bound of
//!   displacements ([`DIVERGENCE_DISPLACEMENT`]), initial velocities and the
//!   slope of an external input within the bound of velocities
//!   ([`DIVERGENCE_VELOCITY`]), the harmonic road's angular frequency
//!   within `sqrt(MAX_RATE)` and the weights of J (Eq. (6)) within
//!   [`MAX_WEIGHT`].
//! - **Rates** ([`check_rates`]): every stiffness, damping and the gain,
//!   over every mass it acts on, at most [`MAX_RATE`] (natural frequencies
//!   up to 1e6 rad/s). With states inside the divergence bounds this keeps
//!   every output finite.
//!
//! [`Simulator::new`](crate::solver::Simulator::new) applies both to its
//! configuration ([`check_config`]) and
//! [`Simulator::set_gain`](crate::solver::Simulator::set_gain) to a tuned
//! gain.

use crate::error::{Error, Result};
use crate::metrics::Weights;
use crate::model::{Params, State, Variant};
use crate::road::RoadSpec;
use crate::solver::{DIVERGENCE_DISPLACEMENT, DIVERGENCE_VELOCITY};

/// Largest stiffness, damping or gain over a mass (1/s²) or damping over a
/// mass (1/s).
pub const MAX_RATE: f64 = 1e12;
/// Largest weight of the objective J.
pub const MAX_WEIGHT: f64 = 1e12;

/// The names of the initial state's components, as the FMU names them.
pub const INITIAL_STATE_NAMES: [&str; 6] = [
    "x_s_start",
    "v_s_start",
    "x_h_start",
    "v_h_start",
    "x_t_start",
    "v_t_start",
];

/// The limit of a named value, if it has one: the bound of its magnitude
/// and what the bound is.
fn value_limit(name: &str) -> Option<(f64, &'static str)> {
    match name {
        "x_s_start" | "x_h_start" | "x_t_start" | "road_amplitude" | "x_g" => Some((
            DIVERGENCE_DISPLACEMENT,
            "the divergence bound of displacements (m)",
        )),
        "v_s_start" | "v_h_start" | "v_t_start" | "x_g derivative" => Some((
            DIVERGENCE_VELOCITY,
            "the divergence bound of velocities (m/s)",
        )),
        "road_angular_frequency" => Some((MAX_RATE.sqrt(), "the numerical limit (rad/s)")),
        "w_ba" | "w_sdd" | "w_tdd" => Some((MAX_WEIGHT, "the numerical limit of the weights")),
        _ => None,
    }
}

/// Refuses a value whose magnitude exceeds the limit of `name` (names
/// without a limit pass).
pub fn check_value(name: &str, value: f64) -> Result<()> {
    match value_limit(name) {
        Some((bound, what)) if value.abs() > bound => Err(Error::BeyondLimit {
            name: name.to_string(),
            value,
            bound,
            what,
        }),
        _ => Ok(()),
    }
}

/// Every coefficient over every mass it acts on at most [`MAX_RATE`].
/// `variant` `None` (an invalid code, refused elsewhere) counts as every
/// part present.
pub fn check_rates(params: &Params, variant: Option<Variant>) -> Result<()> {
    let absorber = variant.is_none_or(Variant::has_absorber);
    let control = variant.is_some_and(Variant::has_control);
    let masses = [
        ("m_s", params.m_s, true),
        ("m_h", params.m_h, absorber),
        ("m_t", params.m_t, true),
    ];
    let coefficients = [
        ("k_s", params.k_s, true),
        ("c_s", params.c_s, true),
        ("k_h", params.k_h, absorber),
        ("c_h", params.c_h, absorber),
        ("k_t", params.k_t, true),
        ("g", params.g, control),
    ];
    for (name, value, used) in coefficients {
        for (mass_name, mass, mass_used) in masses {
            let rate = value.abs() / mass;
            if used && mass_used && rate > MAX_RATE {
                return Err(Error::RateLimit {
                    name,
                    value,
                    mass_name,
                    mass,
                    rate,
                    limit: MAX_RATE,
                });
            }
        }
    }
    Ok(())
}

/// The value limits of an initial state, a road and the weights, then the
/// rates of `params` in `variant`.
pub fn check_config(
    params: &Params,
    variant: Variant,
    road: &RoadSpec,
    initial_state: &State,
    weights: &Weights,
) -> Result<()> {
    for (name, value) in INITIAL_STATE_NAMES.iter().zip(initial_state.iter()) {
        check_value(name, *value)?;
    }
    if let RoadSpec::Harmonic {
        amplitude,
        angular_frequency,
    } = road
    {
        check_value("road_amplitude", *amplitude)?;
        check_value("road_angular_frequency", *angular_frequency)?;
    }
    check_value("w_ba", weights.body_acceleration)?;
    check_value("w_sdd", weights.suspension_deflection)?;
    check_value("w_tdd", weights.tire_deflection)?;
    check_rates(params, Some(variant))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table1_and_the_paper_roads_are_within_the_limits() {
        for variant in [Variant::Cs, Variant::Pvass, Variant::Tdvass] {
            check_config(
                &Params::default(),
                variant,
                &RoadSpec::paper_harmonic(),
                &State::zeros(),
                &Weights::default(),
            )
            .unwrap();
        }
    }

    #[test]
    fn limits_name_variable_and_value() {
        let e = check_value("x_s_start", -2e3).unwrap_err().to_string();
        assert_eq!(
            e,
            "invalid value -2000 for `x_s_start`: its magnitude exceeds 1e3, the divergence bound of displacements (m)"
        );
        let e = check_value("w_tdd", 1e300).unwrap_err().to_string();
        assert!(
            e.contains("`w_tdd`") && e.contains(&1e300.to_string()),
            "{e}"
        );
        check_value("road_angular_frequency", 1e6).unwrap();
        assert!(check_value("road_angular_frequency", 1.000001e6).is_err());
        check_value("m_s", 1e300).unwrap();
        let params = Params {
            k_s: 1e300,
            ..Params::default()
        };
        let e = check_rates(&params, Some(Variant::Tdvass))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("`k_s` = ") && e.contains(&1e300.to_string()),
            "{e}"
        );
    }

    #[test]
    fn rates_count_only_the_parts_a_variant_has() {
        let light_absorber = Params {
            m_h: 1e-300,
            ..Params::default()
        };
        let e = check_rates(&light_absorber, Some(Variant::Pvass)).unwrap_err();
        assert!(e.to_string().contains("m_h"), "{e}");
        check_rates(&light_absorber, Some(Variant::Cs)).unwrap();
        assert!(check_rates(&light_absorber, None).is_err());
        let runaway_gain = Params {
            g: -1e13,
            ..Params::default()
        };
        assert!(check_rates(&runaway_gain, Some(Variant::Tdvass)).is_err());
        check_rates(&runaway_gain, Some(Variant::Pvass)).unwrap();
    }
}
