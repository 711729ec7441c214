//! What the generated model descriptions and documentation pages of every
//! FMI version write alike: the frame of a model description (its root
//! element, `ModelExchange`, `CoSimulation`, the unit definitions, the log
//! categories and the default experiment), the one-line model description,
//! what the pages say of Model Exchange, numbers,
//! elements with text, paragraphs, lists, tables, the model's diagram with
//! the legend of its symbols, and the HTML page around a body (quick-xml,
//! never written by hand). Each model ([`Model`]) has its own name, one-line
//! description and legend of the diagram, and its description defines the
//! types and units its variables use, no others ([`typed_in_use`]).

use quick_xml::Writer;
use quick_xml::events::{BytesDecl, BytesText, Event};
use std::io::Cursor;
use tdvass::solver::CONTINUOUS_STATES;
use tdvass::solver::DEFAULT_TOLERANCE;
use tdvass_fmu::Model;
use tdvass_fmu::variables::{
    Access, Causality, FmiVersion, Quantity, UNITS, UnitDefinition, Variable, by_name,
};
use tdvass_fmu::{
    DEFAULT_START_TIME, DEFAULT_STEP_SIZE, DEFAULT_STOP_TIME, LOG_CATEGORIES, MODEL_IDENTIFIER,
};

/// A writer of XML (or HTML) into memory.
pub type XmlWriter = Writer<Cursor<Vec<u8>>>;
/// What writing into memory returns.
pub type XmlResult = std::io::Result<()>;

/// One-line description of the quarter car ([`Model::QuarterCar`]).
pub const MODEL_DESCRIPTION: &str = "Quarter-car suspension with an annular vibration-absorbing structure and time-delay feedback of the tire displacement (TDVASS), with the conventional (CS) and uncontrolled absorber (PVASS) suspensions for comparison";

/// One-line description of the corner ([`Model::Corner`]).
pub const CORNER_DESCRIPTION: &str = "One corner of a vehicle: the TDVASS suspension (annular absorber, time-delay feedback of the wheel displacement; CS and PVASS for comparison) and its wheel and tire, without the body: the body's attachment point's motion is an input and the force on the body an output";

/// One-line description of the chassis ([`Model::Chassis`]).
pub const CHASSIS_DESCRIPTION: &str = "The body of a vehicle on four corners: a rigid body in heave, pitch and roll (small angles) driven by the four corners' forces, with the attachment points' motion and the ride comfort at a seat point (ISO 2631-1 W_k, VDV); default: the paper's car";

/// The one-line description of `model`: the `description` attribute of
/// its model description and the first paragraph of its page.
pub fn description(model: Model) -> &'static str {
    match model {
        Model::QuarterCar => MODEL_DESCRIPTION,
        Model::Corner => CORNER_DESCRIPTION,
        Model::Chassis => CHASSIS_DESCRIPTION,
    }
}

/// The style sheet of the documentation pages.
const STYLE: &str = "body{font-family:sans-serif;max-width:70em;margin:auto;padding:1em}table{border-collapse:collapse}td,th{border:1px solid #bbb;padding:0.2em 0.5em;text-align:left;vertical-align:top}figure{margin:1em 0}";

/// What the documentation says of the reference results every FMU carries
/// (fmu-build writes them and checks that this paragraph names their file
/// and interval).
pub const REFERENCE_RESULTS: &str = "Reference results (the layered standard FMI-LS-REF): extra/org.fmi-standard.fmi-ls-ref/tdvass_out.csv, named by fmi-ls-manifest.xml beside it, holds every Real output of the default experiment every 0.05 s (time in the first column), computed when the FMU was built by the same slave its binaries wrap. A master that runs the default experiment with communication steps of 0.05 s reproduces every column to within 1e-12 of its largest absolute value.";

/// The model's diagram beside `documentation/index.html` (the FMU's icon,
/// drawn by `tools/draw_icon.py`; fmu-build packs it).
pub const DIAGRAM_FILE: &str = "diagram.png";
/// Width and height of the diagram (px).
pub const DIAGRAM_SIZE_PX: u32 = 320;

