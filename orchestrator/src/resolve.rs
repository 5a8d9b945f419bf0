//! Checks a system against its FMUs' model descriptions before anything is instantiated:
//! every connection joins an existing output to an existing input of the same type, no input is
//! fed twice, parameter values name settable variables, and there is no algebraic loop.
//! Every error names the component, the variable and the FMU file, so a user can fix the
//! system description without guessing.

use crate::system::{Endpoint, Linear, System, Value};
use model_description::{BaseType, Causality, ModelDescription, ScalarVariable};
use std::collections::HashMap;
use std::path::PathBuf;

/// A connection resolved to value references.
#[derive(Debug, Clone, PartialEq)]
pub struct Link {
    /// The producing component's index in [`System::components`].
    pub from: usize,
    /// The output's value reference in the producer's FMU.
    pub from_vr: u32,
    /// The consuming component's index.
    pub to: usize,
    /// The input's value reference in the consumer's FMU.
    pub to_vr: u32,
    /// The type both ends share, which says which fmi2Get/SetXxx carry the value: Real,
    /// Integer (an Enumeration is carried as one) or Boolean, never String.
    pub base: BaseType,
    /// The connection's linear transformation (Real links only).
    pub transform: Option<Linear>,
    /// The output's name, for messages.
    pub from_name: Endpoint,
    /// The input's name, for messages.
    pub to_name: Endpoint,
}

/// A parameter or start value resolved to a value reference.
#[derive(Debug, Clone, PartialEq)]
pub struct Setting {
    /// The component's index in [`System::components`].
    pub component: usize,
    /// The variable's value reference in its FMU.
    pub vr: u32,
    /// The value, already of the variable's type (an Integer given for a Real converted, a
    /// text parsed), so that applying it cannot fail on the type.
    pub value: Value,
    /// The variable's name, for messages.
    pub name: Endpoint,
}

/// The resolved system.
#[derive(Debug, Clone)]
pub struct Plan {
    /// One per connection, in the system's order.
    pub links: Vec<Link>,
    /// Applied before initialization in this order, so a later one for the same variable wins:
    /// the components' parameters in the system's order, then `--set` settings.
    pub settings: Vec<Setting>,
    /// Components in the Gauss-Seidel order: producers before consumers, otherwise in the
    /// order of the system description.
    pub order: Vec<usize>,
}

/// Why a system does not fit its FMUs; each names the connection, parameter or variable to fix.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ResolveError {
    /// A name refers to a component the system does not have.
    #[error("{context}: component '{component}' does not exist (components: {known})")]
    UnknownComponent {
        /// What named it: `connection A.x -> B.y`, `parameter c.v`, `variable c.v`,
        /// `external input c.v`.
        context: String,
        /// The component name as given.
        component: String,
        /// The system's components, comma-separated.
        known: String,
    },
    /// A name refers to a variable the component's FMU does not declare.
    #[error("{context}: component '{component}' ({fmu}) has no variable '{variable}'")]
    UnknownVariable {
        /// What named it: `connection A.x -> B.y`, `parameter c.v`, `variable c.v`,
        /// `external input c.v`.
        context: String,
        /// The component, which exists.
        component: String,
        /// The variable name as given.
        variable: String,
        /// The component's FMU file.
        fmu: PathBuf,
    },
    /// A connection that cannot carry a value: not output to input, types that differ, a
    /// String, a transformation of a non-Real, a component feeding itself.
    #[error("connection {from} -> {to}: {problem}")]
    BadConnection {
        /// The connection's output end.
        from: Endpoint,
        /// The connection's input end.
        to: Endpoint,
        /// What is wrong, with the causalities or types concerned.
        problem: String,
    },
    /// Two connections end at the same input.
    #[error("input {to} is fed by two connections, from {first} and from {second}")]
    InputFedTwice {
        /// The input.
        to: Endpoint,
        /// The output of the first connection to it.
        first: Endpoint,
        /// The output of the second.
        second: Endpoint,
    },
    /// A parameter or start value that cannot be applied: the variable is not a parameter or
    /// input, is a constant, or the value does not fit its type.
    #[error("parameter {name}: {problem}")]
    BadSetting {
        /// The variable set.
        name: Endpoint,
        /// Why it cannot be set, or why the value does not fit.
        problem: String,
    },
    /// Connections that form a cycle in which every component passes its input straight to
    /// its output (direct feedthrough), which a fixed-step master cannot solve.
    #[error("algebraic loop through {}: each of these outputs depends directly on an input fed by the next; break the loop or give the FMUs' outputs dependencies=\"\" where there is no direct feedthrough", .variables.iter().map(|v| v.to_string()).collect::<Vec<_>>().join(" -> "))]
    AlgebraicLoop {
        /// The loop's outputs, each depending directly on the input the next one feeds.
        variables: Vec<Endpoint>,
    },
}

