//! The FMI 2.0 `modelDescription.xml` and `documentation/index.html`,
//! generated from the variable table with quick-xml (no markup is written
//! by hand, so every value is escaped). The output is deterministic: no
//! timestamps. Each model ([`Model`]) has its own, with Model Exchange
//! beside Co-Simulation over its own continuous states
//! ([`Model::continuous_states`]; the corner's and the chassis's without
//! directional derivatives, [`model_exchange_capabilities`]), the
//! chassis's with Co-Simulation capabilities of its own
//! ([`co_simulation_capabilities`]).

use crate::component::{ComponentPage, component_page};
use crate::markup::{
    DescriptionFrame, MODEL_DESCRIPTION, REFERENCE_RESULTS, TIRE_CONTACT, XmlResult, XmlWriter,
    diagram, html_page, list, model_description, model_exchange_text, number, paragraph,
    text_element, typed_in_use, unit_text, variable_table,
};
use quick_xml::events::{BytesText, Event};
use tdvass::exchange::EVENT_INDICATORS;
use tdvass_fmi2::FMI_VERSION;
use tdvass_fmu::Model;
use tdvass_fmu::variables::{
    Access, Causality, FmiVersion, Quantity, VarType, Variable, variables_of,
};
use tdvass_fmu::{
    DEFAULT_START_TIME, DEFAULT_STEP_SIZE, DEFAULT_STOP_TIME, MODEL_IDENTIFIER, MODEL_NAME, guid,
};

fn start_text(v: &Variable) -> Option<String> {
    v.start.map(|s| match v.var_type() {
        VarType::Integer => format!("{}", s as i64),
        _ => number(s),
    })
}

fn bound_text(v: &Variable, b: Option<f64>) -> Option<String> {
    b.map(|b| match v.var_type() {
        VarType::Integer => format!("{}", b as i64),
        _ => number(b),
    })
}

/// The typed quantities the FMI 2.0 variables of `model` declare (every
/// variable of a typed quantity has its `declaredType`).
fn quantities(model: Model) -> Vec<Quantity> {
    typed_in_use(
        variables_of(model, FmiVersion::Fmi2)
            .iter()
            .map(|v| v.quantity),
    )
}

/// `TypeDefinitions`: a `SimpleType` of each of `quantities`.
fn write_type_definitions(w: &mut XmlWriter, quantities: &[Quantity]) -> XmlResult {
    w.create_element("TypeDefinitions")
        .write_inner_content(|w| {
            for q in quantities {
                let (name, quantity, unit) = q.type_definition().expect("typed quantity");
                w.create_element("SimpleType")
                    .with_attribute(("name", name))
                    .write_inner_content(|w| {
                        w.create_element("Real")
                            .with_attribute(("quantity", quantity))
                            .with_attribute(("unit", unit))
                            .write_empty()?;
                        Ok(())
                    })?;
            }
            Ok(())
        })?;
    Ok(())
}

fn write_variable(w: &mut XmlWriter, model: Model, v: &Variable) -> XmlResult {
    let vr = v.vr.to_string();
    let mut element = w
        .create_element("ScalarVariable")
        .with_attribute(("name", v.name))
        .with_attribute(("valueReference", vr.as_str()))
        .with_attribute(("description", v.description))
        .with_attribute(("causality", v.causality.as_str()))
        .with_attribute(("variability", v.variability.as_str()));
    if let Some(initial) = v.initial() {
        element = element.with_attribute(("initial", initial.as_str()));
    }
    element.write_inner_content(|w| {
        let mut attributes: Vec<(&str, String)> = Vec::new();
        if let Some((type_name, _, unit)) = v.quantity.type_definition() {
            attributes.push(("declaredType", type_name.into()));
            attributes.push(("unit", unit.into()));
        }
        if let Some(display) = v.display_unit {
            attributes.push(("displayUnit", display.into()));
        }
        let (min, max) = v.range.bounds();
        if let Some(min) = bound_text(v, min) {
            attributes.push(("min", min));
        }
        if let Some(max) = bound_text(v, max) {
            attributes.push(("max", max));
        }
        if let Some(start) = start_text(v) {
            attributes.push(("start", start));
        }
        if let Access::StateDerivative(i) = v.access {
            attributes.push(("derivative", state_index(model, i).to_string()));
        }
        w.create_element(v.var_type().as_str())
            .with_attributes(attributes.iter().map(|(k, v)| (*k, v.as_str())))
            .write_empty()?;
        Ok(())
    })?;
    Ok(())
}

