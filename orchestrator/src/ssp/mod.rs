//! SSP 1.0 (System Structure and Parameterization): reading a `SystemStructure.ssd` or an `.ssp`
//! archive into a [`System`], and writing a [`System`] as an `.ssp` that other masters
//! (libcosim, OMSimulator, ecos, fmpy) can open.
//!
//! # Reading
//! [`read`] takes a `.ssd` file or an `.ssp` archive (a zip with `SystemStructure.ssd` at its
//! root, FMUs usually under `resources/`; the archive is extracted to a temporary directory that
//! lives as long as the [`LoadedSystem`]). What is understood:
//!
//! - elements are matched by local name, so any namespace prefix (or none) works;
//! - the root `SystemStructureDescription` (its `name` becomes [`System::name`]) with one
//!   `System`, whose `Elements` hold FMU `Component`s (`name`, `source`, optional `type` which
//!   must be `application/x-fmu-sharedlibrary`). `source` is a relative reference (resolved
//!   against the `.ssd`'s directory; percent-decoding applied) or a `file:` URI, returned as an
//!   absolute path; the file must exist, and inside an archive it must stay inside the archive;
//! - `Connectors/Connector` of a component are used only to check connections: when a
//!   component declares connectors, connections must use declared ones; and when both ends
//!   declare a kind, an `input`/`parameter` start with an `output`/`calculatedParameter` end is
//!   read the other way round (SSP's start and end do not fix the direction of the data flow);
//! - `Connections/Connection` with an optional `LinearTransformation` (factor 1 and offset 0
//!   by default);
//! - `ParameterBindings/ParameterBinding` on components and on the system, inline
//!   (`ParameterValues/ParameterSet`) or from an `.ssv` file (`source`, relative to the `.ssd`),
//!   with `prefix`, and Real, Integer, Boolean and String values. Names are relative to where
//!   the binding sits (`variable` on a component, `component.variable` on the system). Each
//!   component gets one entry per variable, in order of first mention, holding the winning
//!   value: the component's own bindings in document order, then the system's (a later binding
//!   beats an earlier one, the system beats the component). A Real's `unit` is not converted;
//! - `DefaultExperiment` `startTime` (default 0) and `stopTime`; SSP 1.0 has no step size, so
//!   [`Experiment::step`](crate::system::Experiment::step) is `None`;
//! - everything else (Annotations, ElementGeometry, SignalDictionaries, Units, ...) is ignored.
//!
//! Refused with an [`SspError::Unsupported`] that says what: sub-systems, connections to the
//! system's own connectors, connections to signal dictionary references, components that are
//! not FMUs or that ask for Model Exchange, parameter mappings, Enumeration and Binary parameter
//! values, boolean/integer/enumeration mapping transformations, non-`file:` URI schemes.
//!
//! # Writing
//! [`write_ssp`] writes `SystemStructure.ssd` and copies every component's FMU to
//! `resources/<component>.fmu` (the name made file- and URI-safe, kept unique). [`to_ssd`]
//! produces the `.ssd` text from the system and the FMUs' model descriptions. The `.ssd` is
//! schema-valid SSP 1.0: every variable a connection uses, and every parameter (causality
//! `parameter`) a binding sets, becomes a typed connector (`kind` = the variable's causality;
//! `ssc:Real`, `ssc:Integer`, `ssc:Boolean` or `ssc:String`, none for an enumeration, whose
//! `ssc:Enumeration` would need the enumeration declared in the SSD). Unconnected inputs and
//! outputs get no connector: fmpy's SSP master requires every input connector to be connected
//! and cannot read String outputs. A component's parameters become one inline
//! `ssv:ParameterSet` (bindings to local variables need no connector), connections carry their
//! `ssc:LinearTransformation`, and the experiment becomes `DefaultExperiment` (the step size
//! cannot be written in SSP 1.0 and is dropped). Connections and parameters are checked against
//! the model descriptions (the variable exists; a connection's variables are connectable; a
//! parameter's value has the variable's type).

mod error;
mod read;
mod write;

use std::path::Path;

pub use error::SspError;
use model_description::ModelDescription;

use crate::system::{Component, System};

