//! Reading: the element tree ([`crate::xml`]) to [`ModelDescription`].
//!
//! Only the elements and attributes the types hold are read; anything else is skipped so that
//! files from other tools load. Attributes with a default in the standard get that default
//! (causality local, variability continuous, CoSimulation flags false, BaseUnit factor 1 and
//! offset 0). Required attributes (per the FMI 2.0 schema) that are missing, and values that do
//! not parse, are errors that name the element, attribute and variable and give a line and
//! column. The reader does not judge the content: that is [`ModelDescription::validate`].

use std::path::Path;
use std::str::FromStr;

use crate::error::ParseError;
use crate::types::*;
use crate::xml::{self, Element, line_column};

impl ModelDescription {
    /// Parses the text of a `modelDescription.xml`.
    pub fn from_xml(xml: &str) -> Result<ModelDescription, ParseError> {
        let xml = xml.strip_prefix('\u{feff}').unwrap_or(xml);
        let root = xml::parse(xml)?;
        Reader { text: xml }.model_description(&root)
    }

    /// Parses the bytes of a `modelDescription.xml`, which must be UTF-8 (as FMI requires): the
    /// first invalid byte is an error with its line and column.
    pub fn from_bytes(bytes: &[u8]) -> Result<ModelDescription, ParseError> {
        match std::str::from_utf8(bytes) {
            Ok(text) => ModelDescription::from_xml(text),
            Err(e) => {
                let valid = e.valid_up_to();
                // The prefix is valid UTF-8 by definition.
                let before = std::str::from_utf8(&bytes[..valid]).unwrap_or_default();
                let (line, column) = line_column(before, valid);
                let utf16 = bytes.starts_with(&[0xff, 0xfe]) || bytes.starts_with(&[0xfe, 0xff]);
                Err(ParseError::Xml {
                    line,
                    column,
                    message: format!(
                        "byte 0x{:02X} (offset {valid}) is not UTF-8{}; modelDescription.xml must be UTF-8",
                        bytes[valid],
                        if utf16 {
                            " (the file starts with a UTF-16 byte-order mark)"
                        } else {
                            ""
                        }
                    ),
                })
            }
        }
    }

    /// Reads and parses a file; errors name the path.
    pub fn from_file(path: &Path) -> Result<ModelDescription, ParseError> {
        let bytes = std::fs::read(path).map_err(|source| ParseError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        ModelDescription::from_bytes(&bytes).map_err(|source| ParseError::InFile {
            path: path.to_path_buf(),
            source: Box::new(source),
        })
    }
}

/// The conversion, with the input text at hand to turn offsets into lines and columns.
struct Reader<'t> {
    text: &'t str,
}

/// The name of the `ScalarVariable` being read, for error messages.
type Var<'a> = Option<&'a str>;

