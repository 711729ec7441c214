//! The FMI 2.0 Co-Simulation state machine, as one declarative table
//! ([`ALLOWED`]) of which function may be called in which phase (the
//! standard's state), checked by one function ([`check`]). The phases are
//! the slave's own ([`Phase`]), which FMI 2.0 names alike
//! ([`Phase::name`]).
//!
//! The table follows the state table of the FMI 2.0 standard (section
//! 4.2.4). This FMU steps synchronously, so `stepInProgress` and
//! `stepCanceled` never occur and `fmi2CancelStep` is never allowed. One
//! deliberate extension: `fmi2FreeInstance` is also allowed in `fatal`, so
//! that a master can always release the memory.
//!
//! `fmi2GetTypesPlatform`, `fmi2GetVersion` and `fmi2Instantiate` take no
//! instance and are always allowed.

use crate::FmiError;

use tdvass_fmu::Phase;

/// A set of phases.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PhaseSet(u16);

impl PhaseSet {
    /// The set of `phases`.
    pub const fn of(phases: &[Phase]) -> PhaseSet {
        let mut bits = 0;
        let mut i = 0;
        while i < phases.len() {
            bits |= phases[i].bit();
            i += 1;
        }
        PhaseSet(bits)
    }

    /// Whether `phase` is in the set.
    pub fn contains(self, phase: Phase) -> bool {
        self.0 & phase.bit() != 0
    }
}

/// The fmi2 functions that take an instance.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Function {
    SetDebugLogging,
    FreeInstance,
    SetupExperiment,
    EnterInitializationMode,
    ExitInitializationMode,
    Terminate,
    Reset,
    GetReal,
    GetInteger,
    GetBoolean,
    GetString,
    SetReal,
    SetInteger,
    SetBoolean,
    SetString,
    GetFmuState,
    SetFmuState,
    FreeFmuState,
    SerializedFmuStateSize,
    SerializeFmuState,
    DeSerializeFmuState,
    GetDirectionalDerivative,
    SetRealInputDerivatives,
    GetRealOutputDerivatives,
    DoStep,
    CancelStep,
    GetStatus,
    GetRealStatus,
    GetIntegerStatus,
    GetBooleanStatus,
    GetStringStatus,
    EnterEventMode,
    NewDiscreteStates,
    EnterContinuousTimeMode,
    CompletedIntegratorStep,
    SetTime,
    SetContinuousStates,
    GetDerivatives,
    GetEventIndicators,
    GetContinuousStates,
    GetNominalsOfContinuousStates,
}

impl Function {
    /// The C name.
    pub fn name(self) -> &'static str {
        use Function::*;
        match self {
            SetDebugLogging => "fmi2SetDebugLogging",
            FreeInstance => "fmi2FreeInstance",
            SetupExperiment => "fmi2SetupExperiment",
            EnterInitializationMode => "fmi2EnterInitializationMode",
            ExitInitializationMode => "fmi2ExitInitializationMode",
            Terminate => "fmi2Terminate",
            Reset => "fmi2Reset",
            GetReal => "fmi2GetReal",
            GetInteger => "fmi2GetInteger",
            GetBoolean => "fmi2GetBoolean",
            GetString => "fmi2GetString",
            SetReal => "fmi2SetReal",
            SetInteger => "fmi2SetInteger",
            SetBoolean => "fmi2SetBoolean",
            SetString => "fmi2SetString",
            GetFmuState => "fmi2GetFMUstate",
            SetFmuState => "fmi2SetFMUstate",
            FreeFmuState => "fmi2FreeFMUstate",
            SerializedFmuStateSize => "fmi2SerializedFMUstateSize",
            SerializeFmuState => "fmi2SerializeFMUstate",
            DeSerializeFmuState => "fmi2DeSerializeFMUstate",
            GetDirectionalDerivative => "fmi2GetDirectionalDerivative",
            SetRealInputDerivatives => "fmi2SetRealInputDerivatives",
            GetRealOutputDerivatives => "fmi2GetRealOutputDerivatives",
            DoStep => "fmi2DoStep",
            CancelStep => "fmi2CancelStep",
            GetStatus => "fmi2GetStatus",
            GetRealStatus => "fmi2GetRealStatus",
            GetIntegerStatus => "fmi2GetIntegerStatus",
            GetBooleanStatus => "fmi2GetBooleanStatus",
            GetStringStatus => "fmi2GetStringStatus",
            EnterEventMode => "fmi2EnterEventMode",
            NewDiscreteStates => "fmi2NewDiscreteStates",
            EnterContinuousTimeMode => "fmi2EnterContinuousTimeMode",
            CompletedIntegratorStep => "fmi2CompletedIntegratorStep",
            SetTime => "fmi2SetTime",
            SetContinuousStates => "fmi2SetContinuousStates",
            GetDerivatives => "fmi2GetDerivatives",
            GetEventIndicators => "fmi2GetEventIndicators",
            GetContinuousStates => "fmi2GetContinuousStates",
            GetNominalsOfContinuousStates => "fmi2GetNominalsOfContinuousStates",
        }
    }

    /// The phases in which the function may be called.
    pub fn allowed_phases(self) -> PhaseSet {
        ALLOWED
            .iter()
            .find(|(f, _)| *f == self)
            .map(|(_, set)| *set)
            .unwrap_or(PhaseSet(0))
    }
}

