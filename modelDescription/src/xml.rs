//! A small element tree built with quick-xml's event reader, byte offsets as lines and columns,
//! and the attribute escaping the writers use. Shared by this crate's `modelDescription.xml`
//! reader and writer and by the orchestrator's SSP reader and writer.
//!
//! Why a tree instead of serde: the parser only has to be well-formedness-strict, and the
//! format-specific conversion then walks the elements it knows and skips everything else
//! (VendorAnnotations, Annotations, SourceFiles, tool extensions), which is what makes it
//! tolerant. Every element and attribute keeps its byte offset in the input, so any later error
//! can be reported with a line and column ([`line_column`]). Text content is dropped: FMI 2.0 and
//! SSP 1.0 keep all of their information in attributes.
//!
//! Names are local names (`ssd:Component` -> `Component`): SSP files from different tools choose
//! different prefixes (or a default namespace), and nothing in SSP 1.0 or FMI 2.0 relies on two
//! namespaces sharing a local name at the same place. FMI files use no prefixes except for
//! schema attributes such as `xsi:noNamespaceSchemaLocation`, which no reader looks up.
//! Namespace declarations (`xmlns`, `xmlns:p`) are checked like any attribute but not kept. An
//! attribute keeps its prefix, and [`Element::attribute`] prefers an unprefixed attribute to a
//! prefixed one with the same local name.

use quick_xml::Reader;
use quick_xml::XmlVersion;
use quick_xml::events::{BytesStart, Event};

/// One element: its local name, attributes in document order, and child elements.
#[derive(Debug, Clone, PartialEq)]
pub struct Element {
    /// Local name (any prefix stripped).
    pub name: String,
    /// Byte offset of the `<` that opens the element.
    pub offset: usize,
    /// Attributes in document order, without namespace declarations.
    pub attributes: Vec<Attribute>,
    /// Child elements in document order (text and comments are not kept).
    pub children: Vec<Element>,
}

/// One attribute of an [`Element`].
#[derive(Debug, Clone, PartialEq)]
pub struct Attribute {
    /// Local name (namespace declarations are not kept).
    pub name: String,
    /// The prefix of a prefixed name (`ssd` for `ssd:name`).
    pub prefix: Option<String>,
    /// The value with entity and character references resolved, normalized per XML 1.0.
    pub value: String,
    /// Byte offset of the attribute name (falls back to the element's `<`).
    pub offset: usize,
}

impl Element {
    /// The attribute with this local name: the unprefixed one if there is one, else the first
    /// prefixed one.
    pub fn attribute(&self, name: &str) -> Option<&Attribute> {
        let mut named = self.attributes.iter().filter(|a| a.name == name);
        let first = named.next()?;
        if first.prefix.is_none() {
            return Some(first);
        }
        Some(named.find(|a| a.prefix.is_none()).unwrap_or(first))
    }

    /// The value of [`Element::attribute`].
    pub fn value(&self, name: &str) -> Option<&str> {
        self.attribute(name).map(|a| a.value.as_str())
    }

    /// The first child element with this local name.
    pub fn child(&self, name: &str) -> Option<&Element> {
        self.children.iter().find(|c| c.name == name)
    }

    /// The child elements with this local name, in document order.
    pub fn children_named<'a>(&'a self, name: &'a str) -> impl Iterator<Item = &'a Element> + 'a {
        self.children.iter().filter(move |c| c.name == name)
    }
}

/// Text that is not well-formed XML: where, and what is wrong.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("line {line}, column {column}: {message}")]
pub struct XmlError {
    /// Byte offset in the text.
    pub offset: usize,
    /// 1-based line of `offset`.
    pub line: usize,
    /// 1-based column of `offset`, counted in characters.
    pub column: usize,
    /// What is wrong, in the reader's words.
    pub message: String,
}

impl XmlError {
    fn new(text: &str, offset: usize, message: String) -> XmlError {
        let (line, column) = line_column(text, offset);
        XmlError {
            offset,
            line,
            column,
            message,
        }
    }
}

