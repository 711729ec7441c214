//! Runs `tdvass.fmu` (FMI 2.0) or `tdvass-fmi3.fmu` (FMI 3.0 Co-Simulation)
//! through the Rust [`fmi`] crate, an importer written independently of this
//! project, and writes the outputs at every communication point as CSV
//! (shortest round-trip decimal, so the values are exact).
//! tests/interop/test_fmi_rs.py compares them with fmpy's.
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
//! The FMI version is read from the FMU's modelDescription.xml. FMI 3.0
//! start values are set by type: Float64, Int32, and Int64 for the
//! Enumerations (`variant`, `road`, `road_class`: FMI 3.0 gets and sets
//! enumerations as Int64, by their integer codes). The crate's schema 0.8.0
//! has no `<Enumeration>` variable element and drops those variables from
//! `model_variables`, so their value references come in the experiment as
//! `"enumerations": {"variant": 1, ...}` (read from modelDescription.xml by
//! the test); a name the crate does know is never taken from there.
//!
//! The communication points are `t_k = k * step_size`, as fmpy's.

use fmi::fmi2::import::Fmi2Import;
use fmi::fmi2::instance::{CoSimulation as _, Common as Common2, InstanceCS as Instance2};
use fmi::fmi2::schema::{Causality as Causality2, ScalarVariableElement};
use fmi::fmi3::import::Fmi3Import;
use fmi::fmi3::instance::InstanceCS as Instance3;
use fmi::fmi3::schema::{Causality as Causality3, VariableType};
use fmi::fmi3::{CoSimulation as _, Common as Common3, Fmi3Model, GetSet as _};
use fmi::schema::MajorVersion;
use fmi::schema::traits::FmiModelDescription;
use fmi::traits::{FmiImport, FmiInstance};
use serde_json::{Map, Value};
use std::io::Write;
use std::process::ExitCode;

type Error = Box<dyn std::error::Error>;

/// The importer's version (pinned in Cargo.toml).
const FMI_CRATE: &str = "0.8.0";

/// The experiment of `EXPERIMENT_JSON`.
struct Experiment {
    stop_time: Option<f64>,
    step_size: Option<f64>,
    start_values: Map<String, Value>,
    source: Option<Map<String, Value>>,
    outputs: Vec<String>,
    /// FMI 3.0: value references of Enumeration variables by name.
    enumerations: Map<String, Value>,
}

impl Experiment {
    fn parse(json: &str) -> Result<Self, Error> {
        let value: Value = serde_json::from_str(json)?;
        let object = |key: &str| value[key].as_object().cloned();
        let outputs = value["outputs"]
            .as_array()
            .ok_or("no outputs")?
            .iter()
            .map(|v| {
                v.as_str()
                    .map(str::to_owned)
                    .ok_or("output names are strings")
            })
            .collect::<Result<_, _>>()?;
        Ok(Self {
            stop_time: value["stop_time"].as_f64(),
            step_size: value["step_size"].as_f64(),
            start_values: object("start_values").unwrap_or_default(),
            source: object("source"),
            outputs,
            enumerations: object("enumerations").unwrap_or_default(),
        })
    }

    /// Stop time and step size, from the `DefaultExperiment` where missing.
    fn times(&self, default: (Option<f64>, Option<f64>)) -> Result<(f64, f64), Error> {
        let stop_time = self.stop_time.or(default.0).ok_or("no stop time")?;
        let step = self.step_size.or(default.1).ok_or("no step size")?;
        Ok((stop_time, step))
    }
}

/// Writes the CSV header and, after each communication step, a row.
struct Table(std::io::BufWriter<std::fs::File>);

impl Table {
    fn create(path: &str, outputs: &[String]) -> Result<Self, Error> {
        let mut file = std::io::BufWriter::new(std::fs::File::create(path)?);
        writeln!(file, "time,{}", outputs.join(","))?;
        Ok(Self(file))
    }

