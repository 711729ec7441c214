//! The quarter-car models of the paper: parameters (Table 1), the three
//! variants and the linear state-space form of Eq. (2).
//!
//! The state is `X = [x_s, v_s, x_h, v_h, x_t, v_t]` (m, m/s) for every
//! variant. For the two-degree-of-freedom conventional suspension the
//! absorber coordinates carry no dynamics (their rows and columns of A are
//! zero and they stay at zero); outputs report `x_h = x_t`, `v_h = v_t`.

mod body;
pub mod dynamics;
mod equations;
pub mod inputs;
mod params;
mod plant;
mod tire;

pub use body::Body;
pub use equations::{Element, MassSpringDamper};
pub(crate) use params::check;
pub use params::{
    PAPER_G1, PAPER_G2, PAPER_TAU1, PAPER_TAU2, Params, STANDARD_GRAVITY, STATE_NAMES, State, V_H,
    V_S, V_T, Variant, X_H, X_S, X_T,
};
pub use plant::{Performance, Plant};
pub use tire::TireContact;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::Error;

    #[test]
    fn table1_defaults_are_valid() {
        Params::default().validate().unwrap();
    }

    #[test]
    fn attaching_the_body_zeroes_its_velocity_row_of_a_and_nothing_else() {
        // Neither the control force nor the road acts on the body: the
        // rows of b and e that the prescribed coordinates' law zeroes are
        // zero already, so the corner's plant is the quarter car's but for
        // A's body row.
        for variant in Variant::ALL {
            let plant = Plant::new(Params::default(), variant).unwrap();
            let attached = plant.clone().with_body(Body::Attached);
            assert_eq!(attached.b, plant.b, "{variant:?}");
            assert_eq!(attached.e, plant.e, "{variant:?}");
            assert!(attached.a.row(V_S).iter().all(|v| *v == 0.0));
            for row in [X_S, X_H, V_H, X_T, V_T] {
                assert_eq!(
                    attached.a.row(row),
                    plant.a.row(row),
                    "{variant:?} row {row}"
                );
            }
        }
    }

    #[test]
    fn invalid_parameters_name_the_parameter_and_value() {
        let p = Params {
            m_h: -1.0,
            ..Params::default()
        };
        let err = p.validate().unwrap_err();
        assert_eq!(
            err,
            Error::InvalidParameter {
                name: "m_h",
                value: -1.0,
                reason: "a mass must be > 0"
            }
        );
        assert!(err.to_string().contains("m_h") && err.to_string().contains("-1"));
        let p = Params {
            tau: f64::NAN,
            ..Params::default()
        };
        assert!(matches!(
            p.validate(),
            Err(Error::InvalidParameter { name: "tau", .. })
        ));
        let p = Params {
            c_s: f64::INFINITY,
            ..Params::default()
        };
        assert!(matches!(
            p.validate(),
            Err(Error::InvalidParameter { name: "c_s", .. })
        ));
        assert!(Plant::new(p, Variant::Cs).is_err());
    }

    #[test]
    fn matrices_match_eq2() {
        let p = Params::default();
        let plant = Plant::new(p, Variant::Tdvass).unwrap();
        assert_eq!(plant.a[(V_H, V_H)], -(p.c_s + p.c_h) / p.m_h);
        assert_eq!(plant.a[(V_T, X_T)], -(p.k_h + p.k_t) / p.m_t);
        assert_eq!(plant.b[V_H], -p.g / p.m_h);
        assert_eq!(plant.b[V_T], p.g / p.m_t);
        assert_eq!(plant.e[V_T], p.k_t / p.m_t);
        let pv = Plant::new(p, Variant::Pvass).unwrap();
        assert_eq!(pv.b, State::zeros());
        assert_eq!(pv.a, plant.a);
    }

    #[test]
    fn static_load_and_deflection_follow_the_weights_on_the_springs() {
        let p = Params::default();
        let g0 = STANDARD_GRAVITY;
        assert_eq!(p.static_load(Variant::Tdvass), (345.0 + 4.05 + 40.5) * g0);
        assert_eq!(
            p.static_load(Variant::Pvass),
            p.static_load(Variant::Tdvass)
        );
        assert_eq!(p.static_load(Variant::Cs), (345.0 + 40.5) * g0);
        let absorber = 345.0 * g0 / 16000.0 + (345.0 + 4.05) * g0 / 6444.0;
        assert!((p.static_deflection(Variant::Pvass) - absorber).abs() < 1e-15);
        assert!((absorber - 0.742_649).abs() < 1e-6);
        assert_eq!(p.static_deflection(Variant::Cs), 345.0 * g0 / 16000.0);
        let loose = Params { k_h: 0.0, ..p };
        assert_eq!(loose.static_deflection(Variant::Pvass), f64::INFINITY);
    }

    #[test]
    fn cs_is_the_two_dof_quarter_car() {
        let p = Params::default();
        let cs = Plant::new(p, Variant::Cs).unwrap();
        // Static equilibrium under a unit road displacement: everything at 1.
        let x = State::new(1.0, 0.0, 0.0, 0.0, 1.0, 0.0);
        let dx = cs.derivative(&x, 0.0, 1.0);
        assert!(dx.norm() < 1e-12, "{dx}");
        assert_eq!(cs.a.row(X_H).norm() + cs.a.row(V_H).norm(), 0.0);
        assert_eq!(cs.a.column(X_H).norm() + cs.a.column(V_H).norm(), 0.0);
        let y = cs.reported_state(&x);
        assert_eq!(y[X_H], 1.0);
    }

    #[test]
    fn variant_codes_round_trip() {
        for v in Variant::ALL {
            assert_eq!(Variant::from_code(v.code() as i64).unwrap(), v);
            assert_eq!(v.name().parse::<Variant>().unwrap(), v);
        }
        assert!(Variant::from_code(4).is_err());
    }
}