/// The name of the system structure description at the root of an .ssp archive.
pub const SSD_NAME: &str = "SystemStructure.ssd";
/// The component type of an FMU (and SSP's default).
pub const FMU_MIME_TYPE: &str = "application/x-fmu-sharedlibrary";
const PARAMETER_SET_MIME_TYPE: &str = "application/x-ssp-parameter-set";

/// A system read from SSP. For an .ssp archive it owns the temporary directory the archive was
/// extracted to, where the components' `source` paths point: keep it alive while the FMUs are
/// in use.
#[derive(Debug)]
pub struct LoadedSystem {
    /// The system, its components' `source` paths absolute.
    pub system: System,
    extracted: Option<tempfile::TempDir>,
}

impl LoadedSystem {
    /// The directory an .ssp archive was extracted to (`None` for a plain .ssd).
    pub fn extracted_dir(&self) -> Option<&Path> {
        self.extracted.as_ref().map(|d| d.path())
    }
}

/// Reads a SystemStructure.ssd file, or an .ssp archive (zip with SystemStructure.ssd at its
/// root and FMUs usually under resources/), or a directory holding SystemStructure.ssd (an
/// extracted archive). A file is taken as an archive when its extension is `.ssp`, or when it
/// is not `.ssd` and starts like a zip. FMU `source` paths are resolved
/// relative to the .ssd's directory (or the archive root) and returned absolute; `file:` URIs
/// are accepted. Errors are wrapped in [`SspError::InFile`] naming the file.
pub fn read(path: &Path) -> Result<LoadedSystem, SspError> {
    read::read(path, &Sources::new())
}

/// Components' FMUs given in place of their `source`, by component name.
pub type Sources = std::collections::BTreeMap<String, std::path::PathBuf>;

/// [`read`], with the FMUs of the components `sources` names taken from there instead of from
/// their `source` attribute (so a shipped description runs with the user's FMUs wherever they
/// were built). A name that is not a component of the system is an error.
pub fn read_with(path: &Path, sources: &Sources) -> Result<LoadedSystem, SspError> {
    let sources = sources
        .iter()
        .map(|(name, fmu)| {
            std::path::absolute(fmu)
                .map(|fmu| (name.clone(), fmu))
                .map_err(|source| SspError::Io {
                    path: fmu.clone(),
                    source,
                })
        })
        .collect::<Result<Sources, _>>()?;
    let loaded = read::read(path, &sources)?;
    if let Some(name) = sources
        .keys()
        .find(|n| loaded.system.component(n).is_none())
    {
        return Err(SspError::NoSuchComponent {
            path: path.to_path_buf(),
            component: name.clone(),
        });
    }
    Ok(loaded)
}

/// Parses the text of a SystemStructure.ssd whose relative URIs (FMUs, .ssv files) resolve
/// against `base_dir`. Errors inside the text are not wrapped in [`SspError::InFile`] (the
/// caller knows the file); errors inside an .ssv file are.
pub fn parse_ssd(xml: &str, base_dir: &Path) -> Result<System, SspError> {
    read::parse_ssd(xml, base_dir, &Sources::new())
}

/// [`parse_ssd`] with the FMUs of the components `sources` names taken from there (absolute
/// paths) instead of from their `source` attribute, as [`read_with`] does.
pub fn parse_ssd_with(xml: &str, base_dir: &Path, sources: &Sources) -> Result<System, SspError> {
    read::parse_ssd(xml, base_dir, sources)
}

/// Writes `system` as an .ssp archive: SystemStructure.ssd plus every component's FMU copied to
/// `resources/<component>.fmu`. Connectors are typed from each FMU's modelDescription.xml. The
/// archive is written to a temporary file next to `out` and renamed into place.
pub fn write_ssp(system: &System, out: &Path) -> Result<(), SspError> {
    write::write_ssp(system, out)
}

/// The text of a SystemStructure.ssd for `system`: `fmu_sources` gives each component's
/// `source` URI (as written, e.g. `resources/plant.fmu`), `descriptions` its FMU's model
/// description (called once per component, in order).
pub fn to_ssd(
    system: &System,
    fmu_sources: &dyn Fn(&Component) -> String,
    descriptions: &dyn Fn(&Component) -> Result<ModelDescription, SspError>,
) -> Result<String, SspError> {
    write::to_ssd(system, fmu_sources, descriptions)
}
