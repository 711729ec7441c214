//! The assembled car: the chassis FMU carrying four corner FMUs, written as
//! the two system-structure files co-simulation masters read.
//!
//! - `SystemStructure.ssd` (SSP 1.0, the Modelica Association's System
//!   Structure and Parameterization): the system `full-car` as it sits in
//!   `full-car.ssp`, next to the FMUs under `resources/`. Any SSP tool
//!   (libcosim, ecos, OMSimulator, ...) imports it.
//! - `OspSystemStructure.xml` (the Open Simulation Platform's own format,
//!   read by libcosim and its Python and command line front ends): the same
//!   car, with a fixed step or with libcosim's energy-conserving step
//!   control (ECCO), which SSP 1.0 cannot express.
//!
//! Five instances: `chassis`, and the corners `fl`, `fr`, `rl`, `rr`
//! (front/rear, left/right). Each corner feeds the force it puts on the body
//! to the chassis, and the chassis feeds back the displacement and velocity
//! of that corner's attachment point: twelve connections. Every corner rolls
//! on the ISO 8608 random road of the quarter car at the default vehicle
//! speed; the rear wheels see their front wheel's road a wheelbase later,
//! `(a + b) / speed` with the chassis's default `a` and `b`, and the right
//! track rolls on a road of its own (the next seed), so that the car pitches
//! and rolls. Every value comes from the library's own defaults, so the
//! files follow the model when a default changes.
//!
//! The functions return the files' text; writing them and packing the SSP
//! archive is the caller's.

use quick_xml::Writer;
use quick_xml::events::{BytesDecl, BytesText, Event};
use std::io::{self, Cursor};
use tdvass::chassis::{ChassisParams, Corner};
use tdvass::road::{RandomRoad, RoadType};
use tdvass_fmu::{DEFAULT_START_TIME, DEFAULT_STEP_SIZE, DEFAULT_STOP_TIME};

/// The name of the system, of its SSD and of its folder beside the FMUs.
pub const SYSTEM_NAME: &str = "full-car";
/// The chassis's instance name.
pub const CHASSIS_INSTANCE: &str = "chassis";
/// The name every corner's parameter set carries in the SSD. libcosim
/// applies every binding it finds; ecos gathers the sets of all components
/// by name and applies the one its `init` names, so one name for all four
/// lets `init(parameter_set="full-car")` set up the whole car.
pub const PARAMETER_SET_NAME: &str = "full-car";
/// The folder of an SSP archive that holds the FMUs its SSD names.
pub const SSP_RESOURCES: &str = "resources";

/// SSP 1.0 System Structure Description namespace (prefix `ssd`).
pub const SSD_NAMESPACE: &str = "http://ssp-standard.org/SSP1/SystemStructureDescription";
/// SSP 1.0 common types namespace: connector types, units, annotations
/// (prefix `ssc`).
pub const SSC_NAMESPACE: &str = "http://ssp-standard.org/SSP1/SystemStructureCommon";
/// SSP 1.0 parameter values namespace (prefix `ssv`).
pub const SSV_NAMESPACE: &str = "http://ssp-standard.org/SSP1/SystemStructureParameterValues";
/// The Open Simulation Platform's SSP annotations (prefix `osp`): libcosim
/// takes its co-simulation algorithm and base step from them.
pub const OSP_ANNOTATIONS_NAMESPACE: &str = "http://opensimulationplatform.com/SSP/OSPAnnotations";
/// The type that marks an SSP annotation as the Open Simulation Platform's.
pub const OSP_ANNOTATION_TYPE: &str = "com.opensimulationplatform";
/// libcosim's `OspSystemStructure.xml` namespace.
pub const OSP_SYSTEM_STRUCTURE_NAMESPACE: &str =
    "http://opensimulationplatform.com/MSMI/OSPSystemStructure";
/// The version of the OSP system-structure format libcosim requires.
pub const OSP_SYSTEM_STRUCTURE_VERSION: &str = "0.1";

/// The step-size control of libcosim's ECCO algorithm (energy-conservation
/// based co-simulation): after each step it measures, for every power bond,
/// the difference between the power one side delivers (force times
/// velocity) and the power the other side receives, and steers the next
/// step with a PI controller so that the energy lost or created per step
/// stays within the tolerances.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EccoSettings {
    /// Factor (< 1) on the step the controller proposes.
    pub safety_factor: f64,
    /// First step (s).
    pub step_size: f64,
    /// Smallest step (s).
    pub minimum_step_size: f64,
    /// Largest step (s).
    pub maximum_step_size: f64,
    /// Least ratio of one step to the one before.
    pub minimum_change_rate: f64,
    /// Greatest ratio of one step to the one before.
    pub maximum_change_rate: f64,
    /// Proportional gain of the controller.
    pub proportional_gain: f64,
    /// Integral gain of the controller.
    pub integral_gain: f64,
    /// Relative tolerance of a step's energy residual, against the largest
    /// residual of the bonds.
    pub relative_tolerance: f64,
    /// Absolute tolerance of a step's energy residual (J).
    pub absolute_tolerance: f64,
}

/// The car's ECCO settings: the FMUs' own default step to start with,
/// between 0.1 ms and 10 ms, and the controller gains and tolerances of
/// libcosim's own ECCO examples.
pub const ECCO_SETTINGS: EccoSettings = EccoSettings {
    safety_factor: 0.8,
    step_size: DEFAULT_STEP_SIZE,
    minimum_step_size: 1e-4,
    maximum_step_size: 1e-2,
    minimum_change_rate: 0.2,
    maximum_change_rate: 1.5,
    proportional_gain: 0.2,
    integral_gain: 0.15,
    relative_tolerance: 1e-4,
    absolute_tolerance: 1e-4,
};

/// The value a parameter is set to, in the type of its FMU variable.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ParameterValue {
    /// A Real (FMI 2.0) / Float64 (FMI 3.0) variable.
    Real(f64),
    /// An Integer variable (`road` and `road_seed` in the FMI 2.0 FMU).
    Integer(i64),
}

/// A parameter set on one instance: name, value and unit (Real values).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParameterSetting {
    /// The FMU variable.
    pub name: &'static str,
    /// Its value.
    pub value: ParameterValue,
    /// The unit of a Real value, as the FMU declares it.
    pub unit: Option<&'static str>,
}

