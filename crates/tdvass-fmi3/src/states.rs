//! The FMI 3.0 Co-Simulation state machine, as one declarative table
//! ([`ALLOWED`]) of which function may be called in which phase (the
//! standard's state, [`Fmi3Phase`]), checked by one function ([`check`]).
//!
//! The table follows the state machine of the FMI 3.0 standard (section
//! 4.2) for an FMU without clocks or tunable structural parameters, so
//! Reconfiguration Mode and Clock Activation Mode never occur; Event Mode
//! and Continuous-Time Mode are those of Model Exchange instances (a
//! Co-Simulation instance never enters them). Two refinements:
//! - Step Mode after a discarded step ([`Fmi3Phase::StepDiscarded`]): the
//!   master may read values, restore an FMU state, reset or terminate, but
//!   not step on.
//! - Inside an intermediate update ([`Fmi3Phase::IntermediateUpdate`]) only
//!   getters and setters are allowed (the instance then admits only the
//!   variables marked `intermediateUpdate`); freeing or resetting the
//!   instance from its own callback is refused.
//!
//! `fmi3FreeInstance` is also allowed in `Fatal`, so that a master can
//! always release the memory. Functions of Scheduled Execution and clocks
//! are not in the table: they are refused in every state, with the reason
//! logged.

use crate::FmiError;
use crate::types::ValueType;

/// The phase of an FMI 3.0 instance (the standard's state): the slave's
/// [`tdvass_fmu::Phase`], refined by Configuration Mode and the
/// intermediate update.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Fmi3Phase {
    Instantiated,
    ConfigurationMode,
    InitializationMode,
    StepMode,
    StepDiscarded,
    IntermediateUpdate,
    Terminated,
    Error,
    Fatal,
    /// Model Exchange: Event Mode.
    EventMode,
    /// Model Exchange: Continuous-Time Mode.
    ContinuousTimeMode,
}

impl Fmi3Phase {
    /// Every phase.
    pub const ALL: [Fmi3Phase; 11] = [
        Fmi3Phase::Instantiated,
        Fmi3Phase::ConfigurationMode,
        Fmi3Phase::InitializationMode,
        Fmi3Phase::StepMode,
        Fmi3Phase::StepDiscarded,
        Fmi3Phase::IntermediateUpdate,
        Fmi3Phase::Terminated,
        Fmi3Phase::Error,
        Fmi3Phase::Fatal,
        Fmi3Phase::EventMode,
        Fmi3Phase::ContinuousTimeMode,
    ];

    /// The standard's name of the state.
    pub fn name(self) -> &'static str {
        match self {
            Fmi3Phase::Instantiated => "Instantiated",
            Fmi3Phase::ConfigurationMode => "Configuration Mode",
            Fmi3Phase::InitializationMode => "Initialization Mode",
            Fmi3Phase::StepMode => "Step Mode",
            Fmi3Phase::StepDiscarded => "Step Mode after a discarded step",
            Fmi3Phase::IntermediateUpdate => "Intermediate Update Mode",
            Fmi3Phase::Terminated => "Terminated",
            Fmi3Phase::Error => "Error",
            Fmi3Phase::Fatal => "Fatal",
            Fmi3Phase::EventMode => "Event Mode",
            Fmi3Phase::ContinuousTimeMode => "Continuous-Time Mode",
        }
    }

    const fn bit(self) -> u16 {
        1 << self as u16
    }
}

/// A set of phases.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PhaseSet(u16);

impl PhaseSet {
    /// The set of `phases`.
    pub const fn of(phases: &[Fmi3Phase]) -> PhaseSet {
        let mut bits = 0;
        let mut i = 0;
        while i < phases.len() {
            bits |= phases[i].bit();
            i += 1;
        }
        PhaseSet(bits)
    }

    /// Whether `phase` is in the set.
    pub fn contains(self, phase: Fmi3Phase) -> bool {
        self.0 & phase.bit() != 0
    }
}

