//! The documentation pages of the components of a vehicle, the models
//! that are one part of a co-simulated car: the corner ([`Model::Corner`])
//! and the chassis ([`Model::Chassis`]). Each page is shorter than the
//! quarter car's: what the component is (its inputs and outputs, its
//! parameters), its diagram, its variables, the default experiment and
//! its Co-Simulation capabilities. The FMI 2.0 and FMI 3.0 pages of a
//! component differ only in what [`ComponentPage`] holds and in what the
//! version changes about its inputs.

use crate::markup::{
    REFERENCE_RESULTS, XmlResult, XmlWriter, description, diagram, html_page, list, number,
    paragraph, table, text_element, variable_table,
};
use tdvass_fmu::variables::{FmiVersion, by_name};
use tdvass_fmu::{
    DEFAULT_START_TIME, DEFAULT_STEP_SIZE, DEFAULT_STOP_TIME, MODEL_IDENTIFIER, Model,
};

/// What a component's page of one FMI version says in its own words.
pub(crate) struct ComponentPage<'a> {
    /// The component: the corner or the chassis.
    pub(crate) model: Model,
    /// The FMI version of the page.
    pub(crate) version: FmiVersion,
    /// How the model description identifies the interface, with what it
    /// hashes: `GUID {...} (a hash of ...)`.
    pub(crate) identity: String,
    /// The header of the type column of the variable table.
    pub(crate) type_header: &'a str,
    /// The rows of the variable table, one per variable.
    pub(crate) rows: Vec<Vec<String>>,
    /// What follows the variable table (FMI 3.0: the enumerations).
    pub(crate) after_variables: &'a dyn Fn(&mut XmlWriter) -> XmlResult,
    /// The attributes of the `CoSimulation` element after `modelIdentifier`.
    pub(crate) co_simulation: &'a [(&'a str, &'a str)],
    /// The attributes of the `ModelExchange` element after
    /// `modelIdentifier`.
    pub(crate) model_exchange: &'a [(&'a str, &'a str)],
    /// The standard, for the references.
    pub(crate) specification: &'a str,
}

/// `FMI 2.0` or `FMI 3.0`.
fn label(version: FmiVersion) -> &'static str {
    match version {
        FmiVersion::Fmi2 => "FMI 2.0",
        FmiVersion::Fmi3 => "FMI 3.0",
    }
}

/// What the page calls the component: `corner`, `chassis`.
/// What the page says of the model's Model Exchange: its continuous
/// states in order, its event indicators, what the master sets.
fn model_exchange_text(model: Model, version: FmiVersion) -> String {
    let variables = tdvass_fmu::variables::variables_of(model, version);
    let states: Vec<&str> = model
        .continuous_states()
        .iter()
        .map(|&i| {
            variables
                .iter()
                .find(|v| v.state_index() == Some(i))
                .map(|v| v.name)
                .unwrap_or_else(|| panic!("no variable of continuous state {i}"))
        })
        .collect();
    let instantiate = match version {
        FmiVersion::Fmi2 => "fmi2Instantiate with fmi2ModelExchange",
        FmiVersion::Fmi3 => "fmi3InstantiateModelExchange",
    };
    let what = match model {
        Model::Chassis => {
            "The event indicators: none. The master sets the four forces at every point it evaluates (each is taken as it is; the forces' rates play no part); heave, pitch, roll and their rates are outputs and states, the W_k filter of the seat acceleration and the integrals behind the RMS accelerations, the RMS of a_w and the VDV are local states. The states are linear in the forces: the master's solver alone sets the accuracy. No delay history: CompletedIntegratorStep is not needed. No directional derivatives."
        }
        _ => {
            "The event indicator contact_indicator is the margin W/k_t - TDD to the loss of tire contact, as in the quarter car. The master sets body_displacement and body_velocity, the attachment point's motion now, before each evaluation of the derivatives (the body's coordinates are inputs, not states), and x_g with road = 0. The delayed x_t(t - tau) comes from a history of the master's points, as in the quarter car: call CompletedIntegratorStep at the solver's accepted steps. No directional derivatives in Model Exchange (those of Co-Simulation remain)."
        }
    };
    format!(
        "The {} also serves Model Exchange ({instantiate}): the master's solver integrates its {} continuous states, in this order: {}. Their derivatives are the local variables der(...). {what}",
        noun(model),
        states.len(),
        states.join(", ")
    )
}

fn noun(model: Model) -> &'static str {
    match model {
        Model::Corner => "corner",
        Model::Chassis => "chassis",
        Model::QuarterCar => panic!("the quarter car has a page of its own"),
    }
}

/// The complete `documentation/index.html` of a component's FMU.
pub(crate) fn component_page(page: &ComponentPage<'_>) -> String {
    html_page(
        &format!("{} {} FMU", page.model.name(), label(page.version)),
        |w| write_body(w, page),
    )
}