/// One connection: an output of one instance drives an input of another.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Connection {
    /// The instance whose output it is.
    pub from_instance: &'static str,
    /// The output.
    pub from_variable: String,
    /// The instance whose input it drives.
    pub to_instance: &'static str,
    /// The input.
    pub to_variable: String,
    /// The power bond the connection is half of, if any: the corner's force
    /// and velocity exchange with the chassis carry the power that flows
    /// through the suspension into the body.
    pub power_bond: Option<String>,
}

/// The direction of a connector, seen from its instance.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Input,
    Output,
    Parameter,
}

impl Kind {
    /// The SSD's `kind`, and libcosim's `causality` of a connection's end.
    fn name(self) -> &'static str {
        match self {
            Kind::Input => "input",
            Kind::Output => "output",
            Kind::Parameter => "parameter",
        }
    }
}

/// A connector an instance offers in the SSD.
#[derive(Debug, Clone, PartialEq)]
struct Connector {
    name: String,
    kind: Kind,
    /// `Some(unit)` for a Real connector, `None` for an Integer one.
    real_unit: Option<&'static str>,
}

/// The units the connectors use, as SI base-unit exponents (kg, m, s).
const UNITS: [(&str, [i32; 3]); 4] = [
    ("N", [1, 1, -2]),
    ("m", [0, 1, 0]),
    ("m/s", [0, 1, -1]),
    ("s", [0, 0, 1]),
];

/// A rear corner, whose road is its front wheel's, a wheelbase later.
fn is_rear(corner: Corner) -> bool {
    matches!(corner, Corner::RearLeft | Corner::RearRight)
}

/// A corner of the right track, which rolls on a road of its own.
fn is_right(corner: Corner) -> bool {
    matches!(corner, Corner::FrontRight | Corner::RearRight)
}

/// The chassis output that carries a corner's attachment displacement.
fn displacement_name(corner: Corner) -> String {
    format!("displacement_{}", corner.name())
}

/// The chassis output that carries a corner's attachment velocity.
fn velocity_name(corner: Corner) -> String {
    format!("velocity_{}", corner.name())
}

/// The name of a corner's power bond with the chassis.
fn power_bond_name(corner: Corner) -> String {
    format!("suspension_{}", corner.name())
}

/// The parameters each corner is given: the ISO 8608 road (`road`), at the
/// default vehicle speed (`vehicle_speed`, on which both the road's
/// spectrum and the rear wheels' delay depend), its seed (`road_seed`: the
/// default on the left track, the next seed on the right) and its delay
/// (`road_delay`: 0 at the front, wheelbase / speed at the rear). The
/// static load is left at the corner's default, a quarter of the default
/// chassis mass with the centre of gravity midway between the axles.
pub fn corner_parameters(corner: Corner) -> Vec<ParameterSetting> {
    let road = RandomRoad::default();
    let chassis = ChassisParams::default();
    let seed = road.seed + u64::from(is_right(corner));
    let delay = if is_rear(corner) {
        (chassis.a + chassis.b) / road.speed
    } else {
        0.0
    };
    vec![
        ParameterSetting {
            name: "road",
            value: ParameterValue::Integer(RoadType::Iso8608.code()),
            unit: None,
        },
        ParameterSetting {
            name: "vehicle_speed",
            value: ParameterValue::Real(road.speed),
            unit: Some("m/s"),
        },
        ParameterSetting {
            name: "road_seed",
            value: ParameterValue::Integer(
                i64::try_from(seed).expect("the default seed is a small number"),
            ),
            unit: None,
        },
        ParameterSetting {
            name: "road_delay",
            value: ParameterValue::Real(delay),
            unit: Some("s"),
        },
    ]
}

/// The twelve connections of the car, corner by corner: the corner's
/// `body_force` drives the chassis's `force_<corner>`, and the chassis's
/// `displacement_<corner>` and `velocity_<corner>` drive the corner's
/// `body_displacement` and `body_velocity`. The force and the velocity
/// connection of a corner form its power bond.
pub fn connections() -> Vec<Connection> {
    Corner::ALL
        .iter()
        .flat_map(|&corner| {
            let instance = corner.name();
            let bond = power_bond_name(corner);
            [
                Connection {
                    from_instance: instance,
                    from_variable: "body_force".to_string(),
                    to_instance: CHASSIS_INSTANCE,
                    to_variable: corner.force_name().to_string(),
                    power_bond: Some(bond.clone()),
                },
                Connection {
                    from_instance: CHASSIS_INSTANCE,
                    from_variable: displacement_name(corner),
                    to_instance: instance,
                    to_variable: "body_displacement".to_string(),
                    power_bond: None,
                },
                Connection {
                    from_instance: CHASSIS_INSTANCE,
                    from_variable: velocity_name(corner),
                    to_instance: instance,
                    to_variable: "body_velocity".to_string(),
                    power_bond: Some(bond),
                },
            ]
        })
        .collect()
}

/// The chassis's connectors: per corner, the force input and the
/// displacement and velocity outputs.
fn chassis_connectors() -> Vec<Connector> {
    Corner::ALL
        .iter()
        .flat_map(|&corner| {
            [
                Connector {
                    name: corner.force_name().to_string(),
                    kind: Kind::Input,
                    real_unit: Some("N"),
                },
                Connector {
                    name: displacement_name(corner),
                    kind: Kind::Output,
                    real_unit: Some("m"),
                },
                Connector {
                    name: velocity_name(corner),
                    kind: Kind::Output,
                    real_unit: Some("m/s"),
                },
            ]
        })
        .collect()
}

/// A corner's connectors: the force output, the body inputs and the
/// parameters it is given.
fn corner_connectors(corner: Corner) -> Vec<Connector> {
    let signals = [
        ("body_force", Kind::Output, "N"),
        ("body_displacement", Kind::Input, "m"),
        ("body_velocity", Kind::Input, "m/s"),
    ]
    .map(|(name, kind, unit)| Connector {
        name: name.to_string(),
        kind,
        real_unit: Some(unit),
    });
    let parameters = corner_parameters(corner).into_iter().map(|p| Connector {
        name: p.name.to_string(),
        kind: Kind::Parameter,
        real_unit: match p.value {
            ParameterValue::Real(_) => p.unit,
            ParameterValue::Integer(_) => None,
        },
    });
    signals.into_iter().chain(parameters).collect()
}