use Phase::{
    ContinuousTimeMode as Cont, Error as Err_, EventMode as Event, Fatal,
    InitializationMode as Init, Instantiated as Inst, StepComplete as Done, StepFailed as Failed,
    Terminated as Term,
};

/// Every phase but `fatal`.
const NOT_FATAL: PhaseSet = PhaseSet::of(&[Inst, Init, Done, Failed, Term, Err_, Event, Cont]);
/// Where values can be read.
const READABLE: PhaseSet = PhaseSet::of(&[Init, Done, Failed, Term, Err_, Event, Cont]);
/// Where values can be set (which ones depends on causality and variability).
const SETTABLE: PhaseSet = PhaseSet::of(&[Inst, Init, Done, Event, Cont]);
/// Model Exchange: where the model's states, derivatives and indicators
/// can be read.
const MODEL_READABLE: PhaseSet = PhaseSet::of(&[Event, Cont, Term, Err_]);
/// Where the step status can be inquired.
const STATUS: PhaseSet = PhaseSet::of(&[Done, Failed, Term]);

/// The state table: which function is allowed in which phase.
pub const ALLOWED: &[(Function, PhaseSet)] = {
    use Function::*;
    &[
        (SetDebugLogging, NOT_FATAL),
        (
            FreeInstance,
            PhaseSet::of(&[Inst, Init, Done, Failed, Term, Err_, Fatal, Event, Cont]),
        ),
        (SetupExperiment, PhaseSet::of(&[Inst])),
        (EnterInitializationMode, PhaseSet::of(&[Inst])),
        (ExitInitializationMode, PhaseSet::of(&[Init])),
        (Terminate, PhaseSet::of(&[Done, Failed, Event, Cont])),
        (Reset, NOT_FATAL),
        (GetReal, READABLE),
        (GetInteger, READABLE),
        (GetBoolean, READABLE),
        (GetString, READABLE),
        (SetReal, SETTABLE),
        (SetInteger, SETTABLE),
        (SetBoolean, SETTABLE),
        (SetString, SETTABLE),
        (GetFmuState, NOT_FATAL),
        (SetFmuState, NOT_FATAL),
        (FreeFmuState, NOT_FATAL),
        (SerializedFmuStateSize, NOT_FATAL),
        (SerializeFmuState, NOT_FATAL),
        (DeSerializeFmuState, NOT_FATAL),
        (GetDirectionalDerivative, READABLE),
        (SetRealInputDerivatives, SETTABLE),
        (
            GetRealOutputDerivatives,
            PhaseSet::of(&[Done, Failed, Term, Err_]),
        ),
        (DoStep, PhaseSet::of(&[Done])),
        // Only in stepInProgress, which a synchronous fmi2DoStep never leaves behind.
        (CancelStep, PhaseSet::of(&[])),
        (GetStatus, STATUS),
        (GetRealStatus, STATUS),
        (GetIntegerStatus, STATUS),
        (GetBooleanStatus, STATUS),
        (GetStringStatus, STATUS),
        (EnterEventMode, PhaseSet::of(&[Cont])),
        (NewDiscreteStates, PhaseSet::of(&[Event])),
        (EnterContinuousTimeMode, PhaseSet::of(&[Event])),
        (CompletedIntegratorStep, PhaseSet::of(&[Cont])),
        (SetTime, PhaseSet::of(&[Event, Cont])),
        (SetContinuousStates, PhaseSet::of(&[Cont])),
        (GetDerivatives, MODEL_READABLE),
        (GetEventIndicators, MODEL_READABLE),
        (GetContinuousStates, MODEL_READABLE),
        (
            GetNominalsOfContinuousStates,
            PhaseSet::of(&[Event, Cont, Term, Err_]),
        ),
    ]
};