fn write_body(w: &mut XmlWriter, page: &ComponentPage<'_>) -> XmlResult {
    let (model, version) = (page.model, label(page.version));
    text_element(
        w,
        "h1",
        &format!(
            "{}: {version} FMU (Co-Simulation and Model Exchange)",
            model.name()
        ),
    )?;
    paragraph(w, description(model))?;
    paragraph(
        w,
        &format!(
            "modelIdentifier {MODEL_IDENTIFIER}, {}, version {}. The shared library is the quarter car's, byte for byte (the quarter car's {version} FMU of the same build carries it too): the token of this model description picks the {} when the FMU is instantiated.",
            page.identity,
            env!("CARGO_PKG_VERSION"),
            noun(model),
        ),
    )?;

    text_element(w, "h2", "The model")?;
    diagram(w, model)?;
    match model {
        Model::Chassis => write_chassis(w, page.version)?,
        _ => write_corner(w)?,
    }

    text_element(w, "h2", "Variables")?;
    variable_table(w, page.type_header, &page.rows)?;
    paragraph(
        w,
        "Parameters are fixed (settable before the end of initialization) unless tunable. Values outside the range, NaN or infinite are refused with an error naming the variable and value.",
    )?;
    (page.after_variables)(w)?;

    text_element(w, "h2", "Default experiment")?;
    let experiment = format!(
        "startTime {DEFAULT_START_TIME} s, stopTime {DEFAULT_STOP_TIME} s, stepSize {DEFAULT_STEP_SIZE} s."
    );
    paragraph(
        w,
        &match model {
            Model::Chassis => format!(
                "{experiment} With the start values the four forces are 0 and the chassis stays at rest at its static equilibrium: every output is 0 throughout (the reference results too). It moves when corners, or the master, apply forces."
            ),
            _ => format!(
                "{experiment} With the start values (TDVASS, g = 5386 N/m, tau = 0.2 ms, harmonic road 0.05 sin 5t, from rest, body_displacement = body_velocity = 0) the corner is the suspension under a body fixed at its static equilibrium, and body_force the dynamic force the suspension puts on that body."
            ),
        },
    )?;
    paragraph(w, REFERENCE_RESULTS)?;

    text_element(w, "h2", "Model Exchange")?;
    paragraph(w, &model_exchange_text(model, page.version))?;
    let rows: Vec<Vec<String>> = page
        .model_exchange
        .iter()
        .map(|(name, value)| vec![name.to_string(), value.to_string()])
        .collect();
    table(w, &["attribute", "value"], &rows)?;

    text_element(w, "h2", "Co-Simulation")?;
    if model == Model::Chassis {
        paragraph(w, chassis_capabilities(page.version))?;
    }
    let rows: Vec<Vec<String>> = page
        .co_simulation
        .iter()
        .map(|(name, value)| vec![name.to_string(), value.to_string()])
        .collect();
    table(w, &["attribute", "value"], &rows)?;

    text_element(w, "h2", "References")?;
    let references: Vec<&str> = match model {
        Model::Chassis => vec![
            "Mechanism of time-delay feedback control of suspension damping with an annular vibration-absorbing structure (the source paper: its quarter car's body, Table 1, is a quarter of the default chassis).",
            "ISO 2631-1: Mechanical vibration and shock - Evaluation of human exposure to whole-body vibration - Part 1: General requirements (the W_k weighting, the RMS and the vibration dose value).",
            page.specification,
        ],
        _ => vec![
            "Mechanism of time-delay feedback control of suspension damping with an annular vibration-absorbing structure (the source paper: model Eq. 1-2, Table 1 parameters).",
            page.specification,
        ],
    };
    list(w, &references)?;
    Ok(())
}

