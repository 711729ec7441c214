//! The FMI 3.0 `modelDescription.xml` and `documentation/index.html`,
//! generated from the one variable table with quick-xml (no markup is
//! written by hand, so every value is escaped). The output is
//! deterministic: no timestamps.
//!
//! Every variable, the independent variable `time` included, comes from
//! the table; beyond it, the description declares the capability flags of
//! Co-Simulation ([`CO_SIMULATION_CAPABILITIES`]) and Model Exchange
//! ([`MODEL_EXCHANGE_CAPABILITIES`]), which the C interface implements.
//! Model Exchange's continuous states, their derivatives and the event
//! indicator are variables of the table too ([`Access::ContinuousState`],
//! [`Access::StateDerivative`], [`Access::EventIndicator`]).
//!
//! Each model ([`Model`]) has its own description, from its variables
//! ([`variables_of`]), each with Model Exchange beside Co-Simulation over
//! its own continuous states ([`Model::continuous_states`]; the corner's
//! and the chassis's without directional derivatives,
//! [`model_exchange_capabilities`]), the chassis's with Co-Simulation
//! capabilities of its own ([`co_simulation_capabilities`]). Each defines the types and
//! units its variables use, no others.

use crate::markup::{
    DescriptionFrame, XmlResult, XmlWriter, model_description, number, typed_in_use,
};
use tdvass_fmi3::types::{Fmi3Type, fmi3_type};
use tdvass_fmi3::{FMI_VERSION, instantiation_token};
use tdvass_fmu::Model;
use tdvass_fmu::variables::{
    Access, Causality, Dimension, Enumeration, FmiVersion, Quantity, Variable, by_name,
    variables_of,
};

/// The attributes of the `ModelExchange` element after `modelIdentifier`:
/// `fmi3CompletedIntegratorStep` is wanted (a master that calls it at its
/// accepted steps keeps its method's order: docs/fmu.md, "Model
/// Exchange"); exact directional and adjoint derivatives of the state
/// derivatives and the outputs.
pub const MODEL_EXCHANGE_CAPABILITIES: [(&str, &str); 8] = [
    ("needsExecutionTool", "false"),
    ("canBeInstantiatedOnlyOncePerProcess", "false"),
    ("canGetAndSetFMUState", "true"),
    ("canSerializeFMUState", "true"),
    ("providesDirectionalDerivatives", "true"),
    ("providesAdjointDerivatives", "true"),
    ("needsCompletedIntegratorStep", "true"),
    ("providesEvaluateDiscreteStates", "false"),
];

/// The chassis's `ModelExchange` attributes ([`Model::Chassis`]): no
/// delay history, so completed integrator steps are not needed; exact
/// directional and adjoint derivatives of its derivatives and outputs.
pub const CHASSIS_MODEL_EXCHANGE_CAPABILITIES: [(&str, &str); 8] = [
    ("needsExecutionTool", "false"),
    ("canBeInstantiatedOnlyOncePerProcess", "false"),
    ("canGetAndSetFMUState", "true"),
    ("canSerializeFMUState", "true"),
    ("providesDirectionalDerivatives", "true"),
    ("providesAdjointDerivatives", "true"),
    ("needsCompletedIntegratorStep", "false"),
    ("providesEvaluateDiscreteStates", "false"),
];

/// The `ModelExchange` attributes of `model` after `modelIdentifier`.
pub fn model_exchange_capabilities(model: Model) -> &'static [(&'static str, &'static str)] {
    match model {
        Model::QuarterCar | Model::Corner => &MODEL_EXCHANGE_CAPABILITIES,
        Model::Chassis => &CHASSIS_MODEL_EXCHANGE_CAPABILITIES,
    }
}

/// The value reference of continuous state `i`'s variable of `model`.
pub fn state_vr(model: Model, i: usize) -> u32 {
    variables_of(model, FmiVersion::Fmi3)
        .iter()
        .find(|v| v.state_index() == Some(i))
        .map(|v| v.vr)
        .unwrap_or_else(|| panic!("no variable of continuous state {i}"))
}

/// The value reference of the derivative of continuous state `i` of
/// `model` (a model with Model Exchange).
pub fn derivative_vr(model: Model, i: usize) -> u32 {
    variables_of(model, FmiVersion::Fmi3)
        .iter()
        .find(|v| matches!(v.access, Access::StateDerivative(j) if j == i))
        .map(|v| v.vr)
        .unwrap_or_else(|| panic!("no derivative of continuous state {i}"))
}

