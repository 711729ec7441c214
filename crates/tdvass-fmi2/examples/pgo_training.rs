//! The training run of the profile-guided build (`fmu-build`, see
//! `fmu-build/src/pgo.rs`): drives the FMI 2.0 C interface as master loops
//! do, so that the profile it records weighs the paths those loops take.
//!
//! Each run instantiates the FMU, sets its structural parameters, steps
//! with a fixed communication step and reads a set of outputs after every
//! step. The default experiment (TDVASS on the harmonic road, 15 s of 1 ms
//! steps, the three RMS values or BA/SDD/TDD) weighs most, as it does in
//! use; then, for 1 s each:
//! - communication steps of 0.7 ms (points inside internal steps), with
//!   every Real output read;
//! - the ISO 8608 and the paper's road, the three variants;
//! - the unilateral tire;
//! - the road as an input (`road` = 0) set before every step.
//!
//! Every call must succeed: a failing call stops the run with an error, so
//! that a broken interface never trains the build (fmu-build then fails).

use tdvass_fmi2::ffi::{
    fmi2DoStep, fmi2EnterInitializationMode, fmi2ExitInitializationMode, fmi2FreeInstance,
    fmi2GetReal, fmi2SetInteger, fmi2SetReal, fmi2SetupExperiment, fmi2Terminate, into_component,
};
use tdvass_fmi2::instance::{FMI2_COSIMULATION, InstantiateRequest};
use tdvass_fmi2::variables::{Causality, FmiVersion, VarType, by_name, variables_of};
use tdvass_fmi2::{Instance, Model, Status};

/// `fmi2OK`.
const OK: i32 = 0;

/// One master loop of the training: `variant`, `road`, `tire_contact`,
/// the communication step (s), the duration (s) and what is read.
type Run = (i32, i32, i32, f64, f64, Outputs);

/// What the master reads after each step.
#[derive(Clone, Copy)]
enum Outputs {
    Rms,
    Instantaneous,
    AllReal,
}

fn vr(name: &str) -> u32 {
    by_name(Model::QuarterCar, FmiVersion::Fmi2, name)
        .unwrap_or_else(|| panic!("no variable `{name}`"))
        .vr
}

fn check(status: i32, what: &str) -> Result<(), String> {
    if status == OK {
        Ok(())
    } else {
        Err(format!("{what} returned status {status}"))
    }
}

/// The x_g (m) the road-input run sets at time t (s).
fn road_input(t: f64) -> f64 {
    0.02 * (9.0 * t).sin() + 0.004 * (60.0 * t).sin()
}

fn run(
    &(variant, road, tire_contact, step, duration, outputs): &Run,
    guid: &str,
) -> Result<(), String> {
    let instance = Instance::instantiate(
        InstantiateRequest {
            instance_name: Some("training"),
            fmu_type: FMI2_COSIMULATION,
            guid: Some(guid),
            ..Default::default()
        },
        // A failing call names the reason here, before its status stops
        // the run.
        Box::new(|status, category, message| {
            if matches!(status, Status::Discard | Status::Error | Status::Fatal) {
                eprintln!("pgo_training: {status:?} [{category}] {message}");
            }
        }),
    )
    .ok_or("the instance was not made")?;
    let read: Vec<u32> = match outputs {
        Outputs::Rms => [
            "rms_body_acceleration",
            "rms_suspension_deflection",
            "rms_tire_deflection",
        ]
        .map(vr)
        .to_vec(),
        Outputs::Instantaneous => [
            "body_acceleration",
            "suspension_deflection",
            "tire_deflection",
        ]
        .map(vr)
        .to_vec(),
        Outputs::AllReal => variables_of(Model::QuarterCar, FmiVersion::Fmi2)
            .iter()
            .filter(|v| v.causality == Causality::Output && v.var_type() == VarType::Real)
            .map(|v| v.vr)
            .collect(),
    };
    let mut values = vec![0.0; read.len()];
    // SAFETY: `c` is a live handle, used only here and freed once; every
    // array passed holds the count given.
    unsafe {
        let c = into_component(instance);
        check(
            fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0),
            "fmi2SetupExperiment",
        )?;
        check(
            fmi2EnterInitializationMode(c),
            "fmi2EnterInitializationMode",
        )?;
        let structural = [vr("variant"), vr("road"), vr("tire_contact")];
        let settings = [variant, road, tire_contact];
        check(
            fmi2SetInteger(c, structural.as_ptr(), 3, settings.as_ptr()),
            "fmi2SetInteger",
        )?;
        if road == 0 {
            let extrapolation = [vr("input_extrapolation")];
            check(
                fmi2SetInteger(c, extrapolation.as_ptr(), 1, [2].as_ptr()),
                "fmi2SetInteger",
            )?;
        }
        check(fmi2ExitInitializationMode(c), "fmi2ExitInitializationMode")?;
        let x_g = [vr("x_g")];
        let points = (duration / step).round() as u64;
        for k in 0..points {
            let t = k as f64 * step;
            if road == 0 {
                check(
                    fmi2SetReal(c, x_g.as_ptr(), 1, [road_input(t)].as_ptr()),
                    "fmi2SetReal",
                )?;
            }
            check(fmi2DoStep(c, t, step, 1), "fmi2DoStep")?;
            check(
                fmi2GetReal(c, read.as_ptr(), read.len(), values.as_mut_ptr()),
                "fmi2GetReal",
            )?;
        }
        check(fmi2Terminate(c), "fmi2Terminate")?;
        fmi2FreeInstance(c);
    }
    Ok(())
}

fn main() -> Result<(), String> {
    let guid = tdvass_fmi2::guid(Model::QuarterCar);
    // The default experiment (TDVASS on the harmonic road, 15 s of 1 ms
    // steps) weighs most, as it does in use; then points inside internal
    // steps, every output, the other variants and roads, the unilateral
    // tire and the road input, 1 s each.
    let mut runs = vec![
        (3, 1, 0, 1e-3, 15.0, Outputs::Rms),
        (3, 1, 0, 1e-3, 15.0, Outputs::Instantaneous),
        (3, 1, 0, 7e-4, 5.0, Outputs::Rms),
        (3, 1, 0, 7e-4, 1.0, Outputs::AllReal),
        (3, 1, 1, 1e-3, 1.0, Outputs::Rms),
        (3, 2, 1, 1e-3, 1.0, Outputs::Instantaneous),
        (3, 0, 0, 1e-3, 1.0, Outputs::Rms),
        (3, 0, 0, 7e-4, 1.0, Outputs::Instantaneous),
    ];
    for road in [2, 3] {
        for variant in [1, 2, 3] {
            runs.push((variant, road, 0, 1e-3, 1.0, Outputs::Rms));
        }
    }
    for variant in [1, 2] {
        runs.push((variant, 1, 0, 1e-3, 1.0, Outputs::Instantaneous));
    }
    for r in &runs {
        run(r, &guid)?;
    }
    Ok(())
}
