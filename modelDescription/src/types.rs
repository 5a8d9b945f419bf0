//! The typed content of an FMI 2.0 `modelDescription.xml` (FMI 2.0.5 spec, section 2.2).
//!
//! These are plain data types: they carry no XML detail, so the FMU crates can build them from
//! their variable tables and the orchestrator can inspect what it read. Optional XML attributes
//! are `Option`s; attributes with a default in the standard hold the default after reading.

/// The root element `fmiModelDescription`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ModelDescription {
    /// Always "2.0" for what we write; kept as read otherwise.
    pub fmi_version: String,
    pub model_name: String,
    pub guid: String,
    pub description: Option<String>,
    pub author: Option<String>,
    pub version: Option<String>,
    pub copyright: Option<String>,
    pub license: Option<String>,
    pub generation_tool: Option<String>,
    pub generation_date_and_time: Option<String>,
    /// "flat" (default) or "structured".
    pub variable_naming_convention: Option<String>,
    pub number_of_event_indicators: Option<u32>,
    pub co_simulation: Option<CoSimulation>,
    /// Only the identifier is kept: we neither export nor import model exchange.
    pub model_exchange_identifier: Option<String>,
    pub unit_definitions: Vec<Unit>,
    pub type_definitions: Vec<SimpleType>,
    pub log_categories: Vec<Category>,
    pub default_experiment: Option<DefaultExperiment>,
    pub model_variables: Vec<ScalarVariable>,
    pub model_structure: ModelStructure,
}

/// The `CoSimulation` element and its capability flags (all default to false).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct CoSimulation {
    pub model_identifier: String,
    pub needs_execution_tool: bool,
    pub can_handle_variable_communication_step_size: bool,
    pub can_interpolate_inputs: bool,
    pub max_output_derivative_order: u32,
    /// Spelled `canRunAsynchronuously` in the standard.
    pub can_run_asynchronuously: bool,
    pub can_be_instantiated_only_once_per_process: bool,
    pub can_not_use_memory_management_functions: bool,
    pub can_get_and_set_fmu_state: bool,
    pub can_serialize_fmu_state: bool,
    pub provides_directional_derivative: bool,
}

/// A `Unit` of `UnitDefinitions`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Unit {
    pub name: String,
    pub base_unit: Option<BaseUnit>,
    pub display_units: Vec<DisplayUnit>,
}

/// SI exponents plus factor and offset: value_SI = factor * value + offset.
#[derive(Debug, Clone, PartialEq)]
pub struct BaseUnit {
    pub kg: i32,
    pub m: i32,
    pub s: i32,
    pub a: i32,
    pub k: i32,
    pub mol: i32,
    pub cd: i32,
    pub rad: i32,
    pub factor: f64,
    pub offset: f64,
}

impl Default for BaseUnit {
    fn default() -> Self {
        BaseUnit {
            kg: 0,
            m: 0,
            s: 0,
            a: 0,
            k: 0,
            mol: 0,
            cd: 0,
            rad: 0,
            factor: 1.0,
            offset: 0.0,
        }
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct DisplayUnit {
    pub name: String,
    pub factor: f64,
    pub offset: f64,
}

/// A `SimpleType` of `TypeDefinitions` (kept for reading; we do not write any).
#[derive(Debug, Clone, PartialEq)]
pub struct SimpleType {
    pub name: String,
    pub description: Option<String>,
    /// "Real", "Integer", "Boolean", "String" or "Enumeration".
    pub base_type: String,
    pub quantity: Option<String>,
    pub unit: Option<String>,
    pub display_unit: Option<String>,
    /// Enumeration items (name, value) when `base_type` is "Enumeration".
    pub items: Vec<(String, i32)>,
}

/// A `Category` of `LogCategories`.
#[derive(Debug, Clone, PartialEq)]
pub struct Category {
    pub name: String,
    pub description: Option<String>,
}

#[derive(Debug, Clone, PartialEq, Default)]
pub struct DefaultExperiment {
    pub start_time: Option<f64>,
    pub stop_time: Option<f64>,
    pub tolerance: Option<f64>,
    pub step_size: Option<f64>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Causality {
    Parameter,
    CalculatedParameter,
    Input,
    Output,
    #[default]
    Local,
    Independent,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Variability {
    Constant,
    Fixed,
    Tunable,
    Discrete,
    #[default]
    Continuous,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Initial {
    Exact,
    Approx,
    Calculated,
}

/// One `ScalarVariable` of `ModelVariables`.
#[derive(Debug, Clone, PartialEq)]
pub struct ScalarVariable {
    pub name: String,
    pub value_reference: u32,
    pub description: Option<String>,
    pub causality: Causality,
    pub variability: Variability,
    /// As written in the file; `None` when the attribute is absent.
    pub initial: Option<Initial>,
    pub can_handle_multiple_set_per_time_instant: Option<bool>,
    pub kind: VariableKind,
}

/// The type element inside a `ScalarVariable`, with its attributes.
#[derive(Debug, Clone, PartialEq)]
pub enum VariableKind {
    Real(RealAttributes),
    Integer(IntegerAttributes),
    Boolean {
        declared_type: Option<String>,
        start: Option<bool>,
    },
    String {
        declared_type: Option<String>,
        start: Option<String>,
    },
    Enumeration(IntegerAttributes),
}

#[derive(Debug, Clone, PartialEq, Default)]
pub struct RealAttributes {
    pub declared_type: Option<String>,
    pub quantity: Option<String>,
    pub unit: Option<String>,
    pub display_unit: Option<String>,
    pub relative_quantity: Option<bool>,
    pub min: Option<f64>,
    pub max: Option<f64>,
    pub nominal: Option<f64>,
    pub unbounded: Option<bool>,
    pub start: Option<f64>,
    /// 1-based index of the variable this one is the derivative of.
    pub derivative: Option<u32>,
    pub reinit: Option<bool>,
}

#[derive(Debug, Clone, PartialEq, Default)]
pub struct IntegerAttributes {
    pub declared_type: Option<String>,
    pub quantity: Option<String>,
    pub min: Option<i32>,
    pub max: Option<i32>,
    pub start: Option<i32>,
}

/// `ModelStructure`: each list refers to variables by 1-based index in `model_variables`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ModelStructure {
    pub outputs: Vec<Unknown>,
    pub derivatives: Vec<Unknown>,
    pub initial_unknowns: Vec<Unknown>,
}

/// An `Unknown` element. `dependencies: None` means the attribute is absent (depends on all
/// knowns); `Some(vec![])` writes `dependencies=""` (depends on none).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Unknown {
    pub index: u32,
    pub dependencies: Option<Vec<u32>>,
    pub dependencies_kind: Option<Vec<String>>,
}

/// The base type of a variable, for code that only needs to know which Get/Set family to call.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum BaseType {
    Real,
    Integer,
    Boolean,
    String,
    Enumeration,
}

impl VariableKind {
    pub fn base_type(&self) -> BaseType {
        match self {
            VariableKind::Real(_) => BaseType::Real,
            VariableKind::Integer(_) => BaseType::Integer,
            VariableKind::Boolean { .. } => BaseType::Boolean,
            VariableKind::String { .. } => BaseType::String,
            VariableKind::Enumeration(_) => BaseType::Enumeration,
        }
    }
}
