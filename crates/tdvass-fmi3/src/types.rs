//! The FMI 3.0 type of each variable of the one table: Float64 for Reals
//! (scalars and arrays), Enumeration for Integer settings with named codes,
//! UInt64 for structural parameters (array sizes), Int32 for the other
//! Integers, Boolean.

use tdvass_fmu::variables::{Causality, VarType, Variable};

/// An FMI 3.0 variable type (the ones this FMU uses).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Fmi3Type {
    Float64,
    Int32,
    UInt64,
    Boolean,
    /// Read and written with `fmi3GetInt64` / `fmi3SetInt64`.
    Enumeration,
}

impl Fmi3Type {
    /// The element name in `ModelVariables`.
    pub fn as_str(self) -> &'static str {
        match self {
            Fmi3Type::Float64 => "Float64",
            Fmi3Type::Int32 => "Int32",
            Fmi3Type::UInt64 => "UInt64",
            Fmi3Type::Boolean => "Boolean",
            Fmi3Type::Enumeration => "Enumeration",
        }
    }
}

/// The FMI 3.0 type of `v`.
pub fn fmi3_type(v: &Variable) -> Fmi3Type {
    match v.var_type() {
        VarType::Real => Fmi3Type::Float64,
        VarType::Boolean => Fmi3Type::Boolean,
        VarType::Integer if v.enumeration.is_some() => Fmi3Type::Enumeration,
        VarType::Integer if v.causality == Causality::StructuralParameter => Fmi3Type::UInt64,
        VarType::Integer | VarType::String => Fmi3Type::Int32,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tdvass_fmu::variables::{ALL_VARIABLES, by_name};

    #[test]
    fn every_variable_has_the_type_the_interface_names() {
        let type_of = |name: &str| fmi3_type(by_name(name).unwrap());
        assert_eq!(type_of("variant"), Fmi3Type::Enumeration);
        assert_eq!(type_of("road"), Fmi3Type::Enumeration);
        assert_eq!(type_of("road_class"), Fmi3Type::Enumeration);
        assert_eq!(type_of("road_seed"), Fmi3Type::Int32);
        assert_eq!(type_of("stable"), Fmi3Type::Boolean);
        assert_eq!(type_of("root_count"), Fmi3Type::UInt64);
        assert_eq!(type_of("rightmost_roots"), Fmi3Type::Float64);
        assert!(ALL_VARIABLES.iter().all(|v| v.var_type() != VarType::String));
    }
}