impl Reader<'_> {
    fn model_description(&self, root: &Element) -> Result<ModelDescription, ParseError> {
        if root.name != "fmiModelDescription" {
            let (line, column) = line_column(self.text, root.offset);
            return Err(ParseError::NotModelDescription {
                line,
                column,
                found: root.name.clone(),
            });
        }
        let mut md = ModelDescription {
            fmi_version: self.required(root, "fmiVersion", None)?.to_string(),
            model_name: self.required(root, "modelName", None)?.to_string(),
            guid: self.required(root, "guid", None)?.to_string(),
            description: string(root, "description"),
            author: string(root, "author"),
            version: string(root, "version"),
            copyright: string(root, "copyright"),
            license: string(root, "license"),
            generation_tool: string(root, "generationTool"),
            generation_date_and_time: string(root, "generationDateAndTime"),
            variable_naming_convention: string(root, "variableNamingConvention"),
            number_of_event_indicators: self.number(root, "numberOfEventIndicators", None)?,
            ..ModelDescription::default()
        };
        if let Some(me) = root.child("ModelExchange") {
            md.model_exchange_identifier =
                Some(self.required(me, "modelIdentifier", None)?.to_string());
        }
        if let Some(cs) = root.child("CoSimulation") {
            md.co_simulation = Some(self.co_simulation(cs)?);
        }
        if let Some(units) = root.child("UnitDefinitions") {
            md.unit_definitions = units
                .children_named("Unit")
                .map(|u| self.unit(u))
                .collect::<Result<_, _>>()?;
        }
        if let Some(types) = root.child("TypeDefinitions") {
            md.type_definitions = types
                .children_named("SimpleType")
                .map(|t| self.simple_type(t))
                .collect::<Result<_, _>>()?;
        }
        if let Some(categories) = root.child("LogCategories") {
            md.log_categories = categories
                .children_named("Category")
                .map(|c| {
                    Ok(Category {
                        name: self.required(c, "name", None)?.to_string(),
                        description: string(c, "description"),
                    })
                })
                .collect::<Result<_, ParseError>>()?;
        }
        if let Some(de) = root.child("DefaultExperiment") {
            md.default_experiment = Some(DefaultExperiment {
                start_time: self.number(de, "startTime", None)?,
                stop_time: self.number(de, "stopTime", None)?,
                tolerance: self.number(de, "tolerance", None)?,
                step_size: self.number(de, "stepSize", None)?,
            });
        }
        // ModelVariables and ModelStructure are required by the schema, but a file without them
        // still describes something: read them as empty and leave the judgement to validate().
        if let Some(vars) = root.child("ModelVariables") {
            md.model_variables = vars
                .children_named("ScalarVariable")
                .map(|v| self.scalar_variable(v))
                .collect::<Result<_, _>>()?;
        }
        if let Some(ms) = root.child("ModelStructure") {
            md.model_structure = ModelStructure {
                outputs: self.unknowns(ms, "Outputs")?,
                derivatives: self.unknowns(ms, "Derivatives")?,
                initial_unknowns: self.unknowns(ms, "InitialUnknowns")?,
            };
        }
        Ok(md)
    }

    fn co_simulation(&self, cs: &Element) -> Result<CoSimulation, ParseError> {
        let flag = |name| self.boolean(cs, name, None).map(|b| b.unwrap_or(false));
        Ok(CoSimulation {
            model_identifier: self.required(cs, "modelIdentifier", None)?.to_string(),
            needs_execution_tool: flag("needsExecutionTool")?,
            can_handle_variable_communication_step_size: flag(
                "canHandleVariableCommunicationStepSize",
            )?,
            can_interpolate_inputs: flag("canInterpolateInputs")?,
            max_output_derivative_order: self
                .number(cs, "maxOutputDerivativeOrder", None)?
                .unwrap_or(0),
            can_run_asynchronuously: flag("canRunAsynchronuously")?,
            can_be_instantiated_only_once_per_process: flag("canBeInstantiatedOnlyOncePerProcess")?,
            can_not_use_memory_management_functions: flag("canNotUseMemoryManagementFunctions")?,
            can_get_and_set_fmu_state: flag("canGetAndSetFMUstate")?,
            can_serialize_fmu_state: flag("canSerializeFMUstate")?,
            provides_directional_derivative: flag("providesDirectionalDerivative")?,
        })
    }

    fn unit(&self, u: &Element) -> Result<Unit, ParseError> {
        let base_unit = match u.child("BaseUnit") {
            Some(b) => {
                let exp = |name| self.number::<i32>(b, name, None).map(|e| e.unwrap_or(0));
                Some(BaseUnit {
                    kg: exp("kg")?,
                    m: exp("m")?,
                    s: exp("s")?,
                    a: exp("A")?,
                    k: exp("K")?,
                    mol: exp("mol")?,
                    cd: exp("cd")?,
                    rad: exp("rad")?,
                    factor: self.number(b, "factor", None)?.unwrap_or(1.0),
                    offset: self.number(b, "offset", None)?.unwrap_or(0.0),
                })
            }
            None => None,
        };
        let display_units = u
            .children_named("DisplayUnit")
            .map(|d| {
                Ok(DisplayUnit {
                    name: self.required(d, "name", None)?.to_string(),
                    factor: self.number(d, "factor", None)?.unwrap_or(1.0),
                    offset: self.number(d, "offset", None)?.unwrap_or(0.0),
                })
            })
            .collect::<Result<_, ParseError>>()?;
        Ok(Unit {
            name: self.required(u, "name", None)?.to_string(),
            base_unit,
            display_units,
        })
    }

    fn simple_type(&self, t: &Element) -> Result<SimpleType, ParseError> {
        let name = self.required(t, "name", None)?.to_string();
        let ty = self.type_element(t, None)?;
        let items = ty
            .children_named("Item")
            .map(|item| {
                Ok((
                    self.required(item, "name", None)?.to_string(),
                    self.parse_value(item, "value", self.required(item, "value", None)?, None)?,
                ))
            })
            .collect::<Result<_, ParseError>>()?;
        Ok(SimpleType {
            name,
            description: string(t, "description"),
            base_type: ty.name.clone(),
            quantity: string(ty, "quantity"),
            unit: string(ty, "unit"),
            display_unit: string(ty, "displayUnit"),
            items,
        })
    }

    fn scalar_variable(&self, v: &Element) -> Result<ScalarVariable, ParseError> {
        let name = self.required(v, "name", None)?;
        let var = Some(name);
        let causality = match self.keyword(
            v,
            "causality",
            var,
            Causality::from_xml_name,
            "one of parameter, calculatedParameter, input, output, local, independent",
        )? {
            Some(c) => c,
            None => Causality::Local,
        };
        let variability = self
            .keyword(
                v,
                "variability",
                var,
                Variability::from_xml_name,
                "one of constant, fixed, tunable, discrete, continuous",
            )?
            .unwrap_or(Variability::Continuous);
        let initial = self.keyword(
            v,
            "initial",
            var,
            Initial::from_xml_name,
            "one of exact, approx, calculated",
        )?;
        let ty = self.type_element(v, var)?;
        let kind = match BaseType::from_xml_name(&ty.name) {
            Some(BaseType::Real) => VariableKind::Real(RealAttributes {
                declared_type: string(ty, "declaredType"),
                quantity: string(ty, "quantity"),
                unit: string(ty, "unit"),
                display_unit: string(ty, "displayUnit"),
                relative_quantity: self.boolean(ty, "relativeQuantity", var)?,
                min: self.number(ty, "min", var)?,
                max: self.number(ty, "max", var)?,
                nominal: self.number(ty, "nominal", var)?,
                unbounded: self.boolean(ty, "unbounded", var)?,
                start: self.number(ty, "start", var)?,
                derivative: self.number(ty, "derivative", var)?,
                reinit: self.boolean(ty, "reinit", var)?,
            }),
            Some(BaseType::Integer) => VariableKind::Integer(self.integer_attributes(ty, var)?),
            Some(BaseType::Enumeration) => {
                VariableKind::Enumeration(self.integer_attributes(ty, var)?)
            }
            Some(BaseType::Boolean) => VariableKind::Boolean {
                declared_type: string(ty, "declaredType"),
                start: self.boolean(ty, "start", var)?,
            },
            Some(BaseType::String) => VariableKind::String {
                declared_type: string(ty, "declaredType"),
                start: string(ty, "start"),
            },
            None => unreachable!("the type element was found by its name"),
        };
        Ok(ScalarVariable {
            name: name.to_string(),
            value_reference: self.parse_value(
                v,
                "valueReference",
                self.required(v, "valueReference", var)?,
                var,
            )?,
            description: string(v, "description"),
            causality,
            variability,
            initial,
            can_handle_multiple_set_per_time_instant: self.boolean(
                v,
                "canHandleMultipleSetPerTimeInstant",
                var,
            )?,
            kind,
        })
    }

    fn integer_attributes(
        &self,
        ty: &Element,
        var: Var<'_>,
    ) -> Result<IntegerAttributes, ParseError> {
        Ok(IntegerAttributes {
            declared_type: string(ty, "declaredType"),
            quantity: string(ty, "quantity"),
            min: self.number(ty, "min", var)?,
            max: self.number(ty, "max", var)?,
            start: self.number(ty, "start", var)?,
        })
    }

    fn unknowns(&self, ms: &Element, list: &'static str) -> Result<Vec<Unknown>, ParseError> {
        let Some(list) = ms.child(list) else {
            return Ok(Vec::new());
        };
        list.children_named("Unknown")
            .map(|u| {
                let index = self.parse_value(u, "index", self.required(u, "index", None)?, None)?;
                let dependencies = match u.attribute("dependencies") {
                    Some(a) => Some(
                        a.value
                            .split_whitespace()
                            .map(|d| {
                                self.parse_value_at(u, "dependencies", &a.value, d, a.offset, None)
                            })
                            .collect::<Result<Vec<u32>, _>>()?,
                    ),
                    None => None,
                };
                let dependencies_kind = u
                    .attribute("dependenciesKind")
                    .map(|a| a.value.split_whitespace().map(str::to_string).collect());
                Ok(Unknown {
                    index,
                    dependencies,
                    dependencies_kind,
                })
            })
            .collect()
    }

    // ---- attribute helpers -------------------------------------------------------------------

    fn required<'e>(
        &self,
        e: &'e Element,
        attribute: &'static str,
        var: Var<'_>,
    ) -> Result<&'e str, ParseError> {
        match e.attribute(attribute) {
            Some(a) => Ok(&a.value),
            None => {
                let (line, column) = line_column(self.text, e.offset);
                Err(ParseError::MissingAttribute {
                    line,
                    column,
                    element: e.name.clone(),
                    attribute,
                    variable: var.map(str::to_string),
                })
            }
        }
    }

    /// The child of a ScalarVariable or SimpleType that gives its type (Real, Integer, ...).
    fn type_element<'e>(&self, e: &'e Element, var: Var<'_>) -> Result<&'e Element, ParseError> {
        e.children
            .iter()
            .find(|c| BaseType::from_xml_name(&c.name).is_some())
            .ok_or_else(|| {
                self.missing_element(e, "Real, Integer, Boolean, String or Enumeration", var)
            })
    }

    fn missing_element(&self, e: &Element, expected: &'static str, var: Var<'_>) -> ParseError {
        let (line, column) = line_column(self.text, e.offset);
        ParseError::MissingElement {
            line,
            column,
            element: e.name.clone(),
            expected,
            variable: var.map(str::to_string),
        }
    }

    /// An optional numeric attribute (f64, i32 or u32), whitespace-trimmed as xs:double and
    /// xs:int are.
    fn number<T: Number>(
        &self,
        e: &Element,
        attribute: &'static str,
        var: Var<'_>,
    ) -> Result<Option<T>, ParseError> {
        match e.attribute(attribute) {
            Some(a) => self.parse_value(e, attribute, &a.value, var).map(Some),
            None => Ok(None),
        }
    }

    fn parse_value<T: Number>(
        &self,
        e: &Element,
        attribute: &'static str,
        value: &str,
        var: Var<'_>,
    ) -> Result<T, ParseError> {
        let offset = e.attribute(attribute).map_or(e.offset, |a| a.offset);
        self.parse_value_at(e, attribute, value, value, offset, var)
    }

    /// Parses `token` (part of `value`), reporting the whole value on failure.
    fn parse_value_at<T: Number>(
        &self,
        e: &Element,
        attribute: &'static str,
        value: &str,
        token: &str,
        offset: usize,
        var: Var<'_>,
    ) -> Result<T, ParseError> {
        T::parse_xml(token.trim())
            .ok_or_else(|| self.invalid(e, attribute, value, offset, T::EXPECTED, var))
    }

    /// xs:boolean: "true", "false", "1" or "0".
    fn boolean(
        &self,
        e: &Element,
        attribute: &'static str,
        var: Var<'_>,
    ) -> Result<Option<bool>, ParseError> {
        let Some(a) = e.attribute(attribute) else {
            return Ok(None);
        };
        match a.value.trim() {
            "true" | "1" => Ok(Some(true)),
            "false" | "0" => Ok(Some(false)),
            _ => Err(self.invalid(e, attribute, &a.value, a.offset, "true or false", var)),
        }
    }

    fn keyword<T>(
        &self,
        e: &Element,
        attribute: &'static str,
        var: Var<'_>,
        parse: fn(&str) -> Option<T>,
        expected: &'static str,
    ) -> Result<Option<T>, ParseError> {
        let Some(a) = e.attribute(attribute) else {
            return Ok(None);
        };
        parse(a.value.trim())
            .map(Some)
            .ok_or_else(|| self.invalid(e, attribute, &a.value, a.offset, expected, var))
    }

    fn invalid(
        &self,
        e: &Element,
        attribute: &'static str,
        value: &str,
        offset: usize,
        expected: &'static str,
        var: Var<'_>,
    ) -> ParseError {
        let (line, column) = line_column(self.text, offset);
        ParseError::InvalidValue {
            line,
            column,
            element: e.name.clone(),
            attribute,
            value: value.to_string(),
            expected,
            variable: var.map(str::to_string),
        }
    }
}

/// An optional string attribute, kept verbatim (after entity resolution).
fn string(e: &Element, attribute: &'static str) -> Option<String> {
    e.attribute(attribute).map(|a| a.value.clone())
}

/// The numeric attribute types, with the XML Schema spellings they accept.
trait Number: Sized {
    const EXPECTED: &'static str;
    fn parse_xml(s: &str) -> Option<Self>;
}

impl Number for f64 {
    const EXPECTED: &'static str = "a floating-point number";
    fn parse_xml(s: &str) -> Option<f64> {
        // xs:double spells the specials INF, -INF and NaN; Rust's parser also accepts "inf",
        // "infinity" in any case, which is harmless leniency.
        match s {
            "INF" | "+INF" => Some(f64::INFINITY),
            "-INF" => Some(f64::NEG_INFINITY),
            _ => f64::from_str(s).ok(),
        }
    }
}

impl Number for i32 {
    const EXPECTED: &'static str = "a 32-bit integer";
    fn parse_xml(s: &str) -> Option<i32> {
        s.parse().ok()
    }
}

impl Number for u32 {
    const EXPECTED: &'static str = "a non-negative 32-bit integer";
    fn parse_xml(s: &str) -> Option<u32> {
        s.parse().ok()
    }
}
