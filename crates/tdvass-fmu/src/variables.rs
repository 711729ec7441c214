//! The one table of FMU variables (a long file on purpose: one declaration
//! per variable, read as one list): [`COMMON_VARIABLES`], the variables of
//! both FMI versions (all of FMI 2.0's), and [`FMI3_VARIABLES`], the same
//! followed by the FMI 3.0 additions: the quarter car's. The corner
//! ([`Model::Corner`]) has the table's variables that are not
//! [`Variable::quarter_car_only`] (and none of Model Exchange), then
//! [`CORNER_ADDITIONS`]. The chassis ([`Model::Chassis`]) has its own
//! list, [`CHASSIS_VARIABLES`] (`variables/chassis.rs`), and FMI 3.0's
//! `time`. [`variables_of`] gives a model's in a version, and
//! [`by_vr`] and [`by_name`] search it.
//!
//! Each variable is declared once: name, value reference, causality,
//! variability, physical quantity (hence type definition and unit), display
//! unit, start value, admissible range (hence `min`/`max` and the check made
//! when it is set), description, its direct dependencies (ModelStructure) and
//! how it is read or written ([`Access`]). Everything else is derived: the
//! get/set dispatch of [`crate::Slave`], the `modelDescription.xml` of
//! every FMI version and `documentation/index.html` (at build time, by
//! `tdvass-describe`), the serialized settings ([`crate::snapshot`]), the GUID
//! ([`guid`]) and the command line's defaults (checked by its tests).
//!
//! Value references are unique across all types.
//!
//! This file is longer than the others on purpose: the table is the single
//! declaration of every variable (about 500 lines of data), and splitting it
//! would scatter what must be read, and changed, in one place.

use crate::chassis_outputs::ChassisOutputId;
use crate::defaults::Model;
use crate::error::FmiError;
use crate::outputs::{IntegerOutputId, OutputId};
use crate::settings::Settings;
use tdvass::limits::Bound;
use tdvass::model::{V_H, V_S, V_T, X_H, X_S, X_T};

/// FMI causality.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Causality {
    Parameter,
    /// FMI 3.0 only: a parameter that sets the size of an array.
    StructuralParameter,
    CalculatedParameter,
    Input,
    Output,
    /// A continuous state or derivative of Model Exchange that is not an
    /// output (readable in both interfaces).
    Local,
    /// FMI 3.0 only: the independent variable `time`.
    Independent,
}

impl Causality {
    /// The XML attribute value.
    pub fn as_str(self) -> &'static str {
        match self {
            Causality::Parameter => "parameter",
            Causality::StructuralParameter => "structuralParameter",
            Causality::CalculatedParameter => "calculatedParameter",
            Causality::Input => "input",
            Causality::Output => "output",
            Causality::Local => "local",
            Causality::Independent => "independent",
        }
    }
}

/// FMI variability.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Variability {
    Fixed,
    Tunable,
    /// Changes at communication points only (the Integer outputs).
    Discrete,
    Continuous,
}

impl Variability {
    /// The XML attribute value.
    pub fn as_str(self) -> &'static str {
        match self {
            Variability::Fixed => "fixed",
            Variability::Tunable => "tunable",
            Variability::Discrete => "discrete",
            Variability::Continuous => "continuous",
        }
    }
}

/// FMI `initial` attribute.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Initial {
    Exact,
    Calculated,
}

impl Initial {
    /// The XML attribute value.
    pub fn as_str(self) -> &'static str {
        match self {
            Initial::Exact => "exact",
            Initial::Calculated => "calculated",
        }
    }
}

/// FMI 2.0 base type of a variable.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum VarType {
    Real,
    Integer,
    Boolean,
    String,
}

impl VarType {
    /// The XML element name.
    pub fn as_str(self) -> &'static str {
        match self {
            VarType::Real => "Real",
            VarType::Integer => "Integer",
            VarType::Boolean => "Boolean",
            VarType::String => "String",
        }
    }
}

/// A unit of `UnitDefinitions`: name, SI base-unit exponents and display
/// units `(name, factor)` (display value = factor × value).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UnitDefinition {
    /// Unit name, as used in the `unit` attributes.
    pub name: &'static str,
    /// `BaseUnit` exponents, e.g. `[("kg", 1), ("s", -2)]`.
    pub base: &'static [(&'static str, i32)],
    /// `DisplayUnit`s.
    pub display: &'static [(&'static str, f64)],
}

/// Every unit used by the variables.
pub const UNITS: &[UnitDefinition] = &[
    UnitDefinition {
        name: "kg",
        base: &[("kg", 1)],
        display: &[],
    },
    UnitDefinition {
        name: "N/m",
        base: &[("kg", 1), ("s", -2)],
        display: &[],
    },
    UnitDefinition {
        name: "N.s/m",
        base: &[("kg", 1), ("s", -1)],
        display: &[],
    },
    UnitDefinition {
        name: "m",
        base: &[("m", 1)],
        display: &[("mm", 1000.0)],
    },
    UnitDefinition {
        name: "m/s",
        base: &[("m", 1), ("s", -1)],
        display: &[("mm/s", 1000.0)],
    },
    UnitDefinition {
        name: "m/s2",
        base: &[("m", 1), ("s", -2)],
        display: &[],
    },
    UnitDefinition {
        name: "N",
        base: &[("kg", 1), ("m", 1), ("s", -2)],
        display: &[],
    },
    UnitDefinition {
        name: "s",
        base: &[("s", 1)],
        display: &[("ms", 1000.0)],
    },
    UnitDefinition {
        name: "rad/s",
        base: &[("s", -1), ("rad", 1)],
        display: &[],
    },
    UnitDefinition {
        name: "Hz",
        base: &[("s", -1)],
        display: &[],
    },
    UnitDefinition {
        name: "1/s",
        base: &[("s", -1)],
        display: &[],
    },
    // ISO 2631-1's vibration dose value: the exponent of s is not an
    // integer, so no BaseUnit can state it.
    UnitDefinition {
        name: "m/s1.75",
        base: &[],
        display: &[],
    },
    // The chassis's angles, angular accelerations and moments of inertia.
    UnitDefinition {
        name: "rad",
        base: &[("rad", 1)],
        display: &[],
    },
    UnitDefinition {
        name: "rad/s2",
        base: &[("s", -2), ("rad", 1)],
        display: &[],
    },
    UnitDefinition {
        name: "kg.m2",
        base: &[("kg", 1), ("m", 2)],
        display: &[],
    },
];

/// Physical quantity of a Real variable: its `TypeDefinitions` entry
/// (`declaredType`) and unit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Quantity {
    /// No unit (codes, weights, the objective, Booleans).
    Dimensionless,
    Mass,
    Stiffness,
    Damping,
    Length,
    Velocity,
    Acceleration,
    Force,
    Time,
    AngularFrequency,
    Frequency,
    Rate,
    /// ISO 2631-1 vibration dose value (m/s^1.75).
    VibrationDose,
    /// An angle (rad): the chassis's pitch and roll.
    Angle,
    /// An angular velocity (rad/s).
    AngularVelocity,
    /// An angular acceleration (rad/s2).
    AngularAcceleration,
    /// A moment of inertia (kg m2).
    Inertia,
}

impl Quantity {
    /// Every quantity that has a type definition, in declaration order.
    pub const TYPED: [Quantity; 16] = [
        Quantity::Mass,
        Quantity::Stiffness,
        Quantity::Damping,
        Quantity::Length,
        Quantity::Velocity,
        Quantity::Acceleration,
        Quantity::Force,
        Quantity::Time,
        Quantity::AngularFrequency,
        Quantity::Frequency,
        Quantity::Rate,
        Quantity::VibrationDose,
        Quantity::Angle,
        Quantity::AngularVelocity,
        Quantity::AngularAcceleration,
        Quantity::Inertia,
    ];

    /// `(type name, quantity, unit)` of the `SimpleType`, `None` when dimensionless.
    pub fn type_definition(self) -> Option<(&'static str, &'static str, &'static str)> {
        Some(match self {
            Quantity::Dimensionless => return None,
            Quantity::Mass => ("Mass", "Mass", "kg"),
            Quantity::Stiffness => ("Stiffness", "TranslationalSpringConstant", "N/m"),
            Quantity::Damping => ("Damping", "TranslationalDampingConstant", "N.s/m"),
            Quantity::Length => ("Length", "Length", "m"),
            Quantity::Velocity => ("Velocity", "Velocity", "m/s"),
            Quantity::Acceleration => ("Acceleration", "Acceleration", "m/s2"),
            Quantity::Force => ("Force", "Force", "N"),
            Quantity::Time => ("Time", "Time", "s"),
            Quantity::AngularFrequency => ("AngularFrequency", "AngularFrequency", "rad/s"),
            Quantity::Frequency => ("Frequency", "Frequency", "Hz"),
            Quantity::Rate => ("GrowthRate", "GrowthRate", "1/s"),
            Quantity::VibrationDose => ("VibrationDose", "VibrationDose", "m/s1.75"),
            Quantity::Angle => ("Angle", "Angle", "rad"),
            Quantity::AngularVelocity => ("AngularVelocity", "AngularVelocity", "rad/s"),
            Quantity::AngularAcceleration => {
                ("AngularAcceleration", "AngularAcceleration", "rad/s2")
            }
            Quantity::Inertia => ("Inertia", "MomentOfInertia", "kg.m2"),
        })
    }