/// The 1-based index of the variable of `model` called `name` in FMI 2.0's
/// `ModelVariables`, by which `ModelStructure` refers to it.
fn index_of(model: Model, name: &str) -> Option<usize> {
    variables_of(model, FmiVersion::Fmi2)
        .iter()
        .position(|v| v.name == name)
        .map(|i| i + 1)
}

/// The 1-based index of continuous state `i`'s variable: a local
/// ([`Access::ContinuousState`]) or an output (`x_s` .. `v_t`,
/// `contact_loss_time`); the `derivative` attribute of `der(...)`.
fn state_index(model: Model, i: usize) -> usize {
    variables_of(model, FmiVersion::Fmi2)
        .iter()
        .position(|v| v.state_index() == Some(i))
        .map(|p| p + 1)
        .unwrap_or_else(|| panic!("no variable of continuous state {i}"))
}

/// An output's `dependencies` (1-based indices, ascending) and their
/// `dependenciesKind`: the inputs it feeds through (`fixed`: `x_g`, the
/// corner's body inputs), the continuous states it is computed from
/// (`dependent`; a model with Model Exchange only).
fn output_dependencies(model: Model, v: &Variable) -> (String, String) {
    let mut found: Vec<(usize, &str)> = v
        .output_dependencies(model, FmiVersion::Fmi2)
        .into_iter()
        .map(|(known, kind)| {
            let index = index_of(model, known.name)
                .unwrap_or_else(|| panic!("unknown dependency `{}`", known.name));
            (index, kind.name())
        })
        .collect();
    found.sort_unstable();
    let join = |parts: Vec<String>| parts.join(" ");
    (
        join(found.iter().map(|(i, _)| i.to_string()).collect()),
        join(found.iter().map(|(_, k)| k.to_string()).collect()),
    )
}

fn indices(model: Model, names: &[&str]) -> String {
    let mut idx: Vec<usize> = names
        .iter()
        .map(|n| index_of(model, n).unwrap_or_else(|| panic!("unknown dependency `{n}`")))
        .collect();
    idx.sort_unstable();
    idx.iter()
        .map(|i| i.to_string())
        .collect::<Vec<_>>()
        .join(" ")
}

/// `ModelStructure`: the outputs, the derivatives (a model with Model
/// Exchange only) and the initial unknowns.
fn write_model_structure(w: &mut XmlWriter, model: Model) -> XmlResult {
    let variables = variables_of(model, FmiVersion::Fmi2);
    w.create_element("ModelStructure")
        .write_inner_content(|w| {
            w.create_element("Outputs").write_inner_content(|w| {
                for (i, v) in variables.iter().enumerate() {
                    if v.causality != Causality::Output {
                        continue;
                    }
                    let (dependencies, kinds) = output_dependencies(model, v);
                    let mut unknown = w
                        .create_element("Unknown")
                        .with_attribute(("index", (i + 1).to_string().as_str()))
                        .with_attribute(("dependencies", dependencies.as_str()));
                    if !kinds.is_empty() {
                        unknown = unknown.with_attribute(("dependenciesKind", kinds.as_str()));
                    }
                    unknown.write_empty()?;
                }
                Ok(())
            })?;
            // In the order of the continuous states (FMI 2.0: the order of
            // the Unknowns is that of fmi2GetContinuousStates); each depends
            // on every known (no `dependencies`).
            if model.offers_model_exchange() {
                w.create_element("Derivatives").write_inner_content(|w| {
                    for &i in model.continuous_states() {
                        let index = variables
                            .iter()
                            .position(|v| matches!(v.access, Access::StateDerivative(j) if j == i))
                            .expect("every state has a derivative")
                            + 1;
                        w.create_element("Unknown")
                            .with_attribute(("index", index.to_string().as_str()))
                            .write_empty()?;
                    }
                    Ok(())
                })?;
            }
            w.create_element("InitialUnknowns")
                .write_inner_content(|w| {
                    for (i, v) in variables.iter().enumerate() {
                        let unknown = w
                            .create_element("Unknown")
                            .with_attribute(("index", (i + 1).to_string().as_str()));
                        match v.access {
                            // The local states and the derivatives depend on
                            // every known of initialization (no `dependencies`).
                            Access::ContinuousState(_) | Access::StateDerivative(_) => {
                                unknown.write_empty()?;
                            }
                            _ if matches!(
                                v.causality,
                                Causality::Output | Causality::CalculatedParameter
                            ) =>
                            {
                                unknown
                                    .with_attribute((
                                        "dependencies",
                                        indices(model, v.initial_dependencies).as_str(),
                                    ))
                                    .write_empty()?;
                            }
                            _ => {}
                        }
                    }
                    Ok(())
                })?;
            Ok(())
        })?;
    Ok(())
}

