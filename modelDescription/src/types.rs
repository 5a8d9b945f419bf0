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
    /// `modelName`: the model's name for people; unlike `model_identifier` it need not be a C
    /// identifier.
    pub model_name: String,
    /// `guid`: must equal the GUID passed to fmi2Instantiate; an FMU refuses an instance made from
    /// another description.
    pub guid: String,
    /// `description`: free text for people.
    pub description: Option<String>,
    /// `author`: free text.
    pub author: Option<String>,
    /// `version`: the model's own version (not FMI's).
    pub version: Option<String>,
    /// `copyright`: free text.
    pub copyright: Option<String>,
    /// `license`: free text.
    pub license: Option<String>,
    /// `generationTool`: the tool that wrote the file.
    pub generation_tool: Option<String>,
    /// `generationDateAndTime`: kept as written (xs:dateTime, not parsed).
    pub generation_date_and_time: Option<String>,
    /// "flat" (default) or "structured".
    pub variable_naming_convention: Option<String>,
    /// `numberOfEventIndicators`: only meaningful for model exchange, so only carried through.
    pub number_of_event_indicators: Option<u32>,
    /// The `CoSimulation` element; `None` for a model-exchange-only FMU, which this toolkit cannot
    /// run.
    pub co_simulation: Option<CoSimulation>,
    /// Only the identifier is kept: we neither export nor import model exchange.
    pub model_exchange_identifier: Option<String>,
    /// `UnitDefinitions`, in document order.
    pub unit_definitions: Vec<Unit>,
    /// `TypeDefinitions`, which variables refer to by `declaredType`.
    pub type_definitions: Vec<SimpleType>,
    /// `LogCategories`: the names fmi2SetDebugLogging accepts.
    pub log_categories: Vec<Category>,
    /// `DefaultExperiment`: the start, stop and step a master uses when the user gives none.
    pub default_experiment: Option<DefaultExperiment>,
    /// `ModelVariables`, in document order: the 1-based indices of `model_structure` count in this
    /// list.
    pub model_variables: Vec<ScalarVariable>,
    /// `ModelStructure`: which variables are outputs and initial unknowns, and what they depend on.
    pub model_structure: ModelStructure,
}

/// The `CoSimulation` element and its capability flags (all default to false).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct CoSimulation {
    /// `modelIdentifier`: the shared library's file stem under `binaries/<platform>/` and the
    /// prefix of its function names, so it must be a C identifier.
    pub model_identifier: String,
    /// `needsExecutionTool`: the FMU calls out to a tool that must be installed.
    pub needs_execution_tool: bool,
    /// `canHandleVariableCommunicationStepSize`: fmi2DoStep accepts a different step each call.
    pub can_handle_variable_communication_step_size: bool,
    /// `canInterpolateInputs`: the FMU can use input derivatives (fmi2SetRealInputDerivatives).
    pub can_interpolate_inputs: bool,
    /// `maxOutputDerivativeOrder`: the highest order fmi2GetRealOutputDerivatives serves (0: none).
    pub max_output_derivative_order: u32,
    /// Spelled `canRunAsynchronuously` in the standard.
    pub can_run_asynchronuously: bool,
    /// `canBeInstantiatedOnlyOncePerProcess`: a second live instance in the same process is not
    /// allowed (the importer refuses it).
    pub can_be_instantiated_only_once_per_process: bool,
    /// `canNotUseMemoryManagementFunctions`: the FMU ignores the allocateMemory/freeMemory
    /// callbacks.
    pub can_not_use_memory_management_functions: bool,
    /// `canGetAndSetFMUstate`: fmi2GetFMUstate/fmi2SetFMUstate work, e.g. for rolling back a step.
    pub can_get_and_set_fmu_state: bool,
    /// `canSerializeFMUstate`: a state can be turned into bytes and back (requires
    /// `can_get_and_set_fmu_state`).
    pub can_serialize_fmu_state: bool,
    /// `providesDirectionalDerivative`: fmi2GetDirectionalDerivative works.
    pub provides_directional_derivative: bool,
}

/// A `Unit` of `UnitDefinitions`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Unit {
    /// The unit's name as variables refer to it in their `unit` attribute (e.g. "m/s2").
    pub name: String,
    /// How the unit maps to SI, when the file says.
    pub base_unit: Option<BaseUnit>,
    /// The units a tool may show values in instead.
    pub display_units: Vec<DisplayUnit>,
}

