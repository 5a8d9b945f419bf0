//! Reading a SystemStructure.ssd (or an .ssp archive) into a [`System`]: the document here;
//! the files and archives it reads in [`files`], parameter bindings in [`parameters`], URIs in
//! [`uri`].

mod files;
mod parameters;
mod uri;

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use files::{absolute, extract, in_file, is_archive, read_text};
use model_description::xml::{self, Element, line_column};
use parameters::{parse_double, set};

use super::error::SspError;
use super::{FMU_MIME_TYPE, LoadedSystem, SSD_NAME, Sources};
use crate::system::{Component, Connection, Endpoint, Experiment, Linear, System};

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
}
