//! Writing: [`ModelDescription`] to schema-valid FMI 2.0 XML.
//!
//! Why hand-written rather than serde: the schema fixes the child order (ModelExchange,
//! CoSimulation, UnitDefinitions, TypeDefinitions, LogCategories, DefaultExperiment,
//! ModelVariables, ModelStructure), forbids present-but-empty lists, and importers read floats
//! with `strtod`, so each of those choices is made explicitly here. What is written:
//! - optional attributes only when `Some`; CoSimulation flags only when true (their default is
//!   false) and maxOutputDerivativeOrder only when > 0; BaseUnit exponents only when non-zero,
//!   factor/offset only when not exactly 1/0;
//! - list elements (UnitDefinitions, TypeDefinitions, LogCategories, Outputs, Derivatives,
//!   InitialUnknowns) only when non-empty; ModelVariables and ModelStructure always (required);
//! - `causality` and `variability` always, even at their defaults, so a reader of the file does
//!   not need to know the defaults;
//! - floats by [`format_f64`], which round-trips exactly.

use std::fmt::Write as _;

use crate::types::*;
use crate::xml::escape_attribute_and_apos;

impl ModelDescription {
    /// The `modelDescription.xml` text (UTF-8, 2-space indentation, one element per line, and an
    /// `<!-- index N -->` comment before each ScalarVariable giving its 1-based index).
    pub fn to_xml(&self) -> String {
        let mut out = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
        let mut root = Tag::new(&mut out, 0, "fmiModelDescription");
        root.attr("fmiVersion", &self.fmi_version)
            .attr("modelName", &self.model_name)
            .attr("guid", &self.guid)
            .opt("description", self.description.as_deref())
            .opt("author", self.author.as_deref())
            .opt("version", self.version.as_deref())
            .opt("copyright", self.copyright.as_deref())
            .opt("license", self.license.as_deref())
            .opt("generationTool", self.generation_tool.as_deref())
            .opt(
                "generationDateAndTime",
                self.generation_date_and_time.as_deref(),
            )
            .opt(
                "variableNamingConvention",
                self.variable_naming_convention.as_deref(),
            )
            .opt_num("numberOfEventIndicators", self.number_of_event_indicators)
            .open();

        if let Some(id) = &self.model_exchange_identifier {
            Tag::new(&mut out, 1, "ModelExchange")
                .attr("modelIdentifier", id)
                .empty();
        }
        if let Some(cs) = &self.co_simulation {
            write_co_simulation(&mut out, cs);
        }
        if !self.unit_definitions.is_empty() {
            open_list(&mut out, 1, "UnitDefinitions");
            for unit in &self.unit_definitions {
                write_unit(&mut out, unit);
            }
            close(&mut out, 1, "UnitDefinitions");
        }
        if !self.type_definitions.is_empty() {
            open_list(&mut out, 1, "TypeDefinitions");
            for ty in &self.type_definitions {
                write_simple_type(&mut out, ty);
            }
            close(&mut out, 1, "TypeDefinitions");
        }
        if !self.log_categories.is_empty() {
            open_list(&mut out, 1, "LogCategories");
            for c in &self.log_categories {
                Tag::new(&mut out, 2, "Category")
                    .attr("name", &c.name)
                    .opt("description", c.description.as_deref())
                    .empty();
            }
            close(&mut out, 1, "LogCategories");
        }
        if let Some(de) = &self.default_experiment {
            Tag::new(&mut out, 1, "DefaultExperiment")
                .opt_f64("startTime", de.start_time)
                .opt_f64("stopTime", de.stop_time)
                .opt_f64("tolerance", de.tolerance)
                .opt_f64("stepSize", de.step_size)
                .empty();
        }
        if self.model_variables.is_empty() {
            Tag::new(&mut out, 1, "ModelVariables").empty();
        } else {
            open_list(&mut out, 1, "ModelVariables");
            for (i, v) in self.model_variables.iter().enumerate() {
                let _ = writeln!(out, "    <!-- index {} -->", i + 1);
                write_variable(&mut out, v);
            }
            close(&mut out, 1, "ModelVariables");
        }
        write_model_structure(&mut out, &self.model_structure);
        close(&mut out, 0, "fmiModelDescription");
        out
    }
}

fn write_co_simulation(out: &mut String, cs: &CoSimulation) {
    let mut tag = Tag::new(out, 1, "CoSimulation");
    tag.attr("modelIdentifier", &cs.model_identifier)
        .flag("needsExecutionTool", cs.needs_execution_tool)
        .flag(
            "canHandleVariableCommunicationStepSize",
            cs.can_handle_variable_communication_step_size,
        )
        .flag("canInterpolateInputs", cs.can_interpolate_inputs);
    if cs.max_output_derivative_order > 0 {
        tag.num("maxOutputDerivativeOrder", cs.max_output_derivative_order);
    }
    tag.flag("canRunAsynchronuously", cs.can_run_asynchronuously)
        .flag(
            "canBeInstantiatedOnlyOncePerProcess",
            cs.can_be_instantiated_only_once_per_process,
        )
        .flag(
            "canNotUseMemoryManagementFunctions",
            cs.can_not_use_memory_management_functions,
        )
        .flag("canGetAndSetFMUstate", cs.can_get_and_set_fmu_state)
        .flag("canSerializeFMUstate", cs.can_serialize_fmu_state)
        .flag(
            "providesDirectionalDerivative",
            cs.provides_directional_derivative,
        )
        .empty();
}