/// The corner's model: the suspension without its body, its inputs and
/// outputs, static load and road.
fn write_corner(w: &mut XmlWriter) -> XmlResult {
    paragraph(
        w,
        "The quarter car's suspension and wheel without its body: the annular absorber (m_h) on the wheel through k_h, c_h, the wheel (m_t) on the road through the tire k_t, the control force u = g x_t(t - tau) between absorber and wheel (TDVASS; PVASS is g = 0; CS has no absorber, and x_h, v_h mirror x_t, v_t), and the suspension spring and damper k_s, c_s up to the body's attachment point. The body is not part of the FMU: another FMU (a chassis) or the master moves it.",
    )?;
    list(
        w,
        &[
            "Inputs body_displacement and body_velocity: the attachment point's displacement from the static equilibrium and its velocity, positive up. From the time they are set, the attachment moves at body_velocity from body_displacement, over the steps that follow, until either is set again (their input derivatives are not used); they reach body_force at once. With input_extrapolation = 1 or 2 (Co-Simulation), the attachment's velocity is extrapolated instead along the line through the last two body_velocity values set at communication points: over a step the attachment moves at that line's mean velocity, reaches the extrapolated displacement and ends at the extrapolated velocity (the first step holds). At their start values (0) the body is fixed at its static equilibrium, and the corner is the suspension under a fixed body.",
            "Output body_force: the force of k_s and c_s on the body at the attachment point, positive up and zero at the static equilibrium (the body's weight is not in it). It depends directly on body_displacement and body_velocity (direct feedthrough; ModelStructure lists both). The suspension deflection is SDD = body_displacement - x_t; the other outputs are the quarter car's, with the attachment point in place of the body.",
            "static_load: this corner's share W_c of the body's weight (default 345 kg g0, the paper's body). The tire's static load W = static_load + (m_h + m_t) g0 (CS: static_load + m_t g0) sets where the unilateral tire (tire_contact = 1) lifts off, and divides the dynamic tire load in rms_dynamic_tire_load_ratio.",
            "Road: road = 0 takes the input x_g (positive up, as the master sets it); road = 1 (the default) is the harmonic road x_g = road_amplitude sin(road_angular_frequency (t - road_delay) + road_phase); road = 2 and 3 are the quarter car's random roads. road_delay (s) is how much later this wheel sees the profile (a rear wheel: wheelbase / speed; must be 0 with road = 0); road_phase (rad) shifts the harmonic road (a right track out of phase with the left excites roll).",
        ],
    )
}

/// The start value of the chassis's parameter `name`.
fn chassis_start(name: &str) -> f64 {
    by_name(Model::Chassis, FmiVersion::Fmi2, name)
        .and_then(|v| v.start)
        .unwrap_or_else(|| panic!("the chassis has no parameter `{name}` with a start value"))
}

/// How the forces act over a communication step in `version`.
fn chassis_inputs(version: FmiVersion) -> &'static str {
    match version {
        FmiVersion::Fmi2 => {
            "Inputs force_fl, force_fr, force_rl and force_rr: the corners' forces on the body at their attachment points (N, positive up; a corner FMU's body_force). Over a communication step a force is held at the value set for it or, when its order-1 derivative is set with fmi2SetRealInputDerivatives (canInterpolateInputs = true), follows the straight line of that value and slope. A force set anew is held unless its derivative is set again; a force not set at a communication point goes on along its line. With input_extrapolation = 1, a force set at a communication point without its derivative follows the line through its last two values set (the first step holds). Higher derivative orders are ignored with a warning. The step is exact (a closed form) for such forces, whatever its length."
        }
        FmiVersion::Fmi3 => {
            "Inputs force_fl, force_fr, force_rl and force_rr: the corners' forces on the body at their attachment points (N, positive up; a corner FMU's body_force). Over a communication step a force is held at the value set for it (FMI 3.0 has no input derivatives, and the chassis provides no intermediate update) or, with input_extrapolation = 1, follows the line through its last two values set at communication points (the first step holds). The step is exact (a closed form), whatever its length."
        }
    }
}

/// The chassis's model: the rigid body, its geometry and sign
/// conventions, its inputs and outputs, the decoupling of front and rear
/// and the defaults.
fn write_chassis(w: &mut XmlWriter, version: FmiVersion) -> XmlResult {
    paragraph(
        w,
        "A rigid body of mass m in heave z (of the centre of gravity), pitch theta and roll phi, with small angles. Displacements and angles are taken from the static equilibrium: z positive up, pitch positive nose up, roll positive left side up. The corners are attached at (x, y) from the centre of gravity, x ahead and y to the left: front left (a, track_front/2), front right (a, -track_front/2), rear left (-b, track_rear/2), rear right (-b, -track_rear/2); the point (x, y) of the body is at z + x theta + y phi. Under the corners' forces f_i (positive up): m z'' = sum of f_i, I_theta theta'' = sum of x_i f_i, I_phi phi'' = sum of y_i f_i. The body's weight is not among the forces: they are the corners' dynamic forces, zero at the static equilibrium.",
    )?;
    let start = chassis_start;
    let defaults = format!(
        "Defaults: the paper's car. mass = 4 x 345 kg = {} kg (each corner carries the paper's quarter-car body), a = {} m, b = {} m, track_front = {} m, track_rear = {} m, pitch_inertia = m a b = {:.1} kg m2, roll_inertia = {} kg m2, the seat point seat_x = {} m ahead of and seat_y = {} m left of the centre of gravity.",
        number(start("mass")),
        number(start("a")),
        number(start("b")),
        number(start("track_front")),
        number(start("track_rear")),
        start("pitch_inertia"),
        number(start("roll_inertia")),
        number(start("seat_x")),
        number(start("seat_y")),
    );
    list(
        w,
        &[
            chassis_inputs(version),
            "Outputs displacement_fl, displacement_fr, displacement_rl, displacement_rr and velocity_fl .. velocity_rr: the attachment points' displacements z + x theta + y phi and their velocities, positive up. They depend on the states only, not directly on the forces (ModelStructure lists no dependencies): corners that take them as their body_displacement and body_velocity and return their body_force as the forces close no algebraic loop.",
            "Outputs heave, pitch, roll and their rates heave_velocity, pitch_rate, roll_rate: the states. The accelerations heave_acceleration, pitch_acceleration, roll_acceleration, seat_acceleration and weighted_seat_acceleration depend directly on the four forces (ModelStructure lists them, dependenciesKind fixed).",
            "Ride comfort at the seat point (seat_x, seat_y): its vertical acceleration seat_acceleration = z'' + seat_x theta'' + seat_y phi'', weighted by the ISO 2631-1 W_k filter integrated exactly over each step (weighted_seat_acceleration, a_w), the running RMS of a_w from the start time (rms_weighted_seat_acceleration) and the vibration dose value (integral of a_w^4)^(1/4) (seat_vibration_dose_value); and the running RMS of the heave, pitch and roll accelerations (rms_heave_acceleration, rms_pitch_acceleration, rms_roll_acceleration), exact for forces that are linear over a step.",
            "With pitch_inertia = m a b (the default) the forces at one axle do not heave or pitch the other axle: the middle of the rear axle, z - b theta, does not respond to the front forces, nor z + a theta to the rear ones. So front and rear decouple when both tracks see the same road (no roll), and each front corner then carries m b / (a + b) / 2 and each rear corner m a / (a + b) / 2, as a quarter car's body would. Roll couples all four corners: left and right never decouple (four corners, three degrees of freedom).",
            &defaults,
        ],
    )
}

