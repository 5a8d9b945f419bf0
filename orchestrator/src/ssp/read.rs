//! Reading a SystemStructure.ssd (or an .ssp archive) into a [`System`].

use std::collections::HashMap;
use std::fs;
use std::io;
use std::path::{Component as PathPart, Path, PathBuf};

use model_description::xml::{self, Element, line_column};

use super::error::SspError;
use super::{FMU_MIME_TYPE, LoadedSystem, PARAMETER_SET_MIME_TYPE, SSD_NAME, Sources};
use crate::system::{Component, Connection, Endpoint, Experiment, Linear, System, Value};

pub fn read(path: &Path, sources: &Sources) -> Result<LoadedSystem, SspError> {
    if path.is_dir() {
        // An extracted archive.
        return read(&path.join(SSD_NAME), sources);
    }
    if is_archive(path)? {
        let dir = tempfile::Builder::new()
            .prefix("ssp-")
            .tempdir()
            .map_err(|source| SspError::Io {
                path: std::env::temp_dir(),
                source,
            })?;
        extract(path, dir.path())?;
        let ssd = dir.path().join(SSD_NAME);
        if !ssd.is_file() {
            return Err(SspError::Archive {
                path: path.to_path_buf(),
                message: format!("no {SSD_NAME} at the archive root"),
            });
        }
        let text = read_text(&ssd, &path.join(SSD_NAME))?;
        let place = Place {
            base_dir: absolute(dir.path())?,
            confine: true,
            shown_dir: path.to_path_buf(),
            sources: sources.clone(),
        };
        let system = parse(&text, &place).map_err(|e| in_file(path.join(SSD_NAME), e))?;
        Ok(LoadedSystem {
            system,
            extracted: Some(dir),
        })
    } else {
        let text = read_text(path, path)?;
        let dir = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        let place = Place {
            base_dir: absolute(dir)?,
            confine: false,
            shown_dir: dir.to_path_buf(),
            sources: sources.clone(),
        };
        let system = parse(&text, &place).map_err(|e| in_file(path.to_path_buf(), e))?;
        Ok(LoadedSystem {
            system,
            extracted: None,
        })
    }
}

pub fn parse_ssd(xml: &str, base_dir: &Path, sources: &Sources) -> Result<System, SspError> {
    let place = Place {
        base_dir: absolute(base_dir)?,
        confine: false,
        shown_dir: base_dir.to_path_buf(),
        sources: sources.clone(),
    };
    parse(xml, &place)
}

/// Where the .ssd sits: relative URIs resolve against `base_dir`; inside an extracted archive
/// (`confine`) they must stay under it; `shown_dir` is how that directory is named in errors
/// (the archive's path for an archive, not the temporary directory); `sources` replace the
/// named components' `source` (the user's FMUs for a shipped description).
struct Place {
    base_dir: PathBuf,
    confine: bool,
    shown_dir: PathBuf,
    sources: Sources,
}

impl Place {
    fn shown(&self, resolved: &Path) -> PathBuf {
        match resolved.strip_prefix(&self.base_dir) {
            Ok(rel) => self.shown_dir.join(rel),
            Err(_) => resolved.to_path_buf(),
        }
    }
}

fn in_file(path: PathBuf, e: SspError) -> SspError {
    SspError::InFile {
        path,
        source: Box::new(e),
    }
}

fn read_text(path: &Path, shown: &Path) -> Result<String, SspError> {
    let bytes =
        crate::input::read_bytes(path, crate::input::XML_LIMIT).map_err(|source| SspError::Io {
            path: shown.to_path_buf(),
            source,
        })?;
    let text = String::from_utf8(bytes).map_err(|e| {
        // Where the first bad byte is, as a line and column of the valid text before it.
        let valid = e.utf8_error().valid_up_to();
        let bytes = e.as_bytes();
        let before = std::str::from_utf8(&bytes[..valid]).unwrap_or_default();
        let (line, column) = line_column(before, valid);
        in_file(
            shown.to_path_buf(),
            SspError::Xml {
                line,
                column,
                message: format!(
                    "byte 0x{:02X} (offset {valid}) is not UTF-8; SSP files must be UTF-8",
                    bytes[valid]
                ),
            },
        )
    })?;
    Ok(match text.strip_prefix('\u{feff}') {
        Some(rest) => rest.to_string(),
        None => text,
    })
}

