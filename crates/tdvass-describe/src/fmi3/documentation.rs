//! `documentation/index.html` of the FMI 3.0 FMU, generated from the one
//! variable table and the declarations of the model description: the
//! quarter car's, and the shorter pages of the corner and the chassis
//! ([`crate::component`]).

use super::{
    CO_SIMULATION_CAPABILITIES, MODEL_EXCHANGE_CAPABILITIES, co_simulation_capabilities,
    enumerations, value_text,
};
use crate::component::{ComponentPage, component_page};
use crate::markup::{
    MODEL_DESCRIPTION, REFERENCE_RESULTS, TIRE_CONTACT, XmlResult, XmlWriter, diagram, html_page,
    list, model_exchange_text, paragraph, table, text_element, unit_text, variable_table,
};
use tdvass_fmi3::instantiation_token;
use tdvass_fmi3::types::{Fmi3Type, fmi3_type};
use tdvass_fmu::Model;
use tdvass_fmu::variables::{
    Causality, Dimension, FMI3_VARIABLES, FmiVersion, Variable, variables_of,
};
use tdvass_fmu::{
    DEFAULT_START_TIME, DEFAULT_STEP_SIZE, DEFAULT_STOP_TIME, LOG_CATEGORIES, MODEL_IDENTIFIER,
    MODEL_NAME,
};

/// The FMI 3.0 type of `v` in words: `Float64`, `Enumeration Variant`,
/// `Float64 [root_count][2]`.
fn type_text(v: &Variable) -> String {
    let mut text = fmi3_type(v).as_str().to_string();
    if let (Fmi3Type::Enumeration, Some(e)) = (fmi3_type(v), v.enumeration) {
        text.push(' ');
        text.push_str(e.type_name);
    }
    if !v.dimensions.is_empty() {
        text.push(' ');
        for d in v.dimensions {
            match d {
                Dimension::Fixed(size) => text.push_str(&format!("[{size}]")),
                Dimension::Structural(name) => text.push_str(&format!("[{name}]")),
            }
        }
    }
    text
}

fn variable_row(v: &Variable) -> Vec<String> {
    let start = match (v.start, v.enumeration) {
        (Some(s), Some(e)) => {
            let code = s as i32;
            let item = e.items.iter().find(|i| i.value == code);
            match item {
                Some(item) => format!("{} ({code})", item.name),
                None => code.to_string(),
            }
        }
        (Some(s), None) => value_text(v, s),
        (None, _) if v.causality == Causality::Independent => "startTime".into(),
        (None, _) => "calculated".into(),
    };
    let mut kind = format!("{}, {}", v.causality.as_str(), v.variability.as_str());
    if v.intermediate_update {
        kind.push_str(", intermediateUpdate");
    }
    vec![
        v.name.to_string(),
        v.vr.to_string(),
        type_text(v),
        kind,
        start,
        unit_text(v),
        v.range.describe(),
        v.description.to_string(),
    ]
}

/// The complete `documentation/index.html` of `model`'s FMI 3.0 FMU.
pub fn documentation_html(model: Model) -> String {
    match model {
        Model::QuarterCar => html_page(&format!("{MODEL_NAME} FMI 3.0 FMU"), write_body),
        Model::Corner | Model::Chassis => component_page(&ComponentPage {
            model,
            version: FmiVersion::Fmi3,
            identity: format!(
                "instantiationToken {} (a hash of the variable names, value references, types, causalities, variabilities, enumeration types and array dimensions)",
                instantiation_token(model)
            ),
            type_header: "FMI 3.0 type",
            rows: variables_of(model, FmiVersion::Fmi3)
                .iter()
                .map(variable_row)
                .collect(),
            // The chassis has no enumerations.
            after_variables: &|w| {
                if enumerations(model).is_empty() {
                    Ok(())
                } else {
                    write_enumerations(w, model)
                }
            },
            co_simulation: co_simulation_capabilities(model),
            model_exchange: super::model_exchange_capabilities(model),
            specification: "Functional Mock-up Interface Specification, version 3.0.",
        }),
    }
}

/// The page: the introduction, then one function per part.
fn write_body(w: &mut XmlWriter) -> XmlResult {
    write_introduction(w)?;
    write_model(w)?;
    write_variables(w)?;
    write_co_simulation(w)?;
    write_model_exchange(w)?;
    write_experiment_and_references(w)
}

