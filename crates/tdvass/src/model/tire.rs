//! The tire's contact law: the paper's linear tire, which pulls as well as
//! pushes, or a unilateral one, which cannot pull, so the wheel can leave
//! the road.

use crate::error::{Error, Result};

/// How the tire acts between road and wheel.
///
/// With the static load W ([`super::Params::static_load`]) the total tire
/// force is `W + k_t (x_g − x_t)` (N). In the model's deviation
/// coordinates the dynamic tire force on the wheel is
/// - [`TireContact::Bilateral`]: `k_t (x_g − x_t)`, Eq. (1), also where it
///   falls below −W (the tire would pull the wheel down);
/// - [`TireContact::Unilateral`]: `max(−W, k_t (x_g − x_t))`: the wheel
///   lifts off where `TDD = x_t − x_g` rises through `W/k_t`, flies under
///   the suspension forces and −W, and touches down where TDD falls back
///   to `W/k_t`.
///
/// Both modes are linear, so each keeps the exact step; the switches are
/// located inside the steps (see `solver::contact`). The stability and
/// frequency-response analyses are about the linear (bilateral) model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum TireContact {
    /// The paper's linear tire (the default).
    #[default]
    Bilateral,
    /// A tire that cannot pull: the wheel can lift off.
    Unilateral,
}

impl TireContact {
    /// Both laws, in code order.
    pub const ALL: [TireContact; 2] = [TireContact::Bilateral, TireContact::Unilateral];

    /// The FMU's integer code: 0 = bilateral, 1 = unilateral.
    pub fn code(self) -> i32 {
        match self {
            TireContact::Bilateral => 0,
            TireContact::Unilateral => 1,
        }
    }

    /// Inverse of [`TireContact::code`].
    pub fn from_code(code: i64) -> Result<TireContact> {
        match code {
            0 => Ok(TireContact::Bilateral),
            1 => Ok(TireContact::Unilateral),
            _ => Err(Error::InvalidSetting {
                name: "tire_contact",
                value: code,
                reason: "must be 0 (bilateral) or 1 (unilateral)",
            }),
        }
    }

    /// Lower-case name as used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            TireContact::Bilateral => "bilateral",
            TireContact::Unilateral => "unilateral",
        }
    }

    /// Whether the wheel can leave the road.
    pub fn is_unilateral(self) -> bool {
        self == TireContact::Unilateral
    }
}

impl std::str::FromStr for TireContact {
    type Err = Error;
    fn from_str(s: &str) -> Result<TireContact> {
        match s.to_ascii_lowercase().as_str() {
            "bilateral" | "0" => Ok(TireContact::Bilateral),
            "unilateral" | "1" => Ok(TireContact::Unilateral),
            _ => Err(Error::UnknownName {
                what: "tire contact",
                given: s.to_string(),
                expected: "bilateral or unilateral (or their codes 0, 1; any case)",
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_and_names_round_trip() {
        for contact in TireContact::ALL {
            assert_eq!(TireContact::from_code(contact.code().into()), Ok(contact));
            assert_eq!(contact.name().parse(), Ok(contact));
        }
        assert!(TireContact::from_code(2).is_err());
        let err = "sticky".parse::<TireContact>().unwrap_err().to_string();
        assert!(err.contains("sticky"), "{err}");
    }
}
