//! The phase of a slave: where it is in its life cycle.

/// The phase of a slave (co-simulation or Model Exchange). The FMI standards call it the state
/// of the instance: FMI 2.0's states are these phases, with these names;
/// the FMI 3.0 front-end refines them (its `Fmi3Phase` adds Configuration
/// Mode and the intermediate update; its Step Mode is
/// [`Phase::StepComplete`], and [`Phase::StepFailed`] after a discarded
/// step). Model Exchange instances go from initialization to
/// [`Phase::EventMode`] and [`Phase::ContinuousTimeMode`] instead of the
/// step phases. The codes are stored in serialized FMU states.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Phase {
    Instantiated,
    InitializationMode,
    StepComplete,
    StepFailed,
    Terminated,
    Error,
    Fatal,
    /// Model Exchange: Event Mode.
    EventMode,
    /// Model Exchange: Continuous-Time Mode.
    ContinuousTimeMode,
}

impl Phase {
    /// Every phase.
    pub const ALL: [Phase; 9] = [
        Phase::Instantiated,
        Phase::InitializationMode,
        Phase::StepComplete,
        Phase::StepFailed,
        Phase::Terminated,
        Phase::Error,
        Phase::Fatal,
        Phase::EventMode,
        Phase::ContinuousTimeMode,
    ];

    /// The name FMI 2.0 gives the phase, its state (`stepComplete`, ...).
    pub fn name(self) -> &'static str {
        match self {
            Phase::Instantiated => "instantiated",
            Phase::InitializationMode => "initializationMode",
            Phase::StepComplete => "stepComplete",
            Phase::StepFailed => "stepFailed",
            Phase::Terminated => "terminated",
            Phase::Error => "error",
            Phase::Fatal => "fatal",
            Phase::EventMode => "eventMode",
            Phase::ContinuousTimeMode => "continuousTimeMode",
        }
    }

    /// Stable code used in serialized FMU states.
    pub fn code(self) -> u8 {
        self as u8
    }

    /// Inverse of [`Phase::code`].
    pub fn from_code(code: u8) -> Option<Phase> {
        Phase::ALL.get(code as usize).copied()
    }

    /// Whether the instance has a running simulation (after initialization).
    pub fn is_simulating(self) -> bool {
        !matches!(self, Phase::Instantiated | Phase::InitializationMode)
    }

    /// The bit of the phase in a set of phases.
    pub const fn bit(self) -> u16 {
        1 << self as u16
    }
}
