//! The reference results each FMU carries (the FMI layered standard
//! FMI-LS-REF): `extra/org.fmi-standard.fmi-ls-ref/fmi-ls-manifest.xml`
//! names `tdvass_out.csv` beside it, the outputs of the default experiment.
//!
//! The results are computed here, at build time, by the same slave the FMU's
//! shared library wraps ([`tdvass_fmu::Slave`], of the FMU's model, in the
//! FMI version's dialect), driven as a master drives the FMU: the start
//! values of the variable table, the DefaultExperiment's start and stop
//! time and tolerance, and communication steps of [`OUTPUT_INTERVAL`] from
//! `start + k·interval` to `start + (k+1)·interval`. Every output is written
//! in Rust's shortest representation that reads back to the same `f64`.
//!
//! The corner's ([`Model::Corner`]) inputs stay at their start values too:
//! the body's attachment point at rest at the static equilibrium
//! (`body_displacement` = `body_velocity` = 0), so that its results are the
//! suspension under a fixed body on the default harmonic road.
//!
//! The chassis's ([`Model::Chassis`]) forces stay at their start values
//! (0): it rests at its static equilibrium, and every column of its
//! results is 0.

use quick_xml::events::{BytesDecl, Event};
use std::cell::RefCell;
use std::rc::Rc;
use tdvass_describe::markup::{XmlResult, XmlWriter, finish, writer};
use tdvass_fmu::Model;
use tdvass_fmu::slave::{Dialect, Logger};
use tdvass_fmu::variables::{Causality, VarType, Variable, variables_of};
use tdvass_fmu::{
    DEFAULT_START_TIME, DEFAULT_STOP_TIME, FmiError, MODEL_IDENTIFIER, Slave, Status,
};

/// The layered standard's folder inside the FMU.
pub const DIRECTORY: &str = "extra/org.fmi-standard.fmi-ls-ref";
/// The layered standard's name, as the manifest declares it.
pub const LAYERED_STANDARD: &str = "org.fmi-standard.fmi-ls-ref";
/// The version of FMI-LS-REF the manifest follows.
pub const LAYERED_STANDARD_VERSION: &str = "1.0.0-alpha.1";
/// The namespace of the attributes every layered standard's manifest has.
pub const MANIFEST_NAMESPACE: &str = "http://fmi-standard.org/fmi-ls-manifest";
/// Output interval of the reference results (s): 301 rows over the
/// default experiment's 15 s (25 per period of the harmonic road), about
/// 130 kB of CSV, a fifth of that compressed.
pub const OUTPUT_INTERVAL: f64 = 0.05;

/// The manifest's path in the FMU.
pub fn manifest_entry() -> String {
    format!("{DIRECTORY}/fmi-ls-manifest.xml")
}

/// The results' file name, `<modelIdentifier>_out.csv`.
pub fn csv_name() -> String {
    format!("{MODEL_IDENTIFIER}_out.csv")
}

/// The results' path in the FMU.
pub fn csv_entry() -> String {
    format!("{DIRECTORY}/{}", csv_name())
}

/// `fmi-ls-manifest.xml`: one related file, the results of the default
/// experiment.
pub fn manifest_xml() -> String {
    let mut w = writer();
    let write = |w: &mut XmlWriter| -> XmlResult {
        w.write_event(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None)))?;
        let description = format!(
            "Outputs of the default experiment ({DEFAULT_START_TIME} s to {DEFAULT_STOP_TIME} s, start values, DefaultExperiment tolerance) every {OUTPUT_INTERVAL} s, computed by the slave this FMU's binaries wrap"
        );
        w.create_element("fmiReferences")
            .with_attribute(("xmlns:fmi-ls", MANIFEST_NAMESPACE))
            .with_attribute(("fmi-ls:fmi-ls-name", LAYERED_STANDARD))
            .with_attribute(("fmi-ls:fmi-ls-version", LAYERED_STANDARD_VERSION))
            .with_attribute((
                "fmi-ls:fmi-ls-description",
                "Reference results of the FMU, for checking an import against the exporter's own numbers",
            ))
            .write_inner_content(|w| {
                w.create_element("Related")
                    .with_attribute(("type", "text/csv"))
                    .with_attribute(("source", csv_name().as_str()))
                    .with_attribute(("role", "result"))
                    .with_attribute(("description", description.as_str()))
                    .write_empty()?;
                Ok(())
            })?;
        Ok(())
    };
    write(&mut w).expect("writing to memory cannot fail");
    finish(w)
}