fn write_unit(out: &mut String, unit: &Unit) {
    let has_children = unit.base_unit.is_some() || !unit.display_units.is_empty();
    let mut tag = Tag::new(out, 2, "Unit");
    tag.attr("name", &unit.name);
    if !has_children {
        tag.empty();
        return;
    }
    tag.open();
    if let Some(b) = &unit.base_unit {
        let mut tag = Tag::new(out, 3, "BaseUnit");
        for (name, exponent) in [
            ("kg", b.kg),
            ("m", b.m),
            ("s", b.s),
            ("A", b.a),
            ("K", b.k),
            ("mol", b.mol),
            ("cd", b.cd),
            ("rad", b.rad),
        ] {
            if exponent != 0 {
                tag.num(name, exponent);
            }
        }
        tag.f64_unless("factor", b.factor, 1.0)
            .f64_unless("offset", b.offset, 0.0)
            .empty();
    }
    for d in &unit.display_units {
        Tag::new(out, 3, "DisplayUnit")
            .attr("name", &d.name)
            .f64_unless("factor", d.factor, 1.0)
            .f64_unless("offset", d.offset, 0.0)
            .empty();
    }
    close(out, 2, "Unit");
}

fn write_simple_type(out: &mut String, ty: &SimpleType) {
    Tag::new(out, 2, "SimpleType")
        .attr("name", &ty.name)
        .opt("description", ty.description.as_deref())
        .open();
    let mut tag = Tag::new(out, 3, &ty.base_type);
    tag.opt("quantity", ty.quantity.as_deref())
        .opt("unit", ty.unit.as_deref())
        .opt("displayUnit", ty.display_unit.as_deref());
    if ty.items.is_empty() {
        tag.empty();
    } else {
        tag.open();
        for (name, value) in &ty.items {
            Tag::new(out, 4, "Item")
                .attr("name", name)
                .num("value", value)
                .empty();
        }
        close(out, 3, &ty.base_type);
    }
    close(out, 2, "SimpleType");
}

fn write_variable(out: &mut String, v: &ScalarVariable) {
    Tag::new(out, 2, "ScalarVariable")
        .attr("name", &v.name)
        .num("valueReference", v.value_reference)
        .opt("description", v.description.as_deref())
        .attr("causality", v.causality.as_str())
        .attr("variability", v.variability.as_str())
        .opt("initial", v.initial.map(Initial::as_str))
        .opt_bool(
            "canHandleMultipleSetPerTimeInstant",
            v.can_handle_multiple_set_per_time_instant,
        )
        .open();
    let mut tag = Tag::new(out, 3, v.kind.base_type().as_str());
    match &v.kind {
        VariableKind::Real(r) => {
            tag.opt("declaredType", r.declared_type.as_deref())
                .opt("quantity", r.quantity.as_deref())
                .opt("unit", r.unit.as_deref())
                .opt("displayUnit", r.display_unit.as_deref())
                .opt_bool("relativeQuantity", r.relative_quantity)
                .opt_f64("min", r.min)
                .opt_f64("max", r.max)
                .opt_f64("nominal", r.nominal)
                .opt_bool("unbounded", r.unbounded)
                .opt_f64("start", r.start)
                .opt_num("derivative", r.derivative)
                .opt_bool("reinit", r.reinit);
        }
        VariableKind::Integer(i) | VariableKind::Enumeration(i) => {
            tag.opt("declaredType", i.declared_type.as_deref())
                .opt("quantity", i.quantity.as_deref())
                .opt_num("min", i.min)
                .opt_num("max", i.max)
                .opt_num("start", i.start);
        }
        VariableKind::Boolean {
            declared_type,
            start,
        } => {
            tag.opt("declaredType", declared_type.as_deref())
                .opt_bool("start", *start);
        }
        VariableKind::String {
            declared_type,
            start,
        } => {
            tag.opt("declaredType", declared_type.as_deref())
                .opt("start", start.as_deref());
        }
    }
    tag.empty();
    close(out, 2, "ScalarVariable");
}

fn write_model_structure(out: &mut String, ms: &ModelStructure) {
    let lists = [
        ("Outputs", &ms.outputs),
        ("Derivatives", &ms.derivatives),
        ("InitialUnknowns", &ms.initial_unknowns),
    ];
    if lists.iter().all(|(_, l)| l.is_empty()) {
        Tag::new(out, 1, "ModelStructure").empty();
        return;
    }
    open_list(out, 1, "ModelStructure");
    for (name, list) in lists {
        if list.is_empty() {
            continue;
        }
        open_list(out, 2, name);
        for u in list {
            Tag::new(out, 3, "Unknown")
                .num("index", u.index)
                .opt(
                    "dependencies",
                    u.dependencies.as_ref().map(|d| join(d)).as_deref(),
                )
                .opt(
                    "dependenciesKind",
                    u.dependencies_kind.as_ref().map(|k| k.join(" ")).as_deref(),
                )
                .empty();
        }
        close(out, 2, name);
    }
    close(out, 1, "ModelStructure");
}