/// What the chassis provides in Co-Simulation in `version`, beside the
/// table of its capabilities.
fn chassis_capabilities(version: FmiVersion) -> &'static str {
    match version {
        FmiVersion::Fmi2 => {
            "The step is a closed form, exact for any communication step size (canHandleVariableCommunicationStepSize = true). The forces' order-1 input derivatives are used (canInterpolateInputs = true; see the inputs above). The chassis provides no output derivatives (maxOutputDerivativeOrder = 0: fmi2GetRealOutputDerivatives fails) and no directional derivatives (providesDirectionalDerivative = false: fmi2GetDirectionalDerivative fails). Its state can be got, set and serialized (fmi2GetFMUstate, fmi2SetFMUstate, fmi2SerializeFMUstate)."
        }
        FmiVersion::Fmi3 => {
            "The step is a closed form, exact for any communication step size (canHandleVariableCommunicationStepSize = true). The chassis provides no output derivatives (maxOutputDerivativeOrder = 0), no directional or adjoint derivatives, no intermediate update (it never calls the importer's intermediateUpdate callback and never returns early from fmi3DoStep) and no event mode. Its state can be got, set and serialized (fmi3GetFMUState, fmi3SetFMUState, fmi3SerializeFMUState)."
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::markup::{CHASSIS_LEGEND, CORNER_LEGEND, DIAGRAM_LEGEND, legend};
    use tdvass_fmu::Model;
    use tdvass_fmu::variables::{FmiVersion, by_name};

    #[test]
    fn the_corner_legend_replaces_the_body_and_the_road_with_its_own_variables() {
        assert_eq!(legend(Model::QuarterCar), DIAGRAM_LEGEND);
        let corner = legend(Model::Corner);
        assert_eq!(corner.len(), DIAGRAM_LEGEND.len());
        for own in CORNER_LEGEND {
            assert!(corner.contains(own), "{}", own.0);
            assert!(DIAGRAM_LEGEND.iter().any(|row| row.0 == own.0), "{}", own.0);
        }
        for model in Model::ALL {
            for (symbol, _, names) in legend(model) {
                for name in names {
                    assert!(
                        by_name(model, FmiVersion::Fmi2, name).is_some(),
                        "{model:?}: {symbol} names {name}"
                    );
                }
            }
        }
    }

    /// The chassis's legend is its own: none of the quarter car's symbols,
    /// every force and attachment point named.
    #[test]
    fn the_chassis_legend_names_its_own_symbols() {
        let chassis = legend(Model::Chassis);
        assert_eq!(chassis, CHASSIS_LEGEND);
        for (symbol, _, _) in &chassis {
            assert!(
                !DIAGRAM_LEGEND.iter().any(|row| row.0 == *symbol),
                "{symbol}"
            );
        }
        let named: Vec<&str> = chassis
            .iter()
            .flat_map(|row| row.2.iter().copied())
            .collect();
        for corner in ["fl", "fr", "rl", "rr"] {
            assert!(named.contains(&format!("force_{corner}").as_str()));
            assert!(named.contains(&format!("displacement_{corner}").as_str()));
        }
    }
}
