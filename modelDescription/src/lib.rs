//! FMI 2.0 `modelDescription.xml` as Rust types: written for our FMUs from the same variable
//! table their code uses, read (and checked) for any FMU the orchestrator loads.
//!
//! - [`ModelDescription::from_xml`] / [`from_file`](ModelDescription::from_file) read any
//!   FMI 2.0 file, skipping elements they do not model (VendorAnnotations, Annotations,
//!   SourceFiles, ...) and filling the standard's defaults. Errors ([`ParseError`]) give the
//!   line and column, the element and attribute, and the variable.
//! - [`ModelDescription::to_xml`] writes a schema-valid file: strict child order, no empty
//!   list elements, default-valued flags left out.
//! - [`ModelDescription::validate`] returns every broken rule as a [`Violation`]: root
//!   attributes, CoSimulation capabilities, unique names and value references,
//!   causality/variability/initial/start per the spec's table, bounds, units and declared
//!   types, and the exact Outputs and InitialUnknowns sets of ModelStructure.
//! - [`ModelStructure::derive`] builds the ModelStructure those rules require, and
//!   [`ScalarVariable::effective_initial`] gives `initial` with the spec's default applied.
//! - [`xml`] is the element tree (local names, byte offsets), offset-to-line/column conversion
//!   and attribute escaping underneath; the orchestrator's SSP reader and writer use it too.
//!
//! Exact floats: every f64 written parses back to the same bits ([`format_f64`]: shortest
//! round-trip digits, exponent form outside 1e-5 <= |x| < 1e15), so a start value or a
//! parameter survives write -> read unchanged.
//!
//! Indices: FMI numbers variables from 1 in ModelStructure; [`ModelDescription::variable_index`]
//! returns that 1-based index.

mod error;
mod names;
mod read;
mod structure;
mod types;
mod validate;
mod write;
pub mod xml;

pub use error::ParseError;
pub use types::*;
pub use validate::Violation;
pub use write::format_f64;