    /// The unit, `None` when dimensionless.
    pub fn unit(self) -> Option<&'static str> {
        self.type_definition().map(|(_, _, unit)| unit)
    }
}

/// Admissible values: checked when a variable is set; `min`/`max` in the
/// description derive from it (`Positive` is declared as `min="0"`, the
/// strict bound is in the check and the description).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Range {
    /// Any finite value.
    Finite,
    /// Finite and `>= min`.
    AtLeast(f64),
    /// Finite and `> 0`.
    Positive,
    /// An integer in `min..=max`.
    Integers(i32, i32),
    /// Computed by the FMU (outputs, calculated parameters): no check.
    Computed,
}

impl Range {
    /// `(min, max)` as declared in the description.
    pub fn bounds(self) -> (Option<f64>, Option<f64>) {
        match self {
            Range::Finite | Range::Computed => (None, None),
            Range::AtLeast(min) => (Some(min), None),
            Range::Positive => (Some(0.0), None),
            Range::Integers(min, max) => (Some(min as f64), Some(max as f64)),
        }
    }

    /// The admissible values in words (documentation).
    pub fn describe(self) -> String {
        match self {
            Range::Finite => "finite".into(),
            Range::AtLeast(min) => format!(">= {min}"),
            Range::Positive => "> 0".into(),
            Range::Integers(min, max) => format!("{min} .. {max}"),
            Range::Computed => String::new(),
        }
    }

    /// Whether `value` is admissible; the error names the variable and value.
    pub fn check(self, name: &str, value: f64) -> Result<(), FmiError> {
        let reason = match self {
            Range::Computed => return Ok(()),
            _ if !value.is_finite() => "must be finite".to_string(),
            Range::Finite => return Ok(()),
            Range::AtLeast(min) if value < min => format!("must be >= {min}"),
            Range::Positive if value <= 0.0 => "must be > 0".to_string(),
            Range::Integers(min, max) if !(min as f64..=max as f64).contains(&value) => {
                format!("must be in {min}..={max}")
            }
            _ => return Ok(()),
        };
        Err(FmiError::error(format!(
            "invalid value {value} for `{name}`: {reason}"
        )))
    }
}

/// A calculated parameter.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Calculated {
    /// Real part of the rightmost characteristic root (1/s).
    SpectralAbscissa,
    /// `spectral_abscissa < 0`.
    Stable,
    /// The `root_count` rightmost characteristic roots, `(re, im)` each
    /// (1/s), rightmost first (an FMI 3.0 array of `root_count` × 2).
    RightmostRoots,
}

/// One named item of an enumeration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EnumerationItem {
    pub name: &'static str,
    /// The integer code (the FMI 2.0 Integer value).
    pub value: i32,
    pub description: &'static str,
}

/// An enumeration type: the FMI 3.0 `EnumerationType` of an Integer
/// setting whose codes have names (FMI 2.0 keeps the Integer).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Enumeration {
    /// The type's name in `TypeDefinitions`.
    pub type_name: &'static str,
    pub items: &'static [EnumerationItem],
}

impl Enumeration {
    /// The code of the item called `name`.
    pub fn value_of(&self, name: &str) -> Option<i32> {
        self.items.iter().find(|i| i.name == name).map(|i| i.value)
    }
}

const fn item(name: &'static str, value: i32, description: &'static str) -> EnumerationItem {
    EnumerationItem {
        name,
        value,
        description,
    }
}

/// `variant`.
pub static VARIANT_ITEMS: Enumeration = Enumeration {
    type_name: "Variant",
    items: &[
        item("CS", 1, "conventional 2-DOF suspension"),
        item("PVASS", 2, "annular vibration absorber, no control"),
        item("TDVASS", 3, "absorber with time-delay feedback"),
    ],
};

/// `road`.
pub static ROAD_ITEMS: Enumeration = Enumeration {
    type_name: "Road",
    items: &[
        item("input", 0, "the input x_g"),
        item(
            "harmonic",
            1,
            "road_amplitude sin(road_angular_frequency t)",
        ),
        item("iso8608", 2, "ISO 8608 filtered white noise"),
        item("paper", 3, "the paper-compatible random road"),
    ],
};

/// `road_class`.
pub static ROAD_CLASS_ITEMS: Enumeration = Enumeration {
    type_name: "RoadClass",
    items: &[
        item("A", 1, "ISO 8608 class A"),
        item("B", 2, "ISO 8608 class B"),
        item("C", 3, "ISO 8608 class C"),
        item("D", 4, "ISO 8608 class D"),
        item("E", 5, "ISO 8608 class E"),
        item("F", 6, "ISO 8608 class F"),
        item("G", 7, "ISO 8608 class G"),
        item("H", 8, "ISO 8608 class H"),
    ],
};

/// `tire_contact`.
pub static TIRE_CONTACT_ITEMS: Enumeration = Enumeration {
    type_name: "TireContact",
    items: &[
        item(
            "bilateral",
            0,
            "the paper's linear tire, which pulls as well as pushes",
        ),
        item(
            "unilateral",
            1,
            "a tire that cannot pull: the wheel lifts off",
        ),
    ],
};

/// The size of one dimension of an array variable.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dimension {
    /// A fixed size.
    Fixed(u64),
    /// The value of the structural parameter of this name.
    Structural(&'static str),
}

/// An FMI version of the FMUs: which variables exist in it
/// ([`variables_of`]), which dialect a slave speaks
/// ([`crate::slave::Dialect`]) and, for fmu-build, which FMU is packed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FmiVersion {
    Fmi2,
    Fmi3,
}

/// How a variable is read and written.
#[derive(Debug, Clone, Copy)]
pub enum Access {
    /// A Real setting (parameter or input).
    Real {
        get: fn(&Settings) -> f64,
        set: fn(&mut Settings, f64),
    },
    /// An Integer setting (parameter).
    Integer {
        get: fn(&Settings) -> i32,
        set: fn(&mut Settings, i32),
    },
    /// A Real output of the simulator.
    Output(OutputId),
    /// A Real output of the chassis ([`Model::Chassis`]).
    ChassisOutput(ChassisOutputId),
    /// An Integer output of the simulator (a count).
    IntegerOutput(IntegerOutputId),
    /// A calculated parameter.
    Calculated(Calculated),
    /// The independent variable: the slave's time.
    Time,
    /// Component i of the continuous states
    /// ([`tdvass::solver::CONTINUOUS_STATES`]) that is not an output.
    ContinuousState(usize),
    /// The time derivative of component i of the continuous states.
    StateDerivative(usize),
    /// Event indicator i of Model Exchange
    /// ([`tdvass::exchange::EVENT_INDICATORS`]).
    EventIndicator(usize),
}

/// How an output depends on one of its knowns (ModelStructure's
/// `dependenciesKind`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DependencyKind {
    /// Linearly, with a factor fixed at initialization.
    Fixed,
    /// In any other way.
    Dependent,
}

impl DependencyKind {
    /// The XML attribute value.
    pub fn name(self) -> &'static str {
        match self {
            DependencyKind::Fixed => "fixed",
            DependencyKind::Dependent => "dependent",
        }
    }
}

/// One FMU variable.
#[derive(Debug, Clone, Copy)]
pub struct Variable {
    pub name: &'static str,
    pub vr: u32,
    pub causality: Causality,
    pub variability: Variability,
    pub quantity: Quantity,
    /// `displayUnit`, one of the unit's display units.
    pub display_unit: Option<&'static str>,
    /// Start value (Integer values are exact in f64); `None` for calculated ones.
    pub start: Option<f64>,
    pub range: Range,
    pub access: Access,
    pub description: &'static str,
    /// Outputs: the inputs the value depends on directly (ModelStructure/Outputs).
    pub feedthrough: &'static [&'static str],
    /// Outputs and calculated parameters: the parameters and inputs the
    /// initial value depends on (ModelStructure/InitialUnknowns).
    pub initial_dependencies: &'static [&'static str],
    /// Named codes of an Integer setting (an FMI 3.0 Enumeration).
    pub enumeration: Option<&'static Enumeration>,
    /// The dimensions of an array (FMI 3.0 only); empty for a scalar.
    pub dimensions: &'static [Dimension],
    /// FMI 3.0: may be read (outputs) or set (the input) inside an
    /// intermediate update.
    pub intermediate_update: bool,
    /// Only the FMI 3.0 FMU has it (these follow the common variables in
    /// the table, so FMI 2.0's `ModelVariables` are a prefix of it).
    pub fmi3_only: bool,
    /// The library's numerical limit on its magnitude, by the kind of value
    /// it is ([`tdvass::limits::Bound`]; `None`: its range alone).
    pub bound: Option<Bound>,
    /// Only the quarter car has it: the corner ([`Model::Corner`]) leaves
    /// it out, or declares its own of the same name and value reference
    /// in [`CORNER_ADDITIONS`].
    pub quarter_car_only: bool,
}