/// A number as XML Schema's `xs:double` reads it back: Rust's shortest
/// representation that round-trips.
fn number(x: f64) -> String {
    format!("{x}")
}

/// A parameter's value as text.
fn value_text(value: ParameterValue) -> String {
    match value {
        ParameterValue::Real(x) => number(x),
        ParameterValue::Integer(n) => n.to_string(),
    }
}

/// A writer into memory, indenting by two spaces.
type XmlWriter = Writer<Cursor<Vec<u8>>>;

/// An XML document: the declaration, then what `write` writes, and a final
/// newline.
fn document(write: impl FnOnce(&mut XmlWriter) -> io::Result<()>) -> String {
    let mut w = Writer::new_with_indent(Cursor::new(Vec::new()), b' ', 2);
    w.write_event(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None)))
        .and_then(|()| write(&mut w))
        .expect("writing to memory cannot fail");
    let mut text = String::from_utf8(w.into_inner().into_inner()).expect("quick-xml writes UTF-8");
    text.push('\n');
    text
}

/// `<name>text</name>`.
fn text_element(w: &mut XmlWriter, name: &str, text: &str) -> io::Result<()> {
    w.create_element(name)
        .write_text_content(BytesText::new(text))?;
    Ok(())
}

/// Every instance with the FMU it instantiates: the chassis first, then the
/// corners.
fn instances<'a>(corner_fmu: &'a str, chassis_fmu: &'a str) -> Vec<(&'static str, &'a str)> {
    std::iter::once((CHASSIS_INSTANCE, chassis_fmu))
        .chain(Corner::ALL.iter().map(|c| (c.name(), corner_fmu)))
        .collect()
}

/// The parameters set on an instance (none on the chassis, whose defaults
/// are the paper's car).
fn parameters_of(instance: &str) -> Vec<ParameterSetting> {
    Corner::ALL
        .iter()
        .find(|c| c.name() == instance)
        .map(|&c| corner_parameters(c))
        .unwrap_or_default()
}

/// `SystemStructure.ssd`, the SSP 1.0 description of the car for
/// `full-car.ssp`, whose `resources/` folder holds `corner_fmu` and
/// `chassis_fmu` (file names, such as `tdvass-corner.fmu`): the five
/// components with the connectors they use, the twelve connections, each
/// corner's road parameters as an inline parameter set (all four named
/// [`PARAMETER_SET_NAME`]), the units, and the
/// default experiment (0 s to 15 s) with libcosim's fixed-step algorithm at
/// the FMUs' 1 ms step as an OSP annotation.
///
/// Namespaces: `ssd` (the description), `ssc` (connector types, units,
/// annotations), `ssv` (the parameter sets) from SSP 1.0, and `osp` for the
/// Open Simulation Platform's annotation. The prefixes are the ones the SSP
/// standard uses throughout, and they are load-bearing: libcosim's SSP
/// parser looks elements up by their prefixed names. Every namespace is
/// declared on the root, because libcosim reads an element's attributes as
/// one of its children, and an algorithm element with an attribute would
/// read as an unknown algorithm.
///
/// The components are Co-Simulation FMUs (`implementation="CoSimulation"`):
/// their own integration of the delay equation is exact, where a Model
/// Exchange import would be as accurate as the master's solver. `road` and
/// `road_seed` are Integer connectors, as the FMI 2.0 FMU declares them
/// (libcosim imports FMI 1.0 and 2.0 FMUs only).
pub fn system_structure_description(corner_fmu: &str, chassis_fmu: &str) -> String {
    document(|w| {
        w.create_element("ssd:SystemStructureDescription")
            .with_attribute(("xmlns:ssd", SSD_NAMESPACE))
            .with_attribute(("xmlns:ssc", SSC_NAMESPACE))
            .with_attribute(("xmlns:ssv", SSV_NAMESPACE))
            .with_attribute(("xmlns:osp", OSP_ANNOTATIONS_NAMESPACE))
            .with_attribute(("version", "1.0"))
            .with_attribute(("name", SYSTEM_NAME))
            .write_inner_content(|w| {
                write_ssd_system(w, corner_fmu, chassis_fmu)?;
                write_ssd_units(w)?;
                write_ssd_default_experiment(w)
            })?;
        Ok(())
    })
}

/// `ssd:System`: the components and the connections.
fn write_ssd_system(w: &mut XmlWriter, corner_fmu: &str, chassis_fmu: &str) -> io::Result<()> {
    w.create_element("ssd:System")
        .with_attribute(("name", SYSTEM_NAME))
        .with_attribute((
            "description",
            "A rigid chassis on four suspension corners, each on the ISO 8608 random road; the rear wheels follow the front ones a wheelbase later, the right track rolls on a road of its own",
        ))
        .write_inner_content(|w| {
            w.create_element("ssd:Elements").write_inner_content(|w| {
                for (instance, fmu) in instances(corner_fmu, chassis_fmu) {
                    write_ssd_component(w, instance, fmu)?;
                }
                Ok(())
            })?;
            w.create_element("ssd:Connections")
                .write_inner_content(|w| {
                    for c in connections() {
                        w.create_element("ssd:Connection")
                            .with_attribute(("startElement", c.from_instance))
                            .with_attribute(("startConnector", c.from_variable.as_str()))
                            .with_attribute(("endElement", c.to_instance))
                            .with_attribute(("endConnector", c.to_variable.as_str()))
                            .write_empty()?;
                    }
                    Ok(())
                })?;
            Ok(())
        })?;
    Ok(())
}