fn type_name(b: BaseType) -> &'static str {
    match b {
        BaseType::Real => "Real",
        BaseType::Integer => "Integer",
        BaseType::Boolean => "Boolean",
        BaseType::String => "String",
        BaseType::Enumeration => "Enumeration",
    }
}

/// Resolves `system` against the model descriptions of its components (same order).
pub fn resolve(system: &System, descriptions: &[&ModelDescription]) -> Result<Plan, ResolveError> {
    let lookup = |e: &Endpoint, context: &str| find(system, descriptions, e, context);

    let mut links = vec![];
    let mut fed: HashMap<(usize, u32), Endpoint> = HashMap::new();
    for c in &system.connections {
        let context = format!("connection {} -> {}", c.from, c.to);
        let (fi, fv) = lookup(&c.from, &context)?;
        let (ti, tv) = lookup(&c.to, &context)?;
        let bad = |problem: String| ResolveError::BadConnection {
            from: c.from.clone(),
            to: c.to.clone(),
            problem,
        };
        if !matches!(fv.causality, Causality::Output) {
            return Err(bad(format!(
                "{} is not an output (causality {:?})",
                c.from, fv.causality
            )));
        }
        if !matches!(tv.causality, Causality::Input) {
            return Err(bad(format!(
                "{} is not an input (causality {:?})",
                c.to, tv.causality
            )));
        }
        let (fb, tb) = (carrier(fv.kind.base_type()), carrier(tv.kind.base_type()));
        if fb != tb {
            return Err(bad(format!(
                "type mismatch: {} is {}, {} is {}",
                c.from,
                type_name(fb),
                c.to,
                type_name(tb)
            )));
        }
        if fb == BaseType::String {
            return Err(bad("String connections are not supported".into()));
        }
        if c.transform.is_some() && fb != BaseType::Real {
            return Err(bad(format!(
                "a linear transformation needs Real variables, these are {}",
                type_name(fb)
            )));
        }
        if fi == ti {
            return Err(bad("a component cannot feed itself".into()));
        }
        if let Some(first) = fed.insert((ti, tv.value_reference), c.from.clone()) {
            return Err(ResolveError::InputFedTwice {
                to: c.to.clone(),
                first,
                second: c.from.clone(),
            });
        }
        links.push(Link {
            from: fi,
            from_vr: fv.value_reference,
            to: ti,
            to_vr: tv.value_reference,
            base: fb,
            transform: c.transform,
            from_name: c.from.clone(),
            to_name: c.to.clone(),
        });
    }

    let mut settings = vec![];
    for (i, comp) in system.components.iter().enumerate() {
        for (name, value) in &comp.parameters {
            let e = Endpoint::new(&comp.name, name);
            let (_, v) = lookup(&e, &format!("parameter {e}"))?;
            settings.push(setting(i, v, value, e)?);
        }
    }

    check_loops(&links, descriptions, system)?;
    let order = gauss_seidel_order(system.components.len(), &links);
    Ok(Plan {
        links,
        settings,
        order,
    })
}