impl Variable {
    /// The FMI base type.
    pub fn var_type(&self) -> VarType {
        match self.access {
            Access::Real { .. }
            | Access::Output(_)
            | Access::ChassisOutput(_)
            | Access::Time
            | Access::ContinuousState(_)
            | Access::StateDerivative(_)
            | Access::EventIndicator(_) => VarType::Real,
            Access::Integer { .. } | Access::IntegerOutput(_) => VarType::Integer,
            Access::Calculated(Calculated::SpectralAbscissa | Calculated::RightmostRoots) => {
                VarType::Real
            }
            Access::Calculated(Calculated::Stable) => VarType::Boolean,
        }
    }

    /// The `initial` attribute (`None` for inputs, where it is not allowed).
    pub fn initial(&self) -> Option<Initial> {
        match self.causality {
            Causality::Parameter | Causality::StructuralParameter => Some(Initial::Exact),
            Causality::CalculatedParameter | Causality::Output | Causality::Local => {
                Some(Initial::Calculated)
            }
            Causality::Input | Causality::Independent => None,
        }
    }

    /// Model Exchange: the index of the continuous state this variable is
    /// among its engine's states ([`tdvass::solver::CONTINUOUS_STATES`],
    /// the chassis's [`tdvass::chassis::CHASSIS_STATES`];
    /// [`Model::continuous_states`] says which the model has), `None` for
    /// the others.
    pub fn state_index(&self) -> Option<usize> {
        match self.access {
            Access::Output(OutputId::State(i)) | Access::ContinuousState(i) => Some(i),
            Access::Output(OutputId::ContactLossTime) => {
                Some(tdvass::solver::CONTINUOUS_STATES - 1)
            }
            Access::ChassisOutput(ChassisOutputId::Position(k)) => Some(k),
            Access::ChassisOutput(ChassisOutputId::Rate(k)) => Some(3 + k),
            _ => None,
        }
    }

    /// Whether the corner has this variable of Model Exchange (a local
    /// state, a derivative or the event indicator): the states of
    /// [`Model::continuous_states`] and their derivatives, the tire's
    /// event indicator.
    fn in_corner_exchange(&self) -> bool {
        match self.access {
            Access::ContinuousState(i) | Access::StateDerivative(i) => {
                Model::Corner.continuous_states().contains(&i)
            }
            Access::EventIndicator(_) => true,
            _ => false,
        }
    }

    /// Outputs: the knowns the value depends on in Continuous-Time and
    /// Event Mode and at communication points (ModelStructure/Outputs,
    /// `fmi3GetVariableDependencies`): the inputs it depends on directly
    /// ([`Variable::feedthrough`], linear with a factor fixed by `road`),
    /// then the variables of the continuous states it is computed from
    /// (Model Exchange's knowns; [`OutputId::state_dependencies`]). Empty
    /// for the other variables.
    pub fn output_dependencies(
        &self,
        model: Model,
        version: FmiVersion,
    ) -> Vec<(&'static Variable, DependencyKind)> {
        let states = match self.access {
            Access::Output(id) => id.state_dependencies(),
            Access::IntegerOutput(id) => id.state_dependencies(),
            Access::ChassisOutput(id) => id.state_dependencies(),
            _ => return Vec::new(),
        };
        let inputs = self.feedthrough.iter().map(|name| {
            let input = by_name(model, version, name)
                .unwrap_or_else(|| panic!("unknown feedthrough input `{name}`"));
            (input, DependencyKind::Fixed)
        });
        // Only the model's own continuous states are knowns (the corner
        // takes the body's coordinates from its inputs).
        let own = model.continuous_states();
        let states = states.filter(|i| own.contains(i)).map(|i| {
            let state = variables_of(model, version)
                .iter()
                .find(|v| v.state_index() == Some(i))
                .unwrap_or_else(|| panic!("no variable of continuous state {i}"));
            (state, DependencyKind::Dependent)
        });
        inputs.chain(states).collect()
    }

    /// The unit, if any.
    pub fn unit(&self) -> Option<&'static str> {
        self.quantity.unit()
    }

    /// Whether the variable exists in `version` (the FMI 3.0 additions
    /// follow the common variables in the table).
    pub fn is_in(&self, version: FmiVersion) -> bool {
        version == FmiVersion::Fmi3 || !self.fmi3_only
    }

    /// Whether the variable is the independent variable `time`.
    fn access_is_time(&self) -> bool {
        matches!(self.access, Access::Time)
    }

    const fn display(mut self, unit: &'static str) -> Variable {
        self.display_unit = Some(unit);
        self
    }

    const fn enumerated(mut self, enumeration: &'static Enumeration) -> Variable {
        self.enumeration = Some(enumeration);
        self
    }

    const fn bounded(mut self, bound: Bound) -> Variable {
        self.bound = Some(bound);
        self
    }

    const fn quarter_car(mut self) -> Variable {
        self.quarter_car_only = true;
        self
    }
}

/// The variables of `model` in `version`, in `ModelVariables` order: for
/// the quarter car [`COMMON_VARIABLES`] (FMI 2.0) and [`FMI3_VARIABLES`]
/// (FMI 3.0); for the corner the table's variables it shares (not the
/// quarter car's own, and of Model Exchange's only those of its own
/// states, [`Model::continuous_states`]), then [`CORNER_ADDITIONS`], then
/// the FMI 3.0 additions (built at the first call).
pub fn variables_of(model: Model, version: FmiVersion) -> &'static [Variable] {
    static CORNER: [std::sync::OnceLock<Vec<Variable>>; 2] =
        [std::sync::OnceLock::new(), std::sync::OnceLock::new()];
    static CHASSIS_FMI3: std::sync::OnceLock<Vec<Variable>> = std::sync::OnceLock::new();
    match (model, version) {
        (Model::QuarterCar, FmiVersion::Fmi2) => COMMON_VARIABLES,
        (Model::QuarterCar, FmiVersion::Fmi3) => FMI3_VARIABLES,
        (Model::Chassis, FmiVersion::Fmi2) => chassis::CHASSIS_VARIABLES,
        (Model::Chassis, FmiVersion::Fmi3) => CHASSIS_FMI3.get_or_init(|| {
            chassis::CHASSIS_VARIABLES
                .iter()
                .chain(FMI3_VARIABLES.iter().filter(|v| v.access_is_time()))
                .copied()
                .collect()
        }),
        (Model::Corner, _) => CORNER[slot(version)].get_or_init(|| {
            let shared = |v: &&Variable| {
                !v.quarter_car_only && (v.causality != Causality::Local || v.in_corner_exchange())
            };
            COMMON_VARIABLES
                .iter()
                .filter(shared)
                .chain(CORNER_ADDITIONS)
                .chain(
                    FMI3_VARIABLES[COMMON_VARIABLES.len()..]
                        .iter()
                        .filter(shared),
                )
                .filter(|v| v.is_in(version))
                .copied()
                .collect()
        }),
    }
}

/// The index of `version` among the FMI versions.
fn slot(version: FmiVersion) -> usize {
    match version {
        FmiVersion::Fmi2 => 0,
        FmiVersion::Fmi3 => 1,
    }
}

/// Looks a variable of `model` in `version` up by value reference: in
/// constant time through a table built at the first lookup (a getter asks
/// for every value reference of every call), the same variable as a
/// search of [`variables_of`] would find.
pub fn by_vr(model: Model, version: FmiVersion, vr: u32) -> Option<&'static Variable> {
    match vr_table(model, version).get(vr as usize) {
        Some(found) => *found,
        None => variables_of(model, version).iter().find(|v| v.vr == vr),
    }
}

/// Builds the lookup table of [`by_vr`] for `model` in `version` now (once
/// per process), so that the first getter or setter after initialization
/// does not allocate it (an instantiation calls this).
pub fn build_lookup(model: Model, version: FmiVersion) {
    vr_table(model, version);
}

/// The variables of `model` in `version` by value reference (the first of
/// each, as a search finds it), for the references below the largest one
/// in use (at most 4096); built at the first lookup.
fn vr_table(model: Model, version: FmiVersion) -> &'static [Option<&'static Variable>] {
    type Lookup = std::sync::OnceLock<Vec<Option<&'static Variable>>>;
    static TABLES: [[Lookup; 2]; 3] = [
        [Lookup::new(), Lookup::new()],
        [Lookup::new(), Lookup::new()],
        [Lookup::new(), Lookup::new()],
    ];
    let model_slot = match model {
        Model::QuarterCar => 0,
        Model::Corner => 1,
        Model::Chassis => 2,
    };
    TABLES[model_slot][slot(version)].get_or_init(|| {
        let variables = variables_of(model, version);
        let len = variables
            .iter()
            .map(|v| v.vr as usize + 1)
            .filter(|&n| n <= 4096)
            .max()
            .unwrap_or(0);
        let mut table = vec![None; len];
        for v in variables {
            if let Some(entry @ None) = table.get_mut(v.vr as usize) {
                *entry = Some(v);
            }
        }
        table
    })
}