/// The title, the identity of the FMU and how it relates to the FMI 2.0 one.
fn write_introduction(w: &mut XmlWriter) -> XmlResult {
    text_element(
        w,
        "h1",
        &format!("{MODEL_NAME}: FMI 3.0 FMU (Co-Simulation and Model Exchange)"),
    )?;
    paragraph(w, MODEL_DESCRIPTION)?;
    paragraph(
        w,
        &format!(
            "modelIdentifier {MODEL_IDENTIFIER}, instantiationToken {} (a hash of the variable names, value references, types, causalities, variabilities, enumeration types and array dimensions), version {}.",
            instantiation_token(Model::QuarterCar),
            env!("CARGO_PKG_VERSION")
        ),
    )?;
    paragraph(
        w,
        "The model, its variables, value references, units, ranges and start values are those of the FMI 2.0 FMU of the same build (tdvass.fmu), from the same variable table. FMI 3.0 adds named enumerations for the integer settings, the rightmost characteristic roots as an array sized by a structural parameter, intermediate update with early return, and adjoint derivatives.",
    )?;

    Ok(())
}

/// The model: its diagram, equations, tire and integration.
fn write_model(w: &mut XmlWriter) -> XmlResult {
    text_element(w, "h2", "The model")?;
    diagram(w, Model::QuarterCar)?;
    paragraph(
        w,
        "State X = [x_s, v_s, x_h, v_h, x_t, v_t]: body, annular absorber and wheel displacements and velocities. The plant is dX/dt = A X + b x_t(t - tau) + e x_g(t) (Eq. 2 of the paper). TDVASS feeds the delayed wheel displacement back as the control force u = g x_t(t - tau); PVASS is the same structure with g = 0; CS is the conventional 2-DOF quarter car, for which x_h and v_h mirror x_t and v_t. The outputs are the states, BA = d2x_s/dt2, SDD = x_s - x_t, TDD = x_t - x_g, their running RMS values from the start time and the objective J (Eq. 6).",
    )?;
    paragraph(w, TIRE_CONTACT)?;
    paragraph(
        w,
        "Integration: the precise integration method of the paper on an internal grid anchored at the start time. The tolerance (relative, of every output metric: the master's from fmi3EnterInitializationMode when it defines one, else the DefaultExperiment's 1e-6) sets the internal step, from an error model checked by a step-doubling probe; the step divides tau exactly when tau is longer and is at most max_internal_step when that is > 0. Results do not depend on how the importer splits time into communication steps (except with road = input, where the input changes at communication points or intermediate updates).",
    )?;

    Ok(())
}

/// The variables, their enumerations and arrays.
fn write_variables(w: &mut XmlWriter) -> XmlResult {
    text_element(w, "h2", "Variables")?;
    let rows: Vec<Vec<String>> = FMI3_VARIABLES.iter().map(variable_row).collect();
    variable_table(w, "FMI 3.0 type", &rows)?;
    paragraph(
        w,
        "Parameters are fixed (settable before the end of initialization) unless tunable. Values outside the range, NaN or infinite are refused with fmi3Error naming the variable and value. The independent variable time is read with fmi3GetFloat64 and never set; it starts at the startTime of fmi3EnterInitializationMode.",
    )?;

    write_enumerations(w, Model::QuarterCar)?;

    text_element(w, "h3", "Arrays")?;
    for v in FMI3_VARIABLES.iter().filter(|v| !v.dimensions.is_empty()) {
        paragraph(
            w,
            &format!(
                "{}: {}, serialized row-major (the last index varies fastest). {}",
                v.name,
                type_text(v),
                v.description
            ),
        )?;
    }
    paragraph(
        w,
        "A structural parameter that sizes an array can only be changed in Configuration Mode (fmi3EnterConfigurationMode after instantiation); its start value is the size an importer that ignores structural parameters sees.",
    )?;

    Ok(())
}

/// The enumeration types of `model`'s variables: for each, the variables
/// of that type and a table of its items.
fn write_enumerations(w: &mut XmlWriter, model: Model) -> XmlResult {
    text_element(w, "h3", "Enumerations")?;
    paragraph(
        w,
        "Read and written with fmi3GetInt64 and fmi3SetInt64; the item values are the integer codes of the FMI 2.0 FMU.",
    )?;
    for e in enumerations(model) {
        let users: Vec<&str> = variables_of(model, FmiVersion::Fmi3)
            .iter()
            .filter(|v| v.enumeration.is_some_and(|u| u.type_name == e.type_name))
            .map(|v| v.name)
            .collect();
        text_element(
            w,
            "h4",
            &format!("{} (variable {})", e.type_name, users.join(", ")),
        )?;
        let rows: Vec<Vec<String>> = e
            .items
            .iter()
            .map(|i| {
                vec![
                    i.name.to_string(),
                    i.value.to_string(),
                    i.description.to_string(),
                ]
            })
            .collect();
        table(w, &["item", "value", "meaning"], &rows)?;
    }
    Ok(())
}