/// The attributes of the `CoSimulation` element after `modelIdentifier`,
/// in the order written: the capabilities the C interface provides (the
/// quarter car's and the corner's).
/// Flags left at their schema default (`false`) are written too, so that
/// the description states each decision: no event mode, no early return
/// other than the one the importer asks for in an intermediate update, no
/// per-element dependencies (`fmi3GetVariableDependencies`).
pub const CO_SIMULATION_CAPABILITIES: [(&str, &str); 14] = [
    ("needsExecutionTool", "false"),
    ("canBeInstantiatedOnlyOncePerProcess", "false"),
    ("canGetAndSetFMUState", "true"),
    ("canSerializeFMUState", "true"),
    ("providesDirectionalDerivatives", "true"),
    ("providesAdjointDerivatives", "true"),
    ("providesPerElementDependencies", "false"),
    ("canHandleVariableCommunicationStepSize", "true"),
    ("maxOutputDerivativeOrder", "1"),
    ("providesIntermediateUpdate", "true"),
    ("mightReturnEarlyFromDoStep", "false"),
    ("canReturnEarlyAfterIntermediateUpdate", "true"),
    ("hasEventMode", "false"),
    ("providesEvaluateDiscreteStates", "false"),
];

/// The chassis's capabilities ([`Model::Chassis`]), in the order of
/// [`CO_SIMULATION_CAPABILITIES`]: its step is a closed form, so it takes
/// any step size; it provides neither output, directional nor adjoint
/// derivatives, no intermediate update and so no early return.
pub const CHASSIS_CO_SIMULATION_CAPABILITIES: [(&str, &str); 14] = [
    ("needsExecutionTool", "false"),
    ("canBeInstantiatedOnlyOncePerProcess", "false"),
    ("canGetAndSetFMUState", "true"),
    ("canSerializeFMUState", "true"),
    ("providesDirectionalDerivatives", "false"),
    ("providesAdjointDerivatives", "false"),
    ("providesPerElementDependencies", "false"),
    ("canHandleVariableCommunicationStepSize", "true"),
    ("maxOutputDerivativeOrder", "0"),
    ("providesIntermediateUpdate", "false"),
    ("mightReturnEarlyFromDoStep", "false"),
    ("canReturnEarlyAfterIntermediateUpdate", "false"),
    ("hasEventMode", "false"),
    ("providesEvaluateDiscreteStates", "false"),
];

/// The `CoSimulation` attributes of `model` after `modelIdentifier`.
pub fn co_simulation_capabilities(model: Model) -> &'static [(&'static str, &'static str)] {
    match model {
        Model::Chassis => &CHASSIS_CO_SIMULATION_CAPABILITIES,
        Model::QuarterCar | Model::Corner => &CO_SIMULATION_CAPABILITIES,
    }
}

/// A value of `v` as its FMI 3.0 type writes it (integers without a
/// fraction).
fn value_text(v: &Variable, value: f64) -> String {
    match fmi3_type(v) {
        Fmi3Type::Float64 => number(value),
        Fmi3Type::Int32 | Fmi3Type::UInt64 | Fmi3Type::Enumeration => {
            format!("{}", value as i64)
        }
        Fmi3Type::Boolean => (value != 0.0).to_string(),
    }
}

/// The value reference of the variable of `model` called `name`.
fn vr_of(model: Model, name: &str) -> u32 {
    by_name(model, FmiVersion::Fmi3, name)
        .unwrap_or_else(|| panic!("unknown variable `{name}`"))
        .vr
}

/// The enumeration types of `model`'s variables, each once, in table order.
pub fn enumerations(model: Model) -> Vec<&'static Enumeration> {
    let mut out: Vec<&'static Enumeration> = Vec::new();
    for e in variables_of(model, FmiVersion::Fmi3)
        .iter()
        .filter_map(|v| v.enumeration)
    {
        if !out.iter().any(|known| known.type_name == e.type_name) {
            out.push(e);
        }
    }
    out
}

/// The `(name, value)` of the `Dimension` element of `dimension`:
/// `start` for a fixed size, `valueReference` of the structural parameter.
fn dimension_attribute(model: Model, dimension: &Dimension) -> (&'static str, String) {
    match dimension {
        Dimension::Fixed(size) => ("start", size.to_string()),
        Dimension::Structural(name) => ("valueReference", vr_of(model, name).to_string()),
    }
}

/// The value references an output of `model` depends on (the inputs it
/// feeds through: `x_g`, the corner's body inputs; the continuous states
/// it is computed from, a model with Model Exchange only) with their
/// `dependenciesKind`, by ascending value reference: what
/// `fmi3GetVariableDependencies` returns.
pub fn output_dependencies(model: Model, v: &Variable) -> Vec<(u32, &'static str)> {
    let mut found: Vec<(u32, &str)> = v
        .output_dependencies(model, FmiVersion::Fmi3)
        .into_iter()
        .map(|(known, kind)| (known.vr, kind.name()))
        .collect();
    found.sort_unstable();
    found
}