/// The variable of `model` in `version` ([`variables_of`]) called `name`.
pub fn by_name(model: Model, version: FmiVersion, name: &str) -> Option<&'static Variable> {
    variables_of(model, version).iter().find(|v| v.name == name)
}

macro_rules! real {
    ($($field:tt)+) => {
        Access::Real {
            get: |s: &Settings| s.$($field)+,
            set: |s: &mut Settings, v: f64| s.$($field)+ = v,
        }
    };
}

macro_rules! integer {
    ($field:ident) => {
        Access::Integer {
            get: |s: &Settings| s.$field,
            set: |s: &mut Settings, v: i32| s.$field = v,
        }
    };
}

#[allow(clippy::too_many_arguments)]
const fn parameter(
    name: &'static str,
    vr: u32,
    variability: Variability,
    quantity: Quantity,
    start: f64,
    range: Range,
    access: Access,
    description: &'static str,
) -> Variable {
    Variable {
        name,
        vr,
        causality: Causality::Parameter,
        variability,
        quantity,
        display_unit: None,
        start: Some(start),
        range,
        access,
        description,
        feedthrough: &[],
        initial_dependencies: &[],
        enumeration: None,
        dimensions: &[],
        intermediate_update: false,
        fmi3_only: false,
        bound: None,
        quarter_car_only: false,
    }
}

const fn output(
    name: &'static str,
    vr: u32,
    quantity: Quantity,
    id: OutputId,
    description: &'static str,
    feedthrough: &'static [&'static str],
    initial_dependencies: &'static [&'static str],
) -> Variable {
    output_read_by(
        name,
        vr,
        quantity,
        Access::Output(id),
        description,
        feedthrough,
        initial_dependencies,
    )
}

/// A continuous Real output read through `access` (the simulator's, or
/// the chassis's).
const fn output_read_by(
    name: &'static str,
    vr: u32,
    quantity: Quantity,
    access: Access,
    description: &'static str,
    feedthrough: &'static [&'static str],
    initial_dependencies: &'static [&'static str],
) -> Variable {
    Variable {
        name,
        vr,
        causality: Causality::Output,
        variability: Variability::Continuous,
        quantity,
        display_unit: None,
        start: None,
        range: Range::Computed,
        access,
        description,
        feedthrough,
        initial_dependencies,
        enumeration: None,
        dimensions: &[],
        intermediate_update: true,
        fmi3_only: false,
        bound: None,
        quarter_car_only: false,
    }
}

/// A continuous state of Model Exchange that is not an output.
const fn local_state(
    name: &'static str,
    vr: u32,
    index: usize,
    quantity: Quantity,
    description: &'static str,
) -> Variable {
    Variable {
        name,
        vr,
        causality: Causality::Local,
        variability: Variability::Continuous,
        quantity,
        display_unit: None,
        start: None,
        range: Range::Computed,
        access: Access::ContinuousState(index),
        description,
        feedthrough: &[],
        initial_dependencies: &[],
        enumeration: None,
        dimensions: &[],
        intermediate_update: false,
        fmi3_only: false,
        bound: None,
        quarter_car_only: false,
    }
}

/// The derivative `der(state)` of continuous state `index`.
const fn derivative(
    name: &'static str,
    vr: u32,
    index: usize,
    quantity: Quantity,
    description: &'static str,
) -> Variable {
    Variable {
        access: Access::StateDerivative(index),
        ..local_state(name, vr, index, quantity, description)
    }
}

const fn calculated(
    name: &'static str,
    vr: u32,
    quantity: Quantity,
    which: Calculated,
    description: &'static str,
) -> Variable {
    Variable {
        name,
        vr,
        causality: Causality::CalculatedParameter,
        // Depends on the tunable g.
        variability: Variability::Tunable,
        quantity,
        display_unit: None,
        start: None,
        range: Range::Computed,
        access: Access::Calculated(which),
        description,
        feedthrough: &[],
        initial_dependencies: SPECTRUM_DEPENDENCIES,
        enumeration: None,
        dimensions: &[],
        intermediate_update: false,
        fmi3_only: false,
        bound: None,
        quarter_car_only: false,
    }
}

use Quantity as Q;
use Variability::{Fixed, Tunable};

const SPECTRUM_DEPENDENCIES: &[&str] = &[
    "variant", "m_s", "m_h", "m_t", "k_s", "k_h", "k_t", "c_s", "c_h", "g", "tau",
];
/// What the tire load and the lift-offs depend on initially (the static
/// load through the masses and k_t, the road, the tire law, the wheel).
const TIRE_LOAD_DEPENDENCIES: &[&str] = &[
    "variant",
    "m_s",
    "m_h",
    "m_t",
    "k_t",
    "road",
    "road_amplitude",
    "road_angular_frequency",
    "tire_contact",
    "x_t_start",
    "x_g",
];
const ROAD_DEPENDENCIES: &[&str] = &["road", "road_amplitude", "road_angular_frequency", "x_g"];

/// The lift-off counter (an Integer output, discrete: it changes at
/// communication points, not inside a step), of the model whose initial
/// tire load depends on `initial_dependencies`.
const fn lift_off_count(
    description: &'static str,
    initial_dependencies: &'static [&'static str],
) -> Variable {
    Variable {
        name: "lift_off_count",
        vr: 61,
        causality: Causality::Output,
        variability: Variability::Discrete,
        quantity: Q::Dimensionless,
        display_unit: None,
        start: None,
        range: Range::Computed,
        access: Access::IntegerOutput(IntegerOutputId::LiftOffCount),
        description,
        feedthrough: &[],
        initial_dependencies,
        enumeration: None,
        dimensions: &[],
        intermediate_update: false,
        fmi3_only: false,
        bound: None,
        quarter_car_only: false,
    }
}

/// What the corner's tire load and lift-offs depend on initially (its
/// static load, the road as it sees it, the tire law, the wheel).
const CORNER_TIRE_LOAD_DEPENDENCIES: &[&str] = &[
    "variant",
    "static_load",
    "m_h",
    "m_t",
    "k_t",
    "road",
    "road_amplitude",
    "road_angular_frequency",
    "road_delay",
    "road_phase",
    "tire_contact",
    "x_t_start",
    "x_g",
];

/// What the road as the corner's wheel sees it depends on initially.
const CORNER_ROAD_DEPENDENCIES: &[&str] = &[
    "road",
    "road_amplitude",
    "road_angular_frequency",
    "road_delay",
    "road_phase",
    "x_g",
];

/// What the corner's tire deflection depends on initially (the wheel and
/// the road as it sees it).
const CORNER_TIRE_DEFLECTION_DEPENDENCIES: &[&str] = &[
    "road",
    "road_amplitude",
    "road_angular_frequency",
    "road_delay",
    "road_phase",
    "x_t_start",
    "x_g",
];

/// An input of the corner's body attachment point (its value and slope
/// the line the attachment follows from where it is set).
const fn body_input(
    name: &'static str,
    vr: u32,
    quantity: Quantity,
    access: Access,
    bound: Bound,
    description: &'static str,
) -> Variable {
    Variable {
        name,
        vr,
        causality: Causality::Input,
        variability: Variability::Continuous,
        quantity,
        display_unit: None,
        start: Some(0.0),
        range: Range::Finite,
        access,
        description,
        feedthrough: &[],
        initial_dependencies: &[],
        enumeration: None,
        dimensions: &[],
        intermediate_update: true,
        fmi3_only: false,
        bound: Some(bound),
        quarter_car_only: false,
    }
}

/// `input_extrapolation` (0 .. 2), as the quarter car and the corner
/// each describe it.
const fn input_extrapolation(description: &'static str) -> Variable {
    parameter(
        "input_extrapolation",
        48,
        Variability::Fixed,
        Q::Dimensionless,
        0.0,
        Range::Integers(0, 2),
        integer!(input_extrapolation),
        description,
    )
}