/// The attributes of the `ModelExchange` element after `modelIdentifier`,
/// in the order written: `fmi2CompletedIntegratorStep` is wanted (a master
/// that calls it at its accepted steps keeps its method's order, and the
/// delay history its bound: docs/fmu.md, "Model Exchange"); exact
/// directional derivatives of the state derivatives and the outputs.
pub const MODEL_EXCHANGE_CAPABILITIES: [(&str, &str); 7] = [
    ("needsExecutionTool", "false"),
    ("completedIntegratorStepNotNeeded", "false"),
    ("canBeInstantiatedOnlyOncePerProcess", "false"),
    ("canNotUseMemoryManagementFunctions", "true"),
    ("canGetAndSetFMUstate", "true"),
    ("canSerializeFMUstate", "true"),
    ("providesDirectionalDerivative", "true"),
];

/// The chassis's `ModelExchange` attributes ([`Model::Chassis`]): no
/// delay history, so completed integrator steps are not needed; exact
/// directional derivatives of its derivatives and outputs.
pub const CHASSIS_MODEL_EXCHANGE_CAPABILITIES: [(&str, &str); 7] = [
    ("needsExecutionTool", "false"),
    ("completedIntegratorStepNotNeeded", "true"),
    ("canBeInstantiatedOnlyOncePerProcess", "false"),
    ("canNotUseMemoryManagementFunctions", "true"),
    ("canGetAndSetFMUstate", "true"),
    ("canSerializeFMUstate", "true"),
    ("providesDirectionalDerivative", "true"),
];

/// The `ModelExchange` attributes of `model` after `modelIdentifier`.
pub fn model_exchange_capabilities(model: Model) -> &'static [(&'static str, &'static str)] {
    match model {
        Model::QuarterCar | Model::Corner => &MODEL_EXCHANGE_CAPABILITIES,
        Model::Chassis => &CHASSIS_MODEL_EXCHANGE_CAPABILITIES,
    }
}

/// The attributes of the `CoSimulation` element after `modelIdentifier`,
/// in the order written: the capabilities the C interface provides (the
/// quarter car's and the corner's).
pub const CO_SIMULATION_CAPABILITIES: [(&str, &str); 9] = [
    ("needsExecutionTool", "false"),
    ("canHandleVariableCommunicationStepSize", "true"),
    ("canInterpolateInputs", "true"),
    ("maxOutputDerivativeOrder", "1"),
    ("canBeInstantiatedOnlyOncePerProcess", "false"),
    ("canNotUseMemoryManagementFunctions", "true"),
    ("canGetAndSetFMUstate", "true"),
    ("canSerializeFMUstate", "true"),
    ("providesDirectionalDerivative", "true"),
];

/// The chassis's capabilities ([`Model::Chassis`]), in the order of
/// [`CO_SIMULATION_CAPABILITIES`]: its step is a closed form for forces
/// linear in time, so it takes any step size and the forces' order-1
/// derivatives; it provides neither output nor directional derivatives.
pub const CHASSIS_CO_SIMULATION_CAPABILITIES: [(&str, &str); 9] = [
    ("needsExecutionTool", "false"),
    ("canHandleVariableCommunicationStepSize", "true"),
    ("canInterpolateInputs", "true"),
    ("maxOutputDerivativeOrder", "0"),
    ("canBeInstantiatedOnlyOncePerProcess", "false"),
    ("canNotUseMemoryManagementFunctions", "true"),
    ("canGetAndSetFMUstate", "true"),
    ("canSerializeFMUstate", "true"),
    ("providesDirectionalDerivative", "false"),
];