/// The outputs of the reference results: every scalar Real (Float64)
/// output of `model` in the FMI version, in the order of its variables.
pub fn outputs(model: Model, dialect: &Dialect) -> Vec<&'static Variable> {
    variables_of(model, dialect.version)
        .iter()
        .filter(|v| {
            v.causality == Causality::Output
                && v.var_type() == VarType::Real
                && v.dimensions.is_empty()
        })
        .collect()
}

/// `v` in the shorter of Rust's two shortest round-trip forms (`0.01`,
/// `1.2e-7`): reading it back gives the same `f64`.
pub fn number(v: f64) -> String {
    let plain = format!("{v}");
    let scientific = format!("{v:e}");
    if scientific.len() < plain.len() {
        scientific
    } else {
        plain
    }
}

/// The time of communication point `k`, as a master computes it.
pub fn time_of(k: usize) -> f64 {
    DEFAULT_START_TIME + k as f64 * OUTPUT_INTERVAL
}

/// Number of communication steps of the default experiment.
pub fn step_count() -> usize {
    ((DEFAULT_STOP_TIME - DEFAULT_START_TIME) / OUTPUT_INTERVAL).round() as usize
}

/// The reference results of the FMU of `model` speaking `dialect` whose
/// serialized states carry `token`, as CSV: a header `time,<output>,...`
/// and one row per communication point from the start to the stop time.
/// Any status other than OK, and any message the slave logs, is an error.
pub fn results_csv(model: Model, dialect: Dialect, token: String) -> Result<String, String> {
    let log: Rc<RefCell<Vec<String>>> = Rc::default();
    let sink = {
        let log = Rc::clone(&log);
        Box::new(move |status: Status, category: &str, message: &str| {
            log.borrow_mut()
                .push(format!("{} [{category}] {message}", status.name()))
        })
    };
    let mut slave = Slave::new(dialect, model, token, Logger::new(sink, false));
    let outputs = outputs(model, &dialect);
    let vrs: Vec<u32> = outputs.iter().map(|v| v.vr).collect();
    let mut values = vec![0.0; vrs.len()];
    let mut csv = String::from("time");
    for v in &outputs {
        csv.push(',');
        csv.push_str(v.name);
    }
    csv.push('\n');
    let context = |what: &str, result: Result<Status, FmiError>| -> Result<(), String> {
        match result {
            Ok(Status::Ok) => Ok(()),
            Ok(status) => Err(format!("{what} returned {}", status.name())),
            Err(e) => Err(format!("{what} failed: {e}")),
        }
    };
    context(
        "the experiment set-up",
        slave.setup_experiment(
            Some(tdvass::solver::DEFAULT_TOLERANCE),
            DEFAULT_START_TIME,
            Some(DEFAULT_STOP_TIME),
        ),
    )?;
    context("entering initialization", slave.enter_initialization_mode())?;
    context("leaving initialization", slave.exit_initialization_mode())?;
    let steps = step_count();
    for k in 0..=steps {
        if k > 0 {
            let from = time_of(k - 1);
            context(
                &format!("the step from {from} s"),
                slave.do_step(from, time_of(k) - from),
            )?;
        }
        context(
            &format!("reading the outputs at {} s", time_of(k)),
            slave.get_real(&vrs, &mut values),
        )?;
        csv.push_str(&number(time_of(k)));
        for value in &values {
            csv.push(',');
            csv.push_str(&number(*value));
        }
        csv.push('\n');
    }
    let log = log.borrow();
    if !log.is_empty() {
        return Err(format!("the default experiment logged: {}", log.join("; ")));
    }
    Ok(csv)
}