/// The symbols of the diagram: symbol, meaning, and the FMU variables that
/// carry it (their start values and units are taken from the variable
/// table). The quarter car's; the corner's replaces some rows
/// ([`CORNER_LEGEND`], [`legend`]).
pub const DIAGRAM_LEGEND: &[(&str, &str, &[&str])] = &[
    ("m_s", "body (sprung) mass", &["m_s"]),
    (
        "k_s, c_s",
        "suspension spring and damper between the body and the absorber",
        &["k_s", "c_s"],
    ),
    (
        "m_h",
        "mass of the annular vibration-absorbing structure (the ring between body and wheel)",
        &["m_h"],
    ),
    (
        "k_h, c_h",
        "spring and damper between the absorber and the wheel",
        &["k_h", "c_h"],
    ),
    ("m_t", "wheel (unsprung) mass", &["m_t"]),
    ("k_t", "tire stiffness (the tire has no damping)", &["k_t"]),
    (
        "x_g",
        "road displacement under the tire: the input x_g when road = 0, else the road model's; reported as road_displacement",
        &["x_g", "road_displacement"],
    ),
    (
        "x_s, x_h, x_t",
        "displacements of body, absorber and wheel from the static equilibrium, positive upwards",
        &["x_s", "x_h", "x_t"],
    ),
    (
        "g e^(-tau s)",
        "the feedback path: the wheel displacement x_t, delayed by tau and multiplied by the gain g (TDVASS; PVASS is g = 0, CS has neither absorber nor feedback)",
        &["g", "tau"],
    ),
    (
        "u = g x_t(t - tau)",
        "the control force of the actuator between absorber and wheel: -u on the absorber, +u on the wheel",
        &["control_force"],
    ),
];

/// The rows of [`DIAGRAM_LEGEND`] that the corner ([`Model::Corner`])
/// replaces: its body is outside the FMU, its road is delayed and shifted.
pub const CORNER_LEGEND: &[(&str, &str, &[&str])] = &[
    (
        "m_s",
        "the body (sprung mass), not part of the corner: its attachment point's displacement and velocity are inputs, the force of k_s and c_s on it is the output; static_load is its weight on this corner",
        &[
            "static_load",
            "body_displacement",
            "body_velocity",
            "body_force",
        ],
    ),
    (
        "x_g",
        "road displacement under the tire: the input x_g when road = 0, else the road model's as this wheel sees it (delayed by road_delay; the harmonic road also shifted by road_phase); reported as road_displacement",
        &["x_g", "road_displacement", "road_delay", "road_phase"],
    ),
    (
        "x_s, x_h, x_t",
        "displacements of the body's attachment point, absorber and wheel from the static equilibrium, positive upwards (x_s is the input body_displacement)",
        &["body_displacement", "x_h", "x_t"],
    ),
];

/// The symbols of the chassis ([`Model::Chassis`]): the diagram beside
/// its page is the library's icon (the quarter car, whose body m_s the
/// chassis generalizes), so that none of the quarter car's symbols is its
/// own.
pub const CHASSIS_LEGEND: &[(&str, &str, &[&str])] = &[
    ("m", "body mass", &["mass"]),
    (
        "I_theta, I_phi",
        "pitch and roll moments of inertia about the centre of gravity",
        &["pitch_inertia", "roll_inertia"],
    ),
    (
        "a, b",
        "centre of gravity to the front and to the rear axle",
        &["a", "b"],
    ),
    (
        "t_f, t_r",
        "front and rear track widths",
        &["track_front", "track_rear"],
    ),
    (
        "z, theta, phi",
        "heave of the centre of gravity, pitch (positive nose up) and roll (positive left side up), from the static equilibrium",
        &["heave", "pitch", "roll"],
    ),
    (
        "f_fl, f_fr, f_rl, f_rr",
        "the corners' forces on the body at their attachment points, positive up",
        &["force_fl", "force_fr", "force_rl", "force_rr"],
    ),
    (
        "z + x theta + y phi",
        "the displacement of the attachment point at (x, y): (a, t_f/2) front left, (a, -t_f/2) front right, (-b, t_r/2) rear left, (-b, -t_r/2) rear right",
        &[
            "displacement_fl",
            "displacement_fr",
            "displacement_rl",
            "displacement_rr",
        ],
    ),
    (
        "(x_seat, y_seat), a_w",
        "the seat point (ahead of and left of the centre of gravity) and its vertical acceleration weighted by ISO 2631-1 W_k",
        &["seat_x", "seat_y", "weighted_seat_acceleration"],
    ),
];