fn join(values: &[u32]) -> String {
    values
        .iter()
        .map(u32::to_string)
        .collect::<Vec<_>>()
        .join(" ")
}

/// Formats an f64 so that parsing the text gives back the identical bits, in the shortest
/// such form: Rust's `{}` (shortest round-trip digits), switched to exponent form `{:e}`
/// (also shortest round-trip) when |x| >= 1e15 or 0 < |x| < 1e-5, so that no value is written
/// with hundreds of digits (`{}` of 1e300 would be 301 characters). Negative zero is "-0".
/// Non-finite values use the XML Schema spellings INF, -INF and NaN.
pub fn format_f64(x: f64) -> String {
    if x.is_nan() {
        "NaN".to_string()
    } else if x.is_infinite() {
        if x > 0.0 { "INF" } else { "-INF" }.to_string()
    } else if x != 0.0 && (x.abs() >= 1e15 || x.abs() < 1e-5) {
        format!("{x:e}")
    } else {
        format!("{x}")
    }
}

fn open_list(out: &mut String, depth: usize, name: &str) {
    indent(out, depth);
    let _ = writeln!(out, "<{name}>");
}

fn close(out: &mut String, depth: usize, name: &str) {
    indent(out, depth);
    let _ = writeln!(out, "</{name}>");
}

fn indent(out: &mut String, depth: usize) {
    for _ in 0..depth {
        out.push_str("  ");
    }
}

/// A start tag being written: attributes are appended, then `empty()` or `open()` ends it.
struct Tag<'o> {
    out: &'o mut String,
}

impl<'o> Tag<'o> {
    fn new(out: &'o mut String, depth: usize, name: &str) -> Tag<'o> {
        indent(out, depth);
        out.push('<');
        out.push_str(name);
        Tag { out }
    }

    fn attr(&mut self, name: &str, value: &str) -> &mut Self {
        self.out.push(' ');
        self.out.push_str(name);
        self.out.push_str("=\"");
        escape_attribute_and_apos(value, self.out);
        self.out.push('"');
        self
    }

    fn opt(&mut self, name: &str, value: Option<&str>) -> &mut Self {
        if let Some(value) = value {
            self.attr(name, value);
        }
        self
    }

    fn num(&mut self, name: &str, value: impl std::fmt::Display) -> &mut Self {
        let _ = write!(self.out, " {name}=\"{value}\"");
        self
    }

    fn opt_num(&mut self, name: &str, value: Option<impl std::fmt::Display>) -> &mut Self {
        if let Some(value) = value {
            self.num(name, value);
        }
        self
    }

    fn opt_f64(&mut self, name: &str, value: Option<f64>) -> &mut Self {
        if let Some(value) = value {
            self.num(name, format_f64(value));
        }
        self
    }

    /// Writes the value unless it is bit-for-bit the schema default (so -0.0 is still written
    /// for a default of 0).
    fn f64_unless(&mut self, name: &str, value: f64, default: f64) -> &mut Self {
        if value.to_bits() != default.to_bits() {
            self.num(name, format_f64(value));
        }
        self
    }

    fn opt_bool(&mut self, name: &str, value: Option<bool>) -> &mut Self {
        if let Some(value) = value {
            self.num(name, value);
        }
        self
    }

    /// A flag whose default is false: written only when true.
    fn flag(&mut self, name: &str, value: bool) -> &mut Self {
        if value {
            self.num(name, "true");
        }
        self
    }

    fn empty(&mut self) {
        self.out.push_str("/>\n");
    }

    fn open(&mut self) {
        self.out.push_str(">\n");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floats_round_trip_and_stay_short() {
        for x in [
            0.0,
            -0.0,
            0.1,
            1.0,
            -2.5,
            1e-5,
            9.99e-6,
            1e-20,
            5e-324,
            f64::MIN_POSITIVE,
            123456789.123,
            1e14,
            999999999999999.9,
            1e15,
            1e300,
            f64::MAX,
            -f64::MAX,
            std::f64::consts::PI,
        ] {
            let s = format_f64(x);
            let back: f64 = s.parse().unwrap();
            assert_eq!(back.to_bits(), x.to_bits(), "{x:?} written as {s}");
            assert!(s.len() <= 24, "{x:?} written as {s} ({} chars)", s.len());
        }
        assert_eq!(format_f64(1e-20), "1e-20");
        assert_eq!(format_f64(1e300), "1e300");
        assert_eq!(format_f64(5e-324), "5e-324");
        assert_eq!(format_f64(0.1), "0.1");
        assert_eq!(format_f64(-0.0), "-0");
        assert_eq!(format_f64(123456789.123), "123456789.123");
        assert_eq!(format_f64(1e15), "1e15");
        assert_eq!(format_f64(1e-5), "0.00001");
        assert_eq!(format_f64(f64::INFINITY), "INF");
    }
}