/// The value references an initial unknown depends on in initialization
/// mode: the table's initial dependencies and, for an array, the
/// structural parameters that size it; ascending (value references of
/// `model`).
pub fn initial_dependencies(model: Model, v: &Variable) -> Vec<u32> {
    let structural = v.dimensions.iter().filter_map(|d| match d {
        Dimension::Structural(name) => Some(*name),
        Dimension::Fixed(_) => None,
    });
    sorted_vrs(
        model,
        v.initial_dependencies.iter().copied().chain(structural),
    )
}

fn sorted_vrs<'a>(model: Model, names: impl Iterator<Item = &'a str>) -> Vec<u32> {
    let mut vrs: Vec<u32> = names.map(|name| vr_of(model, name)).collect();
    vrs.sort_unstable();
    vrs.dedup();
    vrs
}

fn vr_list(vrs: &[u32]) -> String {
    vrs.iter().map(u32::to_string).collect::<Vec<_>>().join(" ")
}

/// Whether `v` is an `InitialUnknown`: outputs (all calculated, the states
/// among them), calculated parameters, the local continuous states and the
/// derivatives (all calculated); not the event indicator.
fn is_initial_unknown(v: &Variable) -> bool {
    matches!(
        v.causality,
        Causality::Output | Causality::CalculatedParameter
    ) || matches!(
        v.access,
        Access::ContinuousState(_) | Access::StateDerivative(_)
    )
}

/// The typed quantities the FMI 3.0 variables of `model` declare: those
/// of its `Float64` variables (an enumeration declares its own type).
fn quantities(model: Model) -> Vec<Quantity> {
    typed_in_use(
        variables_of(model, FmiVersion::Fmi3)
            .iter()
            .filter(|v| fmi3_type(v) == Fmi3Type::Float64)
            .map(|v| v.quantity),
    )
}

/// `TypeDefinitions`: a `Float64Type` of each of `quantities`, then the
/// enumerations of `model`.
fn write_type_definitions(w: &mut XmlWriter, model: Model, quantities: &[Quantity]) -> XmlResult {
    w.create_element("TypeDefinitions")
        .write_inner_content(|w| {
            for q in quantities {
                let (name, quantity, unit) = q.type_definition().expect("typed quantity");
                w.create_element("Float64Type")
                    .with_attribute(("name", name))
                    .with_attribute(("quantity", quantity))
                    .with_attribute(("unit", unit))
                    .write_empty()?;
            }
            for e in enumerations(model) {
                w.create_element("EnumerationType")
                    .with_attribute(("name", e.type_name))
                    .write_inner_content(|w| {
                        for item in e.items {
                            w.create_element("Item")
                                .with_attribute(("name", item.name))
                                .with_attribute(("value", item.value.to_string().as_str()))
                                .with_attribute(("description", item.description))
                                .write_empty()?;
                        }
                        Ok(())
                    })?;
            }
            Ok(())
        })?;
    Ok(())
}

/// The attributes of the variable element of `v` (of `model`), in the
/// order written.
fn variable_attributes(model: Model, v: &Variable) -> Vec<(&'static str, String)> {
    let mut attributes: Vec<(&'static str, String)> = vec![
        ("name", v.name.into()),
        ("valueReference", v.vr.to_string()),
        ("description", v.description.into()),
        ("causality", v.causality.as_str().into()),
        ("variability", v.variability.as_str().into()),
    ];
    if let Some(initial) = v.initial() {
        attributes.push(("initial", initial.as_str().into()));
    }
    match fmi3_type(v) {
        Fmi3Type::Float64 => {
            if let Some((type_name, _, unit)) = v.quantity.type_definition() {
                attributes.push(("declaredType", type_name.into()));
                attributes.push(("unit", unit.into()));
            }
            if let Some(display) = v.display_unit {
                attributes.push(("displayUnit", display.into()));
            }
        }
        Fmi3Type::Enumeration => {
            let e = v.enumeration.expect("an Enumeration has its type");
            attributes.push(("declaredType", e.type_name.into()));
        }
        Fmi3Type::Int32 | Fmi3Type::UInt64 | Fmi3Type::Boolean => {}
    }
    let (min, max) = v.range.bounds();
    if let Some(min) = min {
        attributes.push(("min", value_text(v, min)));
    }
    if let Some(max) = max {
        attributes.push(("max", value_text(v, max)));
    }
    if let Some(start) = v.start {
        attributes.push(("start", value_text(v, start)));
    }
    if v.intermediate_update {
        attributes.push(("intermediateUpdate", "true".into()));
    }
    if let Access::StateDerivative(i) = v.access {
        attributes.push(("derivative", state_vr(model, i).to_string()));
    }
    attributes
}

