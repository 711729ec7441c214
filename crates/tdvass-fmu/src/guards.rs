//! The guards of every slave call, beyond the declared ranges of the
//! variable table: the library's numerical limits ([`tdvass::limits`]:
//! values and rates, which the library checks for every configuration, so
//! the command line refuses the same runaway inputs) mapped onto the FMU's
//! variables, and what bounds the work and time of one call:
//!
//! - **Values and rates** ([`check_variable`], [`check_input_slope`],
//!   [`check_rates`]): the library's checks, by the kind of value each
//!   variable's table entry declares, applied to a value when it is set
//!   (and when a serialized state is read) and to the settings when the
//!   simulation is built or `g` is tuned.
//! - **Work per step** ([`step_work`]): one step may need at most
//!   [`MAX_WORK_PER_STEP`] internal steps and road breakpoints, so that no
//!   call runs for more than a few seconds (a huge communication step
//!   without a stop time, a tiny `max_internal_step` or a tiny
//!   `road_sample_interval`). A longer step is refused: the master splits it.
//! - **Time resolution** ([`check_time_resolution`]).
//! - **Outputs** ([`non_finite_output`], [`non_finite_chassis_output`]):
//!   a last line of defence; a non-finite output is never handed out.

use crate::defaults::Model;
use crate::error::FmiError;
use crate::settings::Settings;
use crate::variables::{Access, FmiVersion, Variable, variables_of};
use tdvass::chassis::Chassis;
use tdvass::limits::Bound;
use tdvass::road::RoadType;
use tdvass::solver::Outputs;

pub use tdvass::limits::{MAX_RATE, MAX_WEIGHT};

/// The library's limit on a value of `var` (already in its declared
/// range): the kind of value its table entry declares ([`Variable::bound`]),
/// none for a variable without one.
pub fn check_variable(var: &Variable, value: f64) -> Result<(), FmiError> {
    match var.bound {
        Some(bound) => Ok(tdvass::limits::check_value(bound, var.name, value)?),
        None => Ok(()),
    }
}

/// The library's limit on the slope of the road input x_g (an input
/// derivative, or the slope of an extrapolation): a velocity.
pub fn check_input_slope(value: f64) -> Result<(), FmiError> {
    Ok(tdvass::limits::check_value(
        Bound::Velocity,
        "x_g derivative",
        value,
    )?)
}

/// Every single-value limit of `settings`.
pub fn check_values(settings: &Settings) -> Result<(), FmiError> {
    for v in variables_of(settings.model, FmiVersion::Fmi3) {
        match v.access {
            Access::Real { get, .. } => check_variable(v, get(settings))?,
            Access::Integer { get, .. } => check_variable(v, get(settings) as f64)?,
            _ => {}
        }
    }
    Ok(())
}

/// The library's rate limit for the parameters of `s` in its variant (an
/// invalid code, refused elsewhere, counts as every part present).
pub fn check_rates(s: &Settings) -> Result<(), FmiError> {
    if !s.model.is_suspension() {
        // The chassis has no rates of its own: its step is a closed form.
        return Ok(());
    }
    match tdvass::limits::check_rates(&s.params(), s.variant().ok()) {
        // The corner's body mass is its static load over g0: name that.
        Err(tdvass::Error::RateLimit {
            name,
            value,
            mass_name: "m_s",
            mass,
            rate,
            limit,
        }) if s.model == Model::Corner => Err(FmiError::error(format!(
            "invalid `static_load` = {} N: the body mass it stands for, static_load / g0 = {mass} kg, makes `{name}` = {value} over it ({rate} 1/s^2) exceed the numerical limit {limit} 1/s^2",
            s.static_load
        ))),
        other => Ok(other?),
    }
}

/// Most internal steps plus road breakpoints in one step (2^22).
pub const MAX_WORK_PER_STEP: f64 = tdvass::limits::MAX_WORK_PER_CALL;
/// Node interval of the ISO 8608 road (s).
const ISO_NODE_INTERVAL: f64 = tdvass::road::ISO_NODE_INTERVAL;

/// The internal steps and road breakpoints a step of `h` s needs with the
/// internal step `grid_step`.
#[inline]
pub fn step_work(s: &Settings, grid_step: f64, h: f64) -> f64 {
    let road = match s.road_type() {
        Some(RoadType::Iso8608) => h / ISO_NODE_INTERVAL,
        Some(RoadType::PaperCompatible) => h / s.road_sample_interval,
        _ => 0.0,
    };
    h / grid_step + road
}

/// Refuses a step of `h` s that needs more than [`MAX_WORK_PER_STEP`]
/// internal steps and road breakpoints in one call of `function`.
pub fn check_step_work(
    s: &Settings,
    grid_step: f64,
    h: f64,
    function: impl std::fmt::Display,
) -> Result<(), FmiError> {
    let work = step_work(s, grid_step, h);
    if work > MAX_WORK_PER_STEP {
        let longest = h * MAX_WORK_PER_STEP / work;
        return Err(FmiError::error(format!(
            "a communication step of {h} s needs {work:e} internal steps (internal step {grid_step:e} s{}), more than the limit of {MAX_WORK_PER_STEP} per {function}; use communication steps of at most {longest:e} s",
            match s.road_type() {
                Some(RoadType::Iso8608) => format!(", road nodes every {ISO_NODE_INTERVAL} s"),
                Some(RoadType::PaperCompatible) => {
                    format!(", road_sample_interval {} s", s.road_sample_interval)
                }
                _ => String::new(),
            }
        )));
    }
    Ok(())
}