/// The `CoSimulation` attributes of `model` after `modelIdentifier`.
pub fn co_simulation_capabilities(model: Model) -> &'static [(&'static str, &'static str)] {
    match model {
        Model::Chassis => &CHASSIS_CO_SIMULATION_CAPABILITIES,
        Model::QuarterCar | Model::Corner => &CO_SIMULATION_CAPABILITIES,
    }
}

/// The complete `modelDescription.xml` of `model`: with `ModelExchange`
/// and `numberOfEventIndicators` when the model offers Model Exchange,
/// the types and units its variables use.
pub fn model_description_xml(model: Model) -> String {
    let guid = guid(model);
    let event_indicators = model.event_indicators().to_string();
    let model_exchange = model.offers_model_exchange();
    let event_indicators = [("numberOfEventIndicators", event_indicators.as_str())];
    let quantities = quantities(model);
    let frame = DescriptionFrame {
        fmi_version: FMI_VERSION,
        model,
        quantities: &quantities,
        token: ("guid", &guid),
        co_simulation: co_simulation_capabilities(model),
        model_exchange: model_exchange.then_some(model_exchange_capabilities(model)),
        root: if model_exchange {
            &event_indicators
        } else {
            &[]
        },
    };
    let write_types = |w: &mut XmlWriter| write_type_definitions(w, &quantities);
    model_description(frame, write_types, |w| {
        w.create_element("ModelVariables")
            .write_inner_content(|w| {
                for (i, v) in variables_of(model, FmiVersion::Fmi2).iter().enumerate() {
                    w.write_event(Event::Comment(BytesText::new(&format!(
                        " index {} ",
                        i + 1
                    ))))?;
                    write_variable(w, model, v)?;
                }
                Ok(())
            })?;
        write_model_structure(w, model)
    })
}

// ------------------------------------------------------------ documentation

fn variable_row(v: &Variable) -> Vec<String> {
    let range = v.range.describe();
    let kind = format!("{}, {}", v.causality.as_str(), v.variability.as_str());
    vec![
        v.name.to_string(),
        v.vr.to_string(),
        v.var_type().as_str().to_string(),
        kind,
        start_text(v).unwrap_or_else(|| "calculated".into()),
        unit_text(v),
        range,
        v.description.to_string(),
    ]
}

/// The complete `documentation/index.html` of `model`'s FMU.
pub fn documentation_html(model: Model) -> String {
    match model {
        Model::QuarterCar => html_page(&format!("{MODEL_NAME} FMU"), write_body),
        Model::Corner | Model::Chassis => component_page(&ComponentPage {
            model,
            version: FmiVersion::Fmi2,
            identity: format!(
                "GUID {} (a hash of the variable names, value references, types, causalities and variabilities)",
                guid(model)
            ),
            type_header: "type",
            rows: variables_of(model, FmiVersion::Fmi2)
                .iter()
                .map(variable_row)
                .collect(),
            after_variables: &|_| Ok(()),
            co_simulation: co_simulation_capabilities(model),
            model_exchange: model_exchange_capabilities(model),
            specification: "Functional Mock-up Interface for Model Exchange and Co-Simulation, version 2.0.",
        }),
    }
}

