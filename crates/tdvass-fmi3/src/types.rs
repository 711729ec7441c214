//! The FMI 3.0 type of each variable of the one table: Float64 for Reals
//! (scalars and arrays), Enumeration for Integer settings with named codes,
//! UInt64 for structural parameters (array sizes), Int32 for the other
//! Integers (`road_seed`, `input_extrapolation`, the count `lift_off_count`),
//! Boolean.

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

/// The value types of the FMI 3.0 getters and setters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ValueType {
    Float32,
    Float64,
    Int8,
    UInt8,
    Int16,
    UInt16,
    Int32,
    UInt32,
    Int64,
    UInt64,
    Boolean,
    String,
    Binary,
}

impl ValueType {
    /// Every value type.
    pub const ALL: [ValueType; 13] = [
        ValueType::Float32,
        ValueType::Float64,
        ValueType::Int8,
        ValueType::UInt8,
        ValueType::Int16,
        ValueType::UInt16,
        ValueType::Int32,
        ValueType::UInt32,
        ValueType::Int64,
        ValueType::UInt64,
        ValueType::Boolean,
        ValueType::String,
        ValueType::Binary,
    ];

    /// The getter's C name.
    pub fn getter(self) -> &'static str {
        match self {
            ValueType::Float32 => "fmi3GetFloat32",
            ValueType::Float64 => "fmi3GetFloat64",
            ValueType::Int8 => "fmi3GetInt8",
            ValueType::UInt8 => "fmi3GetUInt8",
            ValueType::Int16 => "fmi3GetInt16",
            ValueType::UInt16 => "fmi3GetUInt16",
            ValueType::Int32 => "fmi3GetInt32",
            ValueType::UInt32 => "fmi3GetUInt32",
            ValueType::Int64 => "fmi3GetInt64",
            ValueType::UInt64 => "fmi3GetUInt64",
            ValueType::Boolean => "fmi3GetBoolean",
            ValueType::String => "fmi3GetString",
            ValueType::Binary => "fmi3GetBinary",
        }
    }

    /// The setter's C name.
    pub fn setter(self) -> &'static str {
        match self {
            ValueType::Float32 => "fmi3SetFloat32",
            ValueType::Float64 => "fmi3SetFloat64",
            ValueType::Int8 => "fmi3SetInt8",
            ValueType::UInt8 => "fmi3SetUInt8",
            ValueType::Int16 => "fmi3SetInt16",
            ValueType::UInt16 => "fmi3SetUInt16",
            ValueType::Int32 => "fmi3SetInt32",
            ValueType::UInt32 => "fmi3SetUInt32",
            ValueType::Int64 => "fmi3SetInt64",
            ValueType::UInt64 => "fmi3SetUInt64",
            ValueType::Boolean => "fmi3SetBoolean",
            ValueType::String => "fmi3SetString",
            ValueType::Binary => "fmi3SetBinary",
        }
    }

    /// The type name (`Float64`, ...).
    pub fn name(self) -> &'static str {
        &self.getter()["fmi3Get".len()..]
    }
}

impl Fmi3Type {
    /// The getter and setter type of a variable of this type
    /// (Enumerations are Int64).
    pub fn value_type(self) -> ValueType {
        match self {
            Fmi3Type::Float64 => ValueType::Float64,
            Fmi3Type::Int32 => ValueType::Int32,
            Fmi3Type::UInt64 => ValueType::UInt64,
            Fmi3Type::Boolean => ValueType::Boolean,
            Fmi3Type::Enumeration => ValueType::Int64,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tdvass_fmu::Model;
    use tdvass_fmu::variables::{FMI3_VARIABLES, FmiVersion, by_name};

    #[test]
    fn every_variable_has_the_type_the_interface_names() {
        let type_of =
            |name: &str| fmi3_type(by_name(Model::QuarterCar, FmiVersion::Fmi3, name).unwrap());
        assert_eq!(type_of("variant"), Fmi3Type::Enumeration);
        assert_eq!(type_of("road"), Fmi3Type::Enumeration);
        assert_eq!(type_of("road_class"), Fmi3Type::Enumeration);
        assert_eq!(type_of("tire_contact"), Fmi3Type::Enumeration);
        assert_eq!(type_of("lift_off_count"), Fmi3Type::Int32);
        assert_eq!(type_of("road_seed"), Fmi3Type::Int32);
        assert_eq!(type_of("stable"), Fmi3Type::Boolean);
        assert_eq!(type_of("root_count"), Fmi3Type::UInt64);
        assert_eq!(type_of("rightmost_roots"), Fmi3Type::Float64);
        assert!(
            FMI3_VARIABLES
                .iter()
                .all(|v| v.var_type() != VarType::String)
        );
    }
}