/// The legend of the diagram on `model`'s page: [`DIAGRAM_LEGEND`], for
/// the corner with the rows of [`CORNER_LEGEND`] in place of the
/// quarter car's of the same symbol; the chassis's own,
/// [`CHASSIS_LEGEND`].
pub fn legend(model: Model) -> Vec<(&'static str, &'static str, &'static [&'static str])> {
    if model == Model::Chassis {
        return CHASSIS_LEGEND.to_vec();
    }
    DIAGRAM_LEGEND
        .iter()
        .map(|row| match model {
            Model::Corner => CORNER_LEGEND
                .iter()
                .find(|own| own.0 == row.0)
                .copied()
                .unwrap_or(*row),
            _ => *row,
        })
        .collect()
}

/// What the model description of one FMI version states in the frame
/// every version shares ([`model_description`]).
#[derive(Debug, Clone, Copy)]
pub struct DescriptionFrame<'a> {
    /// `fmiVersion`.
    pub fmi_version: &'a str,
    /// The model described: its `modelName` ([`Model::name`]) and
    /// `description` ([`description`]).
    pub model: Model,
    /// The typed quantities its variables declare ([`typed_in_use`]):
    /// `UnitDefinitions` defines their units, no others.
    pub quantities: &'a [Quantity],
    /// The attribute that identifies the interface, after `modelName`:
    /// `("guid", ...)` or `("instantiationToken", ...)`.
    pub token: (&'a str, &'a str),
    /// The attributes of the `CoSimulation` element after
    /// `modelIdentifier`, in the order written.
    pub co_simulation: &'a [(&'a str, &'a str)],
    /// The attributes of the `ModelExchange` element after
    /// `modelIdentifier`, in the order written; `None`: no `ModelExchange`
    /// element (a model without it, [`Model::offers_model_exchange`]).
    pub model_exchange: Option<&'a [(&'a str, &'a str)]>,
    /// Attributes of the root element after `variableNamingConvention`
    /// (FMI 2.0: `numberOfEventIndicators`).
    pub root: &'a [(&'a str, &'a str)],
}

/// A complete `modelDescription.xml`: the XML declaration, the root
/// element, `ModelExchange` (if any), `CoSimulation`, `UnitDefinitions`
/// (of the frame's quantities), then the version's
/// `TypeDefinitions` (`write_type_definitions`), `LogCategories`,
/// `DefaultExperiment`, then the version's `ModelVariables` and
/// `ModelStructure` (`write_model`).
pub fn model_description(
    frame: DescriptionFrame<'_>,
    write_type_definitions: impl Fn(&mut XmlWriter) -> XmlResult,
    write_model: impl Fn(&mut XmlWriter) -> XmlResult,
) -> String {
    let mut w = writer();
    let write = |w: &mut XmlWriter| -> XmlResult {
        w.write_event(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None)))?;
        let tool = format!("tdvass fmu-build {}", env!("CARGO_PKG_VERSION"));
        w.create_element("fmiModelDescription")
            .with_attribute(("fmiVersion", frame.fmi_version))
            .with_attribute(("modelName", frame.model.name()))
            .with_attribute(frame.token)
            .with_attribute(("description", description(frame.model)))
            .with_attribute(("version", env!("CARGO_PKG_VERSION")))
            .with_attribute(("license", "MIT"))
            .with_attribute(("generationTool", tool.as_str()))
            .with_attribute(("variableNamingConvention", "flat"))
            .with_attributes(frame.root.iter().copied())
            .write_inner_content(|w| {
                if let Some(model_exchange) = frame.model_exchange {
                    w.create_element("ModelExchange")
                        .with_attribute(("modelIdentifier", MODEL_IDENTIFIER))
                        .with_attributes(model_exchange.iter().copied())
                        .write_empty()?;
                }
                w.create_element("CoSimulation")
                    .with_attribute(("modelIdentifier", MODEL_IDENTIFIER))
                    .with_attributes(frame.co_simulation.iter().copied())
                    .write_empty()?;
                write_unit_definitions(w, frame.quantities)?;
                write_type_definitions(w)?;
                w.create_element("LogCategories").write_inner_content(|w| {
                    for (name, description) in LOG_CATEGORIES {
                        w.create_element("Category")
                            .with_attribute(("name", name))
                            .with_attribute(("description", description))
                            .write_empty()?;
                    }
                    Ok(())
                })?;
                w.create_element("DefaultExperiment")
                    .with_attribute(("startTime", number(DEFAULT_START_TIME).as_str()))
                    .with_attribute(("stopTime", number(DEFAULT_STOP_TIME).as_str()))
                    .with_attribute(("tolerance", number(DEFAULT_TOLERANCE).as_str()))
                    .with_attribute(("stepSize", number(DEFAULT_STEP_SIZE).as_str()))
                    .write_empty()?;
                write_model(w)
            })?;
        Ok(())
    };
    write(&mut w).expect("writing to memory cannot fail");
    finish(w)
}