/// The fmi3 functions that take an instance and apply to this FMU.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Function {
    SetDebugLogging,
    FreeInstance,
    EnterInitializationMode,
    ExitInitializationMode,
    Terminate,
    Reset,
    Get(ValueType),
    Set(ValueType),
    GetNumberOfVariableDependencies,
    GetVariableDependencies,
    GetFmuState,
    SetFmuState,
    FreeFmuState,
    SerializedFmuStateSize,
    SerializeFmuState,
    DeserializeFmuState,
    GetDirectionalDerivative,
    GetAdjointDerivative,
    EnterConfigurationMode,
    ExitConfigurationMode,
    GetOutputDerivatives,
    DoStep,
    EnterEventMode,
    UpdateDiscreteStates,
    EnterContinuousTimeMode,
    CompletedIntegratorStep,
    SetTime,
    SetContinuousStates,
    GetContinuousStateDerivatives,
    GetEventIndicators,
    GetContinuousStates,
    GetNominalsOfContinuousStates,
    GetNumberOfEventIndicators,
    GetNumberOfContinuousStates,
}

impl Function {
    /// The C name.
    pub fn name(self) -> &'static str {
        use Function::*;
        match self {
            SetDebugLogging => "fmi3SetDebugLogging",
            FreeInstance => "fmi3FreeInstance",
            EnterInitializationMode => "fmi3EnterInitializationMode",
            ExitInitializationMode => "fmi3ExitInitializationMode",
            Terminate => "fmi3Terminate",
            Reset => "fmi3Reset",
            Get(t) => t.getter(),
            Set(t) => t.setter(),
            GetNumberOfVariableDependencies => "fmi3GetNumberOfVariableDependencies",
            GetVariableDependencies => "fmi3GetVariableDependencies",
            GetFmuState => "fmi3GetFMUState",
            SetFmuState => "fmi3SetFMUState",
            FreeFmuState => "fmi3FreeFMUState",
            SerializedFmuStateSize => "fmi3SerializedFMUStateSize",
            SerializeFmuState => "fmi3SerializeFMUState",
            DeserializeFmuState => "fmi3DeserializeFMUState",
            GetDirectionalDerivative => "fmi3GetDirectionalDerivative",
            GetAdjointDerivative => "fmi3GetAdjointDerivative",
            EnterConfigurationMode => "fmi3EnterConfigurationMode",
            ExitConfigurationMode => "fmi3ExitConfigurationMode",
            GetOutputDerivatives => "fmi3GetOutputDerivatives",
            DoStep => "fmi3DoStep",
            EnterEventMode => "fmi3EnterEventMode",
            UpdateDiscreteStates => "fmi3UpdateDiscreteStates",
            EnterContinuousTimeMode => "fmi3EnterContinuousTimeMode",
            CompletedIntegratorStep => "fmi3CompletedIntegratorStep",
            SetTime => "fmi3SetTime",
            SetContinuousStates => "fmi3SetContinuousStates",
            GetContinuousStateDerivatives => "fmi3GetContinuousStateDerivatives",
            GetEventIndicators => "fmi3GetEventIndicators",
            GetContinuousStates => "fmi3GetContinuousStates",
            GetNominalsOfContinuousStates => "fmi3GetNominalsOfContinuousStates",
            GetNumberOfEventIndicators => "fmi3GetNumberOfEventIndicators",
            GetNumberOfContinuousStates => "fmi3GetNumberOfContinuousStates",
        }
    }

    /// The phases in which the function may be called.
    pub fn allowed_phases(self) -> PhaseSet {
        let key = match self {
            Function::Get(_) => Function::Get(ValueType::Float64),
            Function::Set(_) => Function::Set(ValueType::Float64),
            other => other,
        };
        ALLOWED
            .iter()
            .find(|(f, _)| *f == key)
            .map(|(_, set)| *set)
            .unwrap_or(PhaseSet(0))
    }
}

use Fmi3Phase::{
    ConfigurationMode as Conf, ContinuousTimeMode as Cont, Error as Err_, EventMode as Event,
    Fatal, InitializationMode as Init, Instantiated as Inst, IntermediateUpdate as Inter,
    StepDiscarded as Disc, StepMode as Step, Terminated as Term,
};