/// Largest |time| in internal steps (2^42): beyond it, times no longer
/// resolve the internal step well (and at 2^52 not at all). The solver
/// refuses start times beyond it too.
pub const MAX_TIME_IN_STEPS: f64 = tdvass::solver::Simulator::MAX_START_TIME_IN_STEPS;

/// Refuses a time `t` (s) too large for the internal step `grid_step`.
#[inline]
pub fn check_time_resolution(what: &str, t: f64, grid_step: f64) -> Result<(), FmiError> {
    if t.abs() > grid_step * MAX_TIME_IN_STEPS {
        return Err(time_too_large(what, t, grid_step));
    }
    Ok(())
}

/// The error of [`check_time_resolution`], out of the callers' line.
#[cold]
fn time_too_large(what: &str, t: f64, grid_step: f64) -> FmiError {
    FmiError::error(format!(
        "{what} {t} s is too large for the internal step {grid_step:e} s: |time| must be at most {:e} s (2^42 internal steps) so that times resolve the steps",
        grid_step * MAX_TIME_IN_STEPS
    ))
}

/// The first state of `state` (solver order) that is not finite, with its
/// name and value.
pub fn non_finite_state(state: &tdvass::model::State) -> Option<(&'static str, f64)> {
    state
        .iter()
        .zip(tdvass::model::STATE_NAMES)
        .find(|(value, _)| !value.is_finite())
        .map(|(value, name)| (name, *value))
}

/// The first output of `model` in `outputs` that is not finite, with its
/// value.
pub fn non_finite_output(model: Model, outputs: &Outputs) -> Option<(&'static str, f64)> {
    variables_of(model, FmiVersion::Fmi2)
        .iter()
        .find_map(|v| match v.access {
            Access::Output(id) => {
                let value = id.value(outputs);
                (!value.is_finite()).then_some((v.name, value))
            }
            _ => None,
        })
}

/// The first output of the running `chassis` that is not finite, with
/// its value.
pub fn non_finite_chassis_output(chassis: &Chassis) -> Option<(&'static str, f64)> {
    variables_of(Model::Chassis, FmiVersion::Fmi2)
        .iter()
        .find_map(|v| match v.access {
            Access::ChassisOutput(id) => {
                let value = id.value(chassis);
                (!value.is_finite()).then_some((v.name, value))
            }
            _ => None,
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_within_the_limits() {
        let s = Settings::start_values(Model::QuarterCar);
        check_values(&s).unwrap();
        check_rates(&s).unwrap();
        check_step_work(&s, 1e-4, 15.0, "fmi2DoStep").unwrap();
    }

    #[test]
    fn limits_name_variable_and_value() {
        let var = |name| {
            crate::variables::by_name(Model::QuarterCar, crate::variables::FmiVersion::Fmi3, name)
                .unwrap()
        };
        let e = check_variable(var("x_s_start"), -2e3).unwrap_err().message;
        assert!(e.contains("`x_s_start`") && e.contains("-2000"), "{e}");
        let e = check_variable(var("w_tdd"), 1e300).unwrap_err().message;
        assert!(
            e.contains("`w_tdd`") && e.contains(&1e300.to_string()),
            "{e}"
        );
        let e = check_input_slope(2e6).unwrap_err().message;
        assert!(
            e.contains("`x_g derivative`") && e.contains("velocities"),
            "{e}"
        );
        // The table maps its variables onto the library's kinds of value.
        let bounded: Vec<_> = variables_of(Model::QuarterCar, FmiVersion::Fmi3)
            .iter()
            .filter_map(|v| v.bound.map(|b| (v.name, b)))
            .collect();
        let expected = [
            ("road_amplitude", Bound::Displacement),
            ("road_angular_frequency", Bound::AngularFrequency),
            ("w_ba", Bound::Weight),
            ("w_sdd", Bound::Weight),
            ("w_tdd", Bound::Weight),
            ("x_s_start", Bound::Displacement),
            ("v_s_start", Bound::Velocity),
            ("x_h_start", Bound::Displacement),
            ("v_h_start", Bound::Velocity),
            ("x_t_start", Bound::Displacement),
            ("v_t_start", Bound::Velocity),
            ("x_g", Bound::Displacement),
        ];
        assert_eq!(bounded, expected);
        check_variable(var("m_s"), 1e300).unwrap();
        let mut s = Settings::start_values(Model::QuarterCar);
        s.params.k_s = 1e300;
        let e = check_rates(&s).unwrap_err().message;
        assert!(
            e.contains("`k_s` = ") && e.contains(&1e300.to_string()),
            "{e}"
        );
        let mut s = Settings::start_values(Model::QuarterCar);
        s.params.m_h = 1e-300;
        assert!(check_rates(&s).unwrap_err().message.contains("m_h"));
        s.variant = 1;
        check_rates(&s).unwrap();
        let mut s = Settings::start_values(Model::QuarterCar);
        s.params.g = -1e13;
        assert!(check_rates(&s).is_err());
        s.variant = 2;
        check_rates(&s).unwrap();
    }

    #[test]
    fn work_per_step() {
        let mut s = Settings::start_values(Model::QuarterCar);
        assert!(check_step_work(&s, 1e-4, 1e9, "fmi2DoStep").is_err());
        assert!(check_step_work(&s, 1e-12, 0.01, "fmi2DoStep").is_err());
        assert!(check_time_resolution("startTime", -4.3e42, 1e-4).is_err());
        assert!(check_time_resolution("startTime", 4e8, 1e-4).is_ok());
        s.road = 3;
        s.road_sample_interval = 1e-300;
        let e = check_step_work(&s, 1e-4, 0.01, "fmi2DoStep")
            .unwrap_err()
            .message;
        assert!(e.contains("road_sample_interval"), "{e}");
    }
}