/// The typed quantities among `quantities` (those with a type
/// definition), each once, in the order of [`Quantity::TYPED`]: the
/// `TypeDefinitions` of a description whose variables declare
/// `quantities`.
pub fn typed_in_use(quantities: impl IntoIterator<Item = Quantity>) -> Vec<Quantity> {
    let used: Vec<Quantity> = quantities.into_iter().collect();
    Quantity::TYPED
        .into_iter()
        .filter(|q| used.contains(q))
        .collect()
}

/// The definition of the unit called `name` ([`UNITS`]).
fn unit_definition(name: &str) -> &'static UnitDefinition {
    UNITS
        .iter()
        .find(|u| u.name == name)
        .unwrap_or_else(|| panic!("no definition of the unit `{name}`"))
}

/// The units of `quantities`, each once, in the order of [`UNITS`].
pub fn units_in_use(quantities: &[Quantity]) -> Vec<&'static UnitDefinition> {
    let names: Vec<&str> = quantities.iter().filter_map(|q| q.unit()).collect();
    for name in &names {
        unit_definition(name);
    }
    let mut out: Vec<&'static UnitDefinition> = Vec::new();
    for unit in UNITS {
        if names.contains(&unit.name) && !out.iter().any(|known| known.name == unit.name) {
            out.push(unit);
        }
    }
    out
}

/// `UnitDefinitions`: the units of `quantities` ([`units_in_use`]) with
/// their base-unit exponents and display units (the same in FMI 2.0 and
/// 3.0).
fn write_unit_definitions(w: &mut XmlWriter, quantities: &[Quantity]) -> XmlResult {
    w.create_element("UnitDefinitions")
        .write_inner_content(|w| {
            for unit in units_in_use(quantities) {
                w.create_element("Unit")
                    .with_attribute(("name", unit.name))
                    .write_inner_content(|w| {
                        let exponents: Vec<(&str, String)> =
                            unit.base.iter().map(|(b, e)| (*b, e.to_string())).collect();
                        w.create_element("BaseUnit")
                            .with_attributes(exponents.iter().map(|(b, e)| (*b, e.as_str())))
                            .write_empty()?;
                        for (name, factor) in unit.display {
                            w.create_element("DisplayUnit")
                                .with_attribute(("name", *name))
                                .with_attribute(("factor", number(*factor).as_str()))
                                .write_empty()?;
                        }
                        Ok(())
                    })?;
            }
            Ok(())
        })?;
    Ok(())
}

