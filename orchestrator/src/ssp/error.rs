//! What can go wrong reading or writing SSP files.
//!
//! Problems inside an XML document carry a 1-based line and column (columns count characters)
//! and name the element, attribute, component, connector or connection concerned. [`super::read`]
//! wraps them in [`SspError::InFile`] with the file's path (for a file inside an .ssp archive:
//! the archive's path joined with the entry, e.g. `model.ssp/SystemStructure.ssd`), so every
//! message names its file.

use std::path::PathBuf;

/// Why an SSP file could not be read or written.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SspError {
    /// A file could not be read or written.
    #[error("cannot access {}: {source}", path.display())]
    Io {
        /// The file read or written (a .ssd or .ssv, an FMU copied into an archive, the archive
        /// written, an FMU path given in place of a `source` that cannot be made absolute).
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },

    /// An error inside the named file (a .ssd or .ssv, or an archive member).
    #[error("{}: {source}", path.display())]
    InFile {
        /// The file the error is in (inside an archive: the archive's path joined with the entry).
        path: PathBuf,
        /// The error, pointing into that file.
        #[source]
        source: Box<SspError>,
    },

    /// Not well-formed XML.
    #[error("malformed XML at line {line}, column {column}: {message}")]
    Xml {
        /// 1-based line in the document.
        line: usize,
        /// 1-based column, in characters.
        column: usize,
        /// The XML reader's description.
        message: String,
    },

    /// The root element is not the expected one.
    #[error("line {line}, column {column}: the root element is <{found}>, expected <{expected}>")]
    WrongRoot {
        /// 1-based line in the document.
        line: usize,
        /// 1-based column, in characters.
        column: usize,
        /// The root element's name, without its namespace prefix.
        found: String,
        /// The root SSP requires for this kind of file (e.g. `ssd:SystemStructureDescription`).
        expected: &'static str,
    },

    /// A required attribute is absent.
    #[error("line {line}, column {column}: <{element}>{} has no '{attribute}' attribute, which is required", context_suffix(.context))]
    MissingAttribute {
        /// 1-based line in the document.
        line: usize,
        /// 1-based column, in characters.
        column: usize,
        /// The element's name as written.
        element: String,
        /// The attribute SSP requires there.
        attribute: &'static str,
        /// The component, parameter or connection the element belongs to, when known.
        context: Option<String>,
    },

    /// An attribute's value is not what SSP says it is.
    #[error("line {line}, column {column}: attribute '{attribute}' of <{element}>{} is \"{value}\", expected {expected}", context_suffix(.context))]
    InvalidValue {
        /// 1-based line in the document.
        line: usize,
        /// 1-based column, in characters.
        column: usize,
        /// The element's name as written.
        element: String,
        /// The attribute whose value is refused.
        attribute: &'static str,
        /// Its value as written.
        value: String,
        /// What the attribute must hold (e.g. "a floating-point number").
        expected: &'static str,
        /// The component, parameter or connection the element belongs to, when known.
        context: Option<String>,
    },

    /// A required child element is absent.
    #[error("line {line}, column {column}: <{element}>{} has no {expected} element", context_suffix(.context))]
    MissingElement {
        /// 1-based line in the document.
        line: usize,
        /// 1-based column, in characters.
        column: usize,
        /// The element's name as written.
        element: String,
        /// The child element that is required.
        expected: &'static str,
        /// The component, parameter or connection the element belongs to, when known.
        context: Option<String>,
    },

    /// Valid SSP that this master cannot run (sub-systems, system-level connectors, parameter
    /// mappings, ...). `what` says exactly what.
    #[error("line {line}, column {column}: {what} is not supported")]
    Unsupported {
        /// 1-based line in the document.
        line: usize,
        /// 1-based column, in characters.
        column: usize,
        /// The construct, named as a user would find it in the file.
        what: String,
    },

    /// Two components with the same name.
    #[error("line {line}, column {column}: a second component named '{name}'")]
    DuplicateComponent {
        /// 1-based line in the document.
        line: usize,
        /// 1-based column, in characters.
        column: usize,
        /// The name both components carry.
        name: String,
    },

    /// A connection names an element that is not a component of the system.
    #[error(
        "line {line}, column {column}: connection {connection} refers to '{component}', which is not a component of the system"
    )]
    UnknownComponent {
        /// 1-based line in the document.
        line: usize,
        /// 1-based column, in characters.
        column: usize,
        /// The connection as `element.connector -> element.connector`.
        connection: String,
        /// The `startElement` or `endElement` that names no component.
        component: String,
    },

    /// A connection names a connector the component does not declare (only checked for components
    /// that declare connectors).
    #[error(
        "line {line}, column {column}: connection {connection} refers to connector '{connector}' of component '{component}', which the component does not declare"
    )]
    UndeclaredConnector {
        /// 1-based line in the document.
        line: usize,
        /// 1-based column, in characters.
        column: usize,
        /// The connection as `element.connector -> element.connector`.
        connection: String,
        /// The component the connection points at.
        component: String,
        /// The connector name the component does not declare.
        connector: String,
    },

    /// A system-level parameter name that does not start with `<component>.`.
    #[error(
        "line {line}, column {column}: system-level parameter '{parameter}' does not name a component's variable (expected <component>.<variable>)"
    )]
    UnknownParameterTarget {
        /// 1-based line in the document.
        line: usize,
        /// 1-based column, in characters.
        column: usize,
        /// The parameter's name as written.
        parameter: String,
    },

    /// Any other rule of SSP that the document breaks.
    #[error("line {line}, column {column}: {message}")]
    Invalid {
        /// 1-based line in the document.
        line: usize,
        /// 1-based column, in characters.
        column: usize,
        /// The rule broken, with the values concerned.
        message: String,
    },

    /// The .ssp archive cannot be opened or read.
    #[error("{}: not a readable SSP archive: {message}", path.display())]
    Archive {
        /// The .ssp archive.
        path: PathBuf,
        /// What is wrong with it (the zip reader's error, or no SystemStructure.ssd at its root).
        message: String,
    },

    /// An archive entry whose name would be extracted outside the extraction directory.
    #[error("{}: archive entry '{entry}' points outside the archive (absolute or '..' path); refusing the archive", path.display())]
    UnsafeEntry {
        /// The .ssp archive.
        path: PathBuf,
        /// The entry's name as stored.
        entry: String,
    },

    /// An FMU was given (`read_with`) for a component the system does not have.
    #[error("{}: an FMU was given for component '{component}', which the system does not have", path.display())]
    NoSuchComponent {
        /// The system description read.
        path: PathBuf,
        /// The component name given with the FMU.
        component: String,
    },

    /// An FMU to be written into an .ssp cannot be read (not a zip, no modelDescription.xml).
    #[error("component '{component}': cannot read the FMU {}: {message}", path.display())]
    Fmu {
        /// The component whose FMU it is.
        component: String,
        /// The FMU file (the component's `source`).
        path: PathBuf,
        /// Why it cannot be read (the file system's or zip reader's error, or no modelDescription.xml).
        message: String,
    },

    /// An FMU's modelDescription.xml does not parse.
    #[error("component '{component}': modelDescription.xml of {}: {source}", path.display())]
    ModelDescription {
        /// The component whose FMU it is.
        component: String,
        /// The FMU file (the component's `source`).
        path: PathBuf,
        /// The parser's error, with line and column in the XML.
        #[source]
        source: Box<model_description::ParseError>,
    },

    /// A system to be written cannot be expressed as SSP 1.0, or is inconsistent with its FMUs
    /// (unknown component or variable, mismatched value type, ...).
    #[error("cannot write the system as SSP: {message}")]
    NotWritable {
        /// What cannot be written, naming the component or variable.
        message: String,
    },
}