/// One `ssd:Component`: its connectors and, for a corner, its parameter
/// binding.
fn write_ssd_component(w: &mut XmlWriter, instance: &str, fmu: &str) -> io::Result<()> {
    let connectors = match Corner::ALL.iter().find(|c| c.name() == instance) {
        Some(&corner) => corner_connectors(corner),
        None => chassis_connectors(),
    };
    let parameters = parameters_of(instance);
    let source = format!("{SSP_RESOURCES}/{fmu}");
    w.create_element("ssd:Component")
        .with_attribute(("name", instance))
        .with_attribute(("type", "application/x-fmu-sharedlibrary"))
        .with_attribute(("source", source.as_str()))
        .with_attribute(("implementation", "CoSimulation"))
        .write_inner_content(|w| {
            w.create_element("ssd:Connectors")
                .write_inner_content(|w| {
                    for c in &connectors {
                        let connector = w
                            .create_element("ssd:Connector")
                            .with_attribute(("name", c.name.as_str()))
                            .with_attribute(("kind", c.kind.name()));
                        connector.write_inner_content(|w| {
                            match c.real_unit {
                                Some(unit) => w
                                    .create_element("ssc:Real")
                                    .with_attribute(("unit", unit))
                                    .write_empty()?,
                                None => w.create_element("ssc:Integer").write_empty()?,
                            };
                            Ok(())
                        })?;
                    }
                    Ok(())
                })?;
            if !parameters.is_empty() {
                write_ssd_parameter_binding(w, &parameters)?;
            }
            Ok(())
        })?;
    Ok(())
}

/// `ssd:ParameterBindings` with one binding whose values are inline: an
/// `ssv:ParameterSet` named [`PARAMETER_SET_NAME`].
fn write_ssd_parameter_binding(
    w: &mut XmlWriter,
    parameters: &[ParameterSetting],
) -> io::Result<()> {
    w.create_element("ssd:ParameterBindings")
        .write_inner_content(|w| {
            w.create_element("ssd:ParameterBinding")
                .write_inner_content(|w| {
                    w.create_element("ssd:ParameterValues")
                        .write_inner_content(|w| {
                            w.create_element("ssv:ParameterSet")
                                .with_attribute(("version", "1.0"))
                                .with_attribute(("name", PARAMETER_SET_NAME))
                                .write_inner_content(|w| {
                                    w.create_element("ssv:Parameters").write_inner_content(
                                        |w| {
                                            for p in parameters {
                                                write_ssv_parameter(w, p)?;
                                            }
                                            Ok(())
                                        },
                                    )?;
                                    Ok(())
                                })?;
                            Ok(())
                        })?;
                    Ok(())
                })?;
            Ok(())
        })?;
    Ok(())
}

/// One `ssv:Parameter`.
fn write_ssv_parameter(w: &mut XmlWriter, p: &ParameterSetting) -> io::Result<()> {
    let value = value_text(p.value);
    w.create_element("ssv:Parameter")
        .with_attribute(("name", p.name))
        .write_inner_content(|w| {
            match (p.value, p.unit) {
                (ParameterValue::Real(_), Some(unit)) => w
                    .create_element("ssv:Real")
                    .with_attribute(("value", value.as_str()))
                    .with_attribute(("unit", unit))
                    .write_empty()?,
                (ParameterValue::Real(_), None) => w
                    .create_element("ssv:Real")
                    .with_attribute(("value", value.as_str()))
                    .write_empty()?,
                (ParameterValue::Integer(_), _) => w
                    .create_element("ssv:Integer")
                    .with_attribute(("value", value.as_str()))
                    .write_empty()?,
            };
            Ok(())
        })?;
    Ok(())
}

/// `ssd:Units`: the units the connectors and parameters name.
fn write_ssd_units(w: &mut XmlWriter) -> io::Result<()> {
    w.create_element("ssd:Units").write_inner_content(|w| {
        for (name, [kg, m, s]) in UNITS {
            w.create_element("ssc:Unit")
                .with_attribute(("name", name))
                .write_inner_content(|w| {
                    let (kg, m, s) = (kg.to_string(), m.to_string(), s.to_string());
                    w.create_element("ssc:BaseUnit")
                        .with_attribute(("kg", kg.as_str()))
                        .with_attribute(("m", m.as_str()))
                        .with_attribute(("s", s.as_str()))
                        .write_empty()?;
                    Ok(())
                })?;
        }
        Ok(())
    })?;
    Ok(())
}

/// `ssd:DefaultExperiment`, with libcosim's algorithm as an OSP annotation.
fn write_ssd_default_experiment(w: &mut XmlWriter) -> io::Result<()> {
    let (start, stop, step) = (
        number(DEFAULT_START_TIME),
        number(DEFAULT_STOP_TIME),
        number(DEFAULT_STEP_SIZE),
    );
    w.create_element("ssd:DefaultExperiment")
        .with_attribute(("startTime", start.as_str()))
        .with_attribute(("stopTime", stop.as_str()))
        .write_inner_content(|w| {
            w.create_element("ssd:Annotations")
                .write_inner_content(|w| {
                    w.create_element("ssc:Annotation")
                        .with_attribute(("type", OSP_ANNOTATION_TYPE))
                        .write_inner_content(|w| {
                            w.create_element("osp:Algorithm").write_inner_content(|w| {
                                w.create_element("osp:FixedStepAlgorithm")
                                    .with_attribute(("baseStepSize", step.as_str()))
                                    .write_empty()?;
                                Ok(())
                            })?;
                            Ok(())
                        })?;
                    Ok(())
                })?;
            Ok(())
        })?;
    Ok(())
}

/// `OspSystemStructure.xml`, libcosim's description of the car, for the
/// folder `full-car/` beside the FMUs (`corner_fmu` and `chassis_fmu` are
/// their file names; the simulators' sources are `../<fmu>`): start and
/// stop time of the default experiment, the five simulators with the same
/// parameter values as the SSD, and the twelve connections.
///
/// With `ecco == false` the algorithm is libcosim's fixed step at the FMUs'
/// 1 ms. With `ecco == true` it is ECCO ([`ECCO_SETTINGS`], which libcosim
/// requires in full): each corner's force and velocity connections carry
/// the name of the corner's power bond, and each of their ends its
/// causality (the FMU variable's own), from which libcosim pairs the
/// variables of each side of the bond; the displacement connections stay
/// plain. `BaseStepSize` is written in both, for tools that read it.
///
/// One namespace, `http://opensimulationplatform.com/MSMI/OSPSystemStructure`,
/// as the default namespace: libcosim's schema (`OspSystemStructure.xsd`,
/// version 0.1) qualifies every element.
pub fn osp_system_structure(corner_fmu: &str, chassis_fmu: &str, ecco: bool) -> String {
    let algorithm = if ecco { "ecco" } else { "fixedStep" };
    document(|w| {
        w.create_element("OspSystemStructure")
            .with_attribute(("xmlns", OSP_SYSTEM_STRUCTURE_NAMESPACE))
            .with_attribute(("version", OSP_SYSTEM_STRUCTURE_VERSION))
            .write_inner_content(|w| {
                text_element(w, "StartTime", &number(DEFAULT_START_TIME))?;
                text_element(w, "EndTime", &number(DEFAULT_STOP_TIME))?;
                text_element(w, "BaseStepSize", &number(DEFAULT_STEP_SIZE))?;
                text_element(w, "Algorithm", algorithm)?;
                w.create_element("Simulators").write_inner_content(|w| {
                    for (instance, fmu) in instances(corner_fmu, chassis_fmu) {
                        write_osp_simulator(w, instance, fmu)?;
                    }
                    Ok(())
                })?;
                w.create_element("Connections").write_inner_content(|w| {
                    for c in connections() {
                        write_osp_connection(w, &c, ecco)?;
                    }
                    Ok(())
                })?;
                if ecco {
                    write_ecco_configuration(w, &ECCO_SETTINGS)?;
                }
                Ok(())
            })?;
        Ok(())
    })
}