/// What the documentation pages say of Model Exchange: `instantiate` is
/// the call that starts it, `variables` the version's variables (the
/// continuous states are named in their order, from the table).
pub fn model_exchange_text(instantiate: &str, variables: &[Variable]) -> String {
    let state = |i: usize| {
        variables
            .iter()
            .find(|v| v.state_index() == Some(i))
            .unwrap_or_else(|| panic!("no variable of continuous state {i}"))
            .name
    };
    let states: Vec<&str> = (0..CONTINUOUS_STATES).map(state).collect();
    let indicators: Vec<&str> = variables
        .iter()
        .filter(|v| matches!(v.access, Access::EventIndicator(_)))
        .map(|v| v.name)
        .collect();
    format!(
        "The same library also serves Model Exchange ({instantiate}): the importer's solver integrates the {CONTINUOUS_STATES} continuous states, in this order: {}. Their derivatives are the local variables der(...), each with the derivative attribute of its state; the states that are not outputs are local variables. The event indicator {} is the margin W/k_t - TDD to the loss of tire contact (positive in contact); lift-offs and touch-downs are its events. The running RMS values, J, the RMS of a_w, the VDV and the tire-load ratio come from the integral states; the accuracy is the importer's solver's. The delayed x_t(t - tau) comes from a history of the importer's points: call CompletedIntegratorStep at the solver's accepted steps, so that its stages do not enter the history (an explicit Runge-Kutta method then keeps its order) and the importer may go back to the last of them; an importer that never calls it may go back 1 s. Directional derivatives: exact partials of the state derivatives and the Real outputs with respect to the continuous states and x_g.",
        states.join(", "),
        indicators.join(", ")
    )
}

/// What the documentation of every version says of the tire.
pub const TIRE_CONTACT: &str = "Tire (tire_contact): 0 = bilateral, the paper's linear tire, which pulls as well as pushes; where the dynamic tire load falls below minus the static load W the real tire would leave the road and the linear model no longer holds: contact_loss_time accumulates that time and the first crossing is logged as a warning. 1 = unilateral: the tire cannot pull, so the wheel lifts off where TDD rises through W/k_t and flies (tire force -W) until TDD falls back to it; contact and flight are each integrated exactly, with the switches located inside the internal steps. contact_loss_time is then the flight time, and each lift-off is logged under logEvents with its time, TDD and W/k_t. lift_off_count counts the lift-offs in both modes. The stability results (spectral_abscissa, stable) are those of the linear (bilateral) model.";

/// The unit cell of a variable's row: `m (shown in mm)`, `kg`, `-`.
pub fn unit_text(v: &Variable) -> String {
    match (v.unit(), v.display_unit) {
        (Some(u), Some(d)) => format!("{u} (shown in {d})"),
        (Some(u), None) => u.to_string(),
        (None, _) => "-".to_string(),
    }
}

/// The table of variables of a documentation page, one of `rows` per
/// variable; `type_header` names the type column.
pub fn variable_table(w: &mut XmlWriter, type_header: &str, rows: &[Vec<String>]) -> XmlResult {
    table(
        w,
        &[
            "name",
            "value reference",
            type_header,
            "causality, variability",
            "start",
            "unit",
            "range",
            "meaning",
        ],
        rows,
    )
}