/// The corner's own variables ([`Model::Corner`]): its static load, the
/// road as this wheel sees it, the body's attachment point and the force
/// on it, and its own declarations of the outputs whose dependencies name
/// the body (the quarter car's of the same name and value reference are
/// [`Variable::quarter_car_only`]). They follow the shared variables in
/// the corner's `ModelVariables`.
pub const CORNER_ADDITIONS: &[Variable] = &[
    parameter(
        "static_load",
        140,
        Fixed,
        Q::Force,
        345.0 * tdvass::model::STANDARD_GRAVITY,
        Range::Positive,
        real!(static_load),
        "This corner's share W_c of the body's weight (N, > 0; default 345 kg g0, the paper's body): with the corner's own masses it sets the tire's static load W = W_c + (m_h + m_t) g0 (CS: W_c + m_t g0), hence the unilateral tire's lift-off and the tire load ratio",
    ),
    parameter(
        "road_delay",
        141,
        Fixed,
        Q::Time,
        0.0,
        Range::AtLeast(0.0),
        real!(road_delay),
        "The built-in road (road = 1, 2, 3) as this wheel sees it: the profile delayed by this (s, >= 0; a rear wheel: wheelbase / speed). A random road starts at road_delay after the start time; must be 0 with road = 0",
    ),
    parameter(
        "road_phase",
        142,
        Fixed,
        Q::Dimensionless,
        0.0,
        Range::Finite,
        real!(road_phase),
        "Harmonic road only (rad): x_g = road_amplitude sin(road_angular_frequency (t - road_delay) + road_phase) (a right track out of phase with the left excites roll)",
    ),
    input_extrapolation(
        "Co-Simulation: 0 holds the inputs over each communication step (FMI default: the attachment moves at body_velocity, x_g is held). 1 and 2 extrapolate the attachment's velocity linearly from the last two body_velocity values set at communication points: over a step it reaches the extrapolated displacement and ends at the extrapolated velocity (the full car's coupling becomes second order in the step); road = 0: 1 extrapolates x_g linearly from its last two values, 2 along the line closest over the step to the parabola through the last three. The first step holds; an input derivative of x_g, when set, takes precedence",
    ),
    body_input(
        "body_displacement",
        143,
        Q::Length,
        real!(body_displacement),
        Bound::Displacement,
        "The body's attachment point: its displacement from the static equilibrium, positive up; in Co-Simulation the attachment moves at body_velocity (with input_extrapolation >= 1, on the extrapolated velocity) from the time it is set until either input is set again, in Model Exchange it is the attachment now (set before each evaluation)",
    ),
    body_input(
        "body_velocity",
        144,
        Q::Velocity,
        real!(body_velocity),
        Bound::Velocity,
        "The body's attachment point: its velocity, positive up (Co-Simulation: from the time it is set until either input is set again; Model Exchange: now)",
    ),
    output(
        "body_force",
        145,
        Q::Force,
        OutputId::BodyForce,
        "The force of the suspension on the body at the attachment point (spring and damper; positive up, zero at the static equilibrium); depends directly on body_displacement and body_velocity",
        &["body_displacement", "body_velocity"],
        &[
            "variant",
            "k_s",
            "c_s",
            "k_h",
            "c_h",
            "body_displacement",
            "body_velocity",
            "x_h_start",
            "v_h_start",
            "x_t_start",
            "v_t_start",
        ],
    ),
    output(
        "suspension_deflection",
        38,
        Q::Length,
        OutputId::SuspensionDeflection,
        "Suspension dynamic deflection SDD = body_displacement - x_t",
        &["body_displacement"],
        &["body_displacement", "x_t_start"],
    ),
    output(
        "tire_deflection",
        39,
        Q::Length,
        OutputId::TireDeflection,
        "Tire dynamic displacement TDD = x_t - x_g",
        &["x_g"],
        CORNER_TIRE_DEFLECTION_DEPENDENCIES,
    )
    .display("mm"),
    output(
        "road_displacement",
        40,
        Q::Length,
        OutputId::RoadDisplacement,
        "Road displacement x_g actually applied (the built-in road as this wheel sees it: delayed by road_delay, shifted by road_phase)",
        &["x_g"],
        CORNER_ROAD_DEPENDENCIES,
    ),
    output(
        "dynamic_tire_load",
        56,
        Q::Force,
        OutputId::DynamicTireLoad,
        "Dynamic tire load k_t (x_g - x_t) = -k_t TDD (no tire damping); below minus the static load W the tire would leave the road (tire_contact = 1: it never goes below, the wheel flies)",
        &["x_g"],
        CORNER_TIRE_LOAD_DEPENDENCIES,
    ),
    output(
        "rms_dynamic_tire_load_ratio",
        57,
        Q::Dimensionless,
        OutputId::RmsDynamicTireLoadRatio,
        "Running RMS of the dynamic tire load over the static load W = static_load + (m_h + m_t) g0, CS static_load + m_t g0; at most 1/3 keeps the contact with 3-sigma confidence",
        &[],
        &[],
    ),
    lift_off_count(
        "Number of lift-offs since the start time (a start without contact counts one): tire_contact = 1, the switches from contact to flight; tire_contact = 0, the times the dynamic tire load went below minus the static load",
        CORNER_TIRE_LOAD_DEPENDENCIES,
    ),
    output(
        "max_suspension_deflection",
        59,
        Q::Length,
        OutputId::MaxSuspensionDeflection,
        "Running maximum of |SDD| (suspension working space used), located inside the internal steps from the dense output (within the tolerance)",
        &[],
        &["body_displacement", "x_t_start"],
    )
    .display("mm"),
];

/// How many variables both versions have: the FMI 3.0 additions follow
/// them at the end of [`TABLE`].
const fn common_count(table: &[Variable]) -> usize {
    let mut i = 0;
    while i < table.len() && !table[i].fmi3_only {
        i += 1;
    }
    i
}

/// The variables of both FMI versions, in `ModelVariables` order (the
/// FMI 2.0 FMU's variables).
pub static COMMON_VARIABLES: &[Variable] = TABLE.split_at(common_count(TABLE)).0;

/// Every variable of the FMI 3.0 FMU: [`COMMON_VARIABLES`], then the FMI 3.0
/// additions.
pub static FMI3_VARIABLES: &[Variable] = TABLE;

