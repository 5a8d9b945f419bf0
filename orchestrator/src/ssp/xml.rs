//! A small element tree over quick-xml's event reader, and the attribute escaping the writer
//! uses.
//!
//! Names are local names (`ssd:Component` -> `Component`): SSP files from different tools
//! choose different prefixes (or a default namespace), and nothing in SSP 1.0 relies on two
//! namespaces sharing a local name at the same place. Every element and attribute keeps its byte
//! offset so that any later complaint can give a line and column. Text content is dropped: SSP
//! keeps its information in attributes.

use quick_xml::Reader;
use quick_xml::XmlVersion;
use quick_xml::events::{BytesStart, Event};

use super::error::SspError;

#[derive(Debug)]
pub(crate) struct Element {
    /// Local name.
    pub name: String,
    /// Byte offset of the `<` that opens the element.
    pub offset: usize,
    pub attributes: Vec<Attribute>,
    pub children: Vec<Element>,
}

#[derive(Debug)]
pub(crate) struct Attribute {
    /// Local name (namespace declarations are not kept).
    pub name: String,
    /// With entity and character references resolved, normalized per XML 1.0.
    pub value: String,
    pub offset: usize,
}

impl Element {
    pub fn attribute(&self, name: &str) -> Option<&Attribute> {
        self.attributes.iter().find(|a| a.name == name)
    }

    pub fn value(&self, name: &str) -> Option<&str> {
        self.attribute(name).map(|a| a.value.as_str())
    }

    /// The first child with this local name.
    pub fn child(&self, name: &str) -> Option<&Element> {
        self.children.iter().find(|c| c.name == name)
    }

    pub fn children_named<'a>(&'a self, name: &'a str) -> impl Iterator<Item = &'a Element> + 'a {
        self.children.iter().filter(move |c| c.name == name)
    }
}

/// Parses `text` into its root element, or reports the first well-formedness error.
pub(crate) fn parse(text: &str) -> Result<Element, SspError> {
    let mut reader = Reader::from_str(text);
    reader.config_mut().check_end_names = true;
    let mut stack: Vec<Element> = Vec::new();
    let mut root: Option<Element> = None;
    loop {
        // Text is not trimmed, so the position before an event is its first byte.
        let offset = reader.buffer_position() as usize;
        let event = match reader.read_event() {
            Ok(event) => event,
            Err(e) => {
                return Err(xml_error(
                    text,
                    reader.error_position() as usize,
                    e.to_string(),
                ));
            }
        };
        match event {
            Event::Start(start) => stack.push(element(text, offset, &start)?),
            Event::Empty(start) => {
                let element = element(text, offset, &start)?;
                attach(text, &mut stack, &mut root, element)?;
            }
            Event::End(_) => {
                let element = stack
                    .pop()
                    .ok_or_else(|| xml_error(text, offset, "unexpected end tag".into()))?;
                attach(text, &mut stack, &mut root, element)?;
            }
            Event::Text(t) if stack.is_empty() && !t.trim().is_empty() => {
                return Err(xml_error(
                    text,
                    offset,
                    "text outside the root element".into(),
                ));
            }
            Event::Eof => break,
            _ => {}
        }
    }
    if let Some(open) = stack.last() {
        return Err(xml_error(
            text,
            open.offset,
            format!("<{}> is never closed (the input ends first)", open.name),
        ));
    }
    root.ok_or_else(|| xml_error(text, text.len(), "no root element".into()))
}

fn attach(
    text: &str,
    stack: &mut [Element],
    root: &mut Option<Element>,
    element: Element,
) -> Result<(), SspError> {
    match stack.last_mut() {
        Some(parent) => parent.children.push(element),
        None if root.is_none() => *root = Some(element),
        None => {
            return Err(xml_error(
                text,
                element.offset,
                format!(
                    "a second root element <{}> after the first one",
                    element.name
                ),
            ));
        }
    }
    Ok(())
}

