//! modelDescription.xml and documentation/index.html for a model, both generated from its
//! variable table so neither can drift from the code.

use crate::logger::CATEGORIES;
use crate::model::Model;
use crate::units::unit;
use crate::variables::{Start, VarSpec};
use model_description::{
    Category, CoSimulation, DefaultExperiment, IntegerAttributes, ModelDescription, ModelStructure,
    RealAttributes, ScalarVariable, VariableKind,
};

fn scalar_variable(v: &VarSpec) -> ScalarVariable {
    let kind = match v.start {
        Start::Real(x) => VariableKind::Real(RealAttributes {
            unit: v.unit.map(str::to_string),
            min: v.min,
            max: v.max,
            start: v.has_start.then_some(x),
            ..RealAttributes::default()
        }),
        Start::Integer(x) => VariableKind::Integer(IntegerAttributes {
            min: v.min.map(|m| m as i32),
            max: v.max.map(|m| m as i32),
            start: v.has_start.then_some(x),
            ..IntegerAttributes::default()
        }),
        Start::Boolean(x) => VariableKind::Boolean {
            declared_type: None,
            start: v.has_start.then_some(x),
        },
        Start::String(x) => VariableKind::String {
            declared_type: None,
            start: v.has_start.then(|| x.to_string()),
        },
    };
    ScalarVariable {
        name: v.name.to_string(),
        value_reference: v.vr,
        description: (!v.description.is_empty()).then(|| v.description.to_string()),
        causality: v.causality,
        variability: v.variability,
        initial: v.initial,
        can_handle_multiple_set_per_time_instant: None,
        kind,
    }
}

/// The model description of `M`. Output dependencies come from
/// [`Model::output_dependencies`]; by default none (`dependencies=""`): every output is computed
/// inside fmi2DoStep, so setting an input never changes an output before the next step, and
/// masters need not look for algebraic loops.
pub fn model_description<M: Model>() -> ModelDescription {
    let info = M::INFO;
    let variables: Vec<ScalarVariable> = M::variables().iter().map(scalar_variable).collect();
    let mut unit_names: Vec<&str> = M::variables().iter().filter_map(|v| v.unit).collect();
    unit_names.sort_unstable();
    unit_names.dedup();
    let unit_definitions = unit_names
        .iter()
        .map(|u| {
            unit(u).unwrap_or_else(|| panic!("unit '{u}' is not in fmi_abi::units; add it there"))
        })
        .collect();
    let model_structure = ModelStructure::derive(&variables, |v| M::output_dependencies(&v.name));
    ModelDescription {
        fmi_version: "2.0".into(),
        model_name: info.model_name.into(),
        guid: info.guid.into(),
        description: Some(info.description.into()),
        author: Some(info.author.into()),
        version: Some(info.version.into()),
        license: Some("MIT OR Apache-2.0".into()),
        generation_tool: Some(format!("fmi-abi {}", env!("CARGO_PKG_VERSION"))),
        variable_naming_convention: Some("flat".into()),
        number_of_event_indicators: Some(0),
        co_simulation: Some(CoSimulation {
            model_identifier: info.model_identifier.into(),
            can_handle_variable_communication_step_size: true,
            can_not_use_memory_management_functions: true,
            can_get_and_set_fmu_state: true,
            can_serialize_fmu_state: true,
            ..CoSimulation::default()
        }),
        unit_definitions,
        log_categories: CATEGORIES
            .iter()
            .map(|(name, description)| Category {
                name: name.to_str().unwrap_or_default().into(),
                description: Some((*description).into()),
            })
            .collect(),
        default_experiment: Some(DefaultExperiment {
            start_time: Some(info.default_start),
            stop_time: Some(info.default_stop),
            tolerance: None,
            step_size: Some(info.default_step),
        }),
        model_variables: variables,
        model_structure,
        ..ModelDescription::default()
    }
}

fn html_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// documentation/index.html: the method (an HTML fragment the FMU crate writes) followed by a
/// table of every variable, generated from the variable table.
pub fn documentation_html<M: Model>(method_html: &str) -> String {
    let info = M::INFO;
    let mut rows = String::new();
    for v in M::variables() {
        let start = match (v.has_start, v.start) {
            (false, _) => "calculated".to_string(),
            (true, Start::Real(x)) => format!("{x}"),
            (true, Start::Integer(x)) => format!("{x}"),
            (true, Start::Boolean(x)) => format!("{x}"),
            (true, Start::String(x)) => format!("\"{}\"", html_escape(x)),
        };
        let range = match (v.min, v.max) {
            (None, None) => String::new(),
            (a, b) => format!(
                "[{}, {}]",
                a.map_or("-inf".into(), |x| x.to_string()),
                b.map_or("inf".into(), |x| x.to_string())
            ),
        };
        rows.push_str(&format!(
            "<tr><td><code>{}</code></td><td>{:?}</td><td>{:?}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>\n",
            html_escape(v.name),
            v.causality,
            v.variability,
            v.unit.unwrap_or(""),
            start,
            range,
            html_escape(v.description)
        ));
    }
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{name}</title>\n\
         <style>body{{font-family:sans-serif;max-width:60em;margin:auto}}table{{border-collapse:collapse}}\
         td,th{{border:1px solid #ccc;padding:2px 6px;vertical-align:top}}</style></head><body>\n\
         <h1>{name}</h1>\n<p>{desc}</p>\n<p>FMI 2.0 co-simulation, model identifier <code>{id}</code>, GUID <code>{guid}</code>, version {version}.</p>\n\
         {method}\n<h2>Variables</h2>\n<table><tr><th>name</th><th>causality</th><th>variability</th><th>unit</th><th>start</th><th>range</th><th>description</th></tr>\n{rows}</table>\n</body></html>\n",
        name = html_escape(info.model_name),
        desc = html_escape(info.description),
        id = info.model_identifier,
        guid = info.guid,
        version = info.version,
        method = method_html,
    )
}
