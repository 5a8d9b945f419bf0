//! What a co-simulation is made of, independent of how it was described (an SSP file,
//! command-line options, a program): components, connections, parameter values and
//! the experiment.

use std::path::PathBuf;

/// A value for a parameter or a start value.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    Real(f64),
    Integer(i32),
    Boolean(bool),
    String(String),
}

impl Value {
    /// Parses a command-line value for a variable of the given base type.
    pub fn parse(text: &str, base: model_description::BaseType) -> Result<Value, String> {
        use model_description::BaseType as B;
        let t = text.trim();
        match base {
            B::Real => t
                .parse()
                .map(Value::Real)
                .map_err(|_| format!("'{text}' is not a real number")),
            B::Integer | B::Enumeration => t
                .parse()
                .map(Value::Integer)
                .map_err(|_| format!("'{text}' is not an integer")),
            B::Boolean => match t {
                "true" | "1" => Ok(Value::Boolean(true)),
                "false" | "0" => Ok(Value::Boolean(false)),
                _ => Err(format!("'{text}' is not a boolean (true/false/1/0)")),
            },
            B::String => Ok(Value::String(text.to_string())),
        }
    }
}

/// One FMU in the system.
#[derive(Debug, Clone, PartialEq)]
pub struct Component {
    /// Unique within the system; names the CSV columns `component.variable`.
    pub name: String,
    /// The .fmu file.
    pub source: PathBuf,
    /// Parameter (and start) values applied before initialization, in order (later wins).
    pub parameters: Vec<(String, Value)>,
}

/// `component.variable`.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct Endpoint {
    pub component: String,
    pub variable: String,
}

impl Endpoint {
    pub fn new(component: &str, variable: &str) -> Endpoint {
        Endpoint {
            component: component.into(),
            variable: variable.into(),
        }
    }

    /// Parses `component.variable` (the variable name may itself contain dots).
    pub fn parse(text: &str) -> Result<Endpoint, String> {
        match text.split_once('.') {
            Some((c, v)) if !c.is_empty() && !v.is_empty() => Ok(Endpoint::new(c, v)),
            _ => Err(format!("'{text}' is not of the form component.variable")),
        }
    }
}

impl std::fmt::Display for Endpoint {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}.{}", self.component, self.variable)
    }
}

/// `to = factor * from + offset` (SSP's LinearTransformation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Linear {
    pub factor: f64,
    pub offset: f64,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Connection {
    pub from: Endpoint,
    pub to: Endpoint,
    pub transform: Option<Linear>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Experiment {
    pub start: f64,
    pub stop: Option<f64>,
    /// The communication step, when the description gives one.
    pub step: Option<f64>,
}

impl Default for Experiment {
    fn default() -> Self {
        Experiment {
            start: 0.0,
            stop: None,
            step: None,
        }
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct System {
    pub name: String,
    pub components: Vec<Component>,
    /// In the order the Gauss-Seidel master follows.
    pub connections: Vec<Connection>,
    pub experiment: Experiment,
}

impl System {
    pub fn component(&self, name: &str) -> Option<&Component> {
        self.components.iter().find(|c| c.name == name)
    }
}