/// The deepest element nesting [`parse`] accepts. FMI 2.0 files need 4 levels and SSP 1.0
/// files a handful more (tool annotations a few more again); the limit exists because the tree
/// is dropped (and compared, cloned, printed) recursively, so a hostile file of a million
/// nested `<a>` would overflow the stack instead of giving an error.
pub const MAX_DEPTH: usize = 1000;

/// Parses `text` into its root element, or reports the first well-formedness error.
///
/// Elements nested deeper than [`MAX_DEPTH`] are an error, and so are characters XML 1.0
/// does not allow (C0 controls other than tab, newline and carriage return; U+FFFE, U+FFFF). Only the predefined entities and
/// character references are resolved (in attribute values); entities declared in a DOCTYPE are
/// never expanded (an attribute using one is an "unknown entity" error, and references in text
/// are skipped with the text), so entity-expansion attacks ("billion laughs") cost nothing.
pub fn parse(text: &str) -> Result<Element, XmlError> {
    // XML 1.0 allows no C0 control character but tab, newline and carriage return, and neither
    // U+FFFE nor U+FFFF; quick-xml does not check, and a NUL inside a name or a string would
    // reach C code as a truncated string.
    if let Some((offset, c)) = text.char_indices().find(|&(_, c)| {
        (c < ' ' && !matches!(c, '\t' | '\n' | '\r')) || matches!(c, '\u{fffe}' | '\u{ffff}')
    }) {
        return Err(XmlError::new(
            text,
            offset,
            format!("the character U+{:04X} is not allowed in XML", c as u32),
        ));
    }
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
                return Err(XmlError::new(
                    text,
                    reader.error_position() as usize,
                    e.to_string(),
                ));
            }
        };
        match event {
            Event::Start(start) => {
                if stack.len() >= MAX_DEPTH {
                    return Err(XmlError::new(
                        text,
                        offset,
                        format!(
                            "elements are nested more than {MAX_DEPTH} levels deep (<{}> inside <{}>)",
                            start.local_name().as_ref(),
                            stack.last().map_or("", |e| e.name.as_str())
                        ),
                    ));
                }
                stack.push(element(text, offset, &start)?)
            }
            Event::Empty(start) => {
                let element = element(text, offset, &start)?;
                attach(text, &mut stack, &mut root, element)?;
            }
            Event::End(_) => {
                // quick-xml has already checked that the name matches the open tag.
                let element = stack
                    .pop()
                    .ok_or_else(|| XmlError::new(text, offset, "unexpected end tag".into()))?;
                attach(text, &mut stack, &mut root, element)?;
            }
            Event::Text(t) if stack.is_empty() && !t.trim().is_empty() => {
                return Err(XmlError::new(
                    text,
                    offset,
                    "text outside the root element".into(),
                ));
            }
            Event::Eof => break,
            // Text, CDATA, comments, processing instructions, the declaration and DOCTYPE carry
            // no information the readers use.
            _ => {}
        }
    }
    if let Some(open) = stack.last() {
        return Err(XmlError::new(
            text,
            open.offset,
            format!("<{}> is never closed (the input ends first)", open.name),
        ));
    }
    root.ok_or_else(|| XmlError::new(text, text.len(), "no root element".into()))
}