/// One `Simulator` with its initial values.
fn write_osp_simulator(w: &mut XmlWriter, instance: &str, fmu: &str) -> io::Result<()> {
    let source = format!("../{fmu}");
    let parameters = parameters_of(instance);
    let simulator = w
        .create_element("Simulator")
        .with_attribute(("name", instance))
        .with_attribute(("source", source.as_str()));
    if parameters.is_empty() {
        simulator.write_empty()?;
        return Ok(());
    }
    simulator.write_inner_content(|w| {
        w.create_element("InitialValues").write_inner_content(|w| {
            for p in &parameters {
                let value = value_text(p.value);
                let type_name = match p.value {
                    ParameterValue::Real(_) => "Real",
                    ParameterValue::Integer(_) => "Integer",
                };
                w.create_element("InitialValue")
                    .with_attribute(("variable", p.name))
                    .write_inner_content(|w| {
                        w.create_element(type_name)
                            .with_attribute(("value", value.as_str()))
                            .write_empty()?;
                        Ok(())
                    })?;
            }
            Ok(())
        })?;
        Ok(())
    })?;
    Ok(())
}

/// One `VariableConnection`, output end first; in the ECCO file a
/// connection of a power bond names it.
fn write_osp_connection(w: &mut XmlWriter, c: &Connection, ecco: bool) -> io::Result<()> {
    let mut connection = w.create_element("VariableConnection");
    if let (true, Some(bond)) = (ecco, &c.power_bond) {
        connection = connection.with_attribute(("powerBond", bond.as_str()));
    }
    connection.write_inner_content(|w| {
        for (instance, variable, kind) in [
            (c.from_instance, &c.from_variable, Kind::Output),
            (c.to_instance, &c.to_variable, Kind::Input),
        ] {
            w.create_element("Variable")
                .with_attribute(("simulator", instance))
                .with_attribute(("name", variable.as_str()))
                .with_attribute(("causality", kind.name()))
                .write_empty()?;
        }
        Ok(())
    })?;
    Ok(())
}