/// Checks that `value` fits variable `v` and that `v` may be set before initialization.
pub fn setting(
    component: usize,
    v: &ScalarVariable,
    value: &Value,
    name: Endpoint,
) -> Result<Setting, ResolveError> {
    let bad = |problem: String| ResolveError::BadSetting {
        name: name.clone(),
        problem,
    };
    match v.causality {
        Causality::Parameter | Causality::Input => {}
        other => {
            return Err(bad(format!(
                "cannot be set: its causality is {other:?}, not parameter or input"
            )));
        }
    }
    if v.variability == model_description::Variability::Constant {
        return Err(bad("cannot be set: it is a constant".into()));
    }
    let base = v.kind.base_type();
    let value = match (base, value) {
        (BaseType::Real, Value::Real(_))
        | (BaseType::Boolean, Value::Boolean(_))
        | (BaseType::String, Value::String(_)) => value.clone(),
        (BaseType::Integer | BaseType::Enumeration, Value::Integer(_)) => value.clone(),
        (BaseType::Real, Value::Integer(i)) => Value::Real(*i as f64),
        (_, Value::String(s)) => {
            Value::parse(s, base).map_err(|e| bad(format!("{e} ({} expected)", type_name(base))))?
        }
        (b, other) => {
            return Err(bad(format!(
                "{other:?} does not fit a {} variable",
                type_name(b)
            )));
        }
    };
    Ok(Setting {
        component,
        vr: v.value_reference,
        value,
        name,
    })
}

/// Direct feedthrough inside a component: does `output` depend on `input` without a step?
/// `dependencies` absent means "depends on all inputs" (FMI 2.0 2.2.8), the safe assumption.
fn feedthrough(md: &ModelDescription, output_vr: u32, input_vr: u32, base: BaseType) -> bool {
    let idx = |vr: u32| {
        md.model_variables
            .iter()
            .position(|v| v.value_reference == vr && same_space(v.kind.base_type(), base))
            .map(|i| i as u32 + 1)
    };
    let (Some(o), Some(i)) = (idx(output_vr), idx(input_vr)) else {
        return true;
    };
    match md.model_structure.outputs.iter().find(|u| u.index == o) {
        Some(u) => match &u.dependencies {
            None => true,
            Some(deps) => deps.contains(&i),
        },
        None => true,
    }
}

fn same_space(a: BaseType, b: BaseType) -> bool {
    carrier(a) == carrier(b)
}

/// The type whose fmi2Get/fmi2Set functions carry a variable of type `b`: an Enumeration
/// travels as an Integer ([`Link::base`]).
pub(crate) fn carrier(b: BaseType) -> BaseType {
    match b {
        BaseType::Enumeration => BaseType::Integer,
        other => other,
    }
}

/// The component and variable `e` names in `system`, whose FMUs' model descriptions are
/// `descriptions` (in the components' order), or an error naming what is missing; `context`
/// says what named it (a connection, a parameter, `--set`, a recorded variable, an input).
pub(crate) fn find<'a>(
    system: &System,
    descriptions: &[&'a ModelDescription],
    e: &Endpoint,
    context: &str,
) -> Result<(usize, &'a ScalarVariable), ResolveError> {
    let i = system
        .components
        .iter()
        .position(|c| c.name == e.component)
        .ok_or_else(|| ResolveError::UnknownComponent {
            context: context.to_string(),
            component: e.component.clone(),
            known: system
                .components
                .iter()
                .map(|c| c.name.as_str())
                .collect::<Vec<_>>()
                .join(", "),
        })?;
    let v = descriptions[i]
        .variable(&e.variable)
        .ok_or_else(|| ResolveError::UnknownVariable {
            context: context.to_string(),
            component: e.component.clone(),
            variable: e.variable.clone(),
            fmu: system.components[i].source.clone(),
        })?;
    Ok((i, v))
}

