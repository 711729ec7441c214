//! How the chassis FMU's outputs ([`crate::defaults::Model::Chassis`]) are
//! read from a [`Chassis`]: the attachment points' motion (from the states
//! alone), the body's heave, pitch and roll with their rates and
//! accelerations, and the ride-comfort measures at the seat point.

use std::ops::Range;
use tdvass::chassis::{CHASSIS_FILTER_AT, CHASSIS_INTEGRALS_AT, Chassis, Corner};

/// An output of the chassis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ChassisOutputId {
    /// The attachment point's displacement (m).
    Displacement(Corner),
    /// The attachment point's velocity (m/s).
    Velocity(Corner),
    /// Component k of `[z, θ, φ]` (m, rad, rad).
    Position(usize),
    /// Its rate (m/s, rad/s).
    Rate(usize),
    /// Its acceleration (m/s², rad/s²).
    Acceleration(usize),
    /// The seat point's vertical acceleration (m/s²).
    SeatAcceleration,
    /// The running RMS of acceleration k (m/s², rad/s²).
    RmsAcceleration(usize),
    /// The W_k-weighted seat acceleration a_w (m/s²).
    WeightedSeatAcceleration,
    /// The running RMS of a_w (m/s²).
    RmsWeightedSeatAcceleration,
    /// The seat's vibration dose value (m/s^1.75).
    SeatVibrationDoseValue,
}

impl ChassisOutputId {
    /// The continuous states of Model Exchange (indices into
    /// [`Chassis::states`]) the value is computed from at an instant,
    /// besides the forces: the dependencies on states in
    /// ModelStructure/Outputs.
    pub fn state_dependencies(self) -> Range<usize> {
        use ChassisOutputId as C;
        match self {
            C::Displacement(_) => 0..3,
            C::Velocity(_) => 3..6,
            C::Position(k) => k..k + 1,
            C::Rate(k) => 3 + k..4 + k,
            C::Acceleration(_) | C::SeatAcceleration => 0..0,
            C::RmsAcceleration(k) => CHASSIS_INTEGRALS_AT + k..CHASSIS_INTEGRALS_AT + k + 1,
            C::WeightedSeatAcceleration => CHASSIS_FILTER_AT..CHASSIS_INTEGRALS_AT,
            C::RmsWeightedSeatAcceleration => CHASSIS_INTEGRALS_AT + 3..CHASSIS_INTEGRALS_AT + 4,
            C::SeatVibrationDoseValue => CHASSIS_INTEGRALS_AT + 4..CHASSIS_INTEGRALS_AT + 5,
        }
    }

    /// The value of the output of `chassis` now.
    pub fn value(self, chassis: &Chassis) -> f64 {
        use ChassisOutputId as C;
        match self {
            C::Displacement(corner) => chassis.attachment(corner).0,
            C::Velocity(corner) => chassis.attachment(corner).1,
            C::Position(k) => chassis.outputs().position[k],
            C::Rate(k) => chassis.outputs().rate[k],
            C::Acceleration(k) => chassis.outputs().acceleration[k],
            C::SeatAcceleration => chassis.outputs().seat_acceleration,
            C::RmsAcceleration(k) => chassis.outputs().rms_acceleration[k],
            C::WeightedSeatAcceleration => chassis.outputs().weighted_seat_acceleration,
            C::RmsWeightedSeatAcceleration => chassis.outputs().rms_weighted_seat_acceleration,
            C::SeatVibrationDoseValue => chassis.outputs().seat_vibration_dose_value,
        }
    }
}