fn write_variable(w: &mut XmlWriter, model: Model, v: &Variable) -> XmlResult {
    let attributes = variable_attributes(model, v);
    let element = w
        .create_element(fmi3_type(v).as_str())
        .with_attributes(attributes.iter().map(|(k, v)| (*k, v.as_str())));
    if v.dimensions.is_empty() {
        element.write_empty()?;
    } else {
        element.write_inner_content(|w| {
            for d in v.dimensions {
                let (key, value) = dimension_attribute(model, d);
                w.create_element("Dimension")
                    .with_attribute((key, value.as_str()))
                    .write_empty()?;
            }
            Ok(())
        })?;
    }
    Ok(())
}

/// `ModelStructure`: the outputs, the derivatives (a model with Model
/// Exchange only), the initial unknowns and the event indicators (Model
/// Exchange's variables).
fn write_model_structure(w: &mut XmlWriter, model: Model) -> XmlResult {
    let variables = variables_of(model, FmiVersion::Fmi3);
    w.create_element("ModelStructure")
        .write_inner_content(|w| {
            for v in variables
                .iter()
                .filter(|v| v.causality == Causality::Output)
            {
                let (dependencies, kinds): (Vec<u32>, Vec<&str>) =
                    output_dependencies(model, v).into_iter().unzip();
                let kinds = kinds.join(" ");
                let mut unknown = w
                    .create_element("Output")
                    .with_attribute(("valueReference", v.vr.to_string().as_str()))
                    .with_attribute(("dependencies", vr_list(&dependencies).as_str()));
                if !kinds.is_empty() {
                    unknown = unknown.with_attribute(("dependenciesKind", kinds.as_str()));
                }
                unknown.write_empty()?;
            }
            // In the order of the continuous states (that of
            // fmi3GetContinuousStates); each depends on every known (no
            // `dependencies`).
            let states: &[usize] = if model.offers_model_exchange() {
                model.continuous_states()
            } else {
                &[]
            };
            for &i in states {
                w.create_element("ContinuousStateDerivative")
                    .with_attribute((
                        "valueReference",
                        derivative_vr(model, i).to_string().as_str(),
                    ))
                    .write_empty()?;
            }
            for v in variables.iter().filter(|v| is_initial_unknown(v)) {
                let unknown = w
                    .create_element("InitialUnknown")
                    .with_attribute(("valueReference", v.vr.to_string().as_str()));
                match v.access {
                    // On every known of initialization (no `dependencies`).
                    Access::ContinuousState(_) | Access::StateDerivative(_) => {
                        unknown.write_empty()?;
                    }
                    _ => {
                        unknown
                            .with_attribute((
                                "dependencies",
                                vr_list(&initial_dependencies(model, v)).as_str(),
                            ))
                            .write_empty()?;
                    }
                }
            }
            // Continuous Float64 variables, never InitialUnknowns (a model
            // without Model Exchange has none).
            for v in variables
                .iter()
                .filter(|v| matches!(v.access, Access::EventIndicator(_)))
            {
                w.create_element("EventIndicator")
                    .with_attribute(("valueReference", v.vr.to_string().as_str()))
                    .write_empty()?;
            }
            Ok(())
        })?;
    Ok(())
}

/// The complete FMI 3.0 `modelDescription.xml` of `model`: with
/// `ModelExchange` when the model offers it, the types and units its
/// variables use.
pub fn model_description_xml(model: Model) -> String {
    let token = instantiation_token(model);
    let quantities = quantities(model);
    let frame = DescriptionFrame {
        fmi_version: FMI_VERSION,
        model,
        quantities: &quantities,
        token: ("instantiationToken", &token),
        co_simulation: co_simulation_capabilities(model),
        model_exchange: model
            .offers_model_exchange()
            .then_some(model_exchange_capabilities(model)),
        root: &[],
    };
    model_description(
        frame,
        |w| write_type_definitions(w, model, &quantities),
        |w| {
            w.create_element("ModelVariables")
                .write_inner_content(|w| {
                    for v in variables_of(model, FmiVersion::Fmi3) {
                        write_variable(w, model, v)?;
                    }
                    Ok(())
                })?;
            write_model_structure(w, model)
        },
    )
}

mod documentation;
pub use documentation::documentation_html;

#[cfg(test)]
mod tests;