/// A cycle of links in which every component passes its input straight to the output that
/// feeds the next link is an algebraic loop. Depth-first search over links.
fn check_loops(
    links: &[Link],
    descriptions: &[&ModelDescription],
    _system: &System,
) -> Result<(), ResolveError> {
    // Edge a -> b when link b's source output depends directly on link a's target input.
    let n = links.len();
    let mut next: Vec<Vec<usize>> = vec![vec![]; n];
    for (a, la) in links.iter().enumerate() {
        for (b, lb) in links.iter().enumerate() {
            if lb.from == la.to && feedthrough(descriptions[lb.from], lb.from_vr, la.to_vr, la.base)
            {
                next[a].push(b);
            }
        }
    }
    // Iterative DFS with colours; on a back edge, report the cycle's variables.
    let mut colour = vec![0u8; n];
    let mut stack: Vec<(usize, usize)> = vec![];
    for start in 0..n {
        if colour[start] != 0 {
            continue;
        }
        stack.push((start, 0));
        colour[start] = 1;
        while let Some(&mut (node, ref mut k)) = stack.last_mut() {
            if *k < next[node].len() {
                let m = next[node][*k];
                *k += 1;
                match colour[m] {
                    0 => {
                        colour[m] = 1;
                        stack.push((m, 0));
                    }
                    1 => {
                        let pos = stack.iter().position(|&(x, _)| x == m).unwrap_or(0);
                        let mut variables = vec![];
                        for &(x, _) in &stack[pos..] {
                            variables.push(links[x].from_name.clone());
                            variables.push(links[x].to_name.clone());
                        }
                        variables.push(links[m].from_name.clone());
                        return Err(ResolveError::AlgebraicLoop { variables });
                    }
                    _ => {}
                }
            } else {
                colour[node] = 2;
                stack.pop();
            }
        }
    }
    Ok(())
}