/// The capabilities, intermediate update and model structure.
fn write_co_simulation(w: &mut XmlWriter) -> XmlResult {
    text_element(w, "h2", "Co-Simulation capabilities")?;
    let rows: Vec<Vec<String>> = CO_SIMULATION_CAPABILITIES
        .iter()
        .map(|(name, value)| vec![name.to_string(), value.to_string()])
        .collect();
    table(w, &["attribute", "value"], &rows)?;

    text_element(w, "h2", "Intermediate update")?;
    list(
        w,
        &[
            "When the importer passes an intermediateUpdate callback to fmi3InstantiateCoSimulation, fmi3DoStep calls it at internal grid nodes, thinned by the tunable parameter intermediate_update_interval (s of simulated time between two calls; 0 = at every node).",
            "Inside the callback the outputs (intermediateUpdate = true) can be read, and the input x_g (intermediateUpdate = true) can be set: setting it at every node makes a road fed by the importer as accurate as a built-in one. This replaces the input derivatives of FMI 2.0.",
            "When the importer allowed early return at instantiation and asks for it from the callback, fmi3DoStep returns at that node with earlyReturn = true and lastSuccessfulTime the time of the node; the next step starts there. The FMU never returns early on its own.",
        ],
    )?;

    text_element(w, "h2", "Model structure")?;
    paragraph(
        w,
        "Dependencies are value references. The outputs list the knowns of both interfaces they depend on: the input x_g where it feeds through (tire_deflection and road_displacement, with a factor fixed by road) and the continuous states they are computed from (the plant states for the instantaneous outputs, also the W_k filter for a_w, the integral for each time average; a state output depends on itself); the initial values of the outputs and calculated parameters depend on the parameters named in ModelStructure, and rightmost_roots also on root_count.",
    )?;

    Ok(())
}

/// Model Exchange: the states, derivatives and event indicator, and the
/// capabilities.
fn write_model_exchange(w: &mut XmlWriter) -> XmlResult {
    text_element(w, "h2", "Model Exchange")?;
    paragraph(
        w,
        &model_exchange_text("fmi3InstantiateModelExchange", FMI3_VARIABLES),
    )?;
    paragraph(
        w,
        "ModelStructure lists the derivatives as ContinuousStateDerivative elements (in the order of the states) and the event indicator as EventIndicator; the local states and the derivatives are InitialUnknowns that depend on every known of initialization. fmi3GetVariableDependencies returns the dependencies of the outputs as listed here.",
    )?;
    text_element(w, "h3", "Model Exchange capabilities")?;
    let rows: Vec<Vec<String>> = MODEL_EXCHANGE_CAPABILITIES
        .iter()
        .map(|(name, value)| vec![name.to_string(), value.to_string()])
        .collect();
    table(w, &["attribute", "value"], &rows)?;

    Ok(())
}

/// The default experiment, logging and references.
fn write_experiment_and_references(w: &mut XmlWriter) -> XmlResult {
    text_element(w, "h2", "Default experiment")?;
    paragraph(
        w,
        &format!(
            "startTime {DEFAULT_START_TIME} s, stopTime {DEFAULT_STOP_TIME} s, stepSize {DEFAULT_STEP_SIZE} s. With the start values (TDVASS, g = 5386 N/m, tau = 0.2 ms, harmonic road 0.05 sin 5t, from rest) the running RMS outputs at t = 15 s reproduce the TDVASS row of the paper's Table 2: BA 0.3068 m/s2, SDD 0.0388 m, TDD 0.6251 mm; variant = CS and PVASS give the other rows."
        ),
    )?;
    paragraph(w, REFERENCE_RESULTS)?;

    text_element(w, "h2", "Logging")?;
    let categories: Vec<String> = LOG_CATEGORIES
        .iter()
        .map(|(name, description)| format!("{name}: {description}"))
        .collect();
    let categories: Vec<&str> = categories.iter().map(String::as_str).collect();
    list(w, &categories)?;

    text_element(w, "h2", "References")?;
    list(
        w,
        &[
            "Mechanism of time-delay feedback control of suspension damping with an annular vibration-absorbing structure (the source paper: model Eq. 1-2, objective Eq. 6, precise integration section 4.1, Table 1 parameters, Table 2 results).",
            "ISO 8608: Mechanical vibration - Road surface profiles - Reporting of measured data.",
            "Functional Mock-up Interface Specification, version 3.0.",
        ],
    )?;
    Ok(())
}
