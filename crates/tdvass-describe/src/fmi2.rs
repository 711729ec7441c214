//! The FMI 2.0 `modelDescription.xml` and `documentation/index.html`,
//! generated from the variable table with quick-xml (no markup is written
//! by hand, so every value is escaped). The output is deterministic: no
//! timestamps. Each model ([`Model`]) has its own: the quarter car's with
//! Model Exchange beside Co-Simulation, the corner's and the chassis's
//! Co-Simulation only ([`Model::offers_model_exchange`]), the chassis's
//! with capabilities of its own ([`co_simulation_capabilities`]).

use crate::component::{ComponentPage, component_page};
use crate::markup::{
    DescriptionFrame, MODEL_DESCRIPTION, REFERENCE_RESULTS, TIRE_CONTACT, XmlResult, XmlWriter,
    diagram, html_page, list, model_description, model_exchange_text, number, paragraph,
    text_element, typed_in_use, unit_text, variable_table,
};
use quick_xml::events::{BytesText, Event};
use tdvass::exchange::EVENT_INDICATORS;
use tdvass::solver::CONTINUOUS_STATES;
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
                    for i in 0..CONTINUOUS_STATES {
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
    let event_indicators = EVENT_INDICATORS.to_string();
    let model_exchange = model.offers_model_exchange();
    let event_indicators = [("numberOfEventIndicators", event_indicators.as_str())];
    let quantities = quantities(model);
    let frame = DescriptionFrame {
        fmi_version: FMI_VERSION,
        model,
        quantities: &quantities,
        token: ("guid", &guid),
        co_simulation: co_simulation_capabilities(model),
        model_exchange: model_exchange.then_some(&MODEL_EXCHANGE_CAPABILITIES[..]),
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
mod tests {
    use super::*;
    use crate::parsed::elements;
    use tdvass_fmu::variables::COMMON_VARIABLES;

    #[test]
    fn model_description_has_every_variable() {
        let xml = model_description_xml(Model::QuarterCar);
        let els = elements(&xml);
        let root = &els[0];
        assert_eq!(root.name, "fmiModelDescription");
        assert_eq!(root.attr("guid"), guid(Model::QuarterCar));
        assert_eq!(root.attr("modelName"), "TDVASS");
        assert_eq!(root.attr("fmiVersion"), "2.0");
        let cs = els.iter().find(|e| e.name == "CoSimulation").unwrap();
        assert_eq!(cs.attr("modelIdentifier"), "tdvass");
        for flag in [
            "canHandleVariableCommunicationStepSize",
            "canInterpolateInputs",
            "canGetAndSetFMUstate",
            "canSerializeFMUstate",
            "providesDirectionalDerivative",
        ] {
            assert_eq!(cs.attr(flag), "true", "{flag}");
        }
        assert_eq!(cs.attr("maxOutputDerivativeOrder"), "1");
        let experiment = els.iter().find(|e| e.name == "DefaultExperiment").unwrap();
        assert_eq!(experiment.attr("stopTime"), "15");
        assert_eq!(experiment.attr("stepSize"), "0.001");
        let vars: Vec<_> = els.iter().filter(|e| e.name == "ScalarVariable").collect();
        assert_eq!(vars.len(), COMMON_VARIABLES.len());
        for (v, el) in COMMON_VARIABLES.iter().zip(&vars) {
            assert_eq!(el.attr("name"), v.name);
            assert_eq!(el.attr("valueReference"), v.vr.to_string());
            assert_eq!(el.attr("causality"), v.causality.as_str());
        }
        let categories: Vec<_> = els
            .iter()
            .filter(|e| e.name == "Category")
            .map(|e| e.attr("name"))
            .collect();
        for c in [
            "logEvents",
            "logStatusWarning",
            "logStatusError",
            "logStatusFatal",
            "logAll",
        ] {
            assert!(categories.contains(&c), "{c}");
        }
        let mm = els
            .iter()
            .find(|e| e.name == "DisplayUnit" && e.attr("name") == "mm")
            .unwrap();
        assert_eq!(mm.attr("factor"), "1000");
        let tdd = els
            .iter()
            .position(|e| e.name == "ScalarVariable" && e.attr("name") == "tire_deflection")
            .unwrap();
        assert_eq!(els[tdd + 1].attr("displayUnit"), "mm");
        assert_eq!(els[tdd + 1].attr("unit"), "m");
    }

    #[test]
    fn model_structure_lists_outputs_derivatives_and_initial_unknowns() {
        let xml = model_description_xml(Model::QuarterCar);
        let els = elements(&xml);
        let at = |name: &str| els.iter().position(|e| e.name == name).unwrap();
        let (outputs_at, derivatives_at, initial_at) =
            (at("Outputs"), at("Derivatives"), at("InitialUnknowns"));
        let outputs: Vec<_> = els[outputs_at + 1..derivatives_at].iter().collect();
        let derivatives: Vec<_> = els[derivatives_at + 1..initial_at].iter().collect();
        let initial: Vec<_> = els[initial_at + 1..].iter().collect();
        let count = |c: Causality| COMMON_VARIABLES.iter().filter(|v| v.causality == c).count();
        // The locals are not outputs.
        assert_eq!(outputs.len(), count(Causality::Output));
        assert_eq!(outputs.len(), 23);
        let local_states = COMMON_VARIABLES
            .iter()
            .filter(|v| matches!(v.access, Access::ContinuousState(_)))
            .count();
        assert_eq!(local_states, 13);
        // FMI 2.0: the outputs and calculated parameters (all calculated),
        // the states with initial = calculated (the outputs among them
        // once) and every derivative; not the event indicator.
        assert_eq!(
            initial.len(),
            count(Causality::Output)
                + count(Causality::CalculatedParameter)
                + local_states
                + CONTINUOUS_STATES
        );
        assert_eq!(initial.len(), 25 + 13 + 20);
        let initial_indices: Vec<usize> = initial
            .iter()
            .map(|e| e.attr("index").parse().unwrap())
            .collect();
        assert!(initial_indices.windows(2).all(|w| w[0] < w[1]), "ascending");
        for (i, v) in COMMON_VARIABLES.iter().enumerate() {
            let listed = initial_indices.contains(&(i + 1));
            let expected = matches!(
                v.causality,
                Causality::Output | Causality::CalculatedParameter
            ) || matches!(
                v.access,
                Access::ContinuousState(_) | Access::StateDerivative(_)
            );
            assert_eq!(listed, expected, "{}", v.name);
        }
        // The outputs depend on the input x_g where it feeds through
        // (fixed) and on the continuous states they are computed from.
        let x_g = index_of(Model::QuarterCar, "x_g").unwrap();
        for o in &outputs {
            let deps: Vec<usize> = o
                .attr("dependencies")
                .split_whitespace()
                .map(|i| i.parse().unwrap())
                .collect();
            let kinds: Vec<&str> = o
                .get("dependenciesKind")
                .unwrap_or("")
                .split_whitespace()
                .collect();
            assert_eq!(deps.len(), kinds.len(), "{:?}", o.attributes);
            assert!(deps.windows(2).all(|w| w[0] < w[1]), "ascending");
            for (&d, &kind) in deps.iter().zip(&kinds) {
                let known = &COMMON_VARIABLES[d - 1];
                if d == x_g {
                    assert_eq!(kind, "fixed");
                } else {
                    assert!(known.state_index().is_some(), "{}", known.name);
                    assert_eq!(kind, "dependent");
                }
            }
        }
        let output = |name: &str| {
            let index = index_of(Model::QuarterCar, name).unwrap().to_string();
            outputs.iter().find(|e| e.attr("index") == index).unwrap()
        };
        let plant: Vec<usize> = ["x_s", "v_s", "x_h", "v_h", "x_t", "v_t"]
            .iter()
            .map(|n| index_of(Model::QuarterCar, n).unwrap())
            .collect();
        let mut expected: Vec<usize> = plant.iter().copied().chain([x_g]).collect();
        expected.sort_unstable();
        let listed =
            |s: &str| -> Vec<usize> { s.split_whitespace().map(|i| i.parse().unwrap()).collect() };
        assert_eq!(
            listed(output("tire_deflection").attr("dependencies")),
            expected
        );
        let x_s = index_of(Model::QuarterCar, "x_s").unwrap().to_string();
        assert_eq!(output("x_s").attr("dependencies"), x_s);
        assert_eq!(
            output("rms_tire_deflection").attr("dependencies"),
            index_of(Model::QuarterCar, "integral_tire_deflection_squared")
                .unwrap()
                .to_string()
        );

        // One derivative per state, in state order, each without
        // dependencies (on every known), its `derivative` the state's index.
        assert_eq!(derivatives.len(), CONTINUOUS_STATES);
        assert_eq!(derivatives.len(), 20);
        let vars: Vec<_> = els.iter().filter(|e| e.name == "ScalarVariable").collect();
        // The type element (`Real`) of the variable of a 1-based index.
        let typed = |index: usize| {
            let at = els
                .iter()
                .position(|e| std::ptr::eq(e, vars[index - 1]))
                .unwrap();
            &els[at + 1]
        };
        for (i, d) in derivatives.iter().enumerate() {
            assert_eq!(d.get("dependencies"), None);
            let index: usize = d.attr("index").parse().unwrap();
            let der = &COMMON_VARIABLES[index - 1];
            assert!(
                matches!(der.access, Access::StateDerivative(j) if j == i),
                "{}",
                der.name
            );
            let state: usize = typed(index).attr("derivative").parse().unwrap();
            let state = &COMMON_VARIABLES[state - 1];
            assert_eq!(state.state_index(), Some(i));
            assert_eq!(der.name, format!("der({})", state.name));
            assert_eq!(state.variability.as_str(), "continuous");
        }
        let named = |name: &str| typed(index_of(Model::QuarterCar, name).unwrap());
        assert_eq!(
            named("der(x_s)").attr("derivative"),
            index_of(Model::QuarterCar, "x_s").unwrap().to_string()
        );
        assert_eq!(
            named("der(wk_filter_1)").attr("derivative"),
            index_of(Model::QuarterCar, "wk_filter_1")
                .unwrap()
                .to_string()
        );
        assert_eq!(
            named("der(contact_loss_time)").attr("derivative"),
            index_of(Model::QuarterCar, "contact_loss_time")
                .unwrap()
                .to_string()
        );
        // Only the derivatives have the attribute.
        let with_derivative = (1..=vars.len())
            .filter(|&index| typed(index).get("derivative").is_some())
            .count();
        assert_eq!(with_derivative, CONTINUOUS_STATES);
    }

    #[test]
    fn model_exchange_beside_co_simulation() {
        let xml = model_description_xml(Model::QuarterCar);
        let els = elements(&xml);
        let root = &els[0];
        assert_eq!(
            root.attr("numberOfEventIndicators"),
            EVENT_INDICATORS.to_string()
        );
        let top: Vec<&str> = els
            .iter()
            .filter(|e| e.parent == Some(0))
            .map(|e| e.name.as_str())
            .collect();
        assert_eq!(
            &top[..3],
            ["ModelExchange", "CoSimulation", "UnitDefinitions"]
        );
        let me = els.iter().find(|e| e.name == "ModelExchange").unwrap();
        assert_eq!(me.attr("modelIdentifier"), "tdvass");
        for (flag, value) in [
            ("canGetAndSetFMUstate", "true"),
            ("canSerializeFMUstate", "true"),
            ("completedIntegratorStepNotNeeded", "false"),
            ("canNotUseMemoryManagementFunctions", "true"),
            ("providesDirectionalDerivative", "true"),
            ("needsExecutionTool", "false"),
            ("canBeInstantiatedOnlyOncePerProcess", "false"),
        ] {
            assert_eq!(me.attr(flag), value, "{flag}");
        }
        assert_eq!(me.attributes.len(), 1 + MODEL_EXCHANGE_CAPABILITIES.len());
        // The locals are continuous with initial = calculated.
        for v in els
            .iter()
            .filter(|e| e.name == "ScalarVariable" && e.attr("causality") == "local")
        {
            assert_eq!(v.attr("variability"), "continuous", "{}", v.attr("name"));
            assert_eq!(v.attr("initial"), "calculated", "{}", v.attr("name"));
        }
    }

    #[test]
    fn documentation_describes_every_variable() {
        let html = documentation_html(Model::QuarterCar);
        assert!(html.starts_with("<!DOCTYPE html>"));
        elements(html.trim_start_matches("<!DOCTYPE html>"));
        for v in COMMON_VARIABLES {
            assert!(html.contains(&format!("<td>{}</td>", v.name)), "{}", v.name);
        }
        assert!(html.contains("1 - g/k_h"));
        assert!(html.contains("0.3068"));
        assert!(html.contains("FMI 2.0 FMU (Co-Simulation and Model Exchange)"));
        assert!(html.contains("<td>local, continuous</td>"));
        assert!(html.contains("x_s, v_s, x_h, v_h, x_t, v_t, wk_filter_1"));
        assert!(html.contains("integral_weighted_acceleration_fourth, contact_loss_time."));
        assert!(html.contains("The event indicator contact_indicator"));
    }

    #[test]
    fn output_is_deterministic() {
        for model in Model::ALL {
            assert_eq!(model_description_xml(model), model_description_xml(model));
            assert_eq!(documentation_html(model), documentation_html(model));
        }
    }

    /// The corner's description: Co-Simulation only, its own name, GUID
    /// and variables, and a ModelStructure that refers to them.
    #[test]
    fn the_corner_is_described_without_model_exchange() {
        let model = Model::Corner;
        let xml = model_description_xml(model);
        let els = elements(&xml);
        let root = &els[0];
        assert_eq!(root.name, "fmiModelDescription");
        assert_eq!(root.attr("fmiVersion"), "2.0");
        assert_eq!(root.attr("modelName"), "TDVASS corner");
        assert_eq!(root.attr("modelName"), model.name());
        assert_eq!(root.attr("guid"), guid(Model::Corner));
        assert_eq!(
            root.attr("guid"),
            tdvass_fmu::variables::guid(Model::Corner)
        );
        assert_ne!(root.attr("guid"), guid(Model::QuarterCar));
        assert_eq!(root.attr("description"), crate::markup::CORNER_DESCRIPTION);
        assert_eq!(root.get("numberOfEventIndicators"), None);
        let top: Vec<&str> = els
            .iter()
            .filter(|e| e.parent == Some(0))
            .map(|e| e.name.as_str())
            .collect();
        assert_eq!(
            top,
            [
                "CoSimulation",
                "UnitDefinitions",
                "TypeDefinitions",
                "LogCategories",
                "DefaultExperiment",
                "ModelVariables",
                "ModelStructure"
            ]
        );
        assert!(!els.iter().any(|e| e.name == "ModelExchange"));
        let cs = els.iter().find(|e| e.name == "CoSimulation").unwrap();
        assert_eq!(cs.attr("modelIdentifier"), MODEL_IDENTIFIER);
        assert_eq!(cs.attributes.len(), 1 + CO_SIMULATION_CAPABILITIES.len());

        let variables = variables_of(model, FmiVersion::Fmi2);
        let vars: Vec<_> = els.iter().filter(|e| e.name == "ScalarVariable").collect();
        assert_eq!(vars.len(), variables.len());
        for (v, el) in variables.iter().zip(&vars) {
            assert_eq!(el.attr("name"), v.name);
            assert_eq!(el.attr("valueReference"), v.vr.to_string());
            assert_eq!(el.attr("causality"), v.causality.as_str());
            assert_ne!(v.causality, Causality::Local, "{}", v.name);
        }
        assert!(!els.iter().any(|e| e.get("derivative").is_some()));

        // ModelStructure: the outputs and initial unknowns, no derivatives;
        // every dependency an index of an existing variable.
        let structure = els.iter().position(|e| e.name == "ModelStructure").unwrap();
        let parts: Vec<&str> = els
            .iter()
            .filter(|e| e.parent == Some(structure))
            .map(|e| e.name.as_str())
            .collect();
        assert_eq!(parts, ["Outputs", "InitialUnknowns"]);
        let unknowns_of = |part: &str| -> Vec<&crate::parsed::Element> {
            let at = els.iter().position(|e| e.name == part).unwrap();
            els.iter().filter(|e| e.parent == Some(at)).collect()
        };
        let listed =
            |s: &str| -> Vec<usize> { s.split_whitespace().map(|i| i.parse().unwrap()).collect() };
        let outputs = unknowns_of("Outputs");
        let expected: Vec<String> = variables
            .iter()
            .enumerate()
            .filter(|(_, v)| v.causality == Causality::Output)
            .map(|(i, _)| (i + 1).to_string())
            .collect();
        let indices: Vec<&str> = outputs.iter().map(|e| e.attr("index")).collect();
        assert_eq!(indices, expected);
        for unknown in outputs.iter().chain(&unknowns_of("InitialUnknowns")) {
            let deps = listed(unknown.attr("dependencies"));
            assert!(deps.windows(2).all(|w| w[0] < w[1]), "ascending");
            for d in deps {
                assert!(
                    (1..=variables.len()).contains(&d),
                    "{:?}",
                    unknown.attributes
                );
            }
        }
        for o in &outputs {
            let deps = listed(o.attr("dependencies"));
            let kinds: Vec<&str> = o
                .get("dependenciesKind")
                .unwrap_or("")
                .split_whitespace()
                .collect();
            assert_eq!(deps.len(), kinds.len(), "{:?}", o.attributes);
            // No continuous states to depend on: the inputs alone.
            for d in deps {
                assert_eq!(variables[d - 1].causality, Causality::Input);
            }
        }
        let index = |name: &str| index_of(model, name).unwrap();
        let body_force = outputs
            .iter()
            .find(|e| e.attr("index") == index("body_force").to_string())
            .unwrap();
        assert_eq!(
            listed(body_force.attr("dependencies")),
            [index("body_displacement"), index("body_velocity")]
        );
        assert_eq!(body_force.attr("dependenciesKind"), "fixed fixed");
    }

    #[test]
    fn the_corner_documentation_describes_its_variables() {
        let html = documentation_html(Model::Corner);
        assert!(html.starts_with("<!DOCTYPE html>"));
        elements(html.trim_start_matches("<!DOCTYPE html>"));
        assert!(html.contains("<title>TDVASS corner FMI 2.0 FMU</title>"));
        assert!(html.contains("TDVASS corner: FMI 2.0 FMU (Co-Simulation)"));
        assert!(html.contains(&guid(Model::Corner)));
        assert!(html.contains("Co-Simulation only in this version"));
        for v in variables_of(Model::Corner, FmiVersion::Fmi2) {
            assert!(html.contains(&format!("<td>{}</td>", v.name)), "{}", v.name);
        }
        for (flag, _) in CO_SIMULATION_CAPABILITIES {
            assert!(html.contains(&format!("<td>{flag}</td>")), "{flag}");
        }
        assert!(html.contains("body_force (output, N)"));
        assert!(!html.contains("m_s (start"));
    }

    /// Every model's description defines the types and units its
    /// variables use, each once, and no others.
    #[test]
    fn types_and_units_are_those_the_variables_use() {
        for model in Model::ALL {
            let xml = model_description_xml(model);
            let els = elements(&xml);
            let types: Vec<&str> = els
                .iter()
                .filter(|e| e.name == "SimpleType")
                .map(|e| e.attr("name"))
                .collect();
            let units: Vec<&str> = els
                .iter()
                .filter(|e| e.name == "Unit")
                .map(|e| e.attr("name"))
                .collect();
            let vars: Vec<_> = els.iter().filter(|e| e.parent.is_some()).collect();
            let declared: Vec<&str> = vars.iter().filter_map(|e| e.get("declaredType")).collect();
            let used: Vec<&str> = vars.iter().filter_map(|e| e.get("unit")).collect();
            for t in &types {
                assert!(declared.contains(t), "{model:?}: {t} unused");
                assert_eq!(types.iter().filter(|u| *u == t).count(), 1, "{t}");
            }
            for t in &declared {
                assert!(types.contains(t), "{model:?}: {t} undefined");
            }
            for u in &units {
                assert!(used.contains(u), "{model:?}: {u} unused");
                assert_eq!(units.iter().filter(|v| *v == u).count(), 1, "{u}");
            }
            for u in &used {
                assert!(units.contains(u), "{model:?}: {u} undefined");
            }
        }
        // The quarter car uses the twelve of the suspension; the chassis
        // its angles and inertias, which the suspension does not.
        assert_eq!(quantities(Model::QuarterCar).len(), 12);
        for q in [
            Quantity::Angle,
            Quantity::AngularVelocity,
            Quantity::AngularAcceleration,
            Quantity::Inertia,
        ] {
            assert!(!quantities(Model::QuarterCar).contains(&q), "{q:?}");
            assert!(quantities(Model::Chassis).contains(&q), "{q:?}");
        }
    }

    /// The chassis's description: Co-Simulation only with its own
    /// capabilities, its own name, GUID and variables, and a ModelStructure
    /// whose outputs depend on the forces where they feed through.
    #[test]
    fn the_chassis_is_described_with_its_own_capabilities() {
        let model = Model::Chassis;
        let xml = model_description_xml(model);
        let els = elements(&xml);
        let root = &els[0];
        assert_eq!(root.attr("fmiVersion"), "2.0");
        assert_eq!(root.attr("modelName"), "TDVASS chassis");
        assert_eq!(root.attr("guid"), guid(Model::Chassis));
        for other in [Model::QuarterCar, Model::Corner] {
            assert_ne!(root.attr("guid"), guid(other));
        }
        assert_eq!(root.attr("description"), crate::markup::CHASSIS_DESCRIPTION);
        assert_eq!(root.get("numberOfEventIndicators"), None);
        let top: Vec<&str> = els
            .iter()
            .filter(|e| e.parent == Some(0))
            .map(|e| e.name.as_str())
            .collect();
        assert_eq!(
            top,
            [
                "CoSimulation",
                "UnitDefinitions",
                "TypeDefinitions",
                "LogCategories",
                "DefaultExperiment",
                "ModelVariables",
                "ModelStructure"
            ]
        );
        let cs = els.iter().find(|e| e.name == "CoSimulation").unwrap();
        assert_eq!(cs.attr("modelIdentifier"), MODEL_IDENTIFIER);
        assert_eq!(
            cs.attributes.len(),
            1 + CHASSIS_CO_SIMULATION_CAPABILITIES.len()
        );
        for (flag, value) in [
            ("canHandleVariableCommunicationStepSize", "true"),
            ("canInterpolateInputs", "true"),
            ("maxOutputDerivativeOrder", "0"),
            ("canGetAndSetFMUstate", "true"),
            ("canSerializeFMUstate", "true"),
            ("providesDirectionalDerivative", "false"),
            ("needsExecutionTool", "false"),
        ] {
            assert_eq!(cs.attr(flag), value, "{flag}");
        }
        // The same attributes as the quarter car's, in the same order.
        let names = |c: &[(&str, &str)]| c.iter().map(|(n, _)| n.to_string()).collect::<Vec<_>>();
        assert_eq!(
            names(&CHASSIS_CO_SIMULATION_CAPABILITIES),
            names(&CO_SIMULATION_CAPABILITIES)
        );

        let variables = variables_of(model, FmiVersion::Fmi2);
        let vars: Vec<_> = els.iter().filter(|e| e.name == "ScalarVariable").collect();
        assert_eq!(vars.len(), variables.len());
        for (v, el) in variables.iter().zip(&vars) {
            assert_eq!(el.attr("name"), v.name);
            assert_eq!(el.attr("valueReference"), v.vr.to_string());
            assert_eq!(el.attr("causality"), v.causality.as_str());
        }
        let pitch = els
            .iter()
            .position(|e| e.get("name") == Some("pitch"))
            .unwrap();
        assert_eq!(els[pitch + 1].attr("declaredType"), "Angle");
        assert_eq!(els[pitch + 1].attr("unit"), "rad");

        let structure = els.iter().position(|e| e.name == "ModelStructure").unwrap();
        let parts: Vec<&str> = els
            .iter()
            .filter(|e| e.parent == Some(structure))
            .map(|e| e.name.as_str())
            .collect();
        assert_eq!(parts, ["Outputs", "InitialUnknowns"]);
        let unknowns_of = |part: &str| -> Vec<&crate::parsed::Element> {
            let at = els.iter().position(|e| e.name == part).unwrap();
            els.iter().filter(|e| e.parent == Some(at)).collect()
        };
        let listed =
            |s: &str| -> Vec<usize> { s.split_whitespace().map(|i| i.parse().unwrap()).collect() };
        let index = |name: &str| index_of(model, name).unwrap();
        let forces: Vec<usize> = ["force_fl", "force_fr", "force_rl", "force_rr"]
            .iter()
            .map(|n| index(n))
            .collect();
        let outputs = unknowns_of("Outputs");
        let expected: Vec<String> = variables
            .iter()
            .enumerate()
            .filter(|(_, v)| v.causality == Causality::Output)
            .map(|(i, _)| (i + 1).to_string())
            .collect();
        let output_indices: Vec<&str> = outputs.iter().map(|e| e.attr("index")).collect();
        assert_eq!(output_indices, expected);
        let feedthrough = [
            "heave_acceleration",
            "pitch_acceleration",
            "roll_acceleration",
            "seat_acceleration",
            "weighted_seat_acceleration",
        ];
        for o in &outputs {
            let v = &variables[o.attr("index").parse::<usize>().unwrap() - 1];
            let deps = listed(o.attr("dependencies"));
            if feedthrough.contains(&v.name) {
                assert_eq!(deps, forces, "{}", v.name);
                assert_eq!(
                    o.attr("dependenciesKind"),
                    "fixed fixed fixed fixed",
                    "{}",
                    v.name
                );
            } else {
                // The attachment points' motion, the states and the time
                // averages: from the states alone, no algebraic loop.
                assert!(deps.is_empty(), "{}", v.name);
                assert_eq!(o.get("dependenciesKind"), None, "{}", v.name);
            }
        }
        let displacement = outputs
            .iter()
            .find(|e| e.attr("index") == index("displacement_fl").to_string())
            .unwrap();
        assert_eq!(displacement.attr("dependencies"), "");
        // Every output is an initial unknown, with the initial
        // dependencies of the table.
        let initial = unknowns_of("InitialUnknowns");
        assert_eq!(initial.len(), outputs.len());
        for u in &initial {
            let v = &variables[u.attr("index").parse::<usize>().unwrap() - 1];
            assert_eq!(
                u.attr("dependencies"),
                indices(model, v.initial_dependencies),
                "{}",
                v.name
            );
        }
        let seat = initial
            .iter()
            .find(|e| e.attr("index") == index("seat_acceleration").to_string())
            .unwrap();
        assert!(listed(seat.attr("dependencies")).contains(&index("seat_x")));
    }

    #[test]
    fn the_chassis_documentation_describes_its_variables_and_capabilities() {
        let html = documentation_html(Model::Chassis);
        assert!(html.starts_with("<!DOCTYPE html>"));
        elements(html.trim_start_matches("<!DOCTYPE html>"));
        assert!(html.contains("<title>TDVASS chassis FMI 2.0 FMU</title>"));
        assert!(html.contains("TDVASS chassis: FMI 2.0 FMU (Co-Simulation)"));
        assert!(html.contains(&guid(Model::Chassis)));
        assert!(html.contains("Co-Simulation only in this version: the chassis"));
        assert!(html.contains("picks the chassis when the FMU is instantiated"));
        for v in variables_of(Model::Chassis, FmiVersion::Fmi2) {
            assert!(html.contains(&format!("<td>{}</td>", v.name)), "{}", v.name);
        }
        for (flag, value) in CHASSIS_CO_SIMULATION_CAPABILITIES {
            assert!(
                html.contains(&format!("<td>{flag}</td>\n        <td>{value}</td>")),
                "{flag}"
            );
        }
        for text in [
            "positive nose up",
            "positive left side up",
            "z + x theta + y phi",
            "front and rear decouple",
            "fmi2SetRealInputDerivatives",
            "no algebraic loop",
            "mass = 4 x 345 kg = 1380 kg",
            "a = 1.3 m, b = 1.3 m",
            "pitch_inertia = m a b = 2332.2 kg m2, roll_inertia = 400 kg m2",
            "track_front = 1.5 m, track_rear = 1.5 m",
            "ISO 2631-1",
            "mass (start 1380 kg)",
            "force_fl (input, N)",
        ] {
            assert!(html.contains(text), "{text}");
        }
        // Its legend is its own: no symbol of the suspension's.
        assert!(!html.contains("m_s (start"));
        assert!(!html.contains("control_force"));
        assert!(!html.contains("<h3>Enumerations</h3>"));
    }
}
