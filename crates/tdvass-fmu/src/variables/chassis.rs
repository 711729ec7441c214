//! The chassis's variables ([`crate::Model::Chassis`]): its parameters (the
//! paper's car by default, [`tdvass::chassis::ChassisParams`]), the four
//! corners' forces as inputs, and the attachment points' motion, the
//! body's heave, pitch and roll and the seat's comfort measures as
//! outputs. The attachment points' displacements and velocities come
//! from the states alone (no direct feedthrough: a system of corners and
//! chassis has no algebraic loop); the accelerations depend directly on
//! the forces.

use super::{
    Access, Causality, Q, Range, Variability, Variable, derivative, local_state, output_read_by,
    parameter,
};
use crate::chassis_outputs::ChassisOutputId as C;
use crate::settings::Settings;
use tdvass::chassis::Corner;

/// The forces, in the order of [`Corner::ALL`].
const FORCES: &[&str] = &["force_fl", "force_fr", "force_rl", "force_rr"];

/// What the body's accelerations depend on initially: the forces and the
/// body's geometry and inertia.
const ACCELERATION_DEPENDENCIES: &[&str] = &[
    "mass",
    "a",
    "b",
    "track_front",
    "track_rear",
    "pitch_inertia",
    "roll_inertia",
    "force_fl",
    "force_fr",
    "force_rl",
    "force_rr",
];

/// The seat's acceleration depends initially on the seat point too.
const SEAT_DEPENDENCIES: &[&str] = &[
    "mass",
    "a",
    "b",
    "track_front",
    "track_rear",
    "pitch_inertia",
    "roll_inertia",
    "seat_x",
    "seat_y",
    "force_fl",
    "force_fr",
    "force_rl",
    "force_rr",
];

/// A chassis output.
const fn output(
    name: &'static str,
    vr: u32,
    quantity: Q,
    id: C,
    description: &'static str,
    feedthrough: &'static [&'static str],
    initial_dependencies: &'static [&'static str],
) -> Variable {
    Variable {
        // The chassis steps exactly to the communication point; it has no
        // internal nodes to report at.
        intermediate_update: false,
        ..output_read_by(
            name,
            vr,
            quantity,
            Access::ChassisOutput(id),
            description,
            feedthrough,
            initial_dependencies,
        )
    }
}

