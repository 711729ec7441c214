//! Numerical limits beyond the admissible ranges of [`Params::validate`]:
//! what keeps every output finite and every call bounded. They belong to
//! the configuration, so every front-end (the FMU, the command line, a
//! library user) refuses the same runaway inputs with the same messages.
//!
//! - **Values** ([`check_value`], by their kind, [`Bound`]): initial displacements and the road
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
use crate::model::{Body, Params, STATE_NAMES, State, Variant};
use crate::road::RoadSpec;

/// Displacement bound (m): beyond it a run is declared divergent, and no
/// initial displacement or road amplitude may exceed it.
pub const DIVERGENCE_DISPLACEMENT: f64 = 1e3;
/// Velocity bound (m/s): beyond it a run is declared divergent, and no
/// initial velocity or road slope may exceed it.
pub const DIVERGENCE_VELOCITY: f64 = 1e6;

/// The divergence bound of state i: [`DIVERGENCE_DISPLACEMENT`] for the
/// displacements (even i), [`DIVERGENCE_VELOCITY`] for the velocities.
#[inline]
pub(crate) fn divergence_bound(i: usize) -> f64 {
    if i.is_multiple_of(2) {
        DIVERGENCE_DISPLACEMENT
    } else {
        DIVERGENCE_VELOCITY
    }
}

/// Divergence bounds in state order.
pub(crate) const DIVERGENCE_BOUNDS: [f64; 6] = [
    DIVERGENCE_DISPLACEMENT,
    DIVERGENCE_VELOCITY,
    DIVERGENCE_DISPLACEMENT,
    DIVERGENCE_VELOCITY,
    DIVERGENCE_DISPLACEMENT,
    DIVERGENCE_VELOCITY,
];

/// Checks a state at `time` against the divergence bounds: an error
/// naming the first component beyond its bound (or NaN).
#[inline]
pub(crate) fn check_divergence(time: f64, x: &State) -> Result<()> {
    for (i, value) in x.iter().enumerate() {
        let bound = divergence_bound(i);
        if value.is_nan() || value.abs() > bound {
            return Err(Error::Diverged {
                time,
                variable: crate::model::STATE_NAMES[i],
                value: *value,
                bound,
            });
        }
    }
    Ok(())
}

/// Largest stiffness, damping or gain over a mass (1/s²) or damping over a
/// mass (1/s).
pub const MAX_RATE: f64 = 1e12;
/// Largest weight of the objective J.
pub const MAX_WEIGHT: f64 = 1e12;

/// Most internal steps plus road nodes one call may need (2^22): the
/// work of one co-simulation step, and the road nodes one Model Exchange
/// time may generate or keep. A call that would need more is refused, so
/// that no call runs for more than a few seconds or holds more than
/// 32 MiB of road nodes.
pub const MAX_WORK_PER_CALL: f64 = 4_194_304.0;

/// A kind of value whose magnitude has a numerical limit. Front-ends map
/// their variables onto these (the FMU's table declares one per variable
/// that has a limit); the names in messages are the caller's.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Bound {
    /// A displacement (m): an initial displacement, the harmonic road's
    /// amplitude, an external road input.
    Displacement,
    /// A velocity (m/s): an initial velocity, the slope of an external
    /// road input.
    Velocity,
    /// The harmonic road's angular frequency (rad/s).
    AngularFrequency,
    /// A weight of the objective J (Eq. (6)).
    Weight,
}

impl Bound {
    /// The largest admissible magnitude.
    pub fn limit(self) -> f64 {
        match self {
            Bound::Displacement => DIVERGENCE_DISPLACEMENT,
            Bound::Velocity => DIVERGENCE_VELOCITY,
            Bound::AngularFrequency => MAX_RATE.sqrt(),
            Bound::Weight => MAX_WEIGHT,
        }
    }