fn absolute(p: &Path) -> Result<PathBuf, SspError> {
    std::path::absolute(p)
        .map(|p| normalize(&p))
        .map_err(|source| SspError::Io {
            path: p.to_path_buf(),
            source,
        })
}

/// Removes `.` and resolves `..` lexically.
fn normalize(p: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for part in p.components() {
        match part {
            PathPart::CurDir => {}
            PathPart::ParentDir => {
                if !out.pop() {
                    out.push("..");
                }
            }
            other => out.push(other.as_os_str()),
        }
    }
    out
}

// ---------------------------------------------------------------------------------------------
// Archives

fn is_archive(path: &Path) -> Result<bool, SspError> {
    crate::input::regular_file(path).map_err(|source| SspError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("ssp"))
    {
        return Ok(true);
    }
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("ssd"))
    {
        return Ok(false);
    }
    let mut magic = [0u8; 4];
    let mut file = fs::File::open(path).map_err(|source| SspError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    use std::io::Read;
    let n = file.read(&mut magic).map_err(|source| SspError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    Ok(n == 4 && magic == *b"PK\x03\x04")
}

/// Extracts every entry of the archive into `dir`, refusing the whole archive if any entry's
/// name is absolute or climbs out with `..`, or if it is a zip bomb: more entries or more
/// declared uncompressed bytes than fmi-import's [`UnpackLimits::DEFAULT`] (the FMUs inside
/// are unpacked under the same limits later), or an entry that decompresses to more than it
/// declares (cut off one byte past its declared size).
///
/// [`UnpackLimits::DEFAULT`]: fmi_import::UnpackLimits::DEFAULT
fn extract(archive: &Path, dir: &Path) -> Result<(), SspError> {
    let limits = fmi_import::UnpackLimits::DEFAULT;
    let bad = |message: String| SspError::Archive {
        path: archive.to_path_buf(),
        message,
    };
    let file = fs::File::open(archive).map_err(|source| SspError::Io {
        path: archive.to_path_buf(),
        source,
    })?;
    let mut zip = zip::ZipArchive::new(io::BufReader::new(file)).map_err(|e| bad(e.to_string()))?;
    if zip.len() > limits.max_entries {
        return Err(bad(format!(
            "it has {} entries, more than the limit of {}",
            zip.len(),
            limits.max_entries
        )));
    }
    // Check every name (and the declared sizes) before writing anything.
    let mut entries = Vec::with_capacity(zip.len());
    let mut declared_total: u64 = 0;
    for i in 0..zip.len() {
        let entry = zip
            .by_index_raw(i)
            .map_err(|e| bad(format!("entry {i}: {e}")))?;
        let name = entry
            .name()
            .map_err(|e| bad(format!("entry {i}: {e}")))?
            .into_owned();
        declared_total = declared_total.saturating_add(entry.size());
        if declared_total > limits.max_total_bytes {
            return Err(bad(format!(
                "entry '{name}' declares {} bytes, which brings the uncompressed total to {declared_total} bytes, more than the limit of {} bytes",
                entry.size(),
                limits.max_total_bytes
            )));
        }
        let declared = entry.size();
        let absolute_name = name.starts_with('/')
            || name.starts_with('\\')
            || name.as_bytes().get(1) == Some(&b':');
        match entry.enclosed_name() {
            Some(rel) if !absolute_name && !name.contains('\\') => {
                entries.push((rel, entry.is_dir(), declared))
            }
            _ => {
                return Err(SspError::UnsafeEntry {
                    path: archive.to_path_buf(),
                    entry: name,
                });
            }
        }
    }
    for (i, (rel, is_dir, declared)) in entries.into_iter().enumerate() {
        let target = dir.join(&rel);
        let io_err = |source| SspError::Io {
            path: archive.join(&rel),
            source,
        };
        if is_dir {
            fs::create_dir_all(&target).map_err(io_err)?;
            continue;
        }
        if let Some(parent) = target.parent() {
            fs::create_dir_all(parent).map_err(io_err)?;
        }
        let mut entry = zip
            .by_index(i)
            .map_err(|e| bad(format!("entry '{}': {e}", rel.display())))?;
        let mut out = fs::File::create(&target).map_err(io_err)?;
        let written = io::copy(&mut io::Read::take(&mut entry, declared + 1), &mut out)
            .map_err(|e| bad(format!("cannot extract entry '{}': {e}", rel.display())))?;
        if written > declared {
            return Err(bad(format!(
                "entry '{}' decompresses to more than the {declared} bytes it declares (a corrupt or crafted archive)",
                rel.display()
            )));
        }
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// The document

/// A component while it is being read: its declared connectors (name -> kind) and the
/// parameter values of its own bindings.
struct Partial {
    component: Component,
    connectors: Option<HashMap<String, Option<String>>>,
}

struct Reader<'a> {
    text: &'a str,
    place: &'a Place,
}

fn parse(text: &str, place: &Place) -> Result<System, SspError> {
    let root = xml::parse(text)?;
    Reader { text, place }.document(&root)
}

impl Reader<'_> {
    fn at(&self, offset: usize) -> (usize, usize) {
        line_column(self.text, offset)
    }

    fn required<'e>(
        &self,
        e: &'e Element,
        attribute: &'static str,
        context: Option<&str>,
    ) -> Result<&'e str, SspError> {
        e.value(attribute).ok_or_else(|| {
            let (line, column) = self.at(e.offset);
            SspError::MissingAttribute {
                line,
                column,
                element: e.name.clone(),
                attribute,
                context: context.map(str::to_string),
            }
        })
    }

    fn invalid(
        &self,
        e: &Element,
        attribute: &'static str,
        expected: &'static str,
        context: Option<&str>,
    ) -> SspError {
        let attr = e.attribute(attribute);
        let (line, column) = self.at(attr.map_or(e.offset, |a| a.offset));
        SspError::InvalidValue {
            line,
            column,
            element: e.name.clone(),
            attribute,
            value: attr.map(|a| a.value.clone()).unwrap_or_default(),
            expected,
            context: context.map(str::to_string),
        }
    }

    fn optional_double(
        &self,
        e: &Element,
        attribute: &'static str,
        context: Option<&str>,
    ) -> Result<Option<f64>, SspError> {
        match e.value(attribute) {
            None => Ok(None),
            Some(v) => parse_double(v)
                .map(Some)
                .ok_or_else(|| self.invalid(e, attribute, "a floating-point number", context)),
        }
    }

    fn unsupported(&self, offset: usize, what: String) -> SspError {
        let (line, column) = self.at(offset);
        SspError::Unsupported { line, column, what }
    }

    fn document(&self, root: &Element) -> Result<System, SspError> {
        if root.name != "SystemStructureDescription" {
            let (line, column) = self.at(root.offset);
            return Err(SspError::WrongRoot {
                line,
                column,
                found: root.name.clone(),
                expected: "ssd:SystemStructureDescription",
            });
        }
        let mut systems = root.children_named("System");
        let system = systems.next().ok_or_else(|| {
            let (line, column) = self.at(root.offset);
            SspError::MissingElement {
                line,
                column,
                element: root.name.clone(),
                expected: "ssd:System",
                context: None,
            }
        })?;
        if let Some(second) = systems.next() {
            let (line, column) = self.at(second.offset);
            return Err(SspError::Invalid {
                line,
                column,
                message:
                    "a second <System> in <SystemStructureDescription>, which holds exactly one"
                        .into(),
            });
        }
        let name = match root.value("name") {
            Some(n) => n.to_string(),
            None => self.required(system, "name", None)?.to_string(),
        };
        let (components, connections) = self.system(system)?;
        let experiment = match root.child("DefaultExperiment") {
            None => Experiment {
                step: self.annotated_step(None, system)?,
                ..Experiment::default()
            },
            Some(de) => {
                let start = self.optional_double(de, "startTime", None)?.unwrap_or(0.0);
                let stop = self.optional_double(de, "stopTime", None)?;
                for (attribute, value) in [("startTime", Some(start)), ("stopTime", stop)] {
                    if value.is_some_and(|v| !v.is_finite()) {
                        return Err(self.invalid(de, attribute, "a finite time", None));
                    }
                }
                if stop.is_some_and(|stop| stop < start) {
                    return Err(self.invalid(
                        de,
                        "stopTime",
                        "a stop time not before startTime",
                        None,
                    ));
                }
                Experiment {
                    start,
                    stop,
                    step: self.annotated_step(Some(de), system)?,
                }
            }
        };
        Ok(System {
            name,
            components,
            connections,
            experiment,
        })
    }

    /// The communication step other masters' annotations give: the Open Simulation Platform's
    /// `osp:FixedStepAlgorithm baseStepSize` in the DefaultExperiment (libcosim), else
    /// OMSimulator's `oms:FixedStepMaster stepSize` on the system. Must be positive and finite.
    fn annotated_step(
        &self,
        de: Option<&Element>,
        system: &Element,
    ) -> Result<Option<f64>, SspError> {
        let annotations = |e: &'_ Element, kind: &str| -> Vec<Element> {
            e.child("Annotations")
                .into_iter()
                .flat_map(|a| a.children_named("Annotation"))
                .filter(|a| a.value("type") == Some(kind))
                .cloned()
                .collect()
        };
        let find = |e: &Element, path: &[&str]| -> Option<Element> {
            let mut at = e.clone();
            for name in path {
                at = at.child(name)?.clone();
            }
            Some(at)
        };
        let osp = de
            .map(|de| annotations(de, "com.opensimulationplatform"))
            .unwrap_or_default()
            .iter()
            .find_map(|a| find(a, &["Algorithm", "FixedStepAlgorithm"]))
            .map(|e| (e, "baseStepSize"));
        let oms = || {
            annotations(system, "org.openmodelica")
                .iter()
                .find_map(|a| {
                    find(
                        a,
                        &["Annotations", "SimulationInformation", "FixedStepMaster"],
                    )
                    .or_else(|| find(a, &["SimulationInformation", "FixedStepMaster"]))
                })
                .map(|e| (e, "stepSize"))
        };
        let Some((element, attribute)) = osp.or_else(oms) else {
            return Ok(None);
        };
        match self.optional_double(&element, attribute, None)? {
            Some(h) if h > 0.0 && h.is_finite() => Ok(Some(h)),
            Some(_) => Err(self.invalid(&element, attribute, "a positive finite step", None)),
            None => Ok(None),
        }
    }

    fn system(&self, system: &Element) -> Result<(Vec<Component>, Vec<Connection>), SspError> {
        let system_name = system.value("name").unwrap_or("");
        let system_connectors: Vec<&str> = system
            .child("Connectors")
            .map(|c| {
                c.children_named("Connector")
                    .filter_map(|c| c.value("name"))
                    .collect()
            })
            .unwrap_or_default();

        let mut partials: Vec<Partial> = Vec::new();
        let mut index: HashMap<String, usize> = HashMap::new();
        let mut dictionaries: Vec<String> = Vec::new();
        if let Some(elements) = system.child("Elements") {
            for e in &elements.children {
                match e.name.as_str() {
                    "Component" => {
                        let partial = self.component(e)?;
                        let name = partial.component.name.clone();
                        if index.contains_key(&name) {
                            let (line, column) = self.at(e.offset);
                            return Err(SspError::DuplicateComponent { line, column, name });
                        }
                        index.insert(name, partials.len());
                        partials.push(partial);
                    }
                    "System" => {
                        let name = e.value("name").unwrap_or("");
                        return Err(self.unsupported(e.offset, format!("sub-system '{name}' (a <System> inside <Elements>; only flat systems of FMU components are)")));
                    }
                    "SignalDictionaryReference" => {
                        dictionaries.push(e.value("name").unwrap_or("").to_string())
                    }
                    _ => {}
                }
            }
        }

        // System-level bindings: names are `component.variable` (after the prefix); applied
        // after the components' own bindings, so that they win.
        if let Some(bindings) = system.child("ParameterBindings") {
            for binding in bindings.children_named("ParameterBinding") {
                for (name, value, offset) in
                    self.binding(binding, &format!("system '{system_name}'"))?
                {
                    let target = partials
                        .iter_mut()
                        .filter(|p| {
                            name.len() > p.component.name.len() + 1
                                && name.starts_with(&p.component.name)
                                && name.as_bytes()[p.component.name.len()] == b'.'
                        })
                        .max_by_key(|p| p.component.name.len());
                    match target {
                        Some(p) => {
                            let variable = name[p.component.name.len() + 1..].to_string();
                            set(&mut p.component.parameters, variable, value);
                        }
                        None => {
                            let (line, column) = self.at(offset);
                            return Err(SspError::UnknownParameterTarget {
                                line,
                                column,
                                parameter: name,
                            });
                        }
                    }
                }
            }
        }

        let mut connections = Vec::new();
        if let Some(list) = system.child("Connections") {
            for c in list.children_named("Connection") {
                connections.push(self.connection(
                    c,
                    &partials,
                    &index,
                    &dictionaries,
                    &system_connectors,
                )?);
            }
        }
        Ok((
            partials.into_iter().map(|p| p.component).collect(),
            connections,
        ))
    }

    fn component(&self, e: &Element) -> Result<Partial, SspError> {
        let name = self.required(e, "name", None)?;
        if name.is_empty() {
            return Err(self.invalid(e, "name", "a non-empty name", None));
        }
        let context = format!("component '{name}'");
        let ctx = Some(context.as_str());
        if let Some(ty) = e.value("type")
            && ty != FMU_MIME_TYPE
        {
            let offset = e.attribute("type").map_or(e.offset, |a| a.offset);
            return Err(self.unsupported(
                offset,
                format!("component '{name}' of type '{ty}' (only FMUs, type {FMU_MIME_TYPE}, are)"),
            ));
        }
        if e.value("implementation") == Some("ModelExchange") {
            let offset = e.attribute("implementation").map_or(e.offset, |a| a.offset);
            return Err(self.unsupported(offset, format!("component '{name}' with implementation=\"ModelExchange\" (this master runs FMUs for Co-Simulation)")));
        }
        let uri = self.required(e, "source", ctx)?;
        let source = match self.place.sources.get(name) {
            Some(given) => given.clone(),
            None => self.resolve(e, "source", uri, &context)?,
        };
        if !source.is_file() {
            let offset = e.attribute("source").map_or(e.offset, |a| a.offset);
            let (line, column) = self.at(offset);
            let shown = self.place.shown(&source);
            return Err(SspError::Invalid {
                line,
                column,
                message: format!(
                    "the source of {context}, \"{uri}\", is not an existing file ({})",
                    shown.display()
                ),
            });
        }

        let connectors = match e.child("Connectors") {
            None => None,
            Some(list) => {
                let mut map = HashMap::new();
                for c in list.children_named("Connector") {
                    let connector = self.required(c, "name", ctx)?;
                    map.insert(connector.to_string(), c.value("kind").map(str::to_string));
                }
                Some(map)
            }
        };

        let mut parameters = Vec::new();
        if let Some(bindings) = e.child("ParameterBindings") {
            for binding in bindings.children_named("ParameterBinding") {
                for (variable, value, _) in self.binding(binding, &context)? {
                    set(&mut parameters, variable, value);
                }
            }
        }
        Ok(Partial {
            component: Component {
                name: name.to_string(),
                source,
                parameters,
            },
            connectors,
        })
    }

    /// The parameters of one binding, in document order, with the binding's prefix applied and
    /// the offset of each (for errors).
    fn binding(&self, b: &Element, owner: &str) -> Result<Vec<(String, Value, usize)>, SspError> {
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

    fn parameter_set(&self, set: &Element) -> Result<Vec<(String, Value, usize)>, SspError> {
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

    fn connection(
        &self,
        c: &Element,
        partials: &[Partial],
        index: &HashMap<String, usize>,
        dictionaries: &[String],
        system_connectors: &[&str],
    ) -> Result<Connection, SspError> {
        let start_element = c.value("startElement");
        let end_element = c.value("endElement");
        let show = |element: Option<&str>, connector: Option<&str>| match element {
            Some(e) => format!("{e}.{}", connector.unwrap_or("?")),
            None => connector.unwrap_or("?").to_string(),
        };
        let label = format!(
            "{} -> {}",
            show(start_element, c.value("startConnector")),
            show(end_element, c.value("endConnector"))
        );
        let context = format!("connection {label}");
        let start_connector = self.required(c, "startConnector", Some(&context))?;
        let end_connector = self.required(c, "endConnector", Some(&context))?;

        let mut ends = Vec::with_capacity(2);
        for (element, connector, attribute) in [
            (start_element, start_connector, "startElement"),
            (end_element, end_connector, "endElement"),
        ] {
            let Some(element) = element else {
                let known = if system_connectors.contains(&connector) {
                    ""
                } else {
                    " (which the system does not even declare)"
                };
                return Err(self.unsupported(
                    c.offset,
                    format!("connection {label}: it has no {attribute}, so it uses the enclosing system's own connector '{connector}'{known}; connections to system connectors"),
                ));
            };
            let Some(&i) = index.get(element) else {
                let offset = c.attribute(attribute).map_or(c.offset, |a| a.offset);
                if dictionaries.iter().any(|d| d == element) {
                    return Err(self.unsupported(
                        offset,
                        format!("connection {label} to signal dictionary reference '{element}'"),
                    ));
                }
                let (line, column) = self.at(offset);
                return Err(SspError::UnknownComponent {
                    line,
                    column,
                    connection: label,
                    component: element.to_string(),
                });
            };
            let kind = match &partials[i].connectors {
                None => None,
                Some(declared) => match declared.get(connector) {
                    Some(kind) => kind.as_deref(),
                    None => {
                        let attr = if attribute == "startElement" {
                            "startConnector"
                        } else {
                            "endConnector"
                        };
                        let (line, column) =
                            self.at(c.attribute(attr).map_or(c.offset, |a| a.offset));
                        return Err(SspError::UndeclaredConnector {
                            line,
                            column,
                            connection: label,
                            component: element.to_string(),
                            connector: connector.to_string(),
                        });
                    }
                },
            };
            ends.push((Endpoint::new(element, connector), kind));
        }
        let (end, end_kind) = ends.pop().expect("two ends");
        let (start, start_kind) = ends.pop().expect("two ends");

        let mut transform = None;
        for t in &c.children {
            match t.name.as_str() {
                "LinearTransformation" => {
                    let factor = self
                        .optional_double(t, "factor", Some(&context))?
                        .unwrap_or(1.0);
                    let offset = self
                        .optional_double(t, "offset", Some(&context))?
                        .unwrap_or(0.0);
                    transform = Some(Linear { factor, offset });
                }
                "BooleanMappingTransformation"
                | "IntegerMappingTransformation"
                | "EnumerationMappingTransformation" => {
                    return Err(self.unsupported(
                        t.offset,
                        format!(
                            "<{}> on connection {label} (LinearTransformation is)",
                            t.name
                        ),
                    ));
                }
                _ => {}
            }
        }

        // In SSP, start and end do not say which way data flows; the connectors' kinds do.
        let reversed = matches!(start_kind, Some("input" | "parameter"))
            && matches!(end_kind, Some("output" | "calculatedParameter"));
        let (from, to) = if reversed { (end, start) } else { (start, end) };
        Ok(Connection {
            from,
            to,
            transform,
        })
    }

    /// Resolves a URI attribute (relative reference or `file:` URI) to an absolute path.
    fn resolve(
        &self,
        e: &Element,
        attribute: &'static str,
        uri: &str,
        context: &str,
    ) -> Result<PathBuf, SspError> {
        let offset = e.attribute(attribute).map_or(e.offset, |a| a.offset);
        let fail = |reason: String| {
            let (line, column) = self.at(offset);
            SspError::Invalid {
                line,
                column,
                message: format!(
                    "{attribute}=\"{uri}\" of <{}> ({context}): {reason}",
                    e.name
                ),
            }
        };
        if uri.is_empty() {
            return Err(fail("an empty URI".into()));
        }
        if uri.contains('#') {
            return Err(self.unsupported(offset, format!("{attribute}=\"{uri}\" of {context}: a URI with a fragment (a system inside another SSD or SSP)")));
        }
        let path = if let Some(rest) = uri.strip_prefix("file:") {
            let path = match rest.strip_prefix("//") {
                Some(after) => {
                    let slash = after
                        .find('/')
                        .ok_or_else(|| fail("a file: URI without a path".into()))?;
                    let host = &after[..slash];
                    if !host.is_empty() && !host.eq_ignore_ascii_case("localhost") {
                        return Err(fail(format!("a file: URI on another host ('{host}')")));
                    }
                    &after[slash..]
                }
                None => rest,
            };
            let path = PathBuf::from(
                percent_decode(path).ok_or_else(|| fail("bad percent-encoding".into()))?,
            );
            if !path.is_absolute() {
                return Err(fail("a relative file: URI".into()));
            }
            path
        } else {
            if let Some(colon) = uri.find(':') {
                let scheme = &uri[..colon];
                let is_scheme = scheme.len() > 1
                    && scheme.starts_with(|c: char| c.is_ascii_alphabetic())
                    && scheme
                        .chars()
                        .all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c));
                if is_scheme {
                    return Err(self.unsupported(offset, format!("{attribute}=\"{uri}\" of {context}: the URI scheme '{scheme}:' (relative references and file: URIs are)")));
                }
            }
            let decoded = percent_decode(uri).ok_or_else(|| fail("bad percent-encoding".into()))?;
            self.place.base_dir.join(decoded)
        };
        let path = normalize(&path);
        if self.place.confine && !path.starts_with(&self.place.base_dir) {
            return Err(fail("it points outside the .ssp archive".into()));
        }
        Ok(path)
    }
}

/// Sets a parameter: replaces the value in place if the name is already there (later wins),
/// appends it otherwise.
fn set(parameters: &mut Vec<(String, Value)>, name: String, value: Value) {
    match parameters.iter_mut().find(|(n, _)| *n == name) {
        Some(slot) => slot.1 = value,
        None => parameters.push((name, value)),
    }
}

/// An `xs:double`: decimal or exponent notation, `INF`, `-INF`, `NaN` (surrounding whitespace
/// allowed).
fn parse_double(text: &str) -> Option<f64> {
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

fn percent_decode(text: &str) -> Option<String> {
    let bytes = text.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = text.get(i + 1..i + 3)?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
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

    #[test]
    fn percent_decoding() {
        assert_eq!(percent_decode("a%20b/%C3%A9").as_deref(), Some("a b/é"));
        assert_eq!(percent_decode("a%2"), None);
    }

    #[test]
    fn normalization_is_lexical() {
        assert_eq!(normalize(Path::new("/a/./b/../c")), PathBuf::from("/a/c"));
    }
}