/// The one table: every variable, the common ones first.
const TABLE: &[Variable] = &[
    parameter(
        "variant",
        1,
        Fixed,
        Q::Dimensionless,
        3.0,
        Range::Integers(1, 3),
        integer!(variant),
        "Suspension: 1 = CS (conventional 2-DOF), 2 = PVASS (annular absorber, no control), 3 = TDVASS (absorber with time-delay feedback)",
    )
    .enumerated(&VARIANT_ITEMS),
    parameter(
        "m_s",
        2,
        Fixed,
        Q::Mass,
        345.0,
        Range::Positive,
        real!(params.m_s),
        "Body (sprung) mass (> 0)",
    )
    .quarter_car(),
    parameter(
        "m_h",
        3,
        Fixed,
        Q::Mass,
        4.05,
        Range::Positive,
        real!(params.m_h),
        "Annular absorber mass (> 0)",
    ),
    parameter(
        "m_t",
        4,
        Fixed,
        Q::Mass,
        40.5,
        Range::Positive,
        real!(params.m_t),
        "Wheel (unsprung) mass (> 0)",
    ),
    parameter(
        "k_s",
        5,
        Fixed,
        Q::Stiffness,
        16000.0,
        Range::AtLeast(0.0),
        real!(params.k_s),
        "Suspension stiffness",
    ),
    parameter(
        "k_h",
        6,
        Fixed,
        Q::Stiffness,
        6444.0,
        Range::AtLeast(0.0),
        real!(params.k_h),
        "Absorber stiffness",
    ),
    parameter(
        "k_t",
        7,
        Fixed,
        Q::Stiffness,
        190000.0,
        Range::AtLeast(0.0),
        real!(params.k_t),
        "Tire stiffness",
    ),
    parameter(
        "c_s",
        8,
        Fixed,
        Q::Damping,
        1500.0,
        Range::AtLeast(0.0),
        real!(params.c_s),
        "Suspension damping",
    ),
    parameter(
        "c_h",
        9,
        Fixed,
        Q::Damping,
        348.0,
        Range::AtLeast(0.0),
        real!(params.c_h),
        "Absorber damping",
    ),
    parameter(
        "g",
        10,
        Tunable,
        Q::Stiffness,
        5386.0,
        Range::Finite,
        real!(params.g),
        "Feedback gain of u = g x_t(t - tau) (TDVASS only; tunable between steps)",
    ),
    parameter(
        "tau",
        11,
        Fixed,
        Q::Time,
        2e-4,
        Range::AtLeast(0.0),
        real!(params.tau),
        "Feedback delay (>= 0; TDVASS only)",
    ),
    parameter(
        "road",
        12,
        Fixed,
        Q::Dimensionless,
        1.0,
        Range::Integers(0, 3),
        integer!(road),
        "Road: 0 = input x_g, 1 = harmonic road_amplitude sin(road_angular_frequency t), 2 = ISO 8608 filtered white noise, 3 = paper-compatible random road (reproduces the paper's Table 3; about 10 times weaker than a true class-C road)",
    )
    .enumerated(&ROAD_ITEMS),
    parameter(
        "road_amplitude",
        13,
        Fixed,
        Q::Length,
        0.05,
        Range::Finite,
        real!(road_amplitude),
        "Harmonic road amplitude",
    )
    .bounded(Bound::Displacement),
    parameter(
        "road_angular_frequency",
        14,
        Fixed,
        Q::AngularFrequency,
        5.0,
        Range::Finite,
        real!(road_angular_frequency),
        "Harmonic road angular frequency",
    )
    .bounded(Bound::AngularFrequency),
    parameter(
        "road_class",
        15,
        Fixed,
        Q::Dimensionless,
        3.0,
        Range::Integers(1, 8),
        integer!(road_class),
        "ISO 8608 road class 1..8 = A..H (random roads)",
    )
    .enumerated(&ROAD_CLASS_ITEMS),
    parameter(
        "vehicle_speed",
        16,
        Fixed,
        Q::Velocity,
        20.0,
        Range::Positive,
        real!(vehicle_speed),
        "Vehicle speed u (random roads; > 0)",
    ),
    parameter(
        "road_cutoff_frequency",
        17,
        Fixed,
        Q::Frequency,
        0.1,
        Range::Positive,
        real!(road_cutoff_frequency),
        "Lower cut-off frequency f0 of the random roads (> 0)",
    ),
    parameter(
        "road_seed",
        18,
        Fixed,
        Q::Dimensionless,
        1.0,
        Range::Integers(0, i32::MAX),
        integer!(road_seed),
        "Random road seed (same seed, same road)",
    ),
    parameter(
        "road_sample_interval",
        19,
        Fixed,
        Q::Time,
        0.1,
        Range::Positive,
        real!(road_sample_interval),
        "Paper-compatible road: hold interval D of the noise samples (> 0)",
    ),
    parameter(
        "max_internal_step",
        20,
        Fixed,
        Q::Time,
        0.0,
        Range::AtLeast(0.0),
        real!(max_internal_step),
        "Optional upper bound of the internal integration step (0 = none); the step itself follows from the tolerance (the master's, else the DefaultExperiment's 1e-6, relative, of every output metric) and divides tau exactly when tau is longer",
    ),
    parameter(
        "tire_contact",
        60,
        Fixed,
        Q::Dimensionless,
        0.0,
        Range::Integers(0, 1),
        integer!(tire_contact),
        "Tire: 0 = bilateral, the paper's linear tire (it pulls as well as pushes), 1 = unilateral: the tire cannot pull, so the wheel lifts off where TDD rises through W/k_t (W the static load) and flies until it falls back; each lift-off is logged under logEvents, and contact_loss_time is the flight time",
    )
    .enumerated(&TIRE_CONTACT_ITEMS),
    parameter(
        "w_ba",
        21,
        Tunable,
        Q::Dimensionless,
        0.4,
        Range::AtLeast(0.0),
        real!(weights.body_acceleration),
        "Weight z1 of RMS(BA) in the objective J (Eq. 6; tunable)",
    )
    .bounded(Bound::Weight)
    .quarter_car(),
    parameter(
        "w_sdd",
        22,
        Tunable,
        Q::Dimensionless,
        0.2,
        Range::AtLeast(0.0),
        real!(weights.suspension_deflection),
        "Weight z2 of RMS(SDD) in the objective J (Eq. 6; tunable)",
    )
    .bounded(Bound::Weight)
    .quarter_car(),
    parameter(
        "w_tdd",
        23,
        Tunable,
        Q::Dimensionless,
        0.4,
        Range::AtLeast(0.0),
        real!(weights.tire_deflection),
        "Weight z3 of RMS(TDD) in the objective J (Eq. 6, TDD in m; tunable)",
    )
    .bounded(Bound::Weight)
    .quarter_car(),
    input_extrapolation(
        "road = 0: 0 holds x_g over each communication step (FMI default), 1 extrapolates it linearly from the last two values set at communication points, 2 along the line closest over the step to the parabola through the last three (the first step holds); input derivatives, when set, take precedence",
    )
    .quarter_car(),
    parameter(
        "x_s_start",
        24,
        Fixed,
        Q::Length,
        0.0,
        Range::Finite,
        real!(initial_state[0]),
        "Initial body displacement (also the history before the start)",
    )
    .bounded(Bound::Displacement)
    .quarter_car(),
    parameter(
        "v_s_start",
        25,
        Fixed,
        Q::Velocity,
        0.0,
        Range::Finite,
        real!(initial_state[1]),
        "Initial body velocity",
    )
    .bounded(Bound::Velocity)
    .quarter_car(),
    parameter(
        "x_h_start",
        26,
        Fixed,
        Q::Length,
        0.0,
        Range::Finite,
        real!(initial_state[2]),
        "Initial absorber displacement (ignored by CS)",
    )
    .bounded(Bound::Displacement),
    parameter(
        "v_h_start",
        27,
        Fixed,
        Q::Velocity,
        0.0,
        Range::Finite,
        real!(initial_state[3]),
        "Initial absorber velocity (ignored by CS)",
    )
    .bounded(Bound::Velocity),
    parameter(
        "x_t_start",
        28,
        Fixed,
        Q::Length,
        0.0,
        Range::Finite,
        real!(initial_state[4]),
        "Initial wheel displacement (also the delayed history before the start)",
    )
    .bounded(Bound::Displacement),
    parameter(
        "v_t_start",
        29,
        Fixed,
        Q::Velocity,
        0.0,
        Range::Finite,
        real!(initial_state[5]),
        "Initial wheel velocity",
    )
    .bounded(Bound::Velocity),
    Variable {
        name: "x_g",
        vr: 30,
        causality: Causality::Input,
        variability: Variability::Continuous,
        quantity: Q::Length,
        display_unit: None,
        start: Some(0.0),
        range: Range::Finite,
        access: real!(x_g),
        description: "Road displacement when road = 0 (over a step: held, or extrapolated with an FMI 2.0 input derivative or by input_extrapolation; FMI 3.0: settable in intermediate updates)",
        feedthrough: &[],
        initial_dependencies: &[],
        enumeration: None,
        dimensions: &[],
        intermediate_update: true,
        fmi3_only: false,
        bound: Some(Bound::Displacement),
        quarter_car_only: false,
    },
    output(
        "x_s",
        31,
        Q::Length,
        OutputId::State(X_S),
        "Body displacement",
        &[],
        &["x_s_start"],
    )
    .quarter_car(),
    output(
        "v_s",
        32,
        Q::Velocity,
        OutputId::State(V_S),
        "Body velocity",
        &[],
        &["v_s_start"],
    )
    .quarter_car(),
    output(
        "x_h",
        33,
        Q::Length,
        OutputId::State(X_H),
        "Absorber displacement (CS: mirrors x_t)",
        &[],
        &["variant", "x_h_start", "x_t_start"],
    ),
    output(
        "v_h",
        34,
        Q::Velocity,
        OutputId::State(V_H),
        "Absorber velocity (CS: mirrors v_t)",
        &[],
        &["variant", "v_h_start", "v_t_start"],
    ),
    output(
        "x_t",
        35,
        Q::Length,
        OutputId::State(X_T),
        "Wheel displacement",
        &[],
        &["x_t_start"],
    ),
    output(
        "v_t",
        36,
        Q::Velocity,
        OutputId::State(V_T),
        "Wheel velocity",
        &[],
        &["v_t_start"],
    ),
    output(
        "body_acceleration",
        37,
        Q::Acceleration,
        OutputId::BodyAcceleration,
        "Body acceleration BA = d2x_s/dt2",
        &[],
        &[
            "variant",
            "m_s",
            "k_s",
            "c_s",
            "x_s_start",
            "v_s_start",
            "x_h_start",
            "v_h_start",
            "x_t_start",
            "v_t_start",
        ],
    )
    .quarter_car(),
    output(
        "suspension_deflection",
        38,
        Q::Length,
        OutputId::SuspensionDeflection,
        "Suspension dynamic deflection SDD = x_s - x_t",
        &[],
        &["x_s_start", "x_t_start"],
    )
    .quarter_car(),
    output(
        "tire_deflection",
        39,
        Q::Length,
        OutputId::TireDeflection,
        "Tire dynamic displacement TDD = x_t - x_g",
        &["x_g"],
        &[
            "road",
            "road_amplitude",
            "road_angular_frequency",
            "x_t_start",
            "x_g",
        ],
    )
    .display("mm")
    .quarter_car(),
    output(
        "road_displacement",
        40,
        Q::Length,
        OutputId::RoadDisplacement,
        "Road displacement x_g actually applied",
        &["x_g"],
        ROAD_DEPENDENCIES,
    )
    .quarter_car(),
    output(
        "control_force",
        41,
        Q::Force,
        OutputId::ControlForce,
        "Control force u = g x_t(t - tau) (0 unless TDVASS)",
        &[],
        &["variant", "g", "tau", "x_t_start", "v_t_start"],
    ),
    output(
        "rms_body_acceleration",
        42,
        Q::Acceleration,
        OutputId::RmsBodyAcceleration,
        "Running RMS of BA from the start time t0 to now, the time average sqrt(integral of BA^2 dt / (t - t0)): 0 at t0, continuous in t, independent of the internal grid. Model Exchange: from the integral state the master integrates",
        &[],
        &[],
    )
    .quarter_car(),
    output(
        "rms_suspension_deflection",
        43,
        Q::Length,
        OutputId::RmsSuspensionDeflection,
        "Running RMS of SDD from the start time t0 to now, the time average sqrt(integral of SDD^2 dt / (t - t0)): 0 at t0, continuous in t, independent of the internal grid. Model Exchange: from the integral state the master integrates",
        &[],
        &[],
    ),
    output(
        "rms_tire_deflection",
        44,
        Q::Length,
        OutputId::RmsTireDeflection,
        "Running RMS of TDD from the start time t0 to now, the time average sqrt(integral of TDD^2 dt / (t - t0)): 0 at t0, continuous in t, independent of the internal grid. Model Exchange: from the integral state the master integrates",
        &[],
        &[],
    )
    .display("mm"),
    output(
        "objective",
        45,
        Q::Dimensionless,
        OutputId::Objective,
        "Objective J = w_ba RMS(BA) + w_sdd RMS(SDD) + w_tdd RMS(TDD) (Eq. 6, TDD in m) from the running RMS values (Model Exchange: from the integral states)",
        &[],
        &[],
    )
    .quarter_car(),
    calculated(
        "spectral_abscissa",
        46,
        Q::Rate,
        Calculated::SpectralAbscissa,
        "Real part of the rightmost characteristic root at the current (g, tau)",
    )
    .quarter_car(),
    calculated(
        "stable",
        47,
        Q::Dimensionless,
        Calculated::Stable,
        "spectral_abscissa < 0 (asymptotically stable)",
    )
    .quarter_car(),
    output(
        "weighted_body_acceleration",
        53,
        Q::Acceleration,
        OutputId::WeightedBodyAcceleration,
        "ISO 2631-1 W_k frequency-weighted body acceleration a_w(t): BA through the standard's filter (band limits 0.4 and 100 Hz, acceleration-velocity transition 12.5 Hz, upward step 2.37/3.35 Hz), integrated exactly with the plant; the filter starts from rest at t0",
        &[],
        &[],
    )
    .quarter_car(),
    output(
        "rms_weighted_body_acceleration",
        54,
        Q::Acceleration,
        OutputId::RmsWeightedBodyAcceleration,
        "Running RMS of a_w, the time average sqrt(integral of a_w^2 dt / (t - t0)): ISO 2631-1's a_w; below 0.315 m/s2 not uncomfortable, 0.315-0.63 a little uncomfortable, 0.5-1 fairly uncomfortable, 0.8-1.6 uncomfortable, 1.25-2.5 very uncomfortable, above 2 extremely uncomfortable. Model Exchange: from the integral state",
        &[],
        &[],
    )
    .quarter_car(),
    output(
        "vibration_dose_value",
        55,
        Q::VibrationDose,
        OutputId::VibrationDoseValue,
        "ISO 2631-1 vibration dose value VDV = (integral of a_w^4 dt from t0)^(1/4). Model Exchange: from the integral state",
        &[],
        &[],
    )
    .quarter_car(),
    output(
        "dynamic_tire_load",
        56,
        Q::Force,
        OutputId::DynamicTireLoad,
        "Dynamic tire load k_t (x_g - x_t) = -k_t TDD (no tire damping); below minus the static load the tire would leave the road (tire_contact = 1: it never goes below, the wheel flies)",
        &["x_g"],
        // tire_contact = 1 bounds it below by minus the static load.
        TIRE_LOAD_DEPENDENCIES,
    )
    .quarter_car(),
    output(
        "rms_dynamic_tire_load_ratio",
        57,
        Q::Dimensionless,
        OutputId::RmsDynamicTireLoadRatio,
        "Running RMS of the dynamic tire load over the static load (m_s + m_h + m_t) g0, CS (m_s + m_t) g0, g0 = 9.80665 m/s2; at most 1/3 keeps the contact with 3-sigma confidence. Model Exchange: from the integral state of TDD^2",
        &[],
        &[],
    )
    .quarter_car(),
    output(
        "contact_loss_time",
        58,
        Q::Time,
        OutputId::ContactLossTime,
        "Accumulated time with the dynamic tire load below minus the static load, crossings located inside the internal steps. tire_contact = 0: the tire would leave the road and the linear model no longer holds there; the first crossing is logged as a warning. tire_contact = 1: the flight time (the load is then minus the static load). Model Exchange: a continuous state, switched at the events",
        &[],
        &[],
    ),
    lift_off_count(
        "Number of lift-offs since the start time (a start without contact counts one): tire_contact = 1, the switches from contact to flight; tire_contact = 0, the times the dynamic tire load went below minus the static load. Model Exchange: counted at the events of the indicator contact_indicator",
        TIRE_LOAD_DEPENDENCIES,
    )
    .quarter_car(),
    output(
        "max_suspension_deflection",
        59,
        Q::Length,
        OutputId::MaxSuspensionDeflection,
        "Running maximum of |SDD| (suspension working space used), located inside the internal steps from the dense output (within the tolerance). Model Exchange: the largest at completed integrator steps and events, and now",
        &[],
        &["x_s_start", "x_t_start"],
    )
    .display("mm")
    .quarter_car(),
    // Model Exchange: the continuous states that are not outputs, then
    // the derivatives of all of them (x_s ... v_t and contact_loss_time
    // are outputs and states).
    local_state(
        "wk_filter_1",
        120,
        6,
        Q::Acceleration,
        "State 1 of the 8 of the ISO 2631-1 W_k filter of BA (a_w = c_w w); a continuous state of Model Exchange",
    ),
    local_state(
        "wk_filter_2",
        121,
        7,
        Q::Acceleration,
        "State 2 of the 8 of the ISO 2631-1 W_k filter of BA (a_w = c_w w); a continuous state of Model Exchange",
    ),
    local_state(
        "wk_filter_3",
        122,
        8,
        Q::Acceleration,
        "State 3 of the 8 of the ISO 2631-1 W_k filter of BA (a_w = c_w w); a continuous state of Model Exchange",
    ),
    local_state(
        "wk_filter_4",
        123,
        9,
        Q::Acceleration,
        "State 4 of the 8 of the ISO 2631-1 W_k filter of BA (a_w = c_w w); a continuous state of Model Exchange",
    ),
    local_state(
        "wk_filter_5",
        124,
        10,
        Q::Acceleration,
        "State 5 of the 8 of the ISO 2631-1 W_k filter of BA (a_w = c_w w); a continuous state of Model Exchange",
    ),
    local_state(
        "wk_filter_6",
        125,
        11,
        Q::Acceleration,
        "State 6 of the 8 of the ISO 2631-1 W_k filter of BA (a_w = c_w w); a continuous state of Model Exchange",
    ),
    local_state(
        "wk_filter_7",
        126,
        12,
        Q::Acceleration,
        "State 7 of the 8 of the ISO 2631-1 W_k filter of BA (a_w = c_w w); a continuous state of Model Exchange",
    ),
    local_state(
        "wk_filter_8",
        127,
        13,
        Q::Acceleration,
        "State 8 of the 8 of the ISO 2631-1 W_k filter of BA (a_w = c_w w); a continuous state of Model Exchange",
    ),
    local_state(
        "integral_body_acceleration_squared",
        128,
        14,
        Q::Dimensionless,
        "Integral of BA^2 from the start time (m2/s3); a continuous state of Model Exchange, behind rms_body_acceleration",
    ),
    local_state(
        "integral_suspension_deflection_squared",
        129,
        15,
        Q::Dimensionless,
        "Integral of SDD^2 from the start time (m2.s); a continuous state of Model Exchange, behind rms_suspension_deflection",
    ),
    local_state(
        "integral_tire_deflection_squared",
        130,
        16,
        Q::Dimensionless,
        "Integral of TDD^2 from the start time (m2.s); a continuous state of Model Exchange, behind rms_tire_deflection and rms_dynamic_tire_load_ratio",
    ),
    local_state(
        "integral_weighted_acceleration_squared",
        131,
        17,
        Q::Dimensionless,
        "Integral of a_w^2 from the start time (m2/s3); a continuous state of Model Exchange, behind rms_weighted_body_acceleration",
    ),
    local_state(
        "integral_weighted_acceleration_fourth",
        132,
        18,
        Q::Dimensionless,
        "Integral of a_w^4 from the start time (m4/s7); a continuous state of Model Exchange, behind vibration_dose_value",
    ),
    derivative(
        "der(x_s)",
        100,
        0,
        Q::Velocity,
        "Time derivative of x_s (m/s); Model Exchange",
    ),
    derivative(
        "der(v_s)",
        101,
        1,
        Q::Acceleration,
        "Time derivative of v_s (m/s2); Model Exchange",
    ),
    derivative(
        "der(x_h)",
        102,
        2,
        Q::Velocity,
        "Time derivative of x_h (m/s); Model Exchange",
    ),
    derivative(
        "der(v_h)",
        103,
        3,
        Q::Acceleration,
        "Time derivative of v_h (m/s2); Model Exchange",
    ),
    derivative(
        "der(x_t)",
        104,
        4,
        Q::Velocity,
        "Time derivative of x_t (m/s); Model Exchange",
    ),
    derivative(
        "der(v_t)",
        105,
        5,
        Q::Acceleration,
        "Time derivative of v_t (m/s2); Model Exchange",
    ),
    derivative(
        "der(wk_filter_1)",
        106,
        6,
        Q::Dimensionless,
        "Time derivative of wk_filter_1 (m/s3); Model Exchange",
    ),
    derivative(
        "der(wk_filter_2)",
        107,
        7,
        Q::Dimensionless,
        "Time derivative of wk_filter_2 (m/s3); Model Exchange",
    ),
    derivative(
        "der(wk_filter_3)",
        108,
        8,
        Q::Dimensionless,
        "Time derivative of wk_filter_3 (m/s3); Model Exchange",
    ),
    derivative(
        "der(wk_filter_4)",
        109,
        9,
        Q::Dimensionless,
        "Time derivative of wk_filter_4 (m/s3); Model Exchange",
    ),
    derivative(
        "der(wk_filter_5)",
        110,
        10,
        Q::Dimensionless,
        "Time derivative of wk_filter_5 (m/s3); Model Exchange",
    ),
    derivative(
        "der(wk_filter_6)",
        111,
        11,
        Q::Dimensionless,
        "Time derivative of wk_filter_6 (m/s3); Model Exchange",
    ),
    derivative(
        "der(wk_filter_7)",
        112,
        12,
        Q::Dimensionless,
        "Time derivative of wk_filter_7 (m/s3); Model Exchange",
    ),
    derivative(
        "der(wk_filter_8)",
        113,
        13,
        Q::Dimensionless,
        "Time derivative of wk_filter_8 (m/s3); Model Exchange",
    ),
    derivative(
        "der(integral_body_acceleration_squared)",
        114,
        14,
        Q::Dimensionless,
        "Time derivative of integral_body_acceleration_squared; Model Exchange",
    ),
    derivative(
        "der(integral_suspension_deflection_squared)",
        115,
        15,
        Q::Dimensionless,
        "Time derivative of integral_suspension_deflection_squared; Model Exchange",
    ),
    derivative(
        "der(integral_tire_deflection_squared)",
        116,
        16,
        Q::Dimensionless,
        "Time derivative of integral_tire_deflection_squared; Model Exchange",
    ),
    derivative(
        "der(integral_weighted_acceleration_squared)",
        117,
        17,
        Q::Dimensionless,
        "Time derivative of integral_weighted_acceleration_squared; Model Exchange",
    ),
    derivative(
        "der(integral_weighted_acceleration_fourth)",
        118,
        18,
        Q::Dimensionless,
        "Time derivative of integral_weighted_acceleration_fourth; Model Exchange",
    ),
    derivative(
        "der(contact_loss_time)",
        119,
        19,
        Q::Dimensionless,
        "Time derivative of contact_loss_time; Model Exchange",
    ),
    Variable {
        access: Access::EventIndicator(0),
        ..local_state(
            "contact_indicator",
            133,
            0,
            Q::Length,
            "The event indicator of Model Exchange: the margin W/k_t - TDD to the loss of tire contact (m), moved off zero by a hysteresis of 1e-12 W/k_t after each event (positive in contact); it changes sign at every lift-off and touch-down",
        )
    },
    // FMI 3.0 only, from here to the end.
    Variable {
        fmi3_only: true,
        ..parameter(
        "intermediate_update_interval",
        49,
        Tunable,
        Q::Time,
        0.0,
        Range::AtLeast(0.0),
        real!(intermediate_update_interval),
        "FMI 3.0: simulated time between two intermediate updates inside a step, at internal grid nodes (0 = at every node); used when the master passes an intermediateUpdate callback",
        )
    },
    Variable {
        name: "root_count",
        vr: 50,
        causality: Causality::StructuralParameter,
        variability: Fixed,
        quantity: Q::Dimensionless,
        display_unit: None,
        start: Some(3.0),
        range: Range::Integers(1, 16),
        access: integer!(root_count),
        description: "FMI 3.0: how many rightmost characteristic roots rightmost_roots lists",
        feedthrough: &[],
        initial_dependencies: &[],
        enumeration: None,
        dimensions: &[],
        intermediate_update: false,
        fmi3_only: true,
        bound: None,
        quarter_car_only: true,
    },
    Variable {
        dimensions: &[Dimension::Structural("root_count"), Dimension::Fixed(2)],
        fmi3_only: true,
        ..calculated(
            "rightmost_roots",
            51,
            Q::Rate,
            Calculated::RightmostRoots,
            "FMI 3.0: the root_count rightmost characteristic roots as (real, imaginary) pairs, rightmost first",
        )
    .quarter_car()
    },
    Variable {
        name: "time",
        vr: 52,
        causality: Causality::Independent,
        variability: Variability::Continuous,
        quantity: Q::Time,
        display_unit: None,
        start: None,
        range: Range::Computed,
        access: Access::Time,
        description: "FMI 3.0: simulation time",
        feedthrough: &[],
        initial_dependencies: &[],
        enumeration: None,
        dimensions: &[],
        intermediate_update: false,
        fmi3_only: true,
        bound: None,
        quarter_car_only: false,
    },
];