fn element(text: &str, offset: usize, start: &BytesStart<'_>) -> Result<Element, SspError> {
    let name = start.local_name().as_ref().to_string();
    let mut attributes = Vec::new();
    for attr in start.attributes() {
        let attr = attr.map_err(|e| {
            use quick_xml::events::attributes::AttrError::*;
            // Positions are relative to the tag content, which starts after the '<'.
            let (rel, what) = match e {
                ExpectedEq(p) => (p, "an attribute name is not followed by '='"),
                ExpectedValue(p) => (p, "an attribute has no value after '='"),
                UnquotedValue(p) => (p, "an attribute value is not in quotes"),
                ExpectedQuote(p, _) => (p, "an attribute value has no closing quote"),
                Duplicated(p, _) => (p, "an attribute is given twice"),
            };
            xml_error(text, offset + 1 + rel, format!("in <{name}>: {what}"))
        })?;
        let key: &str = attr.key.0;
        if key == "xmlns" || key.starts_with("xmlns:") {
            continue;
        }
        let attr_offset = offset_in(text, key).unwrap_or(offset);
        let value = attr
            .normalized_value(XmlVersion::Implicit1_0)
            .map_err(|e| {
                xml_error(
                    text,
                    attr_offset,
                    format!("in attribute '{key}' of <{name}>: {e}"),
                )
            })?
            .into_owned();
        attributes.push(Attribute {
            name: attr.key.local_name().as_ref().to_string(),
            value,
            offset: attr_offset,
        });
    }
    Ok(Element {
        name,
        offset,
        attributes,
        children: Vec::new(),
    })
}

/// The byte offset of `part` inside `whole`, if `part` borrows from it.
fn offset_in(whole: &str, part: &str) -> Option<usize> {
    let start = whole.as_ptr() as usize;
    let p = part.as_ptr() as usize;
    (p >= start && p + part.len() <= start + whole.len()).then(|| p - start)
}

fn xml_error(text: &str, offset: usize, message: String) -> SspError {
    let (line, column) = line_column(text, offset);
    SspError::Xml {
        line,
        column,
        message,
    }
}

/// A byte offset as a 1-based line and a 1-based column counted in characters.
pub(crate) fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = &text[..offset];
    let line = before.bytes().filter(|&b| b == b'\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    (line, before[line_start..].chars().count() + 1)
}

/// Appends `value` escaped for a double-quoted attribute; tab, newline and carriage return as
/// character references so that attribute-value normalization does not turn them into spaces.
pub(crate) fn escape_attribute(value: &str, out: &mut String) {
    for c in value.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\t' => out.push_str("&#9;"),
            '\n' => out.push_str("&#10;"),
            '\r' => out.push_str("&#13;"),
            c => out.push(c),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn local_names_offsets_and_namespace_declarations() {
        let text = "<?xml version=\"1.0\"?>\n<ssd:A xmlns:ssd=\"u\" ssd:x=\"1&amp;2\">\n  <ssc:B y='&lt;'/>\n</ssd:A>\n";
        let root = parse(text).unwrap();
        assert_eq!(root.name, "A");
        assert_eq!(line_column(text, root.offset), (2, 1));
        assert_eq!(root.attributes.len(), 1);
        assert_eq!(root.value("x"), Some("1&2"));
        assert_eq!(
            line_column(text, root.attribute("x").unwrap().offset),
            (2, 22)
        );
        let b = root.child("B").unwrap();
        assert_eq!(b.value("y"), Some("<"));
        assert_eq!(line_column(text, b.offset), (3, 3));
    }

    #[test]
    fn mismatched_end_tag_has_a_position() {
        match parse("<a>\n  <b>\n  </c>\n</a>").unwrap_err() {
            SspError::Xml { line, column, .. } => assert_eq!((line, column), (3, 3)),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn escaping_round_trips() {
        let mut s = String::new();
        escape_attribute("a&<>\"'\t\n", &mut s);
        assert_eq!(s, "a&amp;&lt;&gt;&quot;'&#9;&#10;");
        let root = parse(&format!("<a v=\"{s}\"/>")).unwrap();
        assert_eq!(root.value("v"), Some("a&<>\"'\t\n"));
    }
}