/// Producers before consumers (Kahn's algorithm, ties in description order); components in a
/// feedback cycle (which is legal when not algebraic) keep their description order.
fn gauss_seidel_order(n: usize, links: &[Link]) -> Vec<usize> {
    let mut indegree = vec![0usize; n];
    let mut edges = vec![vec![]; n];
    for l in links {
        if !edges[l.from].contains(&l.to) {
            edges[l.from].push(l.to);
            indegree[l.to] += 1;
        }
    }
    let mut order = vec![];
    let mut done = vec![false; n];
    while let Some(next) = (0..n).find(|&i| !done[i] && indegree[i] == 0) {
        done[next] = true;
        order.push(next);
        for &t in &edges[next] {
            indegree[t] -= 1;
        }
    }
    order.extend((0..n).filter(|&i| !done[i]));
    order
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::system::{Component, Connection, Experiment};

    /// A model description with the given (name, causality, base, dependencies) variables.
    fn md(vars: &[(&str, Causality, BaseType, Option<Vec<u32>>)]) -> ModelDescription {
        use model_description::*;
        let model_variables: Vec<ScalarVariable> = vars
            .iter()
            .enumerate()
            .map(|(i, (name, causality, base, _))| ScalarVariable {
                name: name.to_string(),
                value_reference: i as u32,
                description: None,
                causality: *causality,
                variability: if *base == BaseType::Real {
                    Variability::Continuous
                } else {
                    Variability::Discrete
                },
                initial: None,
                can_handle_multiple_set_per_time_instant: None,
                kind: match base {
                    BaseType::Real => VariableKind::Real(RealAttributes {
                        start: Some(0.0),
                        ..Default::default()
                    }),
                    BaseType::Integer => VariableKind::Integer(IntegerAttributes {
                        start: Some(0),
                        ..Default::default()
                    }),
                    BaseType::Boolean => VariableKind::Boolean {
                        declared_type: None,
                        start: Some(false),
                    },
                    _ => VariableKind::String {
                        declared_type: None,
                        start: Some(String::new()),
                    },
                },
            })
            .collect();
        let outputs = vars
            .iter()
            .enumerate()
            .filter(|(_, v)| v.1 == Causality::Output)
            .map(|(i, v)| Unknown {
                index: i as u32 + 1,
                dependencies: v.3.clone(),
                dependencies_kind: None,
            })
            .collect();
        ModelDescription {
            model_variables,
            model_structure: ModelStructure {
                outputs,
                ..Default::default()
            },
            ..Default::default()
        }
    }

    fn system(connections: &[(&str, &str)]) -> System {
        System {
            name: "t".into(),
            components: ["a", "b"]
                .iter()
                .map(|n| Component {
                    name: n.to_string(),
                    source: format!("{n}.fmu").into(),
                    parameters: vec![],
                })
                .collect(),
            connections: connections
                .iter()
                .map(|(f, t)| Connection {
                    from: Endpoint::parse(f).unwrap(),
                    to: Endpoint::parse(t).unwrap(),
                    transform: None,
                })
                .collect(),
            experiment: Experiment::default(),
        }
    }

    fn pair(
        dep_a: Option<Vec<u32>>,
        dep_b: Option<Vec<u32>>,
    ) -> (ModelDescription, ModelDescription) {
        use BaseType::*;
        use Causality::*;
        (
            md(&[
                ("u", Input, Real, None),
                ("y", Output, Real, dep_a),
                ("n", Output, Integer, Some(vec![])),
                ("k", Parameter, Real, None),
            ]),
            md(&[
                ("u", Input, Real, None),
                ("y", Output, Real, dep_b),
                ("m", Input, Integer, None),
                ("s", Input, String, None),
            ]),
        )
    }

    #[test]
    fn a_chain_resolves_with_producers_first() {
        let (a, b) = pair(Some(vec![]), Some(vec![1]));
        let plan = resolve(&system(&[("a.y", "b.u"), ("a.n", "b.m")]), &[&a, &b]).unwrap();
        assert_eq!(plan.links.len(), 2);
        assert_eq!(plan.links[1].base, BaseType::Integer);
        assert_eq!(plan.order, vec![0, 1]);
    }

    #[test]
    fn errors_name_what_is_wrong() {
        let (a, b) = pair(Some(vec![]), Some(vec![]));
        let err = |c: &[(&str, &str)]| resolve(&system(c), &[&a, &b]).unwrap_err().to_string();
        let e = err(&[("a.yy", "b.u")]);
        assert!(
            e.contains("'a'") && e.contains("'yy'") && e.contains("a.fmu"),
            "{e}"
        );
        assert!(err(&[("c.y", "b.u")]).contains("component 'c' does not exist"));
        assert!(err(&[("a.u", "b.u")]).contains("a.u is not an output"));
        assert!(err(&[("a.y", "b.y")]).contains("b.y is not an input"));
        assert!(err(&[("a.y", "b.m")]).contains("type mismatch: a.y is Real, b.m is Integer"));
        assert!(err(&[("a.y", "b.u"), ("a.y", "b.u")]).contains("fed by two connections"));
        let mut s = system(&[]);
        s.components[0]
            .parameters
            .push(("k".into(), Value::String("abc".into())));
        assert!(
            resolve(&s, &[&a, &b])
                .unwrap_err()
                .to_string()
                .contains("'abc' is not a real number")
        );
        let mut s = system(&[]);
        s.components[0]
            .parameters
            .push(("y".into(), Value::Real(1.0)));
        assert!(
            resolve(&s, &[&a, &b])
                .unwrap_err()
                .to_string()
                .contains("causality is Output")
        );
    }

    #[test]
    fn an_algebraic_loop_is_reported_by_its_variables() {
        // Both outputs depend directly on their inputs (index 1 = u): a -> b -> a is a loop.
        let (a, b) = pair(Some(vec![1]), Some(vec![1]));
        let e = resolve(&system(&[("a.y", "b.u"), ("b.y", "a.u")]), &[&a, &b]).unwrap_err();
        let text = e.to_string();
        assert!(matches!(e, ResolveError::AlgebraicLoop { .. }));
        assert!(
            text.contains("a.y")
                && text.contains("b.u")
                && text.contains("b.y")
                && text.contains("a.u"),
            "{text}"
        );
        // Absent dependencies mean "depends on everything": also a loop.
        let (a, b) = pair(None, None);
        assert!(resolve(&system(&[("a.y", "b.u"), ("b.y", "a.u")]), &[&a, &b]).is_err());
        // No feedthrough in one of them: a legal feedback loop, stepped in description order.
        let (a, b) = pair(Some(vec![]), Some(vec![1]));
        let plan = resolve(&system(&[("a.y", "b.u"), ("b.y", "a.u")]), &[&a, &b]).unwrap();
        assert_eq!(plan.order, vec![0, 1]);
    }

    #[test]
    fn order_puts_producers_first() {
        let (a, b) = pair(Some(vec![]), Some(vec![]));
        let plan = resolve(&system(&[("b.y", "a.u")]), &[&a, &b]).unwrap();
        assert_eq!(plan.order, vec![1, 0]);
    }
}