/// `EccoConfiguration`: every setting libcosim reads.
fn write_ecco_configuration(w: &mut XmlWriter, s: &EccoSettings) -> io::Result<()> {
    let settings = [
        ("SafetyFactor", s.safety_factor),
        ("StepSize", s.step_size),
        ("MinimumStepSize", s.minimum_step_size),
        ("MaximumStepSize", s.maximum_step_size),
        ("MinimumChangeRate", s.minimum_change_rate),
        ("MaximumChangeRate", s.maximum_change_rate),
        ("ProportionalGain", s.proportional_gain),
        ("IntegralGain", s.integral_gain),
        ("RelativeTolerance", s.relative_tolerance),
        ("AbsoluteTolerance", s.absolute_tolerance),
    ];
    w.create_element("EccoConfiguration")
        .write_inner_content(|w| {
            for (name, value) in settings {
                text_element(w, name, &number(value))?;
            }
            Ok(())
        })?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use quick_xml::events::BytesStart;
    use quick_xml::name::ResolveResult;
    use quick_xml::{NsReader, XmlVersion};
    use std::collections::{BTreeMap, BTreeSet};

    const CORNER_FMU: &str = "tdvass-corner.fmu";
    const CHASSIS_FMU: &str = "tdvass-chassis.fmu";

    /// An element as read back: its namespace (resolved), prefix, local
    /// name, attributes, children and text.
    #[derive(Debug, Default)]
    struct Node {
        namespace: String,
        prefix: String,
        name: String,
        attributes: BTreeMap<String, String>,
        children: Vec<Node>,
        text: String,
    }

    impl Node {
        /// The children of that local name.
        fn children_named<'a>(&'a self, name: &str) -> impl Iterator<Item = &'a Node> {
            let name = name.to_string();
            self.children.iter().filter(move |c| c.name == name)
        }

        /// The one child of that local name.
        fn child(&self, name: &str) -> &Node {
            let found: Vec<&Node> = self.children_named(name).collect();
            assert_eq!(found.len(), 1, "one <{name}> in <{}>", self.name);
            found[0]
        }

        /// An attribute that must be there.
        fn attribute(&self, name: &str) -> &str {
            self.attributes
                .get(name)
                .unwrap_or_else(|| panic!("<{}> has no attribute {name}", self.name))
        }

        /// This element and every element inside it, in document order.
        fn descendants(&self) -> Vec<&Node> {
            let mut all = vec![self];
            for c in &self.children {
                all.extend(c.descendants());
            }
            all
        }
    }

    /// An element without its content, from its start tag.
    fn element(e: &BytesStart, namespace: String) -> Node {
        Node {
            namespace,
            prefix: e
                .name()
                .prefix()
                .map(|p| p.as_ref().to_string())
                .unwrap_or_default(),
            name: e.local_name().as_ref().to_string(),
            attributes: e
                .attributes()
                .map(|a| {
                    let a = a.expect("a well-formed attribute");
                    let value = a
                        .normalized_value(XmlVersion::Implicit1_0)
                        .expect("a well-formed value");
                    (a.key.as_ref().to_string(), value.into_owned())
                })
                .collect(),
            ..Node::default()
        }
    }

    /// The root element of a document, every element's namespace resolved.
    fn parse(xml: &str) -> Node {
        let mut reader = NsReader::from_str(xml);
        reader.config_mut().trim_text(true);
        let mut open = vec![Node::default()];
        loop {
            let (resolved, event) = reader.read_resolved_event().expect("well-formed XML");
            let namespace = match resolved {
                ResolveResult::Bound(ns) => ns.as_ref().to_string(),
                ResolveResult::Unbound => String::new(),
                ResolveResult::Unknown(prefix) => panic!("undeclared prefix {prefix}"),
            };
            match event {
                Event::Start(e) => open.push(element(&e, namespace)),
                Event::Empty(e) => {
                    let node = element(&e, namespace);
                    open.last_mut()
                        .expect("inside the document")
                        .children
                        .push(node);
                }
                Event::End(_) => {
                    let node = open.pop().expect("an open element");
                    open.last_mut()
                        .expect("inside the document")
                        .children
                        .push(node);
                }
                Event::Text(t) => open
                    .last_mut()
                    .expect("inside the document")
                    .text
                    .push_str(&t.xml10_content()),
                Event::Eof => break,
                _ => {}
            }
        }
        let mut document = open.pop().expect("the document");
        assert!(open.is_empty(), "every element is closed");
        assert_eq!(document.children.len(), 1, "one root element");
        document.children.remove(0)
    }

    /// The twelve connections the car needs, spelled out: (from instance,
    /// output, to instance, input).
    fn expected_connections() -> BTreeSet<(String, String, String, String)> {
        let mut all = BTreeSet::new();
        for c in ["fl", "fr", "rl", "rr"] {
            let mut add = |a: &str, b: String, c: &str, d: String| {
                all.insert((a.to_string(), b, c.to_string(), d));
            };
            add(c, "body_force".into(), "chassis", format!("force_{c}"));
            add(
                "chassis",
                format!("displacement_{c}"),
                c,
                "body_displacement".into(),
            );
            add(
                "chassis",
                format!("velocity_{c}"),
                c,
                "body_velocity".into(),
            );
        }
        all
    }

    /// The parameters each corner must get, spelled out: (instance, name)
    /// to value, Integer values as whole numbers.
    fn expected_parameters() -> BTreeMap<(String, String), f64> {
        let mut all = BTreeMap::new();
        for (corner, seed, delay) in [
            ("fl", 1.0, 0.0),
            ("fr", 2.0, 0.0),
            ("rl", 1.0, 0.13),
            ("rr", 2.0, 0.13),
        ] {
            for (name, value) in [
                ("road", 2.0),
                ("vehicle_speed", 20.0),
                ("road_seed", seed),
                ("road_delay", delay),
            ] {
                all.insert((corner.to_string(), name.to_string()), value);
            }
        }
        all
    }

    /// Value type (`Real`, `Integer`) and value of one parameter element.
    fn typed_value(value: &Node) -> (String, f64) {
        let number: f64 = value.attribute("value").parse().expect("a number");
        (value.name.clone(), number)
    }

    /// The car's SSD, read back.
    fn ssd() -> Node {
        parse(&system_structure_description(CORNER_FMU, CHASSIS_FMU))
    }

    /// The SSD's components.
    fn components(root: &Node) -> Vec<&Node> {
        root.child("System")
            .child("Elements")
            .children_named("Component")
            .collect()
    }

    /// (instance, name) to (type, value) of every parameter the SSD binds.
    fn ssd_parameters(root: &Node) -> BTreeMap<(String, String), (String, f64)> {
        let mut all = BTreeMap::new();
        for component in components(root) {
            for binding in component.children_named("ParameterBindings") {
                for b in binding.children_named("ParameterBinding") {
                    let set = b.child("ParameterValues").child("ParameterSet");
                    assert_eq!(set.namespace, SSV_NAMESPACE);
                    assert_eq!(set.attribute("name"), "full-car", "one set name for ecos");
                    for p in set.child("Parameters").children_named("Parameter") {
                        assert_eq!(p.children.len(), 1, "one value per parameter");
                        let key = (
                            component.attribute("name").to_string(),
                            p.attribute("name").to_string(),
                        );
                        let previous = all.insert(key, typed_value(&p.children[0]));
                        assert!(previous.is_none(), "each parameter bound once");
                    }
                }
            }
        }
        all
    }

    /// The car's OSP file, read back.
    fn osp(ecco: bool) -> Node {
        parse(&osp_system_structure(CORNER_FMU, CHASSIS_FMU, ecco))
    }

    /// (simulator, variable) to (type, value) of every initial value.
    fn osp_initial_values(root: &Node) -> BTreeMap<(String, String), (String, f64)> {
        let mut all = BTreeMap::new();
        for s in root.child("Simulators").children_named("Simulator") {
            for values in s.children_named("InitialValues") {
                for v in values.children_named("InitialValue") {
                    assert_eq!(v.children.len(), 1, "one value per initial value");
                    let key = (
                        s.attribute("name").to_string(),
                        v.attribute("variable").to_string(),
                    );
                    let previous = all.insert(key, typed_value(&v.children[0]));
                    assert!(previous.is_none(), "each initial value set once");
                }
            }
        }
        all
    }

    /// One end of an OSP connection: (simulator, variable, causality).
    type OspEnd = (String, String, String);

    /// The connections of an OSP file, with the power bond each names.
    fn osp_connections(root: &Node) -> Vec<(OspEnd, OspEnd, Option<String>)> {
        let connections = root.child("Connections");
        assert!(
            connections
                .children
                .iter()
                .all(|c| c.name == "VariableConnection"),
            "plain variable connections only"
        );
        connections
            .children
            .iter()
            .map(|c| {
                let ends: Vec<OspEnd> = c
                    .children_named("Variable")
                    .map(|v| {
                        (
                            v.attribute("simulator").to_string(),
                            v.attribute("name").to_string(),
                            v.attribute("causality").to_string(),
                        )
                    })
                    .collect();
                assert_eq!(ends.len(), 2, "a connection joins two variables");
                (
                    ends[0].clone(),
                    ends[1].clone(),
                    c.attributes.get("powerBond").cloned(),
                )
            })
            .collect()
    }

    /// The SSD is an SSP 1.0 description of `full-car` with the five instances and their FMUs.
    #[test]
    fn the_ssd_is_an_ssp_1_0_description_of_the_five_instances() {
        let root = ssd();
        assert_eq!(root.namespace, SSD_NAMESPACE);
        assert_eq!(root.name, "SystemStructureDescription");
        assert_eq!(root.attribute("version"), "1.0");
        assert_eq!(root.attribute("name"), "full-car");
        assert_eq!(root.child("System").attribute("name"), "full-car");
        let sources: BTreeMap<&str, &str> = components(&root)
            .iter()
            .map(|c| (c.attribute("name"), c.attribute("source")))
            .collect();
        assert_eq!(
            sources,
            BTreeMap::from([
                ("chassis", "resources/tdvass-chassis.fmu"),
                ("fl", "resources/tdvass-corner.fmu"),
                ("fr", "resources/tdvass-corner.fmu"),
                ("rl", "resources/tdvass-corner.fmu"),
                ("rr", "resources/tdvass-corner.fmu"),
            ])
        );
        for c in components(&root) {
            assert_eq!(c.attribute("type"), "application/x-fmu-sharedlibrary");
            assert_eq!(c.attribute("implementation"), "CoSimulation");
        }
    }

    /// The twelve connections, each from a declared Real output to a declared Real input.
    #[test]
    fn the_ssd_connects_every_corner_to_the_chassis_through_declared_connectors() {
        let root = ssd();
        let mut connectors = BTreeMap::new();
        for c in components(&root) {
            for connector in c.child("Connectors").children_named("Connector") {
                assert_eq!(connector.children.len(), 1, "a typed connector");
                let key = (
                    c.attribute("name").to_string(),
                    connector.attribute("name").to_string(),
                );
                let value = (
                    connector.attribute("kind").to_string(),
                    connector.children[0].name.clone(),
                );
                assert!(connectors.insert(key, value).is_none(), "declared once");
            }
        }
        let connections: Vec<&Node> = root
            .child("System")
            .child("Connections")
            .children_named("Connection")
            .collect();
        let found: BTreeSet<_> = connections
            .iter()
            .map(|c| {
                (
                    c.attribute("startElement").to_string(),
                    c.attribute("startConnector").to_string(),
                    c.attribute("endElement").to_string(),
                    c.attribute("endConnector").to_string(),
                )
            })
            .collect();
        assert_eq!(connections.len(), 12);
        assert_eq!(found, expected_connections());
        for (from, output, to, input) in found {
            assert_eq!(
                connectors.get(&(from, output)),
                Some(&("output".to_string(), "Real".to_string()))
            );
            assert_eq!(
                connectors.get(&(to, input)),
                Some(&("input".to_string(), "Real".to_string()))
            );
        }
    }

    /// Each corner's road: ISO 8608, 20 m/s, seed 2 on the right, 0.13 s delay at the rear, typed as the FMI 2.0 FMU declares them.
    #[test]
    fn the_ssd_puts_every_corner_on_its_own_iso_8608_road() {
        let root = ssd();
        let bound = ssd_parameters(&root);
        let values: BTreeMap<_, f64> = bound.iter().map(|(k, (_, v))| (k.clone(), *v)).collect();
        assert_eq!(
            values.keys().collect::<Vec<_>>(),
            expected_parameters().keys().collect::<Vec<_>>()
        );
        for (key, expected) in expected_parameters() {
            assert!(
                (values[&key] - expected).abs() < 1e-12,
                "{key:?}: {} where {expected} was expected",
                values[&key]
            );
        }
        for c in components(&root) {
            let instance = c.attribute("name");
            for ((owner, name), (value_type, _)) in &bound {
                if owner != instance {
                    continue;
                }
                let expected_type = if name == "road" || name == "road_seed" {
                    "Integer"
                } else {
                    "Real"
                };
                assert_eq!(value_type, expected_type, "{owner}.{name}");
                let connector = c
                    .child("Connectors")
                    .children_named("Connector")
                    .find(|k| k.attribute("name") == name)
                    .unwrap_or_else(|| panic!("{owner}.{name} is declared"));
                assert_eq!(connector.attribute("kind"), "parameter");
                assert_eq!(connector.children[0].name, expected_type);
            }
        }
        let chassis = components(&root)
            .into_iter()
            .find(|c| c.attribute("name") == "chassis")
            .expect("the chassis");
        assert_eq!(chassis.children_named("ParameterBindings").count(), 0);
    }

    /// The default experiment, libcosim's algorithm annotation, and a unit declaration for every unit named.
    #[test]
    fn the_ssd_runs_15_s_with_the_fixed_step_libcosim_reads() {
        let root = ssd();
        let experiment = root.child("DefaultExperiment");
        assert_eq!(experiment.attribute("startTime").parse::<f64>(), Ok(0.0));
        assert_eq!(experiment.attribute("stopTime").parse::<f64>(), Ok(15.0));
        let annotation = experiment.child("Annotations").child("Annotation");
        assert_eq!(annotation.namespace, SSC_NAMESPACE);
        assert_eq!(annotation.attribute("type"), "com.opensimulationplatform");
        let algorithm = annotation.child("Algorithm");
        assert_eq!(algorithm.namespace, OSP_ANNOTATIONS_NAMESPACE);
        assert!(algorithm.attributes.is_empty());
        let fixed = algorithm.child("FixedStepAlgorithm");
        assert_eq!(fixed.attribute("baseStepSize").parse::<f64>(), Ok(0.001));
        let declared: BTreeSet<&str> = root
            .child("Units")
            .children_named("Unit")
            .map(|u| u.attribute("name"))
            .collect();
        for node in root.descendants() {
            if let Some(unit) = node.attributes.get("unit") {
                assert!(declared.contains(unit.as_str()), "unit {unit} is declared");
            }
        }
    }

    /// The standard prefixes on every element and namespace declarations on the root only, as libcosim and ecos read them.
    #[test]
    fn the_ssd_writes_the_prefixes_libcosim_looks_elements_up_by() {
        let root = ssd();
        let prefixes = BTreeMap::from([
            (SSD_NAMESPACE, "ssd"),
            (SSC_NAMESPACE, "ssc"),
            (SSV_NAMESPACE, "ssv"),
            (OSP_ANNOTATIONS_NAMESPACE, "osp"),
        ]);
        for node in root.descendants() {
            assert_eq!(
                prefixes.get(node.namespace.as_str()),
                Some(&node.prefix.as_str()),
                "<{}:{}> in {}",
                node.prefix,
                node.name,
                node.namespace
            );
            if !std::ptr::eq(node, &root) {
                assert!(
                    node.attributes.keys().all(|k| !k.starts_with("xmlns")),
                    "namespaces are declared on the root only"
                );
            }
        }
    }

    /// The fixed-step OSP file: schema order, the five simulators, the SSD's values and its twelve connections.
    #[test]
    fn the_fixed_step_osp_file_holds_the_car_of_the_ssd() {
        let root = osp(false);
        assert_eq!(root.namespace, OSP_SYSTEM_STRUCTURE_NAMESPACE);
        assert_eq!(root.name, "OspSystemStructure");
        assert_eq!(root.attribute("version"), "0.1");
        let order: Vec<&str> = root.children.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(
            order,
            [
                "StartTime",
                "EndTime",
                "BaseStepSize",
                "Algorithm",
                "Simulators",
                "Connections"
            ]
        );
        assert_eq!(root.child("StartTime").text.parse::<f64>(), Ok(0.0));
        assert_eq!(root.child("EndTime").text.parse::<f64>(), Ok(15.0));
        assert_eq!(root.child("BaseStepSize").text.parse::<f64>(), Ok(0.001));
        assert_eq!(root.child("Algorithm").text, "fixedStep");
        let sources: BTreeMap<&str, &str> = root
            .child("Simulators")
            .children_named("Simulator")
            .map(|s| (s.attribute("name"), s.attribute("source")))
            .collect();
        assert_eq!(
            sources,
            BTreeMap::from([
                ("chassis", "../tdvass-chassis.fmu"),
                ("fl", "../tdvass-corner.fmu"),
                ("fr", "../tdvass-corner.fmu"),
                ("rl", "../tdvass-corner.fmu"),
                ("rr", "../tdvass-corner.fmu"),
            ])
        );
        assert_eq!(osp_initial_values(&root), ssd_parameters(&ssd()));
        let connections = osp_connections(&root);
        assert_eq!(connections.len(), 12);
        let found: BTreeSet<_> = connections
            .iter()
            .map(|(from, to, bond)| {
                assert_eq!((from.2.as_str(), to.2.as_str()), ("output", "input"));
                assert_eq!(bond, &None, "no power bonds at a fixed step");
                (from.0.clone(), from.1.clone(), to.0.clone(), to.1.clone())
            })
            .collect();
        assert_eq!(found, expected_connections());
    }

    /// The ECCO OSP file: one power bond per corner whose sides libcosim pairs as corner and chassis, and a complete ECCO configuration.
    #[test]
    fn the_ecco_osp_file_bonds_force_and_velocity_of_every_corner() {
        let root = osp(true);
        let order: Vec<&str> = root.children.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(
            order,
            [
                "StartTime",
                "EndTime",
                "BaseStepSize",
                "Algorithm",
                "Simulators",
                "Connections",
                "EccoConfiguration"
            ]
        );
        assert_eq!(root.child("Algorithm").text, "ecco");
        assert_eq!(osp_initial_values(&root), ssd_parameters(&ssd()));
        let connections = osp_connections(&root);
        let found: BTreeSet<_> = connections
            .iter()
            .map(|(from, to, _)| (from.0.clone(), from.1.clone(), to.0.clone(), to.1.clone()))
            .collect();
        assert_eq!(found, expected_connections());

        let mut bonds: BTreeMap<&str, Vec<(&OspEnd, &OspEnd)>> = BTreeMap::new();
        for (a, b, bond) in &connections {
            match bond {
                Some(name) => bonds.entry(name.as_str()).or_default().push((a, b)),
                None => assert!(
                    b.1 == "body_displacement",
                    "only displacements are unbonded"
                ),
            }
        }
        assert_eq!(bonds.len(), 4, "one bond per corner");
        for (name, pair) in bonds {
            assert_eq!(pair.len(), 2, "{name} joins two connections");
            // libcosim's pairing: the input end of the first connection and
            // the output end of the second are one side of the bond, and
            // the other two ends the other side.
            let end = |(a, b): (&OspEnd, &OspEnd), causality: &str| -> OspEnd {
                let end = if a.2 == causality { a } else { b };
                assert_eq!(end.2, causality);
                end.clone()
            };
            let side_a = [end(pair[0], "input"), end(pair[1], "output")];
            let side_b = [end(pair[1], "input"), end(pair[0], "output")];
            let mut sides: Vec<(String, BTreeSet<String>)> = [side_a, side_b]
                .iter()
                .map(|side| {
                    assert_eq!(side[0].0, side[1].0, "{name}: one simulator per side");
                    (
                        side[0].0.clone(),
                        side.iter().map(|e| e.1.clone()).collect::<BTreeSet<_>>(),
                    )
                })
                .collect();
            sides.sort();
            let corner = sides[1].0.clone();
            assert_eq!(
                sides,
                vec![
                    (
                        "chassis".to_string(),
                        BTreeSet::from([format!("force_{corner}"), format!("velocity_{corner}")])
                    ),
                    (
                        corner.clone(),
                        BTreeSet::from(["body_force".to_string(), "body_velocity".to_string()])
                    ),
                ]
            );
        }

        let settings: BTreeMap<&str, f64> = root
            .child("EccoConfiguration")
            .children
            .iter()
            .map(|s| (s.name.as_str(), s.text.parse().expect("a number")))
            .collect();
        let names: BTreeSet<&str> = settings.keys().copied().collect();
        assert_eq!(
            names,
            BTreeSet::from([
                "SafetyFactor",
                "StepSize",
                "MinimumStepSize",
                "MaximumStepSize",
                "MinimumChangeRate",
                "MaximumChangeRate",
                "ProportionalGain",
                "IntegralGain",
                "RelativeTolerance",
                "AbsoluteTolerance",
            ])
        );
        assert!(settings.values().all(|v| *v > 0.0));
        assert!(settings["SafetyFactor"] < 1.0);
        assert!(settings["MinimumStepSize"] <= settings["StepSize"]);
        assert!(settings["StepSize"] <= settings["MaximumStepSize"]);
        assert!(settings["MinimumChangeRate"] < 1.0 && settings["MaximumChangeRate"] > 1.0);
    }
}