/// Every phase but `Fatal` and the intermediate update.
const NOT_FATAL: PhaseSet = PhaseSet::of(&[Inst, Conf, Init, Step, Disc, Term, Err_, Event, Cont]);
/// Where values can be read (inside an intermediate update: the
/// intermediate variables only; in Configuration Mode: structural
/// parameters only).
const READABLE: PhaseSet = PhaseSet::of(&[Conf, Init, Step, Disc, Inter, Term, Err_, Event, Cont]);
/// Where values can be set (which ones depends on causality, variability
/// and, inside an intermediate update, on the variable's flag).
const SETTABLE: PhaseSet = PhaseSet::of(&[Inst, Conf, Init, Step, Inter, Event, Cont]);
/// Where the model's partial derivatives and dependencies can be
/// evaluated (Model Exchange: in Event and Continuous-Time Mode too).
const LINEARIZABLE: PhaseSet = PhaseSet::of(&[Init, Step, Disc, Term, Err_, Event, Cont]);
/// Model Exchange: where states, derivatives and indicators can be read.
const MODEL_READABLE: PhaseSet = PhaseSet::of(&[Event, Cont, Term, Err_]);
/// Model Exchange: where the model's sizes can be asked.
const SIZES: PhaseSet = PhaseSet::of(&[Conf, Init, Event, Cont, Term, Err_]);

/// The state table: which function is allowed in which phase. Getters and
/// setters of every type share one row each.
pub const ALLOWED: &[(Function, PhaseSet)] = {
    use Function::*;
    &[
        (SetDebugLogging, NOT_FATAL),
        (
            FreeInstance,
            PhaseSet::of(&[Inst, Conf, Init, Step, Disc, Term, Err_, Fatal, Event, Cont]),
        ),
        (EnterInitializationMode, PhaseSet::of(&[Inst])),
        (ExitInitializationMode, PhaseSet::of(&[Init])),
        (Terminate, PhaseSet::of(&[Step, Disc, Event, Cont])),
        (Reset, NOT_FATAL),
        (Get(ValueType::Float64), READABLE),
        (Set(ValueType::Float64), SETTABLE),
        (GetNumberOfVariableDependencies, LINEARIZABLE),
        (GetVariableDependencies, LINEARIZABLE),
        (GetFmuState, NOT_FATAL),
        (SetFmuState, NOT_FATAL),
        (FreeFmuState, NOT_FATAL),
        (SerializedFmuStateSize, NOT_FATAL),
        (SerializeFmuState, NOT_FATAL),
        (DeserializeFmuState, NOT_FATAL),
        (GetDirectionalDerivative, LINEARIZABLE),
        (GetAdjointDerivative, LINEARIZABLE),
        (EnterConfigurationMode, PhaseSet::of(&[Inst])),
        (ExitConfigurationMode, PhaseSet::of(&[Conf])),
        (
            GetOutputDerivatives,
            PhaseSet::of(&[Step, Disc, Term, Err_]),
        ),
        (DoStep, PhaseSet::of(&[Step])),
        (EnterEventMode, PhaseSet::of(&[Cont])),
        (UpdateDiscreteStates, PhaseSet::of(&[Event])),
        (EnterContinuousTimeMode, PhaseSet::of(&[Event])),
        (CompletedIntegratorStep, PhaseSet::of(&[Cont])),
        (SetTime, PhaseSet::of(&[Event, Cont])),
        (SetContinuousStates, PhaseSet::of(&[Cont])),
        (GetContinuousStateDerivatives, MODEL_READABLE),
        (GetEventIndicators, MODEL_READABLE),
        (GetContinuousStates, MODEL_READABLE),
        (GetNominalsOfContinuousStates, MODEL_READABLE),
        (GetNumberOfEventIndicators, SIZES),
        (GetNumberOfContinuousStates, SIZES),
    ]
};

