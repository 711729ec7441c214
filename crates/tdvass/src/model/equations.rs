//! Eq. (1) of the paper, once: the quarter car as masses joined by
//! spring–damper elements,
//! `M ẍ + C ẋ + K x = k_t x_g e_wheel + f x_t(t − tau)`,
//! with `x = [x_s, x_h, x_t]` (CS: `[x_s, x_t]`). The state-space form of
//! Eq. (2) ([`super::Plant`]), the frequency response of Eq. (3)
//! (`analysis::frf`) and the characteristic polynomials of Eq. (8)-(9)
//! (`analysis::characteristic`) are all assembled from it.
//!
//! Sums are formed element by element in the order of [`MassSpringDamper::elements`],
//! so every consumer adds the same terms in the same order.

use super::params::{Params, Variant, X_H, X_S, X_T};
use crate::error::Result;

/// One spring–damper element of Eq. (1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Element {
    /// The coordinate (index into [`MassSpringDamper::coordinates`]) it acts on.
    pub from: usize,
    /// The other coordinate, or `None` for the road (the tire).
    pub to: Option<usize>,
    /// Stiffness (N/m).
    pub stiffness: f64,
    /// Damping (N·s/m).
    pub damping: f64,
}

/// The quarter car of one variant as Eq. (1).
#[derive(Debug, Clone, PartialEq)]
pub struct MassSpringDamper {
    /// The state index (`X_S`, `X_H`, `X_T`) of each displacement coordinate.
    pub coordinates: Vec<usize>,
    /// The mass of each coordinate (kg).
    pub masses: Vec<f64>,
    /// The elements: the suspension (body–absorber, CS: body–wheel), the
    /// tire (wheel–road), and for PVASS/TDVASS the absorber
    /// (absorber–wheel), in that order.
    pub elements: Vec<Element>,
    /// The force on each coordinate per unit delayed wheel displacement
    /// `x_t(t − tau)` (N/m): `[0, −g, g]` for the TDVASS (the gain that acts
    /// in the variant), zero otherwise.
    pub feedback: Vec<f64>,
}

impl MassSpringDamper {
    /// Eq. (1) for `variant` after validating `params`.
    pub fn new(params: &Params, variant: Variant) -> Result<MassSpringDamper> {
        params.validate()?;
        let tire = |wheel| Element {
            from: wheel,
            to: None,
            stiffness: params.k_t,
            damping: 0.0,
        };
        Ok(match variant {
            Variant::Cs => MassSpringDamper {
                coordinates: vec![X_S, X_T],
                masses: vec![params.m_s, params.m_t],
                elements: vec![
                    Element {
                        from: 0,
                        to: Some(1),
                        stiffness: params.k_s,
                        damping: params.c_s,
                    },
                    tire(1),
                ],
                feedback: vec![0.0, 0.0],
            },
            Variant::Pvass | Variant::Tdvass => {
                let g = params.effective_gain(variant);
                MassSpringDamper {
                    coordinates: vec![X_S, X_H, X_T],
                    masses: vec![params.m_s, params.m_h, params.m_t],
                    elements: vec![
                        Element {
                            from: 0,
                            to: Some(1),
                            stiffness: params.k_s,
                            damping: params.c_s,
                        },
                        tire(2),
                        Element {
                            from: 1,
                            to: Some(2),
                            stiffness: params.k_h,
                            damping: params.c_h,
                        },
                    ],
                    feedback: vec![0.0, -g, g],
                }
            }
        })
    }

    /// Number of coordinates (degrees of freedom).
    pub fn dimension(&self) -> usize {
        self.coordinates.len()
    }

    /// The index of the wheel coordinate `x_t`.
    pub fn wheel(&self) -> usize {
        self.dimension() - 1
    }

    /// The element joining coordinates i and j (i ≠ j), if any.
    pub fn joining(&self, i: usize, j: usize) -> Option<&Element> {
        self.elements
            .iter()
            .find(|e| (e.from == i && e.to == Some(j)) || (e.from == j && e.to == Some(i)))
    }

    /// The elements that act on coordinate i, in order.
    pub fn acting_on(&self, i: usize) -> impl Iterator<Item = &Element> {
        self.elements
            .iter()
            .filter(move |e| e.from == i || e.to == Some(i))
    }

    /// Entry (i, j) of a matrix assembled from the elements: the sum of
    /// `value(element)` over the elements acting on i on the diagonal, minus
    /// the value of the element joining i and j off it, `None` where no
    /// element joins them.
    pub fn assemble<T>(
        &self,
        i: usize,
        j: usize,
        zero: T,
        value: impl Fn(&Element) -> T,
    ) -> Option<T>
    where
        T: std::ops::Add<Output = T> + std::ops::Neg<Output = T>,
    {
        if i == j {
            Some(self.acting_on(i).fold(zero, |sum, e| sum + value(e)))
        } else {
            self.joining(i, j).map(|e| -value(e))
        }
    }

    /// `K_ij` (N/m), `None` where no element joins i and j.
    pub fn stiffness(&self, i: usize, j: usize) -> Option<f64> {
        self.assemble(i, j, 0.0, |e| e.stiffness)
    }

    /// `C_ij` (N·s/m), `None` where no element joins i and j.
    pub fn damping(&self, i: usize, j: usize) -> Option<f64> {
        self.assemble(i, j, 0.0, |e| e.damping)
    }

    /// The road's stiffness on coordinate i (N/m): `k_t` on the wheel.
    pub fn road_stiffness(&self, i: usize) -> f64 {
        self.acting_on(i)
            .filter(|e| e.to.is_none())
            .map(|e| e.stiffness)
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matrices_of_eq1() {
        let p = Params::default();
        let m = MassSpringDamper::new(&p, Variant::Tdvass).unwrap();
        assert_eq!(m.stiffness(1, 1), Some(p.k_s + p.k_h));
        assert_eq!(m.stiffness(2, 2), Some(p.k_t + p.k_h));
        assert_eq!(m.stiffness(0, 1), Some(-p.k_s));
        assert_eq!(m.stiffness(0, 2), None);
        assert_eq!(m.damping(2, 2), Some(p.c_h));
        assert_eq!(m.road_stiffness(2), p.k_t);
        assert_eq!(m.feedback, vec![0.0, -p.g, p.g]);
        let cs = MassSpringDamper::new(&p, Variant::Cs).unwrap();
        assert_eq!(cs.stiffness(1, 1), Some(p.k_s + p.k_t));
        assert_eq!(cs.damping(1, 1), Some(p.c_s));
        assert_eq!(cs.feedback, vec![0.0, 0.0]);
        let pvass = MassSpringDamper::new(&p, Variant::Pvass).unwrap();
        assert_eq!(pvass.feedback, vec![0.0, -0.0, 0.0]);
        assert!(MassSpringDamper::new(&Params { m_h: 0.0, ..p }, Variant::Pvass).is_err());
    }
}