/// FNV-1a, 128 bits.
fn fnv1a_128(bytes: &[u8]) -> u128 {
    const OFFSET: u128 = 0x6c62272e07bb014262b821756295c58d;
    const PRIME: u128 = 0x0000000001000000000000000000013B;
    bytes
        .iter()
        .fold(OFFSET, |h, &b| (h ^ b as u128).wrapping_mul(PRIME))
}

/// A hash of `text` formatted as a GUID,
/// `{xxxxxxxx-xxxx-xxxx-xxxx-xxxxxxxxxxxx}`.
fn guid_format(text: &str) -> String {
    let h = format!("{:032x}", fnv1a_128(text.as_bytes()));
    format!(
        "{{{}-{}-{}-{}-{}}}",
        &h[0..8],
        &h[8..12],
        &h[12..16],
        &h[16..20],
        &h[20..32]
    )
}

/// The first line of the text a token hashes: the quarter car's as it has
/// always been, so that its GUID and instantiation token stay the same.
fn token_header(model: Model, version: &str) -> String {
    match model {
        Model::QuarterCar => format!("tdvass FMI {version} Co-Simulation interface\n"),
        Model::Corner => format!("tdvass corner FMI {version} Co-Simulation interface\n"),
        Model::Chassis => format!("tdvass chassis FMI {version} Co-Simulation interface\n"),
    }
}

