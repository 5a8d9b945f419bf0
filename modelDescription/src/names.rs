//! The XML spellings of the enumerations, in one place so that the reader, the writer and the
//! validator's messages can never disagree about them.

use std::fmt;

use crate::types::{BaseType, Causality, Initial, Variability};

impl Causality {
    /// All causalities, in the order the FMI 2.0 specification lists them.
    pub const ALL: [Causality; 6] = [
        Causality::Parameter,
        Causality::CalculatedParameter,
        Causality::Input,
        Causality::Output,
        Causality::Local,
        Causality::Independent,
    ];

    /// The attribute value as written in `modelDescription.xml`.
    pub fn as_str(self) -> &'static str {
        match self {
            Causality::Parameter => "parameter",
            Causality::CalculatedParameter => "calculatedParameter",
            Causality::Input => "input",
            Causality::Output => "output",
            Causality::Local => "local",
            Causality::Independent => "independent",
        }
    }

    /// Parses the exact (case-sensitive) XML spelling.
    pub fn from_xml_name(s: &str) -> Option<Causality> {
        Causality::ALL.into_iter().find(|c| c.as_str() == s)
    }
}

impl Variability {
    /// All variabilities, in the order the FMI 2.0 specification lists them.
    pub const ALL: [Variability; 5] = [
        Variability::Constant,
        Variability::Fixed,
        Variability::Tunable,
        Variability::Discrete,
        Variability::Continuous,
    ];

    /// The attribute value as written in `modelDescription.xml`.
    pub fn as_str(self) -> &'static str {
        match self {
            Variability::Constant => "constant",
            Variability::Fixed => "fixed",
            Variability::Tunable => "tunable",
            Variability::Discrete => "discrete",
            Variability::Continuous => "continuous",
        }
    }

    /// Parses the exact (case-sensitive) XML spelling.
    pub fn from_xml_name(s: &str) -> Option<Variability> {
        Variability::ALL.into_iter().find(|v| v.as_str() == s)
    }
}

impl Initial {
    /// All values of `initial`.
    pub const ALL: [Initial; 3] = [Initial::Exact, Initial::Approx, Initial::Calculated];

    /// The attribute value as written in `modelDescription.xml`.
    pub fn as_str(self) -> &'static str {
        match self {
            Initial::Exact => "exact",
            Initial::Approx => "approx",
            Initial::Calculated => "calculated",
        }
    }

    /// Parses the exact (case-sensitive) XML spelling.
    pub fn from_xml_name(s: &str) -> Option<Initial> {
        Initial::ALL.into_iter().find(|i| i.as_str() == s)
    }
}

impl BaseType {
    /// The element name inside `ScalarVariable` / `SimpleType`.
    pub fn as_str(self) -> &'static str {
        match self {
            BaseType::Real => "Real",
            BaseType::Integer => "Integer",
            BaseType::Boolean => "Boolean",
            BaseType::String => "String",
            BaseType::Enumeration => "Enumeration",
        }
    }

    /// Parses an element name ("Real", "Integer", ...).
    pub fn from_xml_name(s: &str) -> Option<BaseType> {
        [
            BaseType::Real,
            BaseType::Integer,
            BaseType::Boolean,
            BaseType::String,
            BaseType::Enumeration,
        ]
        .into_iter()
        .find(|b| b.as_str() == s)
    }

    /// The value-reference space: FMI 2.0 has four (Real, Integer, Boolean, String), and
    /// Enumeration variables are read and written through the Integer functions.
    pub fn value_reference_space(self) -> BaseType {
        match self {
            BaseType::Enumeration => BaseType::Integer,
            other => other,
        }
    }
}

macro_rules! display_as_str {
    ($($t:ty),*) => {$(
        impl fmt::Display for $t {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str(self.as_str())
            }
        }
    )*};
}

display_as_str!(Causality, Variability, Initial, BaseType);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spellings_round_trip() {
        for c in Causality::ALL {
            assert_eq!(Causality::from_xml_name(c.as_str()), Some(c));
        }
        for v in Variability::ALL {
            assert_eq!(Variability::from_xml_name(v.as_str()), Some(v));
        }
        for i in Initial::ALL {
            assert_eq!(Initial::from_xml_name(i.as_str()), Some(i));
        }
        assert_eq!(
            Causality::from_xml_name("Input"),
            None,
            "XML names are case-sensitive"
        );
        assert_eq!(
            Causality::CalculatedParameter.to_string(),
            "calculatedParameter"
        );
        assert_eq!(
            BaseType::Enumeration.value_reference_space(),
            BaseType::Integer
        );
    }
}