fn write_body(w: &mut XmlWriter) -> XmlResult {
    text_element(
        w,
        "h1",
        &format!("{MODEL_NAME}: FMI 2.0 FMU (Co-Simulation and Model Exchange)"),
    )?;
    paragraph(w, MODEL_DESCRIPTION)?;
    paragraph(
        w,
        &format!(
            "modelIdentifier {MODEL_IDENTIFIER}, GUID {} (a hash of the variable names, value references, types, causalities and variabilities), version {}.",
            guid(Model::QuarterCar),
            env!("CARGO_PKG_VERSION")
        ),
    )?;

    text_element(w, "h2", "The model")?;
    diagram(w, Model::QuarterCar)?;
    paragraph(
        w,
        "State X = [x_s, v_s, x_h, v_h, x_t, v_t]: body, annular absorber and wheel displacements and velocities. The plant is dX/dt = A X + b x_t(t - tau) + e x_g(t) (Eq. 2 of the paper): the body (m_s) sits on the absorber through k_s, c_s; the absorber (m_h) on the wheel through k_h, c_h; the wheel (m_t) on the road through k_t. TDVASS adds the control force u = g x_t(t - tau), acting with -u on the absorber and +u on the wheel. PVASS is the same structure with g = 0; CS is the conventional 2-DOF quarter car (body on wheel through k_s, c_s), for which x_h and v_h mirror x_t and v_t.",
    )?;
    paragraph(
        w,
        "Outputs: BA = d2x_s/dt2, SDD = x_s - x_t, TDD = x_t - x_g, their running RMS values from the start time t0 (time averages sqrt(integral of y^2 dt / (t - t0)), Eq. 6 with the mean taken over time) and J = w_ba RMS(BA) + w_sdd RMS(SDD) + w_tdd RMS(TDD) with TDD in metres.",
    )?;
    paragraph(
        w,
        "Integration: the precise (fine) integration method of the paper (section 4.1) on an internal grid anchored at the start time. The tolerance (relative, of every output metric: the master's from fmi2SetupExperiment when it defines one, else the DefaultExperiment's 1e-6) sets the internal step, from an error model checked by a step-doubling probe; the step divides tau exactly when tau is longer and is at most max_internal_step when that is > 0. The delayed wheel displacement is a cubic Hermite interpolant of the stored history, the road is exact over each internal step. Results do not depend on how the master splits time into communication steps (except with road = 0, where the input changes at communication points).",
    )?;
    paragraph(w, TIRE_CONTACT)?;
    text_element(w, "h3", "Static gain of the controlled suspension")?;
    paragraph(
        w,
        "The controller feeds back the absolute wheel displacement. This changes the static body gain: at zero frequency X_s/X_g = 1 - g/k_h (0.164 at g = 5386 N/m, k_h = 6444 N/m), so a slowly changing road (a ramp, a hill) moves the body by only a sixth of its height, and for g > k_h the body moves against the road. Keep this in mind for roads with a large low-frequency content.",
    )?;
    text_element(w, "h3", "Roads")?;
    list(
        w,
        &[
            "road = 0: the input x_g, set by the master at each communication point; with fmi2SetRealInputDerivatives (order 1) the FMU extrapolates it linearly over the step (until x_g or its slope is set again); fmi2SetReal on x_g resets the slope to 0. Without derivatives the input is held constant over each step, and TDD = x_t - x_g sampled where the held input jumps is biased by about half a step of road change; prefer input derivatives, or communication steps that do not coincide with the internal grid.",
            "road = 1: x_g = road_amplitude sin(road_angular_frequency t), the paper's 0.05 sin 5t by default (Table 2).",
            "road = 2: ISO 8608 filtered white noise dx_g/dt = -2 pi f0 x_g + 2 pi n0 sqrt(Gq(n0) u) w(t), class road_class, speed vehicle_speed, cut-off road_cutoff_frequency, seed road_seed.",
            "road = 3: the paper-compatible random road that reproduces the paper's Table 3 (noise samples held for road_sample_interval without 1/sqrt(D) scaling); about ten times weaker than a true class-C road. Say so when you report results obtained with it.",
        ],
    )?;

    text_element(w, "h2", "Variables")?;
    let rows: Vec<Vec<String>> = variables_of(Model::QuarterCar, FmiVersion::Fmi2)
        .iter()
        .map(variable_row)
        .collect();
    variable_table(w, "type", &rows)?;
    paragraph(
        w,
        "Parameters are fixed (settable before the end of initialization) unless tunable: g, w_ba, w_sdd and w_tdd can be changed between communication steps. Values outside the range, NaN or infinite are refused with fmi2Error naming the variable and value; the remaining checks (for example a delay needing too many history nodes) are made by fmi2ExitInitializationMode, which then stays in initialization mode so that the value can be corrected.",
    )?;

    text_element(w, "h2", "Default experiment")?;
    paragraph(
        w,
        &format!(
            "startTime {DEFAULT_START_TIME} s, stopTime {DEFAULT_STOP_TIME} s, stepSize {DEFAULT_STEP_SIZE} s. With the start values (TDVASS, Table 1, g = 5386 N/m, tau = 0.2 ms, harmonic road 0.05 sin 5t, from rest) the running RMS outputs at t = 15 s reproduce the TDVASS row of the paper's Table 2: BA 0.3068 m/s2, SDD 0.0388 m, TDD 0.6251 mm. variant = 1 and 2 give the CS and PVASS rows."
        ),
    )?;
    paragraph(w, REFERENCE_RESULTS)?;
    paragraph(
        w,
        "To reproduce the paper's stability verification (section 3.3), set g and tau (for example g = -40000 N/m, tau = 0.11 s, unstable) and the initial state x_s_start = 0.01 m; spectral_abscissa and stable report the rightmost characteristic root.",
    )?;

    text_element(w, "h2", "Behaviour")?;
    list(
        w,
        &[
            "Divergence: an unstable (g, tau) makes the states grow; before anything becomes non-finite (|displacement| > 1000 m or |velocity| > 1e6 m/s) fmi2DoStep returns fmi2Discard, logs time, variable and value, and the FMU stays at the last good internal grid node: fmi2GetRealStatus(fmi2LastSuccessfulTime) tells where, fmi2GetBooleanStatus(fmi2Terminated) is true. Outputs stay finite. An unstable (g, tau) is also reported as a warning by fmi2ExitInitializationMode and when g is tuned.",
            "fmi2DoStep: currentCommunicationPoint must equal the FMU time (relative 1e-9), the step must be finite and > 0 and must not pass a stop time given to fmi2SetupExperiment. Any step length is accepted.",
            "Refused calls (wrong state, unknown value reference, bad value) return fmi2Error, are logged and change nothing.",
            "FMU states: fmi2GetFMUstate copies everything (settings, time, solver state, delay history, road generator, RMS accumulators). fmi2SetFMUstate and fmi2FreeFMUstate accept states of the same instance only. Serialized states (versioned, checksummed, position independent) restore in any instance or process of the same FMU and continue bit-identically; they carry every parameter value.",
            "fmi2GetDirectionalDerivative: Co-Simulation, exact partials of the outputs with respect to the input x_g and the states, the latter addressed by the value references of the outputs x_s .. v_t (the running RMS values and J depend on the past only: partials 0); Model Exchange, exact partials of the state derivatives der(...) and the Real outputs with respect to the 20 continuous states and x_g.",
            "fmi2GetRealOutputDerivatives: exact first derivatives (order 1); the running RMS values and J are piecewise constant in time (derivative 0).",
            "Logging categories: logEvents, logStatusWarning, logStatusDiscard, logStatusError, logStatusFatal, logAll. Discards, errors and fatal errors are always reported; warnings unless switched off.",
        ],
    )?;

    text_element(w, "h2", "Model Exchange")?;
    paragraph(
        w,
        &model_exchange_text(
            "fmi2Instantiate with fmi2ModelExchange",
            variables_of(Model::QuarterCar, FmiVersion::Fmi2),
        ),
    )?;
    let capabilities: Vec<String> = MODEL_EXCHANGE_CAPABILITIES
        .iter()
        .map(|(name, value)| format!("{name} = {value}"))
        .collect();
    paragraph(
        w,
        &format!(
            "numberOfEventIndicators = {EVENT_INDICATORS}; ModelExchange: {}.",
            capabilities.join(", ")
        ),
    )?;

    text_element(w, "h2", "References")?;
    list(
        w,
        &[
            "Mechanism of time-delay feedback control of suspension damping with an annular vibration-absorbing structure (the source paper: model Eq. 1-2, objective Eq. 6, precise integration section 4.1, Table 1 parameters, Table 2 results).",
            "ISO 8608: Mechanical vibration - Road surface profiles - Reporting of measured data.",
            "Functional Mock-up Interface for Model Exchange and Co-Simulation, version 2.0.",
        ],
    )?;
    Ok(())
}

#[cfg(test)]
mod tests;
