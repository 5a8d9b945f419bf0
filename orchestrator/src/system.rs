//! What a co-simulation is made of, independent of how it was described (an SSP file,
//! command-line options, a program): components, connections, parameter values and
//! the experiment.

use std::path::PathBuf;

/// A value for a parameter or a start value.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    /// For a Real variable (an Integer value is accepted there too, converted when resolved).
    Real(f64),
    /// For an Integer or Enumeration variable (an enumeration's item number).
    Integer(i32),
    /// For a Boolean variable.
    Boolean(bool),
    /// For a String variable; also the raw text of a value whose type is not known until the
    /// FMU's model description is read (`--set`), parsed then by [`Value::parse`].
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

/// The value as [`Value::parse`] reads it back (a Real at full precision, shortest form).
impl std::fmt::Display for Value {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Value::Real(x) => write!(f, "{x}"),
            Value::Integer(i) => write!(f, "{i}"),
            Value::Boolean(b) => write!(f, "{b}"),
            Value::String(t) => write!(f, "{t}"),
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
    /// A [`Component::name`] of the system.
    pub component: String,
    /// The FMI variable's name in that component's model description (may contain dots).
    pub variable: String,
}

impl Endpoint {
    /// Joins the two names as given; nothing is checked until the system is resolved.
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
    /// Multiplies the output's value (unit conversion or sign change).
    pub factor: f64,
    /// Added after the factor, in the input's unit.
    pub offset: f64,
}

/// One output feeding one input: the master copies the value at every communication step.
/// Checked only when resolved ([`crate::resolve`]): output to input, same base type, no input
/// fed twice.
#[derive(Debug, Clone, PartialEq)]
pub struct Connection {
    /// The output read (causality output).
    pub from: Endpoint,
    /// The input written (causality input).
    pub to: Endpoint,
    /// Applied on the way; only between Real variables.
    pub transform: Option<Linear>,
}

/// The system description's default experiment: what a run uses where the command line gives
/// nothing (see [`crate::cli::Common::options`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Experiment {
    /// Start time \[s\] (SSP `startTime`, 0 when absent): where `run` starts unless `--start`
    /// says otherwise; written back by `export-ssp`.
    pub start: f64,
    /// Stop time \[s\] (SSP `stopTime`), not before `start`; none when the description gives
    /// none.
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

/// A co-simulation as described (an SSP file, command-line options, a program), before it is
/// checked against the FMUs ([`crate::resolve::resolve`]).
#[derive(Debug, Clone, PartialEq)]
pub struct System {
    /// The system's name (SSP `System name`), carried into an exported SSP.
    pub name: String,
    /// The FMUs, in the order of the description: component indices elsewhere (a resolved
    /// plan, the master's instances) count in this order.
    pub components: Vec<Component>,
    /// In the order the Gauss-Seidel master follows.
    pub connections: Vec<Connection>,
    /// Start, stop and step, where the description gives them.
    pub experiment: Experiment,
}

impl System {
    /// The component named `name`, if any (the first, should a program have built a system
    /// with two; the SSP reader refuses that).
    pub fn component(&self, name: &str) -> Option<&Component> {
        self.components.iter().find(|c| c.name == name)
    }
}

#[cfg(test)]
mod tests {
    use super::Value;
    use model_description::BaseType as B;

    /// Every kind of value is written as text that `parse` reads back to the same value, a
    /// Real to the last bit at both ends of its range.
    #[test]
    fn a_value_written_as_text_parses_back_to_itself() {
        for (v, base) in [
            (Value::Real(0.1), B::Real),
            (Value::Real(-1e-300), B::Real),
            (Value::Real(1.7976931348623157e308), B::Real),
            (Value::Integer(-7), B::Integer),
            (Value::Boolean(true), B::Boolean),
            (Value::String("learned-nominal.taps".into()), B::String),
        ] {
            assert_eq!(Value::parse(&v.to_string(), base), Ok(v));
        }
        assert_eq!(Value::Real(0.1).to_string(), "0.1");
    }
}