    fn row(&mut self, time: f64, values: &[f64]) -> Result<(), Error> {
        write!(self.0, "{time:e}")?;
        for v in values {
            write!(self.0, ",{v:e}")?;
        }
        writeln!(self.0)?;
        Ok(())
    }
}

// ------------------------------------------------------------------ FMI 2.0

/// Value reference and whether the variable is an Integer (else a Real).
fn variable2(import: &Fmi2Import, name: &str) -> Result<(u32, bool), Error> {
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
fn start2(
    import: &Fmi2Import,
    name: &str,
    start_values: &Map<String, Value>,
    stop_time: f64,
) -> Result<Instance2, Error> {
    let mut instance = import.instantiate_cs(name, false, false)?;
    for (key, value) in start_values {
        let (vr, integer) = variable2(import, key)?;
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
    Common2::exit_initialization_mode(&mut instance)?;
    Ok(instance)
}

fn run_fmi2(fmu: &str, experiment: &Experiment, output: &str) -> Result<(), Error> {
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
    let (stop_time, step) = experiment.times((
        default.and_then(|d| d.stop_time),
        default.and_then(|d| d.step_size),
    ))?;
    let mut output_vrs = Vec::new();
    for name in &experiment.outputs {
        let var = md.model_variable_by_name(name)?;
        if var.causality != Causality2::Output {
            return Err(format!("`{name}` is not an output").into());
        }
        output_vrs.push(var.value_reference);
    }

    let mut sink = start2(&import, "sink", &experiment.start_values, stop_time)?;
    let mut source = match &experiment.source {
        Some(values) => Some(start2(&import, "source", values, stop_time)?),
        None => None,
    };
    let (x_g, _) = variable2(&import, "x_g")?;
    let (road, _) = variable2(&import, "road_displacement")?;

    let mut table = Table::create(output, &experiment.outputs)?;
    let n = (stop_time / step).round() as u64;
    let mut values = vec![0.0; output_vrs.len()];
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
        table.row(next, &values)?;
        t = next;
    }
    table.0.flush()?;
    Common2::terminate(&mut sink)?;
    if let Some(source) = source.as_mut() {
        Common2::terminate(source)?;
    }
    Ok(())
}

// ------------------------------------------------------------------ FMI 3.0

/// Value reference and type of an FMI 3.0 variable: the crate's, or for a
/// variable it does not list, an Enumeration of the experiment's
/// `enumerations` (Int64 in the C API).
fn variable3(
    import: &Fmi3Import,
    experiment: &Experiment,
    name: &str,
) -> Result<(u32, VariableType), Error> {
    let variables = &import.model_description().model_variables;
    if let Some(var) = variables.find_by_name(name) {
        return Ok((var.value_reference(), var.data_type()));
    }
    match experiment.enumerations.get(name).and_then(Value::as_u64) {
        Some(vr) => Ok((u32::try_from(vr)?, VariableType::FmiInt64)),
        None => Err(format!("no variable `{name}`").into()),
    }
}

/// Instantiates (no event mode, no early return, no intermediate update),
/// sets the start values and initializes up to `stop_time`.
fn start3(
    import: &Fmi3Import,
    experiment: &Experiment,
    name: &str,
    start_values: &Map<String, Value>,
    stop_time: f64,
) -> Result<Instance3, Error> {
    let mut instance = import.instantiate_cs(name, false, false, false, false, &[])?;
    for (key, value) in start_values {
        let integer = || {
            value
                .as_i64()
                .ok_or(format!("`{key}`: expected an integer"))
        };
        match variable3(import, experiment, key)? {
            (vr, VariableType::FmiInt64) => instance.set_int64(&[vr], &[integer()?])?,
            (vr, VariableType::FmiInt32) => {
                instance.set_int32(&[vr], &[i32::try_from(integer()?)?])?
            }
            (vr, VariableType::FmiFloat64) => {
                let v = value
                    .as_f64()
                    .ok_or(format!("`{key}`: expected a number"))?;
                instance.set_float64(&[vr], &[v])?
            }
            (_, other) => return Err(format!("`{key}`: cannot set a {other:?}").into()),
        };
    }
    Common3::enter_initialization_mode(&mut instance, None, 0.0, Some(stop_time))?;
    Common3::exit_initialization_mode(&mut instance)?;
    Ok(instance)
}

/// One fmi3DoStep that must reach `t + h`: no early return, no event, no
/// request to terminate.
fn step3(instance: &mut Instance3, t: f64, h: f64) -> Result<(), Error> {
    let (mut event, mut terminate, mut early, mut last) = (false, false, false, f64::NAN);
    instance.do_step(
        t,
        h,
        true,
        &mut event,
        &mut terminate,
        &mut early,
        &mut last,
    )?;
    if event || terminate || early || last != t + h {
        return Err(format!(
            "fmi3DoStep({t}, {h}): eventHandlingNeeded {event}, terminateSimulation \
             {terminate}, earlyReturn {early}, lastSuccessfulTime {last}"
        )
        .into());
    }
    Ok(())
}

fn run_fmi3(fmu: &str, experiment: &Experiment, output: &str) -> Result<(), Error> {
    let import: Fmi3Import = fmi::import::from_path(fmu)?;
    let md = import.model_description();
    eprintln!(
        "interop-fmi-rs: fmi {} loaded {} (FMI {}, instantiationToken {}, {} variables)",
        FMI_CRATE,
        md.model_name,
        md.fmi_version,
        md.instantiation_token,
        md.model_variables.len()
    );
    let default = md.default_experiment.as_ref();
    let (stop_time, step) = experiment.times((
        default.and_then(|d| d.stop_time),
        default.and_then(|d| d.step_size),
    ))?;
    let mut output_vrs = Vec::new();
    for name in &experiment.outputs {
        let var = md
            .model_variables
            .find_by_name(name)
            .ok_or(format!("no variable `{name}`"))?;
        if var.causality() != Causality3::Output || var.data_type() != VariableType::FmiFloat64 {
            return Err(format!("`{name}` is not a Float64 output").into());
        }
        output_vrs.push(var.value_reference());
    }

    let mut sink = start3(
        &import,
        experiment,
        "sink",
        &experiment.start_values,
        stop_time,
    )?;
    let mut source = match &experiment.source {
        Some(values) => Some(start3(&import, experiment, "source", values, stop_time)?),
        None => None,
    };
    let (x_g, _) = variable3(&import, experiment, "x_g")?;
    let (road, _) = variable3(&import, experiment, "road_displacement")?;

    let mut table = Table::create(output, &experiment.outputs)?;
    let n = (stop_time / step).round() as u64;
    let mut values = vec![0.0; output_vrs.len()];
    let mut t = 0.0;
    for k in 1..=n {
        let next = k as f64 * step;
        if let Some(source) = source.as_mut() {
            let mut x = [0.0];
            source.get_float64(&[road], &mut x)?;
            sink.set_float64(&[x_g], &x)?;
            step3(source, t, next - t)?;
        }
        step3(&mut sink, t, next - t)?;
        sink.get_float64(&output_vrs, &mut values)?;
        table.row(next, &values)?;
        t = next;
    }
    table.0.flush()?;
    Common3::terminate(&mut sink)?;
    if let Some(source) = source.as_mut() {
        Common3::terminate(source)?;
    }
    Ok(())
}

fn run(fmu: &str, experiment: &str, output: &str) -> Result<(), Error> {
    let experiment = Experiment::parse(experiment)?;
    match fmi::import::peek_descr_path(fmu)?.major_version()? {
        MajorVersion::FMI2 => run_fmi2(fmu, &experiment, output),
        MajorVersion::FMI3 => run_fmi3(fmu, &experiment, output),
        other => Err(format!("unsupported FMI version {other}").into()),
    }
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