/// The variables of `model` of a legend row, with their start values and
/// units (`m_s (start 345 kg)`, `x_s (output, m)`).
fn legend_variables(model: Model, names: &[&str]) -> String {
    names
        .iter()
        .map(|name| {
            let v = by_name(model, FmiVersion::Fmi2, name)
                .unwrap_or_else(|| panic!("the legend names `{name}`, not a variable"));
            let unit = v.unit().map(|u| format!(" {u}")).unwrap_or_default();
            match v.start {
                Some(start) if v.causality != Causality::Input => {
                    format!("{name} (start {}{unit})", number(start))
                }
                _ => format!(
                    "{name} ({}{})",
                    v.causality.as_str(),
                    v.unit().map(|u| format!(", {u}")).unwrap_or_default()
                ),
            }
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// The model's diagram ([`DIAGRAM_FILE`] beside the page) and the legend of
/// its symbols ([`legend`]) with `model`'s variables.
pub fn diagram(w: &mut XmlWriter, model: Model) -> XmlResult {
    let size = DIAGRAM_SIZE_PX.to_string();
    w.create_element("figure").write_inner_content(|w| {
        w.create_element("img")
            .with_attribute(("src", DIAGRAM_FILE))
            .with_attribute(("width", size.as_str()))
            .with_attribute(("height", size.as_str()))
            .with_attribute((
                "alt",
                "Quarter car: body m_s on k_s and c_s, annular absorber m_h on k_h and c_h, wheel m_t on the tire spring k_t over the road x_g; an actuator between absorber and wheel applies u = g x_t(t - tau)",
            ))
            .write_empty()?;
        text_element(
            w,
            "figcaption",
            match model {
                Model::QuarterCar => {
                    "The quarter car with the annular absorber and the delayed feedback u = g x_t(t - tau)."
                }
                Model::Corner => {
                    "The quarter car with the annular absorber and the delayed feedback u = g x_t(t - tau): the corner is all of it but the body m_s, whose attachment point's motion is its input."
                }
                Model::Chassis => {
                    "The library's icon, the quarter car: the chassis is its body m_s grown into the rigid body of a whole car, which four corners carry at their attachment points. The symbols below are the chassis's own."
                }
            },
        )
    })?;
    let rows: Vec<Vec<String>> = legend(model)
        .iter()
        .map(|(symbol, meaning, names)| {
            vec![
                symbol.to_string(),
                meaning.to_string(),
                legend_variables(model, names),
            ]
        })
        .collect();
    table(w, &["symbol", "meaning", "FMU variables"], &rows)
}

/// Short number formatting: Rust's shortest round-trip representation.
pub fn number(v: f64) -> String {
    format!("{v}")
}

/// A writer indenting by two spaces.
pub fn writer() -> XmlWriter {
    Writer::new_with_indent(Cursor::new(Vec::new()), b' ', 2)
}

/// The text written, with a final newline.
pub fn finish(w: XmlWriter) -> String {
    let mut text = String::from_utf8(w.into_inner().into_inner()).expect("quick-xml writes UTF-8");
    text.push('\n');
    text
}

/// `<name>text</name>`, the text escaped.
pub fn text_element(w: &mut XmlWriter, name: &str, text: &str) -> XmlResult {
    w.create_element(name)
        .write_text_content(BytesText::new(text))?;
    Ok(())
}

/// `<p>text</p>`.
pub fn paragraph(w: &mut XmlWriter, text: &str) -> XmlResult {
    text_element(w, "p", text)
}

/// A `<ul>` of `items`.
pub fn list(w: &mut XmlWriter, items: &[&str]) -> XmlResult {
    w.create_element("ul").write_inner_content(|w| {
        for item in items {
            text_element(w, "li", item)?;
        }
        Ok(())
    })?;
    Ok(())
}

/// A `<table>` with a header row and `rows`.
pub fn table(w: &mut XmlWriter, header: &[&str], rows: &[Vec<String>]) -> XmlResult {
    w.create_element("table").write_inner_content(|w| {
        w.create_element("tr").write_inner_content(|w| {
            for h in header {
                text_element(w, "th", h)?;
            }
            Ok(())
        })?;
        for row in rows {
            w.create_element("tr").write_inner_content(|w| {
                for cell in row {
                    text_element(w, "td", cell)?;
                }
                Ok(())
            })?;
        }
        Ok(())
    })?;
    Ok(())
}

/// A complete HTML page titled `title` whose body `write_body` writes.
pub fn html_page(title: &str, write_body: impl Fn(&mut XmlWriter) -> XmlResult) -> String {
    let mut w = writer();
    let write = |w: &mut XmlWriter| -> XmlResult {
        w.write_event(Event::DocType(BytesText::from_escaped("html")))?;
        w.create_element("html")
            .with_attribute(("lang", "en"))
            .write_inner_content(|w| {
                w.create_element("head").write_inner_content(|w| {
                    w.create_element("meta")
                        .with_attribute(("charset", "utf-8"))
                        .write_empty()?;
                    text_element(w, "title", title)?;
                    text_element(w, "style", STYLE)
                })?;
                w.create_element("body").write_inner_content(&write_body)?;
                Ok(())
            })?;
        Ok(())
    };
    write(&mut w).expect("writing to memory cannot fail");
    finish(w)
}