    /// What the limit is, for messages.
    pub fn what(self) -> &'static str {
        match self {
            Bound::Displacement => "the divergence bound of displacements (m)",
            Bound::Velocity => "the divergence bound of velocities (m/s)",
            Bound::AngularFrequency => "the numerical limit (rad/s)",
            Bound::Weight => "the numerical limit of the weights",
        }
    }
}

/// Checks the values `[position (m), velocity (m/s)]` of the input
/// `input` (an index into [`crate::model::inputs::PRESCRIBED`], a corner's
/// body attachment) for a configuration with the body `body`: an input
/// only where it applies, finite and within the divergence bounds. The
/// error names the variable and the value.
pub fn check_prescribed(body: Body, input: usize, values: [f64; 2]) -> Result<()> {
    let p = &crate::model::inputs::PRESCRIBED[input];
    // False for NaN: a value not finite is refused below.
    let within = values[0].abs() <= Bound::Displacement.limit()
        && values[1].abs() <= Bound::Velocity.limit();
    if within && (p.applies)(body) {
        return Ok(());
    }
    refuse_prescribed(body, p, values)
}

/// The refusal of [`check_prescribed`], naming the variable and the value.
#[cold]
fn refuse_prescribed(
    body: Body,
    p: &crate::model::inputs::Prescribed,
    values: [f64; 2],
) -> Result<()> {
    if !(p.applies)(body) {
        return Err(Error::InvalidSetting {
            name: "body",
            value: body.code() as i64,
            reason: p.absent,
        });
    }
    for ((name, value), bound) in p
        .names
        .into_iter()
        .zip(values)
        .zip([Bound::Displacement, Bound::Velocity])
    {
        if !value.is_finite() {
            return Err(Error::InvalidParameter {
                name,
                value,
                reason: "must be finite",
            });
        }
        check_value(bound, name, value)?;
    }
    Ok(())
}

/// Refuses a value of kind `bound` whose magnitude exceeds its limit;
/// `name` names the value in the message.
pub fn check_value(bound: Bound, name: &str, value: f64) -> Result<()> {
    if value.abs() > bound.limit() {
        Err(Error::BeyondLimit {
            name: name.to_string(),
            value,
            bound: bound.limit(),
            what: bound.what(),
        })
    } else {
        Ok(())
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
    for (i, value) in initial_state.iter().enumerate() {
        let bound = if i % 2 == 0 {
            Bound::Displacement
        } else {
            Bound::Velocity
        };
        check_value(bound, &format!("initial {}", STATE_NAMES[i]), *value)?;
    }
    if let RoadSpec::Harmonic {
        amplitude,
        angular_frequency,
    } = road
    {
        check_value(Bound::Displacement, "road_amplitude", *amplitude)?;
        check_value(
            Bound::AngularFrequency,
            "road_angular_frequency",
            *angular_frequency,
        )?;
    }
    check_value(Bound::Weight, "w_ba", weights.body_acceleration)?;
    check_value(Bound::Weight, "w_sdd", weights.suspension_deflection)?;
    check_value(Bound::Weight, "w_tdd", weights.tire_deflection)?;
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
        let e = check_value(Bound::Displacement, "initial x_s", -2e3)
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "invalid value -2000 for `initial x_s`: its magnitude exceeds 1e3, the divergence bound of displacements (m)"
        );
        let e = check_value(Bound::Weight, "w_tdd", 1e300)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("`w_tdd`") && e.contains(&1e300.to_string()),
            "{e}"
        );
        check_value(Bound::AngularFrequency, "omega", 1e6).unwrap();
        assert!(check_value(Bound::AngularFrequency, "omega", 1.000001e6).is_err());
        let mut state = State::zeros();
        state[crate::model::V_T] = 2e6;
        let e = check_config(
            &Params::default(),
            Variant::Cs,
            &RoadSpec::paper_harmonic(),
            &state,
            &Weights::default(),
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("`initial v_t`") && e.contains("velocities"),
            "{e}"
        );
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
