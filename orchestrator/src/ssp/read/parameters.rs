//! Parameter bindings of a component: inline parameter sets or `.ssv` files, their values
//! typed as `xs:` types.

use model_description::xml::{self, Element};

use super::super::PARAMETER_SET_MIME_TYPE;
use super::super::error::SspError;
use super::Reader;
use super::files::read_text;
use crate::system::Value;

impl Reader<'_> {
    /// The parameters of one binding, in document order, with the binding's prefix applied and
    /// the offset of each (for errors).
    pub(super) fn binding(
        &self,
        b: &Element,
        owner: &str,
    ) -> Result<Vec<(String, Value, usize)>, SspError> {
        let context = format!("parameter binding of {owner}");
        if let Some(ty) = b.value("type")
            && ty != PARAMETER_SET_MIME_TYPE
        {
            let offset = b.attribute("type").map_or(b.offset, |a| a.offset);
            return Err(self.unsupported(offset, format!("{context} of type '{ty}' (only SSP parameter sets, {PARAMETER_SET_MIME_TYPE}, are)")));
        }
        if b.value("sourceBase") == Some("component") {
            let offset = b.attribute("sourceBase").map_or(b.offset, |a| a.offset);
            return Err(self.unsupported(
                offset,
                format!(
                    "{context} with sourceBase=\"component\" (a parameter file inside the FMU)"
                ),
            ));
        }
        if let Some(mapping) = b.child("ParameterMapping") {
            return Err(self.unsupported(
                mapping.offset,
                format!("<ParameterMapping> in the {context}"),
            ));
        }
        let prefix = b.value("prefix").unwrap_or("");
        let mut out = Vec::new();
        let inline = b.child("ParameterValues");
        if let Some(uri) = b.value("source") {
            if let Some(values) = inline
                && !values.children.is_empty()
            {
                let (line, column) = self.at(values.offset);
                return Err(SspError::Invalid {
                    line,
                    column,
                    message: format!(
                        "the {context} has both a source attribute and inline <ParameterValues>; it must have one or the other"
                    ),
                });
            }
            let path = self.resolve(b, "source", uri, &context)?;
            let shown = self.place.shown(&path);
            let text = read_text(&path, &shown).map_err(|e| {
                let offset = b.attribute("source").map_or(b.offset, |a| a.offset);
                let (line, column) = self.at(offset);
                SspError::Invalid {
                    line,
                    column,
                    message: format!("source=\"{uri}\" of the {context}: {e}"),
                }
            })?;
            let values = (|| {
                let root = xml::parse(&text)?;
                let ssv = Reader {
                    text: &text,
                    place: self.place,
                };
                if root.name != "ParameterSet" {
                    let (line, column) = ssv.at(root.offset);
                    return Err(SspError::WrongRoot {
                        line,
                        column,
                        found: root.name.clone(),
                        expected: "ssv:ParameterSet",
                    });
                }
                ssv.parameter_set(&root)
            })()
            .map_err(|e| SspError::InFile {
                path: shown,
                source: Box::new(e),
            })?;
            out.extend(values);
        } else if let Some(values) = inline {
            for set in values.children_named("ParameterSet") {
                out.extend(self.parameter_set(set)?);
            }
        }
        Ok(out
            .into_iter()
            .map(|(name, value, offset)| (format!("{prefix}{name}"), value, offset))
            .collect())
    }

    pub(super) fn parameter_set(
        &self,
        set: &Element,
    ) -> Result<Vec<(String, Value, usize)>, SspError> {
        let parameters = set.child("Parameters").ok_or_else(|| {
            let (line, column) = self.at(set.offset);
            SspError::MissingElement {
                line,
                column,
                element: set.name.clone(),
                expected: "ssv:Parameters",
                context: set.value("name").map(|n| format!("parameter set '{n}'")),
            }
        })?;
        let mut out = Vec::new();
        for p in parameters.children_named("Parameter") {
            let name = self.required(p, "name", None)?;
            let context = format!("parameter '{name}'");
            let ctx = Some(context.as_str());
            let typed = p
                .children
                .iter()
                .find(|c| {
                    matches!(
                        c.name.as_str(),
                        "Real" | "Integer" | "Boolean" | "String" | "Enumeration" | "Binary"
                    )
                })
                .ok_or_else(|| {
                    let (line, column) = self.at(p.offset);
                    SspError::MissingElement {
                        line,
                        column,
                        element: p.name.clone(),
                        expected: "ssv:Real, ssv:Integer, ssv:Boolean or ssv:String",
                        context: Some(context.clone()),
                    }
                })?;
            let text = self.required(typed, "value", ctx)?;
            let value = match typed.name.as_str() {
                "Real" => Value::Real(parse_double(text).ok_or_else(|| self.invalid(typed, "value", "a floating-point number", ctx))?),
                "Integer" => Value::Integer(text.trim().parse().map_err(|_| self.invalid(typed, "value", "a 32-bit integer", ctx))?),
                "Boolean" => Value::Boolean(match text.trim() {
                    "true" | "1" => true,
                    "false" | "0" => false,
                    _ => return Err(self.invalid(typed, "value", "true, false, 1 or 0", ctx)),
                }),
                "String" => Value::String(text.to_string()),
                other => return Err(self.unsupported(typed.offset, format!("the {other} value of parameter '{name}' (Real, Integer, Boolean and String are)"))),
            };
            out.push((name.to_string(), value, p.offset));
        }
        Ok(out)
    }
}

/// Sets a parameter: replaces the value in place if the name is already there (later wins),
/// appends it otherwise.
pub(super) fn set(parameters: &mut Vec<(String, Value)>, name: String, value: Value) {
    match parameters.iter_mut().find(|(n, _)| *n == name) {
        Some(slot) => slot.1 = value,
        None => parameters.push((name, value)),
    }
}

/// An `xs:double`: decimal or exponent notation, `INF`, `-INF`, `NaN` (surrounding whitespace
/// allowed).
pub(super) fn parse_double(text: &str) -> Option<f64> {
    match text.trim() {
        "INF" | "+INF" => Some(f64::INFINITY),
        "-INF" => Some(f64::NEG_INFINITY),
        "NaN" => Some(f64::NAN),
        t if t
            .bytes()
            .all(|b| b.is_ascii_digit() || b"+-.eE".contains(&b))
            && !t.is_empty() =>
        {
            t.parse().ok()
        }
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn doubles_follow_xs_double() {
        assert_eq!(parse_double(" 1.5e3 "), Some(1500.0));
        assert_eq!(parse_double("-INF"), Some(f64::NEG_INFINITY));
        assert!(parse_double("NaN").unwrap().is_nan());
        assert_eq!(parse_double("inf"), None);
        assert_eq!(parse_double(""), None);
        assert_eq!(parse_double("0x10"), None);
    }
}