fn context_suffix(context: &Option<String>) -> String {
    match context {
        Some(c) => format!(" ({c})"),
        None => String::new(),
    }
}

impl SspError {
    /// The 1-based (line, column) the error points at, if it points into a document.
    pub fn line_column(&self) -> Option<(usize, usize)> {
        use SspError::*;
        match self {
            Xml { line, column, .. }
            | WrongRoot { line, column, .. }
            | MissingAttribute { line, column, .. }
            | InvalidValue { line, column, .. }
            | MissingElement { line, column, .. }
            | Unsupported { line, column, .. }
            | DuplicateComponent { line, column, .. }
            | UnknownComponent { line, column, .. }
            | UndeclaredConnector { line, column, .. }
            | UnknownParameterTarget { line, column, .. }
            | Invalid { line, column, .. } => Some((*line, *column)),
            InFile { source, .. } => source.line_column(),
            _ => None,
        }
    }

    /// The error itself, without the [`SspError::InFile`] wrappers that name its file.
    pub fn innermost(&self) -> &SspError {
        match self {
            SspError::InFile { source, .. } => source.innermost(),
            other => other,
        }
    }
}

impl From<model_description::xml::XmlError> for SspError {
    fn from(e: model_description::xml::XmlError) -> SspError {
        SspError::Xml {
            line: e.line,
            column: e.column,
            message: e.message,
        }
    }
}
