//! The variable table an FMU crate declares once, and the value store built from it.
//!
//! The same `&'static [VarSpec]` drives three things: the values the FMU holds (and checks get/set
//! against), the modelDescription.xml written at packaging time, and the HTML documentation. So
//! the XML can never drift from the code. Value references are explicit constants in the FMU
//! crate, numbered densely from 0 within each base type, which is what makes the store a set of
//! plain vectors indexed by value reference.

use model_description::{Causality, Initial, Variability};
use serde::{Deserialize, Serialize};

/// The base type and start value of a variable.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Start {
    /// A Real, exchanged with fmi2GetReal/fmi2SetReal.
    Real(f64),
    /// An Integer, exchanged with fmi2GetInteger/fmi2SetInteger.
    Integer(i32),
    /// A Boolean, exchanged with fmi2GetBoolean/fmi2SetBoolean.
    Boolean(bool),
    /// A String, exchanged with fmi2GetString/fmi2SetString.
    String(&'static str),
}

/// One row of the variable table.
#[derive(Debug, Clone, Copy)]
pub struct VarSpec {
    /// The value reference: dense from 0 within the variable's base type, as it indexes [`Values`].
    pub vr: u32,
    /// The `name` in modelDescription.xml, and what the layer's messages quote.
    pub name: &'static str,
    /// The `description` in modelDescription.xml and the documentation's table: what it means, its
    /// sign convention.
    pub description: &'static str,
    /// Written as `causality`; with `variability` it decides in which states the layer accepts a
    /// set.
    pub causality: Causality,
    /// Written as `variability`; only tunable parameters may be set between steps.
    pub variability: Variability,
    /// `None` writes no `initial` attribute (required for inputs).
    pub initial: Option<Initial>,
    /// The base type, and the start value written to the XML and held before the first set.
    pub start: Start,
    /// Whether the start value is written to the XML (not for `initial="calculated"`).
    pub has_start: bool,
    /// The `unit` of a Real (SI, as written, e.g. "m/s2"); declared in `UnitDefinitions`.
    pub unit: Option<&'static str>,
    /// Written as `min`; for parameters the layer also refuses a value below it at
    /// fmi2ExitInitializationMode.
    pub min: Option<f64>,
    /// Written as `max`; for parameters the layer also refuses a value above it at
    /// fmi2ExitInitializationMode.
    pub max: Option<f64>,
}

impl VarSpec {
    const fn new(vr: u32, name: &'static str, start: Start, description: &'static str) -> Self {
        VarSpec {
            vr,
            name,
            description,
            causality: Causality::Local,
            variability: Variability::Continuous,
            initial: None,
            start,
            has_start: true,
            unit: None,
            min: None,
            max: None,
        }
    }

    /// A continuous real input; inputs carry a start value and no `initial`.
    pub const fn real_input(
        vr: u32,
        name: &'static str,
        unit: &'static str,
        start: f64,
        description: &'static str,
    ) -> Self {
        let mut v = Self::new(vr, name, Start::Real(start), description);
        v.causality = Causality::Input;
        v.unit = Some(unit);
        v
    }

    /// A real output computed by each step; `start` is its value before the first step.
    pub const fn real_output(
        vr: u32,
        name: &'static str,
        unit: &'static str,
        start: f64,
        description: &'static str,
    ) -> Self {
        let mut v = Self::new(vr, name, Start::Real(start), description);
        v.causality = Causality::Output;
        v.initial = Some(Initial::Exact);
        v.unit = Some(unit);
        v
    }

    /// A real output whose initial value depends on parameters (listed in InitialUnknowns).
    pub const fn real_output_calculated(
        vr: u32,
        name: &'static str,
        unit: &'static str,
        description: &'static str,
    ) -> Self {
        let mut v = Self::real_output(vr, name, unit, 0.0, description);
        v.initial = Some(Initial::Calculated);
        v.has_start = false;
        v
    }

    /// A fixed real parameter (set before initialization only).
    pub const fn real_parameter(
        vr: u32,
        name: &'static str,
        unit: &'static str,
        start: f64,
        description: &'static str,
    ) -> Self {
        let mut v = Self::new(vr, name, Start::Real(start), description);
        v.causality = Causality::Parameter;
        v.variability = Variability::Fixed;
        v.initial = Some(Initial::Exact);
        v.unit = Some(unit);
        v
    }

    /// A fixed Integer parameter (set before initialization ends only).
    pub const fn integer_parameter(
        vr: u32,
        name: &'static str,
        start: i32,
        description: &'static str,
    ) -> Self {
        let mut v = Self::new(vr, name, Start::Integer(start), description);
        v.causality = Causality::Parameter;
        v.variability = Variability::Fixed;
        v.initial = Some(Initial::Exact);
        v
    }

