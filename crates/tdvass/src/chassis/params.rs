//! The chassis's parameters: its corners, their positions on the body,
//! the mass and inertias and the seat point (the module documentation of
//! [`super`] states the geometry and the dynamics they enter).
//!
//! Layer: engines (docs/architecture.md), with the chassis; it imports the
//! crate's `error`.

use crate::error::{Error, Result};

/// A corner of the vehicle.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Corner {
    FrontLeft,
    FrontRight,
    RearLeft,
    RearRight,
}

impl Corner {
    /// The four, in the order of the force inputs: `fl`, `fr`, `rl`, `rr`.
    pub const ALL: [Corner; 4] = [
        Corner::FrontLeft,
        Corner::FrontRight,
        Corner::RearLeft,
        Corner::RearRight,
    ];

    /// Its place in [`Corner::ALL`] (the order of the force inputs).
    pub fn index(self) -> usize {
        match self {
            Corner::FrontLeft => 0,
            Corner::FrontRight => 1,
            Corner::RearLeft => 2,
            Corner::RearRight => 3,
        }
    }

    /// The name of its force input (`force_fl` …).
    pub fn force_name(self) -> &'static str {
        match self {
            Corner::FrontLeft => "force_fl",
            Corner::FrontRight => "force_fr",
            Corner::RearLeft => "force_rl",
            Corner::RearRight => "force_rr",
        }
    }

    /// The short name (`fl`, `fr`, `rl`, `rr`).
    pub fn name(self) -> &'static str {
        match self {
            Corner::FrontLeft => "fl",
            Corner::FrontRight => "fr",
            Corner::RearLeft => "rl",
            Corner::RearRight => "rr",
        }
    }
}

/// The chassis's parameters (the defaults are the paper's car: four times
/// its 345 kg body, the centre of gravity midway between the axles, and
/// the pitch inertia `m a b` that decouples front and rear).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChassisParams {
    /// m (kg).
    pub mass: f64,
    /// a (m): centre of gravity to the front axle.
    pub a: f64,
    /// b (m): centre of gravity to the rear axle.
    pub b: f64,
    /// Front track (m).
    pub track_front: f64,
    /// Rear track (m).
    pub track_rear: f64,
    /// I_θ (kg·m²).
    pub pitch_inertia: f64,
    /// I_φ (kg·m²): a mid-size sedan's, scaled to the mass.
    pub roll_inertia: f64,
    /// The seat point ahead of the centre of gravity (m).
    pub seat_x: f64,
    /// The seat point left of the centre of gravity (m).
    pub seat_y: f64,
}

impl Default for ChassisParams {
    fn default() -> Self {
        let (mass, a, b) = (4.0 * 345.0, 1.3, 1.3);
        ChassisParams {
            mass,
            a,
            b,
            track_front: 1.5,
            track_rear: 1.5,
            pitch_inertia: mass * a * b,
            roll_inertia: 400.0,
            seat_x: 0.3,
            seat_y: 0.35,
        }
    }
}

impl ChassisParams {
    /// Checks every parameter; the error names it.
    pub fn validate(&self) -> Result<()> {
        for (name, value) in [
            ("mass", self.mass),
            ("pitch_inertia", self.pitch_inertia),
            ("roll_inertia", self.roll_inertia),
            ("track_front", self.track_front),
            ("track_rear", self.track_rear),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(Error::InvalidParameter {
                    name,
                    value,
                    reason: "must be finite and positive",
                });
            }
        }
        for (name, value) in [("a", self.a), ("b", self.b)] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(Error::InvalidParameter {
                    name,
                    value,
                    reason: "must be finite and not negative",
                });
            }
        }
        if self.a + self.b <= 0.0 {
            return Err(Error::InvalidParameter {
                name: "b",
                value: self.b,
                reason: "the wheelbase a + b must be positive",
            });
        }
        for (name, value) in [("seat_x", self.seat_x), ("seat_y", self.seat_y)] {
            if !value.is_finite() {
                return Err(Error::InvalidParameter {
                    name,
                    value,
                    reason: "must be finite",
                });
            }
        }
        Ok(())
    }

    /// The attachment point of `corner`: `(x, y)` (m) from the centre of
    /// gravity, ahead and to the left.
    pub fn position(&self, corner: Corner) -> (f64, f64) {
        match corner {
            Corner::FrontLeft => (self.a, 0.5 * self.track_front),
            Corner::FrontRight => (self.a, -0.5 * self.track_front),
            Corner::RearLeft => (-self.b, 0.5 * self.track_rear),
            Corner::RearRight => (-self.b, -0.5 * self.track_rear),
        }
    }

    /// How a point `(x, y)` moves with `[z, θ, φ]`: `[1, x, y]`.
    pub fn point(x: f64, y: f64) -> [f64; 3] {
        [1.0, x, y]
    }

    /// The generalized accelerations `[z'', θ'', φ'']` of the corners'
    /// forces `f`.
    pub fn accelerations(&self, f: &[f64; 4]) -> [f64; 3] {
        let mut generalized = [0.0; 3];
        for (corner, force) in Corner::ALL.iter().zip(f) {
            let (x, y) = self.position(*corner);
            for (g, p) in generalized.iter_mut().zip(Self::point(x, y)) {
                *g += p * force;
            }
        }
        [
            generalized[0] / self.mass,
            generalized[1] / self.pitch_inertia,
            generalized[2] / self.roll_inertia,
        ]
    }
}
