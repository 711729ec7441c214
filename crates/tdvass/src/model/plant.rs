//! The linear plant of Eq. (2) built from Eq. (1), and the performance
//! outputs Y of Eq. (2).
//!
//! Layer: data (docs/architecture.md), with the model; it imports the
//! model's `params`, `equations` and the crate's `error`.

use super::body::Body;
use super::equations::MassSpringDamper;
use super::params::{Params, State, V_H, V_S, V_T, Variant, X_H, X_S, X_T};
use crate::error::Result;
use nalgebra::{Matrix6, RowVector6};

/// The linear plant of Eq. (2) for one variant:
/// `dX/dt = A X + b x_t(t - tau) + e x_g(t)`.
///
/// `b` already contains the gain: `b = [0, 0, 0, -g/m_h, 0, g/m_t]`
/// (notes.md section 1; the paper's `g_t` in B means `g`).
/// `e = [0, 0, 0, 0, 0, k_t/m_t]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Plant {
    /// The variant this plant describes.
    pub variant: Variant,
    /// The parameters it was built from.
    pub params: Params,
    /// State matrix A of Eq. (2).
    pub a: Matrix6<f64>,
    /// Delayed-feedback column (B of Eq. (2) times g).
    pub b: State,
    /// Road column E of Eq. (2).
    pub e: State,
    /// What carries the suspension ([`Body`]).
    pub body: Body,
    /// The suspension's force on the body (N) per unit of each state:
    /// `m_s` times Eq. (2)'s body row of A (the spring and damper between
    /// the body and the absorber, or the wheel for the CS). Zero at the
    /// static equilibrium, positive up.
    pub body_force_row: RowVector6<f64>,
}

impl Plant {
    /// Builds A, b, e for `variant` after validating `params`, from Eq. (1)
    /// ([`MassSpringDamper`]): for each coordinate x_i with mass m_i,
    /// `dx_i/dt = v_i`, `dv_i/dt = −(K x + C v)_i / m_i + …`.
    pub fn new(params: Params, variant: Variant) -> Result<Plant> {
        let eq1 = MassSpringDamper::new(&params, variant)?;
        let mut a = Matrix6::zeros();
        let mut b = State::zeros();
        let mut e = State::zeros();
        for (i, &x_i) in eq1.coordinates.iter().enumerate() {
            let (v_i, mass) = (x_i + 1, eq1.masses[i]);
            a[(x_i, v_i)] = 1.0;
            for (j, &x_j) in eq1.coordinates.iter().enumerate() {
                if let Some(stiffness) = eq1.stiffness(i, j) {
                    a[(v_i, x_j)] = -stiffness / mass;
                }
                if let Some(damping) = eq1.damping(i, j) {
                    a[(v_i, x_j + 1)] = -damping / mass;
                }
            }
            if eq1.coordinates.len() == 3 {
                b[v_i] = eq1.feedback[i] / mass;
            }
            if i == eq1.wheel() {
                e[v_i] = eq1.road_stiffness(i) / mass;
            }
        }
        let body_force_row = a.row(V_S) * params.m_s;
        Ok(Plant {
            variant,
            params,
            a,
            b,
            e,
            body: Body::Mass,
            body_force_row,
        })
    }

    /// This plant carrying `body`: every coordinate an input prescribes in
    /// that configuration ([`super::inputs::PRESCRIBED`]; with
    /// [`Body::Attached`] the body's attachment point) moves at its given
    /// velocity (the velocity's rows of A, b and e are zero, `dv_s/dt = 0`;
    /// the position's row, `dx_s/dt = v_s`, stays), its motion set from
    /// outside. (The body's rows of b and e are zero already: neither the
    /// control force nor the road acts on the body.)
    pub fn with_body(mut self, body: Body) -> Plant {
        self.body = body;
        for input in super::inputs::PRESCRIBED {
            if (input.applies)(body) {
                let velocity = input.coordinates[1];
                self.a.row_mut(velocity).fill(0.0);
                self.b[velocity] = 0.0;
                self.e[velocity] = 0.0;
            }
        }
        self
    }

    /// The suspension's force on the body (N), positive up, zero at the
    /// static equilibrium: [`Self::body_force_row`] times the state. With
    /// the sprung mass it is `m_s BA`.
    #[inline]
    pub fn body_force(&self, x: &State) -> f64 {
        self.body_force_row.dot(&x.transpose())
    }

    /// Body acceleration BA = d²x_s/dt² (m/s²), first row of Eq. (26).
    /// It does not depend on the road or the control force.
    #[inline]
    pub fn body_acceleration(&self, x: &State) -> f64 {
        self.a.row(V_S).dot(&x.transpose())
    }

    /// The state as reported: for CS the absorber coordinates mirror the wheel.
    pub fn reported_state(&self, x: &State) -> State {
        let mut y = *x;
        if self.variant == Variant::Cs {
            y[X_H] = x[X_T];
            y[V_H] = x[V_T];
        }
        y
    }
}

/// The three performance outputs of Eq. (2), `Y = [BA, SDD, TDD]`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Performance {
    /// Body acceleration BA = d²x_s/dt² (m/s²).
    pub body_acceleration: f64,
    /// Suspension dynamic deflection SDD = x_s − x_t (m).
    pub suspension_deflection: f64,
    /// Tire dynamic displacement TDD = x_t − x_g (m).
    pub tire_deflection: f64,
}

impl Performance {
    /// Evaluates Y of Eq. (2) at state `x` and road displacement `road`.
    #[inline]
    pub fn at(plant: &Plant, x: &State, road: f64) -> Performance {
        Performance {
            body_acceleration: plant.body_acceleration(x),
            suspension_deflection: x[X_S] - x[X_T],
            tire_deflection: x[X_T] - road,
        }
    }
}