/// A corner's force on the body.
const fn force(name: &'static str, vr: u32, access: Access, description: &'static str) -> Variable {
    Variable {
        name,
        vr,
        causality: Causality::Input,
        variability: Variability::Continuous,
        quantity: Q::Force,
        display_unit: None,
        start: Some(0.0),
        range: Range::Finite,
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

macro_rules! chassis_real {
    ($field:ident) => {
        Access::Real {
            get: |s: &Settings| s.chassis.$field,
            set: |s: &mut Settings, v: f64| s.chassis.$field = v,
        }
    };
}

macro_rules! force_input {
    ($i:expr) => {
        Access::Real {
            get: |s: &Settings| s.forces[$i],
            set: |s: &mut Settings, v: f64| s.forces[$i] = v,
        }
    };
}

use Variability::Fixed;

/// The chassis's variables of both FMI versions, in `ModelVariables`
/// order (FMI 3.0 adds `time`).
pub const CHASSIS_VARIABLES: &[Variable] = &[
    parameter(
        "mass",
        200,
        Fixed,
        Q::Mass,
        4.0 * 345.0,
        Range::Positive,
        chassis_real!(mass),
        "Body mass m (kg, > 0; default 4 x 345 kg: the paper's car)",
    ),
    parameter(
        "a",
        201,
        Fixed,
        Q::Length,
        1.3,
        Range::AtLeast(0.0),
        chassis_real!(a),
        "Centre of gravity to the front axle (m, >= 0)",
    ),
    parameter(
        "b",
        202,
        Fixed,
        Q::Length,
        1.3,
        Range::AtLeast(0.0),
        chassis_real!(b),
        "Centre of gravity to the rear axle (m, >= 0; a + b > 0)",
    ),
    parameter(
        "track_front",
        203,
        Fixed,
        Q::Length,
        1.5,
        Range::Positive,
        chassis_real!(track_front),
        "Front track width (m, > 0)",
    ),
    parameter(
        "track_rear",
        204,
        Fixed,
        Q::Length,
        1.5,
        Range::Positive,
        chassis_real!(track_rear),
        "Rear track width (m, > 0)",
    ),
    parameter(
        "pitch_inertia",
        205,
        Fixed,
        Q::Inertia,
        4.0 * 345.0 * 1.3 * 1.3,
        Range::Positive,
        chassis_real!(pitch_inertia),
        "Pitch moment of inertia I_theta (kg m2, > 0; default m a b: under the same road on both tracks front and rear decouple and each corner is the paper's quarter car)",
    ),
    parameter(
        "roll_inertia",
        206,
        Fixed,
        Q::Inertia,
        400.0,
        Range::Positive,
        chassis_real!(roll_inertia),
        "Roll moment of inertia I_phi (kg m2, > 0; default 400: a mid-size sedan's, scaled to the mass)",
    ),
    parameter(
        "seat_x",
        207,
        Fixed,
        Q::Length,
        0.3,
        Range::Finite,
        chassis_real!(seat_x),
        "The seat point ahead of the centre of gravity (m)",
    ),
    parameter(
        "seat_y",
        208,
        Fixed,
        Q::Length,
        0.35,
        Range::Finite,
        chassis_real!(seat_y),
        "The seat point left of the centre of gravity (m)",
    ),
    force(
        "force_fl",
        210,
        force_input!(0),
        "The front left corner's force on the body (N, positive up: its body_force), held over a communication step (or along its input derivative)",
    ),
    force(
        "force_fr",
        211,
        force_input!(1),
        "The front right corner's force on the body (N, positive up)",
    ),
    force(
        "force_rl",
        212,
        force_input!(2),
        "The rear left corner's force on the body (N, positive up)",
    ),
    force(
        "force_rr",
        213,
        force_input!(3),
        "The rear right corner's force on the body (N, positive up)",
    ),
    output(
        "displacement_fl",
        220,
        Q::Length,
        C::Displacement(Corner::FrontLeft),
        "The front left attachment point's displacement from the static equilibrium z + a theta + (track_front/2) phi (m, positive up; from the states alone)",
        &[],
        &[],
    ),
    output(
        "displacement_fr",
        221,
        Q::Length,
        C::Displacement(Corner::FrontRight),
        "The front right attachment point's displacement z + a theta - (track_front/2) phi (m)",
        &[],
        &[],
    ),
    output(
        "displacement_rl",
        222,
        Q::Length,
        C::Displacement(Corner::RearLeft),
        "The rear left attachment point's displacement z - b theta + (track_rear/2) phi (m)",
        &[],
        &[],
    ),
    output(
        "displacement_rr",
        223,
        Q::Length,
        C::Displacement(Corner::RearRight),
        "The rear right attachment point's displacement z - b theta - (track_rear/2) phi (m)",
        &[],
        &[],
    ),
    output(
        "velocity_fl",
        224,
        Q::Velocity,
        C::Velocity(Corner::FrontLeft),
        "The front left attachment point's velocity (m/s, positive up; from the states alone)",
        &[],
        &[],
    ),
    output(
        "velocity_fr",
        225,
        Q::Velocity,
        C::Velocity(Corner::FrontRight),
        "The front right attachment point's velocity (m/s)",
        &[],
        &[],
    ),
    output(
        "velocity_rl",
        226,
        Q::Velocity,
        C::Velocity(Corner::RearLeft),
        "The rear left attachment point's velocity (m/s)",
        &[],
        &[],
    ),
    output(
        "velocity_rr",
        227,
        Q::Velocity,
        C::Velocity(Corner::RearRight),
        "The rear right attachment point's velocity (m/s)",
        &[],
        &[],
    ),
    output(
        "heave",
        230,
        Q::Length,
        C::Position(0),
        "Heave z of the centre of gravity from the static equilibrium (m, positive up)",
        &[],
        &[],
    ),
    output(
        "pitch",
        231,
        Q::Angle,
        C::Position(1),
        "Pitch theta (rad, positive nose up; small angles)",
        &[],
        &[],
    ),
    output(
        "roll",
        232,
        Q::Angle,
        C::Position(2),
        "Roll phi (rad, positive left side up; small angles)",
        &[],
        &[],
    ),
    output(
        "heave_velocity",
        233,
        Q::Velocity,
        C::Rate(0),
        "Heave velocity z' (m/s)",
        &[],
        &[],
    ),
    output(
        "pitch_rate",
        234,
        Q::AngularVelocity,
        C::Rate(1),
        "Pitch rate theta' (rad/s)",
        &[],
        &[],
    ),
    output(
        "roll_rate",
        235,
        Q::AngularVelocity,
        C::Rate(2),
        "Roll rate phi' (rad/s)",
        &[],
        &[],
    ),
    output(
        "heave_acceleration",
        236,
        Q::Acceleration,
        C::Acceleration(0),
        "Heave acceleration z'' = (sum of the forces) / m (m/s2); depends directly on the forces",
        FORCES,
        ACCELERATION_DEPENDENCIES,
    ),
    output(
        "pitch_acceleration",
        237,
        Q::AngularAcceleration,
        C::Acceleration(1),
        "Pitch acceleration theta'' = a (f_fl + f_fr) - b (f_rl + f_rr), over I_theta (rad/s2); depends directly on the forces",
        FORCES,
        ACCELERATION_DEPENDENCIES,
    ),
    output(
        "roll_acceleration",
        238,
        Q::AngularAcceleration,
        C::Acceleration(2),
        "Roll acceleration phi'' = the forces' moments about the roll axis (half tracks, left positive) over I_phi (rad/s2); depends directly on the forces",
        FORCES,
        ACCELERATION_DEPENDENCIES,
    ),
    output(
        "seat_acceleration",
        239,
        Q::Acceleration,
        C::SeatAcceleration,
        "The seat point's vertical acceleration z'' + seat_x theta'' + seat_y phi'' (m/s2); depends directly on the forces",
        FORCES,
        SEAT_DEPENDENCIES,
    ),
    output(
        "rms_heave_acceleration",
        240,
        Q::Acceleration,
        C::RmsAcceleration(0),
        "Running RMS of the heave acceleration from the start time (m/s2; exact: the forces are linear over each step)",
        &[],
        &[],
    ),
    output(
        "rms_pitch_acceleration",
        241,
        Q::AngularAcceleration,
        C::RmsAcceleration(1),
        "Running RMS of the pitch acceleration (rad/s2)",
        &[],
        &[],
    ),
    output(
        "rms_roll_acceleration",
        242,
        Q::AngularAcceleration,
        C::RmsAcceleration(2),
        "Running RMS of the roll acceleration (rad/s2)",
        &[],
        &[],
    ),
    output(
        "weighted_seat_acceleration",
        243,
        Q::Acceleration,
        C::WeightedSeatAcceleration,
        "The seat's acceleration weighted by ISO 2631-1 W_k, a_w (m/s2; the filter integrated exactly over each step): an output of the filter's states (W_k has no direct feedthrough), so a force changes it over the step that follows",
        &[],
        &[],
    ),
    output(
        "rms_weighted_seat_acceleration",
        244,
        Q::Acceleration,
        C::RmsWeightedSeatAcceleration,
        "Running RMS of a_w from the start time (m/s2; ISO 2631-1 overall ride comfort at the seat)",
        &[],
        &[],
    ),
    output(
        "seat_vibration_dose_value",
        245,
        Q::VibrationDose,
        C::SeatVibrationDoseValue,
        "The seat's vibration dose value VDV = (integral of a_w^4)^(1/4) from the start time (m/s1.75)",
        &[],
        &[],
    ),
    // Model Exchange: the continuous states that are not outputs, then
    // the derivatives of all of them (heave ... roll_rate are outputs and
    // states), in the order of `tdvass::chassis::CHASSIS_STATE_NAMES`.
    local_state(
        "seat_wk_filter_1",
        250,
        6,
        Q::Acceleration,
        "State 1 of the 8 of the ISO 2631-1 W_k filter of the seat acceleration (a_w = c_w w); a continuous state of Model Exchange",
    ),
    local_state(
        "seat_wk_filter_2",
        251,
        7,
        Q::Acceleration,
        "State 2 of the 8 of the ISO 2631-1 W_k filter of the seat acceleration (a_w = c_w w); a continuous state of Model Exchange",
    ),
    local_state(
        "seat_wk_filter_3",
        252,
        8,
        Q::Acceleration,
        "State 3 of the 8 of the ISO 2631-1 W_k filter of the seat acceleration (a_w = c_w w); a continuous state of Model Exchange",
    ),
    local_state(
        "seat_wk_filter_4",
        253,
        9,
        Q::Acceleration,
        "State 4 of the 8 of the ISO 2631-1 W_k filter of the seat acceleration (a_w = c_w w); a continuous state of Model Exchange",
    ),
    local_state(
        "seat_wk_filter_5",
        254,
        10,
        Q::Acceleration,
        "State 5 of the 8 of the ISO 2631-1 W_k filter of the seat acceleration (a_w = c_w w); a continuous state of Model Exchange",
    ),
    local_state(
        "seat_wk_filter_6",
        255,
        11,
        Q::Acceleration,
        "State 6 of the 8 of the ISO 2631-1 W_k filter of the seat acceleration (a_w = c_w w); a continuous state of Model Exchange",
    ),
    local_state(
        "seat_wk_filter_7",
        256,
        12,
        Q::Acceleration,
        "State 7 of the 8 of the ISO 2631-1 W_k filter of the seat acceleration (a_w = c_w w); a continuous state of Model Exchange",
    ),
    local_state(
        "seat_wk_filter_8",
        257,
        13,
        Q::Acceleration,
        "State 8 of the 8 of the ISO 2631-1 W_k filter of the seat acceleration (a_w = c_w w); a continuous state of Model Exchange",
    ),
    local_state(
        "integral_heave_acceleration_squared",
        258,
        14,
        Q::Dimensionless,
        "Integral of the heave acceleration squared from the start time (m2/s3); a continuous state of Model Exchange, behind rms_heave_acceleration",
    ),
    local_state(
        "integral_pitch_acceleration_squared",
        259,
        15,
        Q::Dimensionless,
        "Integral of the pitch acceleration squared from the start time (rad2/s3); a continuous state of Model Exchange, behind rms_pitch_acceleration",
    ),
    local_state(
        "integral_roll_acceleration_squared",
        260,
        16,
        Q::Dimensionless,
        "Integral of the roll acceleration squared from the start time (rad2/s3); a continuous state of Model Exchange, behind rms_roll_acceleration",
    ),
    local_state(
        "integral_weighted_seat_acceleration_squared",
        261,
        17,
        Q::Dimensionless,
        "Integral of a_w^2 from the start time (m2/s3); a continuous state of Model Exchange, behind rms_weighted_seat_acceleration",
    ),
    local_state(
        "integral_weighted_seat_acceleration_fourth",
        262,
        18,
        Q::Dimensionless,
        "Integral of a_w^4 from the start time (m4/s7); a continuous state of Model Exchange, behind seat_vibration_dose_value",
    ),
    derivative(
        "der(heave)",
        270,
        0,
        Q::Velocity,
        "Time derivative of heave (m/s); Model Exchange",
    ),
    derivative(
        "der(pitch)",
        271,
        1,
        Q::AngularVelocity,
        "Time derivative of pitch (rad/s); Model Exchange",
    ),
    derivative(
        "der(roll)",
        272,
        2,
        Q::AngularVelocity,
        "Time derivative of roll (rad/s); Model Exchange",
    ),
    derivative(
        "der(heave_velocity)",
        273,
        3,
        Q::Acceleration,
        "Time derivative of heave_velocity (m/s2); Model Exchange",
    ),
    derivative(
        "der(pitch_rate)",
        274,
        4,
        Q::AngularAcceleration,
        "Time derivative of pitch_rate (rad/s2); Model Exchange",
    ),
    derivative(
        "der(roll_rate)",
        275,
        5,
        Q::AngularAcceleration,
        "Time derivative of roll_rate (rad/s2); Model Exchange",
    ),
    derivative(
        "der(seat_wk_filter_1)",
        276,
        6,
        Q::Dimensionless,
        "Time derivative of seat_wk_filter_1 (m/s3); Model Exchange",
    ),
    derivative(
        "der(seat_wk_filter_2)",
        277,
        7,
        Q::Dimensionless,
        "Time derivative of seat_wk_filter_2 (m/s3); Model Exchange",
    ),
    derivative(
        "der(seat_wk_filter_3)",
        278,
        8,
        Q::Dimensionless,
        "Time derivative of seat_wk_filter_3 (m/s3); Model Exchange",
    ),
    derivative(
        "der(seat_wk_filter_4)",
        279,
        9,
        Q::Dimensionless,
        "Time derivative of seat_wk_filter_4 (m/s3); Model Exchange",
    ),
    derivative(
        "der(seat_wk_filter_5)",
        280,
        10,
        Q::Dimensionless,
        "Time derivative of seat_wk_filter_5 (m/s3); Model Exchange",
    ),
    derivative(
        "der(seat_wk_filter_6)",
        281,
        11,
        Q::Dimensionless,
        "Time derivative of seat_wk_filter_6 (m/s3); Model Exchange",
    ),
    derivative(
        "der(seat_wk_filter_7)",
        282,
        12,
        Q::Dimensionless,
        "Time derivative of seat_wk_filter_7 (m/s3); Model Exchange",
    ),
    derivative(
        "der(seat_wk_filter_8)",
        283,
        13,
        Q::Dimensionless,
        "Time derivative of seat_wk_filter_8 (m/s3); Model Exchange",
    ),
    derivative(
        "der(integral_heave_acceleration_squared)",
        284,
        14,
        Q::Dimensionless,
        "Time derivative of integral_heave_acceleration_squared; Model Exchange",
    ),
    derivative(
        "der(integral_pitch_acceleration_squared)",
        285,
        15,
        Q::Dimensionless,
        "Time derivative of integral_pitch_acceleration_squared; Model Exchange",
    ),
    derivative(
        "der(integral_roll_acceleration_squared)",
        286,
        16,
        Q::Dimensionless,
        "Time derivative of integral_roll_acceleration_squared; Model Exchange",
    ),
    derivative(
        "der(integral_weighted_seat_acceleration_squared)",
        287,
        17,
        Q::Dimensionless,
        "Time derivative of integral_weighted_seat_acceleration_squared; Model Exchange",
    ),
    derivative(
        "der(integral_weighted_seat_acceleration_fourth)",
        288,
        18,
        Q::Dimensionless,
        "Time derivative of integral_weighted_seat_acceleration_fourth; Model Exchange",
    ),
];