/// Refuses `function` in `phase` with "not allowed in state Y" (the caller
/// prefixes the function name; the message speaks the standard's word).
pub fn check(function: Function, phase: Phase) -> Result<(), FmiError> {
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

    /// The standard's table, restated independently: one row per function,
    /// columns instantiated, initializationMode, stepComplete, stepFailed,
    /// terminated, error, fatal, eventMode, continuousTimeMode.
    const EXPECTED: &[(&str, &str)] = &[
        ("fmi2SetDebugLogging", "xxxxxx.xx"),
        ("fmi2FreeInstance", "xxxxxxxxx"),
        ("fmi2SetupExperiment", "x........"),
        ("fmi2EnterInitializationMode", "x........"),
        ("fmi2ExitInitializationMode", ".x......."),
        ("fmi2Terminate", "..xx...xx"),
        ("fmi2Reset", "xxxxxx.xx"),
        ("fmi2GetReal", ".xxxxx.xx"),
        ("fmi2GetInteger", ".xxxxx.xx"),
        ("fmi2GetBoolean", ".xxxxx.xx"),
        ("fmi2GetString", ".xxxxx.xx"),
        ("fmi2SetReal", "xxx....xx"),
        ("fmi2SetInteger", "xxx....xx"),
        ("fmi2SetBoolean", "xxx....xx"),
        ("fmi2SetString", "xxx....xx"),
        ("fmi2GetFMUstate", "xxxxxx.xx"),
        ("fmi2SetFMUstate", "xxxxxx.xx"),
        ("fmi2FreeFMUstate", "xxxxxx.xx"),
        ("fmi2SerializedFMUstateSize", "xxxxxx.xx"),
        ("fmi2SerializeFMUstate", "xxxxxx.xx"),
        ("fmi2DeSerializeFMUstate", "xxxxxx.xx"),
        ("fmi2GetDirectionalDerivative", ".xxxxx.xx"),
        ("fmi2SetRealInputDerivatives", "xxx....xx"),
        ("fmi2GetRealOutputDerivatives", "..xxxx..."),
        ("fmi2DoStep", "..x......"),
        ("fmi2CancelStep", "........."),
        ("fmi2GetStatus", "..xxx...."),
        ("fmi2GetRealStatus", "..xxx...."),
        ("fmi2GetIntegerStatus", "..xxx...."),
        ("fmi2GetBooleanStatus", "..xxx...."),
        ("fmi2GetStringStatus", "..xxx...."),
        ("fmi2EnterEventMode", "........x"),
        ("fmi2NewDiscreteStates", ".......x."),
        ("fmi2EnterContinuousTimeMode", ".......x."),
        ("fmi2CompletedIntegratorStep", "........x"),
        ("fmi2SetTime", ".......xx"),
        ("fmi2SetContinuousStates", "........x"),
        ("fmi2GetDerivatives", "....xx.xx"),
        ("fmi2GetEventIndicators", "....xx.xx"),
        ("fmi2GetContinuousStates", "....xx.xx"),
        ("fmi2GetNominalsOfContinuousStates", "....xx.xx"),
    ];

    #[test]
    fn every_function_appears_once() {
        for (i, (f, _)) in ALLOWED.iter().enumerate() {
            assert!(
                ALLOWED[i + 1..].iter().all(|(g, _)| g != f),
                "{} twice",
                f.name()
            );
        }
        assert_eq!(ALLOWED.len(), EXPECTED.len());
    }

    #[test]
    fn table_matches_the_standard() {
        for (name, row) in EXPECTED {
            let (function, set) = ALLOWED
                .iter()
                .find(|(f, _)| f.name() == *name)
                .unwrap_or_else(|| panic!("{name} missing"));
            for (state, mark) in Phase::ALL.iter().zip(row.chars()) {
                assert_eq!(
                    set.contains(*state),
                    mark == 'x',
                    "{name} in {}",
                    state.name()
                );
                let checked = check(*function, *state);
                assert_eq!(checked.is_ok(), mark == 'x');
                if let Err(e) = checked {
                    assert_eq!(e.message, format!("not allowed in state {}", state.name()));
                    assert_eq!(e.status, crate::Status::Error);
                }
            }
        }
    }

    #[test]
    fn state_codes_round_trip() {
        for s in Phase::ALL {
            assert_eq!(Phase::from_code(s.code()), Some(s));
        }
        assert_eq!(Phase::from_code(9), None);
    }
}