/// The GUID of `model`'s FMI 2.0 interface: a hash of every variable's
/// name, value reference, type, causality and variability, formatted
/// `{xxxxxxxx-xxxx-xxxx-xxxx-xxxxxxxxxxxx}`.
pub fn guid(model: Model) -> String {
    guid_of(model, variables_of(model, FmiVersion::Fmi2))
}

/// The GUID of `model` with the FMI 2.0 variables `variables`.
pub fn guid_of(model: Model, variables: &[Variable]) -> String {
    let mut text = token_header(model, "2.0");
    for v in variables {
        text.push_str(&format!(
            "{}\t{}\t{}\t{}\t{}\n",
            v.name,
            v.vr,
            v.var_type().as_str(),
            v.causality.as_str(),
            v.variability.as_str()
        ));
    }
    guid_format(&text)
}

/// The FMI 3.0 `instantiationToken` of `model`: like [`guid`], over every
/// variable of FMI 3.0, with the enumeration types and array dimensions.
pub fn instantiation_token(model: Model) -> String {
    let mut text = token_header(model, "3.0");
    for v in variables_of(model, FmiVersion::Fmi3) {
        text.push_str(&format!(
            "{}\t{}\t{}\t{}\t{}\t{}\t{:?}\n",
            v.name,
            v.vr,
            v.var_type().as_str(),
            v.causality.as_str(),
            v.variability.as_str(),
            v.enumeration.map(|e| e.type_name).unwrap_or(""),
            v.dimensions
        ));
    }
    guid_format(&text)
}

/// The token of `model` in `version` (its GUID or instantiation token).
pub fn token(model: Model, version: FmiVersion) -> String {
    match version {
        FmiVersion::Fmi2 => guid(model),
        FmiVersion::Fmi3 => instantiation_token(model),
    }
}

/// The model whose token in `version` is `given`, if any.
pub fn model_of_token(version: FmiVersion, given: &str) -> Option<Model> {
    Model::ALL
        .into_iter()
        .find(|&model| token(model, version) == given)
}

impl Settings {
    /// The settings of `model` with every start value of its FMI 3.0
    /// variables (FMI 2.0's are a subset with the same starts).
    pub fn start_values(model: Model) -> Settings {
        let mut s = Settings::zeroed(model);
        for v in variables_of(model, FmiVersion::Fmi3) {
            match (v.access, v.start) {
                (Access::Real { set, .. }, Some(start)) => set(&mut s, start),
                (Access::Integer { set, .. }, Some(start)) => set(&mut s, start as i32),
                _ => {}
            }
        }
        s
    }
}

mod chassis;
pub use chassis::CHASSIS_VARIABLES;

#[cfg(test)]
mod tests;