    /// A fixed Boolean parameter (set before initialization ends only).
    pub const fn boolean_parameter(
        vr: u32,
        name: &'static str,
        start: bool,
        description: &'static str,
    ) -> Self {
        let mut v = Self::new(vr, name, Start::Boolean(start), description);
        v.causality = Causality::Parameter;
        v.variability = Variability::Fixed;
        v.initial = Some(Initial::Exact);
        v
    }

    /// A fixed String parameter (set before initialization ends only).
    pub const fn string_parameter(
        vr: u32,
        name: &'static str,
        start: &'static str,
        description: &'static str,
    ) -> Self {
        let mut v = Self::new(vr, name, Start::String(start), description);
        v.causality = Causality::Parameter;
        v.variability = Variability::Fixed;
        v.initial = Some(Initial::Exact);
        v
    }

    /// A discrete Boolean input (changes only at communication points); inputs carry a start
    /// value and no `initial`.
    pub const fn boolean_input(
        vr: u32,
        name: &'static str,
        start: bool,
        description: &'static str,
    ) -> Self {
        let mut v = Self::new(vr, name, Start::Boolean(start), description);
        v.causality = Causality::Input;
        v.variability = Variability::Discrete;
        v
    }

    /// A discrete Integer input (changes only at communication points); inputs carry a start
    /// value and no `initial`.
    pub const fn integer_input(
        vr: u32,
        name: &'static str,
        start: i32,
        description: &'static str,
    ) -> Self {
        let mut v = Self::new(vr, name, Start::Integer(start), description);
        v.causality = Causality::Input;
        v.variability = Variability::Discrete;
        v
    }

    /// A discrete Integer output set by each step; `start` is its value before the first step.
    pub const fn integer_output(
        vr: u32,
        name: &'static str,
        start: i32,
        description: &'static str,
    ) -> Self {
        let mut v = Self::new(vr, name, Start::Integer(start), description);
        v.causality = Causality::Output;
        v.variability = Variability::Discrete;
        v.initial = Some(Initial::Exact);
        v
    }

    /// A discrete Boolean output set by each step; `start` is its value before the first step.
    pub const fn boolean_output(
        vr: u32,
        name: &'static str,
        start: bool,
        description: &'static str,
    ) -> Self {
        let mut v = Self::new(vr, name, Start::Boolean(start), description);
        v.causality = Causality::Output;
        v.variability = Variability::Discrete;
        v.initial = Some(Initial::Exact);
        v
    }

    /// A Real that changes only at communication points (a sampled or switched signal):
    /// masters hold it between them rather than interpolate it.
    pub const fn discrete(mut self) -> Self {
        self.variability = Variability::Discrete;
        self
    }

    /// Parameters a master may change between steps.
    pub const fn tunable(mut self) -> Self {
        self.variability = Variability::Tunable;
        self
    }

    /// Sets the `min` field: written to the XML, and enforced on parameters.
    pub const fn min(mut self, min: f64) -> Self {
        self.min = Some(min);
        self
    }

    /// Sets the `max` field: written to the XML, and enforced on parameters.
    pub const fn max(mut self, max: f64) -> Self {
        self.max = Some(max);
        self
    }

    /// Which value-reference space the variable lives in, from its start value's type.
    pub fn base(&self) -> Base {
        match self.start {
            Start::Real(_) => Base::Real,
            Start::Integer(_) => Base::Integer,
            Start::Boolean(_) => Base::Boolean,
            Start::String(_) => Base::String,
        }
    }

    /// Parameters are range-checked at fmi2ExitInitializationMode and trigger
    /// `Model::parameters_changed` when tuned.
    pub fn is_parameter(&self) -> bool {
        self.causality == Causality::Parameter
    }
}

/// The four value-reference spaces of FMI 2.0.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Base {
    /// fmi2GetReal / fmi2SetReal.
    Real,
    /// fmi2GetInteger / fmi2SetInteger.
    Integer,
    /// fmi2GetBoolean / fmi2SetBoolean.
    Boolean,
    /// fmi2GetString / fmi2SetString.
    String,
}

impl Base {
    /// The four spaces, for code that must cover each (the fuzzer picks from them).
    pub const ALL: [Base; 4] = [Base::Real, Base::Integer, Base::Boolean, Base::String];

    /// The FMI type name, as the XML element and the fmi2Get/fmi2Set functions spell it.
    pub fn name(self) -> &'static str {
        match self {
            Base::Real => "Real",
            Base::Integer => "Integer",
            Base::Boolean => "Boolean",
            Base::String => "String",
        }
    }
}