/// Refuses `function` in `phase` with "not allowed in state Y" (the caller
/// prefixes the function name).
pub fn check(function: Function, phase: Fmi3Phase) -> Result<(), FmiError> {
    if function.allowed_phases().contains(phase) {
        Ok(())
    } else {
        Err(FmiError::error(format!(
            "not allowed in state {}",
            phase.name()
        )))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The table restated independently: one row per function, columns
    /// Instantiated, Configuration, Initialization, Step, Step after a
    /// discard, Intermediate Update, Terminated, Error, Fatal.
    const EXPECTED: &[(&str, &str)] = &[
        ("fmi3SetDebugLogging", "xxxxx.xx."),
        ("fmi3FreeInstance", "xxxxx.xxx"),
        ("fmi3EnterInitializationMode", "x........"),
        ("fmi3ExitInitializationMode", "..x......"),
        ("fmi3Terminate", "...xx...."),
        ("fmi3Reset", "xxxxx.xx."),
        ("fmi3GetFloat64", ".xxxxxxx."),
        ("fmi3GetInt64", ".xxxxxxx."),
        ("fmi3SetFloat64", "xxxx.x..."),
        ("fmi3SetBinary", "xxxx.x..."),
        ("fmi3GetVariableDependencies", "..xxx.xx.xx"),
        ("fmi3GetFMUState", "xxxxx.xx."),
        ("fmi3DeserializeFMUState", "xxxxx.xx."),
        ("fmi3GetDirectionalDerivative", "..xxx.xx.xx"),
        ("fmi3GetAdjointDerivative", "..xxx.xx.xx"),
        ("fmi3EnterConfigurationMode", "x........"),
        ("fmi3ExitConfigurationMode", ".x......."),
        ("fmi3GetOutputDerivatives", "...xx.xx."),
        ("fmi3DoStep", "...x......."),
        ("fmi3EnterEventMode", "..........x"),
        ("fmi3UpdateDiscreteStates", ".........x."),
        ("fmi3EnterContinuousTimeMode", ".........x."),
        ("fmi3CompletedIntegratorStep", "..........x"),
        ("fmi3SetTime", ".........xx"),
        ("fmi3SetContinuousStates", "..........x"),
        ("fmi3GetContinuousStateDerivatives", "......xx.xx"),
        ("fmi3GetEventIndicators", "......xx.xx"),
        ("fmi3GetContinuousStates", "......xx.xx"),
        ("fmi3GetNominalsOfContinuousStates", "......xx.xx"),
        ("fmi3GetNumberOfEventIndicators", ".xx...xx.xx"),
        ("fmi3GetNumberOfContinuousStates", ".xx...xx.xx"),
    ];

    fn by_name(name: &str) -> Function {
        use Function::*;
        let mut all = vec![
            SetDebugLogging,
            FreeInstance,
            EnterInitializationMode,
            ExitInitializationMode,
            Terminate,
            Reset,
            GetNumberOfVariableDependencies,
            GetVariableDependencies,
            GetFmuState,
            SetFmuState,
            FreeFmuState,
            SerializedFmuStateSize,
            SerializeFmuState,
            DeserializeFmuState,
            GetDirectionalDerivative,
            GetAdjointDerivative,
            EnterConfigurationMode,
            ExitConfigurationMode,
            GetOutputDerivatives,
            DoStep,
            EnterEventMode,
            UpdateDiscreteStates,
            EnterContinuousTimeMode,
            CompletedIntegratorStep,
            SetTime,
            SetContinuousStates,
            GetContinuousStateDerivatives,
            GetEventIndicators,
            GetContinuousStates,
            GetNominalsOfContinuousStates,
            GetNumberOfEventIndicators,
            GetNumberOfContinuousStates,
        ];
        for t in ValueType::ALL {
            all.push(Get(t));
            all.push(Set(t));
        }
        all.into_iter().find(|f| f.name() == name).unwrap()
    }

    #[test]
    fn the_table_is_the_restated_one() {
        for (name, row) in EXPECTED {
            let function = by_name(name);
            for (state, mark) in Fmi3Phase::ALL.iter().zip(row.chars()) {
                assert_eq!(
                    check(function, *state).is_ok(),
                    mark == 'x',
                    "{name} in {}",
                    state.name()
                );
            }
        }
    }

    #[test]
    fn refusals_name_the_state() {
        let e = check(Function::DoStep, Fmi3Phase::InitializationMode).unwrap_err();
        assert_eq!(e.message, "not allowed in state Initialization Mode");
    }
}
