//! Runs `tdvass.fmu` through the Rust [`fmi`] crate, an FMI 2.0 importer
//! written independently of this project, and writes the outputs at every
//! communication point as CSV (shortest round-trip decimal, so the values
//! are exact). tests/interop/test_fmi_rs.py compares them with fmpy's.
//!
//! ```text
//! interop-fmi-rs FMU EXPERIMENT_JSON OUTPUT_CSV
//! ```
//!
//! `EXPERIMENT_JSON` (tests/interop/interop.py `Experiment.to_json`):
//! `{"stop_time": 15, "step_size": 0.001, "start_values": {"variant": 1},
//! "source": null | {start values}, "outputs": ["x_s", ...]}`; a missing
//! `stop_time` or `step_size` is taken from the `DefaultExperiment`. With a
//! `source`, a second instance (those start values) drives the input `x_g`
//! of the first through its `road_displacement`, Jacobi style: the value at
//! the start of each communication step is held over it.
//!
//! The communication points are `t_k = k * step_size`, as fmpy's.

use fmi::fmi2::import::Fmi2Import;
use fmi::fmi2::instance::{CoSimulation, Common, InstanceCS};
use fmi::fmi2::schema::{Causality, ScalarVariableElement};
use fmi::traits::{FmiImport, FmiInstance};
use serde_json::Value;
use std::io::Write;
use std::process::ExitCode;

type Error = Box<dyn std::error::Error>;

/// The importer's version (pinned in Cargo.toml).
const FMI_CRATE: &str = "0.8.0";

/// Value reference and whether the variable is an Integer (else a Real).
fn variable(import: &Fmi2Import, name: &str) -> Result<(u32, bool), Error> {
    let var = import
        .model_description()
        .model_variable_by_name(name)
        .map_err(|e| format!("variable `{name}`: {e}"))?;
    let integer = match var.elem {
        ScalarVariableElement::Integer(_) => true,
        ScalarVariableElement::Real(_) => false,
        _ => return Err(format!("`{name}` is neither Real nor Integer").into()),
    };
    Ok((var.value_reference, integer))
}

/// Instantiates, sets the start values and initializes up to `stop_time`.
fn start(
    import: &Fmi2Import,
    name: &str,
    start_values: &serde_json::Map<String, Value>,
    stop_time: f64,
) -> Result<InstanceCS, Error> {
    let mut instance = import.instantiate_cs(name, false, false)?;
    for (key, value) in start_values {
        let (vr, integer) = variable(import, key)?;
        if integer {
            let v = value
                .as_i64()
                .ok_or(format!("`{key}`: expected an integer"))?;
            instance.set_integer(&[vr], &[i32::try_from(v)?])?;
        } else {
            let v = value
                .as_f64()
                .ok_or(format!("`{key}`: expected a number"))?;
            instance.set_real(&[vr], &[v])?;
        }
    }
    // The crate's enter_initialization_mode calls fmi2SetupExperiment first.
    FmiInstance::enter_initialization_mode(&mut instance, None, 0.0, Some(stop_time))?;
    Common::exit_initialization_mode(&mut instance)?;
    Ok(instance)
}

fn run(fmu: &str, experiment: &str, output: &str) -> Result<(), Error> {
    let experiment: Value = serde_json::from_str(experiment)?;
    let import: Fmi2Import = fmi::import::from_path(fmu)?;
    let md = import.model_description();
    eprintln!(
        "interop-fmi-rs: fmi {} loaded {} (FMI {}, GUID {}, {} variables)",
        FMI_CRATE,
        md.model_name,
        md.fmi_version,
        md.guid,
        md.get_model_variables().count()
    );
    let default = md.default_experiment.as_ref();
    let stop_time = match experiment["stop_time"].as_f64() {
        Some(t) => t,
        None => default.and_then(|d| d.stop_time).ok_or("no stop time")?,
    };
    let step = match experiment["step_size"].as_f64() {
        Some(h) => h,
        None => default.and_then(|d| d.step_size).ok_or("no step size")?,
    };
    let no_values = serde_json::Map::new();
    let start_values = experiment["start_values"].as_object().unwrap_or(&no_values);
    let outputs: Vec<&str> = experiment["outputs"]
        .as_array()
        .ok_or("no outputs")?
        .iter()
        .map(|v| v.as_str().ok_or("output names are strings"))
        .collect::<Result<_, _>>()?;
    let mut output_vrs = Vec::new();
    for name in &outputs {
        let var = md.model_variable_by_name(name)?;
        if var.causality != Causality::Output {
            return Err(format!("`{name}` is not an output").into());
        }
        output_vrs.push(var.value_reference);
    }

    let mut sink = start(&import, "sink", start_values, stop_time)?;
    let mut source = match experiment["source"].as_object() {
        Some(values) => Some(start(&import, "source", values, stop_time)?),
        None => None,
    };
    let (x_g, _) = variable(&import, "x_g")?;
    let (road, _) = variable(&import, "road_displacement")?;

    let mut file = std::io::BufWriter::new(std::fs::File::create(output)?);
    writeln!(file, "time,{}", outputs.join(","))?;
    let n = (stop_time / step).round() as u64;
    let mut values = vec![0.0; outputs.len()];
    let mut t = 0.0;
    for k in 1..=n {
        let next = k as f64 * step;
        if let Some(source) = source.as_mut() {
            let mut x = [0.0];
            source.get_real(&[road], &mut x)?;
            sink.set_real(&[x_g], &x)?;
            source.do_step(t, next - t, true)?;
        }
        sink.do_step(t, next - t, true)?;
        sink.get_real(&output_vrs, &mut values)?;
        write!(file, "{next:e}")?;
        for v in &values {
            write!(file, ",{v:e}")?;
        }
        writeln!(file)?;
        t = next;
    }
    file.flush()?;
    Common::terminate(&mut sink)?;
    if let Some(source) = source.as_mut() {
        Common::terminate(source)?;
    }
    Ok(())
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().collect();
    if args.len() != 4 {
        eprintln!("usage: interop-fmi-rs FMU EXPERIMENT_JSON OUTPUT_CSV");
        return ExitCode::from(2);
    }
    match run(&args[1], &args[2], &args[3]) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("interop-fmi-rs: {e}");
            ExitCode::FAILURE
        }
    }
}