/// Looks up a variable's table row by base type and value reference.
#[derive(Debug, Clone)]
pub struct VarIndex {
    real: Vec<usize>,
    integer: Vec<usize>,
    boolean: Vec<usize>,
    string: Vec<usize>,
}

impl VarIndex {
    /// Builds the index and checks that value references are dense and unique per base type;
    /// a table that breaks this is a programming error of the FMU crate, reported by name.
    pub fn new(table: &[VarSpec]) -> Result<VarIndex, String> {
        let mut idx = VarIndex {
            real: vec![],
            integer: vec![],
            boolean: vec![],
            string: vec![],
        };
        for (row, v) in table.iter().enumerate() {
            let list = idx.list_mut(v.base());
            let vr = v.vr as usize;
            if list.len() <= vr {
                list.resize(vr + 1, usize::MAX);
            }
            if list[vr] != usize::MAX {
                return Err(format!(
                    "variables '{}' and '{}' share {} value reference {}",
                    table[list[vr]].name,
                    v.name,
                    v.base().name(),
                    vr
                ));
            }
            list[vr] = row;
        }
        for base in [Base::Real, Base::Integer, Base::Boolean, Base::String] {
            if let Some(gap) = idx.list(base).iter().position(|&r| r == usize::MAX) {
                return Err(format!(
                    "{} value reference {} is not used: value references must be dense",
                    base.name(),
                    gap
                ));
            }
        }
        Ok(idx)
    }

    fn list(&self, base: Base) -> &Vec<usize> {
        match base {
            Base::Real => &self.real,
            Base::Integer => &self.integer,
            Base::Boolean => &self.boolean,
            Base::String => &self.string,
        }
    }

    fn list_mut(&mut self, base: Base) -> &mut Vec<usize> {
        match base {
            Base::Real => &mut self.real,
            Base::Integer => &mut self.integer,
            Base::Boolean => &mut self.boolean,
            Base::String => &mut self.string,
        }
    }

    /// The table row of `vr` in `base`, if it exists.
    pub fn row(&self, base: Base, vr: u32) -> Option<usize> {
        self.list(base).get(vr as usize).copied()
    }
}

/// The current values of every variable, indexed by value reference within each base type.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Values {
    /// Real values, by value reference.
    pub real: Vec<f64>,
    /// Integer values, by value reference.
    pub integer: Vec<i32>,
    /// Boolean values, by value reference.
    pub boolean: Vec<bool>,
    /// String values, by value reference.
    pub string: Vec<String>,
}

impl Values {
    /// The start values of the table (zero for calculated variables).
    pub fn from_table(table: &[VarSpec]) -> Values {
        let count = |b: Base| table.iter().filter(|v| v.base() == b).count();
        let mut values = Values {
            real: vec![0.0; count(Base::Real)],
            integer: vec![0; count(Base::Integer)],
            boolean: vec![false; count(Base::Boolean)],
            string: vec![String::new(); count(Base::String)],
        };
        for v in table {
            let i = v.vr as usize;
            match v.start {
                Start::Real(x) => values.real[i] = x,
                Start::Integer(x) => values.integer[i] = x,
                Start::Boolean(x) => values.boolean[i] = x,
                Start::String(x) => values.string[i] = x.to_string(),
            }
        }
        values
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TABLE: &[VarSpec] = &[
        VarSpec::real_input(0, "u", "m", 0.0, "input"),
        VarSpec::real_output(1, "y", "m", 0.0, "output"),
        VarSpec::integer_parameter(0, "n", 3, "count"),
    ];

    #[test]
    fn values_start_from_the_table() {
        let v = Values::from_table(TABLE);
        assert_eq!(v.real, vec![0.0, 0.0]);
        assert_eq!(v.integer, vec![3]);
    }

    #[test]
    fn duplicate_and_sparse_value_references_are_refused() {
        let dup = [
            VarSpec::real_input(0, "a", "m", 0.0, ""),
            VarSpec::real_input(0, "b", "m", 0.0, ""),
        ];
        let err = VarIndex::new(&dup).unwrap_err();
        assert!(err.contains("'a'") && err.contains("'b'"), "{err}");
        let gap = [VarSpec::real_input(1, "a", "m", 0.0, "")];
        assert!(VarIndex::new(&gap).unwrap_err().contains("dense"));
        let idx = VarIndex::new(TABLE).unwrap();
        assert_eq!(idx.row(Base::Real, 1), Some(1));
        assert_eq!(idx.row(Base::Integer, 0), Some(2));
        assert_eq!(idx.row(Base::Boolean, 0), None);
    }
}