/// SI exponents plus factor and offset: value_SI = factor * value + offset.
#[derive(Debug, Clone, PartialEq)]
pub struct BaseUnit {
    /// Exponent of the kilogram.
    pub kg: i32,
    /// Exponent of the metre.
    pub m: i32,
    /// Exponent of the second.
    pub s: i32,
    /// Exponent of the ampere.
    pub a: i32,
    /// Exponent of the kelvin.
    pub k: i32,
    /// Exponent of the mole.
    pub mol: i32,
    /// Exponent of the candela.
    pub cd: i32,
    /// Exponent of the radian (FMI keeps angles apart from 1, unlike SI).
    pub rad: i32,
    /// Multiplies the value to get SI (default 1).
    pub factor: f64,
    /// Added after `factor` to get SI (default 0; non-zero for e.g. degC).
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

/// A `DisplayUnit` of a `Unit`: how a tool may show values to people; never used in the values
/// exchanged with the FMU.
#[derive(Debug, Clone, PartialEq)]
pub struct DisplayUnit {
    /// The name shown to users and used in `displayUnit` attributes.
    pub name: String,
    /// value_display = factor * value_unit + offset.
    pub factor: f64,
    /// See `factor`.
    pub offset: f64,
}

/// A `SimpleType` of `TypeDefinitions` (kept for reading; we do not write any).
#[derive(Debug, Clone, PartialEq)]
pub struct SimpleType {
    /// The name variables give in `declaredType`.
    pub name: String,
    /// Free text for people.
    pub description: Option<String>,
    /// "Real", "Integer", "Boolean", "String" or "Enumeration".
    pub base_type: String,
    /// `quantity`: the physical quantity (e.g. "Velocity"); values of different quantities should
    /// not be connected.
    pub quantity: Option<String>,
    /// `unit`: a name from `UnitDefinitions`, inherited by variables of this type.
    pub unit: Option<String>,
    /// `displayUnit`: a display unit of `unit`.
    pub display_unit: Option<String>,
    /// Enumeration items (name, value) when `base_type` is "Enumeration".
    pub items: Vec<(String, i32)>,
}

/// A `Category` of `LogCategories`.
#[derive(Debug, Clone, PartialEq)]
pub struct Category {
    /// The name passed to fmi2SetDebugLogging and given back in the logger's category argument.
    pub name: String,
    /// What the category logs, for people.
    pub description: Option<String>,
}

/// `DefaultExperiment`: what the model was made to run with; every attribute is optional.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct DefaultExperiment {
    /// `startTime` in seconds, when set.
    pub start_time: Option<f64>,
    /// `stopTime` in seconds, when set.
    pub stop_time: Option<f64>,
    /// `tolerance`: relative tolerance for the FMU's internal solver, when set.
    pub tolerance: Option<f64>,
    /// `stepSize` in seconds: the communication step the model was made for, when set.
    pub step_size: Option<f64>,
}

/// `causality` (FMI 2.0 section 2.2.7): who gives the variable its value, and so whether a
/// master may set it, connect it or only read it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Causality {
    /// Set by the user or master (with `fixed` variability: only before initialization ends;
    /// `tunable`: also between steps).
    Parameter,
    /// Computed by the FMU from parameters during initialization; read-only.
    CalculatedParameter,
    /// Set by the master, typically from another FMU's output, before each step.
    Input,
    /// Computed by the FMU; what a master connects to other FMUs' inputs.
    Output,
    /// Internal: may be read for inspection, never set or connected (the standard's default).
    #[default]
    Local,
    /// The independent variable (time): at most one, a Real without `start`.
    Independent,
}

/// `variability`: when the value may change, which decides when a master may set a parameter.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Variability {
    /// Never changes.
    Constant,
    /// Fixed once initialization ends (fmi2ExitInitializationMode).
    Fixed,
    /// Constant between events; in co-simulation a parameter a master may change between steps.
    Tunable,
    /// Changes only at events (in co-simulation: at communication points).
    Discrete,
    /// May change at any time; Real variables only (the standard's default).
    #[default]
    Continuous,
}

/// `initial`: what `start` means, and so whether it must be present.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Initial {
    /// Initialized with `start` (required).
    Exact,
    /// `start` is a guess for an iteration in initialization mode (required).
    Approx,
    /// The FMU computes the value during initialization; no `start` allowed.
    Calculated,
}

/// One `ScalarVariable` of `ModelVariables`.
#[derive(Debug, Clone, PartialEq)]
pub struct ScalarVariable {
    /// Unique among the variables; with the "structured" naming convention dots separate levels.
    pub name: String,
    /// The handle the fmi2Get/fmi2Set functions take; unique per base type only, so two variables
    /// of different types may share one.
    pub value_reference: u32,
    /// Free text for people.
    pub description: Option<String>,
    /// Who sets or reads the variable (default local after reading).
    pub causality: Causality,
    /// When its value may change (default continuous after reading).
    pub variability: Variability,
    /// As written in the file; `None` when the attribute is absent.
    pub initial: Option<Initial>,
    /// `canHandleMultipleSetPerTimeInstant`: only meaningful for model-exchange inputs; carried
    /// through.
    pub can_handle_multiple_set_per_time_instant: Option<bool>,
    /// The type element (Real, Integer, ...) with its type-specific attributes.
    pub kind: VariableKind,
}