fn attach(
    text: &str,
    stack: &mut [Element],
    root: &mut Option<Element>,
    element: Element,
) -> Result<(), XmlError> {
    match stack.last_mut() {
        Some(parent) => parent.children.push(element),
        None if root.is_none() => *root = Some(element),
        None => {
            return Err(XmlError::new(
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

fn element(text: &str, offset: usize, start: &BytesStart<'_>) -> Result<Element, XmlError> {
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
            XmlError::new(text, offset + 1 + rel, format!("in <{name}>: {what}"))
        })?;
        let key: &str = attr.key.0;
        let attr_offset = offset_in(text, key).unwrap_or(offset);
        let value = attr
            // Attribute-value normalization as XML 1.0 requires (literal tabs and newlines
            // become spaces; character references like &#10; survive).
            .normalized_value(XmlVersion::Implicit1_0)
            .map_err(|e| {
                XmlError::new(
                    text,
                    attr_offset,
                    format!("in attribute '{key}' of <{name}>: {e}"),
                )
            })?
            .into_owned();
        if attr.key.as_namespace_binding().is_some() {
            continue;
        }
        let (local, prefix) = attr.key.decompose();
        attributes.push(Attribute {
            name: local.as_ref().to_string(),
            prefix: prefix.map(|p| p.as_ref().to_string()),
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

/// Converts a byte offset into a 1-based line and a 1-based column counted in characters (a
/// tab counts as one). An offset past the end is the end; one inside a character is that
/// character.
pub fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = &text[..offset];
    let line = before.bytes().filter(|&b| b == b'\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let column = before[line_start..].chars().count() + 1;
    (line, column)
}

/// Appends `value` escaped for a double-quoted attribute: markup characters and `"` as entities,
/// and tab, newline and carriage return as character references (a literal one would be
/// normalized to a space by any conforming reader). `'` is left as it is.
pub fn escape_attribute(value: &str, out: &mut String) {
    escape(value, false, out);
}

/// [`escape_attribute`], and `'` as `&apos;` too, so that the result is also safe between
/// single quotes.
pub fn escape_attribute_and_apos(value: &str, out: &mut String) {
    escape(value, true, out);
}

fn escape(value: &str, apos: bool, out: &mut String) {
    for c in value.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' if apos => out.push_str("&apos;"),
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

    fn err_at(text: &str) -> (usize, usize, String) {
        let XmlError {
            line,
            column,
            message,
            ..
        } = parse(text).unwrap_err();
        (line, column, message)
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
    fn unprefixed_attributes_win_and_declarations_are_checked() {
        // As in FMI files: a default namespace, an xsi declaration and a schema attribute.
        let root =
            parse("<m xmlns='d' xmlns:xsi='i' xsi:name='p' name='n' xsi:only='o'/>").unwrap();
        let names: Vec<_> = root.attributes.iter().map(|a| a.name.as_str()).collect();
        assert_eq!(names, ["name", "name", "only"]);
        assert_eq!(root.attributes[0].prefix.as_deref(), Some("xsi"));
        assert_eq!(root.value("name"), Some("n"));
        assert_eq!(root.value("only"), Some("o"));
        assert_eq!(root.value("xmlns"), None);
        assert_eq!(root.value("xsi"), None);
        // A namespace declaration is dropped only after its value is checked.
        let (line, column, message) = err_at("<m\n xmlns:p='&nope;'/>");
        assert_eq!((line, column), (2, 2), "{message}");
        assert!(message.contains("'xmlns:p'"), "{message}");
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

    #[test]
    fn errors_keep_the_offset_and_show_line_and_column() {
        let text = "<a>\n  <b>\n  </c>\n</a>";
        let err = parse(text).unwrap_err();
        assert_eq!(err.offset, text.find("</c>").unwrap());
        assert!(err.to_string().starts_with("line 3, column 3: "), "{err}");
        assert_eq!(parse("").unwrap_err().offset, 0);
    }

    #[test]
    fn line_column_counts_from_one_in_characters() {
        let text = "ab\ncdé\nf";
        assert_eq!(line_column(text, 0), (1, 1));
        assert_eq!(line_column(text, 2), (1, 3));
        assert_eq!(line_column(text, 3), (2, 1));
        // 'é' is two bytes: the offset after it is column 4, not 5.
        assert_eq!(line_column(text, 8), (3, 1));
        assert_eq!(line_column(text, 7), (2, 4));
        assert_eq!(line_column(text, 100), (3, 2));
    }

    #[test]
    fn escaping_round_trips() {
        let mut s = String::new();
        escape_attribute("a&<>\"'\t\n", &mut s);
        assert_eq!(s, "a&amp;&lt;&gt;&quot;'&#9;&#10;");
        let root = parse(&format!("<a v=\"{s}\"/>")).unwrap();
        assert_eq!(root.value("v"), Some("a&<>\"'\t\n"));
    }

    #[test]
    fn attributes_are_escaped() {
        let mut s = String::new();
        escape_attribute_and_apos("a<b>&\"c'\n\td\r", &mut s);
        assert_eq!(s, "a&lt;b&gt;&amp;&quot;c&apos;&#10;&#9;d&#13;");
        let root = parse(&format!("<a v='{s}'/>")).unwrap();
        assert_eq!(root.value("v"), Some("a<b>&\"c'\n\td\r"));
    }
}
