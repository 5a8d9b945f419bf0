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
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },

    /// An error inside the named file (a .ssd or .ssv, or an archive member).
    #[error("{}: {source}", path.display())]
    InFile {
        path: PathBuf,
        #[source]
        source: Box<SspError>,
    },

    /// Not well-formed XML.
    #[error("malformed XML at line {line}, column {column}: {message}")]
    Xml {
        line: usize,
        column: usize,
        message: String,
    },

    /// The root element is not the expected one.
    #[error("line {line}, column {column}: the root element is <{found}>, expected <{expected}>")]
    WrongRoot {
        line: usize,
        column: usize,
        found: String,
        expected: &'static str,
    },

    /// A required attribute is absent.
    #[error("line {line}, column {column}: <{element}>{} has no '{attribute}' attribute, which is required", context_suffix(.context))]
    MissingAttribute {
        line: usize,
        column: usize,
        element: String,
        attribute: &'static str,
        /// The component, parameter or connection the element belongs to, when known.
        context: Option<String>,
    },

    /// An attribute's value is not what SSP says it is.
    #[error("line {line}, column {column}: attribute '{attribute}' of <{element}>{} is \"{value}\", expected {expected}", context_suffix(.context))]
    InvalidValue {
        line: usize,
        column: usize,
        element: String,
        attribute: &'static str,
        value: String,
        expected: &'static str,
        context: Option<String>,
    },

    /// A required child element is absent.
    #[error("line {line}, column {column}: <{element}>{} has no {expected} element", context_suffix(.context))]
    MissingElement {
        line: usize,
        column: usize,
        element: String,
        expected: &'static str,
        context: Option<String>,
    },

    /// Valid SSP that this master cannot run (sub-systems, system-level connectors, parameter
    /// mappings, ...). `what` says exactly what.
    #[error("line {line}, column {column}: {what} is not supported")]
    Unsupported {
        line: usize,
        column: usize,
        what: String,
    },

    /// Two components with the same name.
    #[error("line {line}, column {column}: a second component named '{name}'")]
    DuplicateComponent {
        line: usize,
        column: usize,
        name: String,
    },

    /// A connection names an element that is not a component of the system.
    #[error(
        "line {line}, column {column}: connection {connection} refers to '{component}', which is not a component of the system"
    )]
    UnknownComponent {
        line: usize,
        column: usize,
        connection: String,
        component: String,
    },

    /// A connection names a connector the component does not declare (only checked for components
    /// that declare connectors).
    #[error(
        "line {line}, column {column}: connection {connection} refers to connector '{connector}' of component '{component}', which the component does not declare"
    )]
    UndeclaredConnector {
        line: usize,
        column: usize,
        connection: String,
        component: String,
        connector: String,
    },

    /// A system-level parameter name that does not start with `<component>.`.
    #[error(
        "line {line}, column {column}: system-level parameter '{parameter}' does not name a component's variable (expected <component>.<variable>)"
    )]
    UnknownParameterTarget {
        line: usize,
        column: usize,
        parameter: String,
    },

    /// Any other rule of SSP that the document breaks.
    #[error("line {line}, column {column}: {message}")]
    Invalid {
        line: usize,
        column: usize,
        message: String,
    },

    /// The .ssp archive cannot be opened or read.
    #[error("{}: not a readable SSP archive: {message}", path.display())]
    Archive { path: PathBuf, message: String },

    /// An archive entry whose name would be extracted outside the extraction directory.
    #[error("{}: archive entry '{entry}' points outside the archive (absolute or '..' path); refusing the archive", path.display())]
    UnsafeEntry { path: PathBuf, entry: String },

    /// An FMU was given (`read_with`) for a component the system does not have.
    #[error("{}: an FMU was given for component '{component}', which the system does not have", path.display())]
    NoSuchComponent { path: PathBuf, component: String },

    /// An FMU to be written into an .ssp cannot be read (not a zip, no modelDescription.xml).
    #[error("component '{component}': cannot read the FMU {}: {message}", path.display())]
    Fmu {
        component: String,
        path: PathBuf,
        message: String,
    },

    /// An FMU's modelDescription.xml does not parse.
    #[error("component '{component}': modelDescription.xml of {}: {source}", path.display())]
    ModelDescription {
        component: String,
        path: PathBuf,
        #[source]
        source: Box<model_description::ParseError>,
    },

    /// A system to be written cannot be expressed as SSP 1.0, or is inconsistent with its FMUs
    /// (unknown component or variable, mismatched value type, ...).
    #[error("cannot write the system as SSP: {message}")]
    NotWritable { message: String },
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
