//! A small element tree built with quick-xml's event reader.
//!
//! Why a tree instead of serde: the reader only has to be well-formedness-strict, and the
//! FMI-specific conversion (`read.rs`) then walks the elements it knows and skips everything
//! else (VendorAnnotations, Annotations, SourceFiles, tool extensions), which is what makes it
//! tolerant. Every element and attribute keeps its byte offset in the input, so any later
//! error can be reported with a line and column. Text content is dropped: FMI 2.0 keeps all of
//! its information in attributes.

use quick_xml::Reader;
use quick_xml::XmlVersion;
use quick_xml::events::{BytesStart, Event};

use crate::error::{ParseError, line_column};

/// One element: its (local) name, attributes in document order, and child elements.
#[derive(Debug)]
pub(crate) struct Element {
    pub name: String,
    /// Byte offset of the `<` that opens the element.
    pub offset: usize,
    pub attributes: Vec<Attribute>,
    pub children: Vec<Element>,
}

#[derive(Debug)]
pub(crate) struct Attribute {
    pub name: String,
    /// The value with entity and character references resolved.
    pub value: String,
    /// Byte offset of the attribute name (falls back to the element's `<`).
    pub offset: usize,
}

impl Element {
    pub fn attribute(&self, name: &str) -> Option<&Attribute> {
        self.attributes.iter().find(|a| a.name == name)
    }

    /// The first child element with this name.
    pub fn child(&self, name: &str) -> Option<&Element> {
        self.children.iter().find(|c| c.name == name)
    }

    pub fn children_named<'a>(&'a self, name: &'a str) -> impl Iterator<Item = &'a Element> + 'a {
        self.children.iter().filter(move |c| c.name == name)
    }
}

/// Parses `text` into its root element, or reports the first well-formedness error.
pub(crate) fn parse(text: &str) -> Result<Element, ParseError> {
    let mut reader = Reader::from_str(text);
    reader.config_mut().check_end_names = true;
    let mut stack: Vec<Element> = Vec::new();
    let mut root: Option<Element> = None;
    loop {
        // With text trimming off, the position before an event is the event's first byte,
        // i.e. the '<' of a tag.
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
                // quick-xml has already checked that the name matches the open tag.
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
            // Text, CDATA, comments, processing instructions, the declaration and DOCTYPE carry
            // no FMI 2.0 information.
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
) -> Result<(), ParseError> {
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

fn element(text: &str, offset: usize, start: &BytesStart<'_>) -> Result<Element, ParseError> {
    let name = start.local_name().as_ref().to_string();
    let mut attributes = Vec::new();
    for attr in start.attributes() {
        let attr = attr.map_err(|e| {
            // Attribute errors carry a position relative to the tag content, which starts
            // right after the '<'.
            use quick_xml::events::attributes::AttrError::*;
            let (rel, what) = match e {
                ExpectedEq(p) => (p, "an attribute name is not followed by '='"),
                ExpectedValue(p) => (p, "an attribute has no value after '='"),
                UnquotedValue(p) => (p, "an attribute value is not in quotes"),
                ExpectedQuote(p, _) => (p, "an attribute value has no closing quote"),
                Duplicated(p, _) => (p, "an attribute is given twice"),
            };
            xml_error(text, offset + 1 + rel, format!("in <{name}>: {what}"))
        })?;
        let key = attr.key.0;
        let attr_offset = offset_in(text, key).unwrap_or(offset);
        let value = attr
            // Attribute-value normalization as XML 1.0 requires (literal tabs and newlines
            // become spaces; character references like &#10; survive).
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
            name: key.to_string(),
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

/// The byte offset of `part` inside `whole`, if `part` is a slice of it (it is whenever the
/// reader borrows from the input, which `Reader::from_str` does).
fn offset_in(whole: &str, part: &str) -> Option<usize> {
    let start = whole.as_ptr() as usize;
    let p = part.as_ptr() as usize;
    (p >= start && p + part.len() <= start + whole.len()).then(|| p - start)
}

fn xml_error(text: &str, offset: usize, message: String) -> ParseError {
    let (line, column) = line_column(text, offset);
    ParseError::Xml {
        line,
        column,
        message,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn err_at(text: &str) -> (usize, usize, String) {
        match parse(text).unwrap_err() {
            ParseError::Xml {
                line,
                column,
                message,
            } => (line, column, message),
            other => panic!("unexpected error {other:?}"),
        }
    }

    #[test]
    fn builds_the_tree_with_offsets() {
        let text = "<?xml version=\"1.0\"?>\n<a x=\"1&amp;2\">\n  <b y='&lt;'/><!-- c -->\n  <c>text</c>\n</a>\n";
        let root = parse(text).unwrap();
        assert_eq!(root.name, "a");
        assert_eq!(line_column(text, root.offset), (2, 1));
        assert_eq!(root.attribute("x").unwrap().value, "1&2");
        assert_eq!(
            line_column(text, root.attribute("x").unwrap().offset),
            (2, 4)
        );
        assert_eq!(root.children.len(), 2);
        let b = root.child("b").unwrap();
        assert_eq!(b.attribute("y").unwrap().value, "<");
        assert_eq!(line_column(text, b.offset), (3, 3));
        assert_eq!(root.children[1].name, "c");
    }

    #[test]
    fn mismatched_end_tag_points_at_the_end_tag() {
        let (line, column, message) = err_at("<a>\n  <b>\n  </c>\n</a>");
        assert_eq!((line, column), (3, 3), "{message}");
        assert!(
            message.contains("</b>") || message.contains('b'),
            "{message}"
        );
    }

    #[test]
    fn unclosed_element_points_at_its_start_tag() {
        let (line, column, message) = err_at("<a>\n  <b>\n");
        assert_eq!((line, column), (2, 3), "{message}");
        assert!(message.contains("<b>"), "{message}");
    }

    #[test]
    fn bad_attribute_syntax_points_into_the_tag() {
        // Points at the unquoted value.
        let (line, column, message) = err_at("<a>\n <b x=1/>\n</a>");
        assert_eq!((line, column), (2, 7), "{message}");
        assert!(message.contains("not in quotes"), "{message}");
    }

    #[test]
    fn duplicate_attribute_is_an_error() {
        let (line, column, message) = err_at("<a x='1' x='2'/>");
        assert_eq!((line, column), (1, 10));
        assert!(message.contains("twice"), "{message}");
    }

    #[test]
    fn unknown_entity_names_the_attribute() {
        let (line, column, message) = err_at("<a>\n<b name='&nope;'/></a>");
        assert_eq!((line, column), (2, 4));
        assert!(message.contains("'name'"), "{message}");
    }
}