/// The type element inside a `ScalarVariable`, with its attributes.
#[derive(Debug, Clone, PartialEq)]
pub enum VariableKind {
    /// `<Real>`: exchanged with fmi2GetReal/fmi2SetReal.
    Real(RealAttributes),
    /// `<Integer>`: exchanged with fmi2GetInteger/fmi2SetInteger.
    Integer(IntegerAttributes),
    /// `<Boolean>`: exchanged with fmi2GetBoolean/fmi2SetBoolean.
    Boolean {
        /// A `SimpleType` name whose attributes the variable inherits.
        declared_type: Option<String>,
        /// `start`, when present (its presence is governed by `initial`).
        start: Option<bool>,
    },
    /// `<String>`: exchanged with fmi2GetString/fmi2SetString.
    String {
        /// A `SimpleType` name whose attributes the variable inherits.
        declared_type: Option<String>,
        /// `start`, when present (its presence is governed by `initial`).
        start: Option<String>,
    },
    /// `<Enumeration>`: an integer whose `declared_type` (required) lists the items; exchanged
    /// with fmi2GetInteger/fmi2SetInteger, sharing Integer's value references.
    Enumeration(IntegerAttributes),
}

/// The attributes of a `<Real>` type element; each absent one is `None` (the variable's
/// `declared_type` may supply it).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RealAttributes {
    /// A `SimpleType` name whose attributes the variable inherits where its own are absent.
    pub declared_type: Option<String>,
    /// `quantity`: the physical quantity (e.g. "Velocity").
    pub quantity: Option<String>,
    /// `unit`: a name from `UnitDefinitions`; the values exchanged are in this unit.
    pub unit: Option<String>,
    /// `displayUnit`: a display unit of `unit`, for people only.
    pub display_unit: Option<String>,
    /// `relativeQuantity`: a difference (e.g. a temperature difference), so a unit's offset must
    /// not be applied; `None`: absent (false).
    pub relative_quantity: Option<bool>,
    /// `min`: the variable never goes below it, and a master must not set less.
    pub min: Option<f64>,
    /// `max`: the variable never goes above it, and a master must not set more.
    pub max: Option<f64>,
    /// `nominal`: the typical magnitude, for scaling tolerances.
    pub nominal: Option<f64>,
    /// `unbounded`: a state whose error a solver should not control (it may grow without bound);
    /// `None`: absent (false).
    pub unbounded: Option<bool>,
    /// `start`, when present (its presence is governed by `initial`).
    pub start: Option<f64>,
    /// 1-based index of the variable this one is the derivative of.
    pub derivative: Option<u32>,
    /// `reinit`: model exchange only (a state the FMU may change at an event); carried through.
    pub reinit: Option<bool>,
}

/// The attributes of an `<Integer>` or `<Enumeration>` type element; each absent one is `None`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct IntegerAttributes {
    /// A `SimpleType` name whose attributes the variable inherits where its own are absent.
    pub declared_type: Option<String>,
    /// `quantity`: the physical quantity.
    pub quantity: Option<String>,
    /// `min`: the variable never goes below it, and a master must not set less.
    pub min: Option<i32>,
    /// `max`: the variable never goes above it, and a master must not set more.
    pub max: Option<i32>,
    /// `start`, when present (its presence is governed by `initial`).
    pub start: Option<i32>,
}

/// `ModelStructure`: each list refers to variables by 1-based index in `model_variables`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ModelStructure {
    /// One entry per variable of causality output, with what it depends on.
    pub outputs: Vec<Unknown>,
    /// The state derivatives (model exchange; empty for our FMUs).
    pub derivatives: Vec<Unknown>,
    /// The values computed during initialization mode, with what they depend on.
    pub initial_unknowns: Vec<Unknown>,
}

/// An `Unknown` element. `dependencies: None` means the attribute is absent (depends on all
/// knowns); `Some(vec![])` writes `dependencies=""` (depends on none).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Unknown {
    /// 1-based index into `model_variables`.
    pub index: u32,
    /// 1-based indices of the knowns this unknown depends on; see the type's doc for `None`.
    pub dependencies: Option<Vec<u32>>,
    /// One kind per dependency ("dependent", "constant", "fixed", "tunable", "discrete"): how the
    /// dependency enters; `None` when absent.
    pub dependencies_kind: Option<Vec<String>>,
}

/// The base type of a variable, for code that only needs to know which Get/Set family to call.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum BaseType {
    /// fmi2GetReal / fmi2SetReal.
    Real,
    /// fmi2GetInteger / fmi2SetInteger.
    Integer,
    /// fmi2GetBoolean / fmi2SetBoolean.
    Boolean,
    /// fmi2GetString / fmi2SetString.
    String,
    /// fmi2GetInteger / fmi2SetInteger, like Integer (value references are shared with it).
    Enumeration,
}

impl VariableKind {
    /// Which Get/Set family carries this variable, without its attributes.
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
