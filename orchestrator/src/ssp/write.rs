//! Writing a [`System`] as a SystemStructure.ssd, and as an .ssp archive with its FMUs.

use std::collections::{HashMap, HashSet};
use std::fmt::Write as _;
use std::fs;
use std::io::{self, Write};
use std::path::Path;

use model_description::xml::escape_attribute;
use model_description::{BaseType, Causality, ModelDescription, ScalarVariable, format_f64};

use super::error::SspError;
use super::{FMU_MIME_TYPE, SSD_NAME};
use crate::system::{Component, System, Value};

const NS_SSD: &str = "http://ssp-standard.org/SSP1/SystemStructureDescription";
const NS_SSC: &str = "http://ssp-standard.org/SSP1/SystemStructureCommon";
const NS_SSV: &str = "http://ssp-standard.org/SSP1/SystemStructureParameterValues";
/// The Open Simulation Platform's annotations (libcosim reads the step from them; it matches
/// the prefixes `ssc:` and `osp:` literally).
const NS_OSP: &str = "http://opensimulationplatform.com/SSP/OSPAnnotations";
/// OMSimulator's annotations (it needs the system's FixedStepMaster to load a co-simulation).
const NS_OMS: &str =
    "https://raw.githubusercontent.com/OpenModelica/OMSimulator/master/schema/oms.xsd";

pub fn write_ssp(system: &System, out: &Path) -> Result<(), SspError> {
    // resources/<component>.fmu, with the name made safe as a file name and as a URI.
    let mut files: HashMap<&str, String> = HashMap::new();
    let mut taken: HashSet<String> = HashSet::new();
    for c in &system.components {
        let stem: String = c
            .name
            .chars()
            .map(|ch| {
                if ch.is_ascii_alphanumeric() || "-_.".contains(ch) {
                    ch
                } else {
                    '_'
                }
            })
            .collect();
        let stem = if stem.trim_matches('.').is_empty() {
            "component".to_string()
        } else {
            stem
        };
        let mut file = format!("{stem}.fmu");
        let mut n = 2;
        while !taken.insert(file.to_ascii_lowercase()) {
            file = format!("{stem}_{n}.fmu");
            n += 1;
        }
        files.insert(c.name.as_str(), file);
    }
    let sources = |c: &Component| format!("resources/{}", files[c.name.as_str()]);
    let ssd = super::to_ssd(system, &sources, &|c: &Component| fmu_model_description(c))?;

    let io_err = |source| SspError::Io {
        path: out.to_path_buf(),
        source,
    };
    let dir = match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let mut builder = tempfile::Builder::new();
    builder.prefix(".ssp-").suffix(".tmp");
    // An ordinary file once renamed into place (a temporary file is owner-only by default).
    #[cfg(unix)]
    builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
    let tmp = builder.tempfile_in(dir).map_err(io_err)?;
    let mut zip = zip::ZipWriter::new(io::BufWriter::new(tmp.as_file()));
    let zip_err = |e: zip::result::ZipError| io_err(io::Error::other(e));
    let deflated = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated);
    // FMUs are zip archives already: store them.
    let stored = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Stored)
        .large_file(true);
    zip.start_file(SSD_NAME, deflated).map_err(zip_err)?;
    zip.write_all(ssd.as_bytes()).map_err(io_err)?;
    zip.add_directory("resources/", deflated).map_err(zip_err)?;
    for c in &system.components {
        zip.start_file(sources(c), stored).map_err(zip_err)?;
        let mut fmu = fs::File::open(&c.source).map_err(|source| SspError::Io {
            path: c.source.clone(),
            source,
        })?;
        io::copy(&mut fmu, &mut zip).map_err(|source| SspError::Io {
            path: c.source.clone(),
            source,
        })?;
    }
    let mut buffered = zip.finish().map_err(zip_err)?;
    buffered.flush().map_err(io_err)?;
    drop(buffered);
    tmp.persist(out).map_err(|e| io_err(e.error))?;
    Ok(())
}

/// The modelDescription.xml inside a component's FMU.
fn fmu_model_description(c: &Component) -> Result<ModelDescription, SspError> {
    let fail = |message: String| SspError::Fmu {
        component: c.name.clone(),
        path: c.source.clone(),
        message,
    };
    let file = fs::File::open(&c.source).map_err(|e| fail(e.to_string()))?;
    let mut zip = zip::ZipArchive::new(io::BufReader::new(file))
        .map_err(|e| fail(format!("not a zip archive: {e}")))?;
    let entry = zip
        .by_name("modelDescription.xml")
        .map_err(|e| fail(format!("no modelDescription.xml: {e}")))?;
    // Bounded: a zip bomb's modelDescription.xml must not exhaust the memory.
    let limit = fmi_import::UnpackLimits::DEFAULT.max_model_description_bytes;
    let text = fmi_abi::resource::read_limited(entry, limit)
        .map_err(|e| fail(format!("modelDescription.xml: {e}")))?
        .ok_or_else(|| {
            fail(format!(
                "modelDescription.xml is larger than the limit of {limit} bytes"
            ))
        })?;
    ModelDescription::from_xml(&text).map_err(|source| SspError::ModelDescription {
        component: c.name.clone(),
        path: c.source.clone(),
        source: Box::new(source),
    })
}

fn not_writable(message: String) -> SspError {
    SspError::NotWritable { message }
}

fn kind(causality: Causality) -> Option<&'static str> {
    match causality {
        Causality::Input => Some("input"),
        Causality::Output => Some("output"),
        Causality::Parameter => Some("parameter"),
        Causality::CalculatedParameter => Some("calculatedParameter"),
        Causality::Local | Causality::Independent => None,
    }
}

fn fits(value: &Value, base: BaseType) -> bool {
    matches!(
        (value, base),
        (Value::Real(_), BaseType::Real)
            | (Value::Integer(_), BaseType::Integer | BaseType::Enumeration)
            | (Value::Boolean(_), BaseType::Boolean)
            | (Value::String(_), BaseType::String)
    )
}

fn value_type(value: &Value) -> &'static str {
    match value {
        Value::Real(_) => "Real",
        Value::Integer(_) => "Integer",
        Value::Boolean(_) => "Boolean",
        Value::String(_) => "String",
    }
}

pub fn to_ssd(
    system: &System,
    fmu_sources: &dyn Fn(&Component) -> String,
    descriptions: &dyn Fn(&Component) -> Result<ModelDescription, SspError>,
) -> Result<String, SspError> {
    let mut index: HashMap<&str, usize> = HashMap::new();
    for (i, c) in system.components.iter().enumerate() {
        if c.name.is_empty() {
            return Err(not_writable(format!(
                "component {} has an empty name",
                i + 1
            )));
        }
        if index.insert(c.name.as_str(), i).is_some() {
            return Err(not_writable(format!(
                "two components are named '{}'",
                c.name
            )));
        }
    }
    let mds = system
        .components
        .iter()
        .map(descriptions)
        .collect::<Result<Vec<_>, _>>()?;
    let variable = |component: &str,
                    name: &str,
                    usage: &dyn Fn() -> String|
     -> Result<(usize, &ScalarVariable), SspError> {
        let &i = index.get(component).ok_or_else(|| {
            not_writable(format!(
                "{} refers to '{component}', which is not a component of the system",
                usage()
            ))
        })?;
        let v = mds[i].variable(name).ok_or_else(|| {
            not_writable(format!(
                "{}: component '{component}' ({}) has no variable '{name}'",
                usage(),
                system.components[i].source.display()
            ))
        })?;
        Ok((i, v))
    };

    // Connectors: the variables connections use, and the parameters that parameter bindings set
    // (bindings need no connector, but tools show them). Not every input and output: fmpy's SSP
    // master insists that each input connector be connected and cannot read String outputs.
    let mut used: Vec<HashSet<&str>> = vec![HashSet::new(); system.components.len()];
    for conn in &system.connections {
        let label = || format!("connection {} -> {}", conn.from, conn.to);
        let (fi, fv) = variable(&conn.from.component, &conn.from.variable, &label)?;
        let (ti, tv) = variable(&conn.to.component, &conn.to.variable, &label)?;
        for (i, v) in [(fi, fv), (ti, tv)] {
            if kind(v.causality).is_none() {
                return Err(not_writable(format!(
                    "{}: variable '{}' of component '{}' has causality {}, and SSP connectors are inputs, outputs, parameters or calculated parameters",
                    label(),
                    v.name,
                    system.components[i].name,
                    v.causality.as_str()
                )));
            }
            used[i].insert(v.name.as_str());
        }
        // The reader takes an input/parameter -> output/calculatedParameter connection the
        // other way round, as SSP says; such a connection could not come back unchanged.
        if matches!(fv.causality, Causality::Input | Causality::Parameter)
            && matches!(
                tv.causality,
                Causality::Output | Causality::CalculatedParameter
            )
        {
            return Err(not_writable(format!(
                "{}: it goes from an {} to an {}; data flows from outputs to inputs",
                label(),
                fv.causality.as_str(),
                tv.causality.as_str()
            )));
        }
    }
    for c in &system.components {
        for (name, value) in &c.parameters {
            let usage = || format!("parameter '{}' of component '{}'", name, c.name);
            let (i, v) = variable(&c.name, name, &usage)?;
            if v.causality == Causality::Parameter {
                used[i].insert(v.name.as_str());
            }
            let base = v.kind.base_type();
            if !fits(value, base) {
                return Err(not_writable(format!(
                    "{}: a {} value for a variable of type {}",
                    usage(),
                    value_type(value),
                    base.as_str()
                )));
            }
        }
    }

    let mut x = String::new();
    let attr = |x: &mut String, name: &str, value: &str| {
        let _ = write!(x, " {name}=\"");
        escape_attribute(value, x);
        x.push('"');
    };
    x.push_str("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<ssd:SystemStructureDescription version=\"1.0\"");
    attr(&mut x, "name", &system.name);
    attr(
        &mut x,
        "generationTool",
        concat!("orchestrator ", env!("CARGO_PKG_VERSION")),
    );
    let _ = write!(
        x,
        "\n    xmlns:ssd=\"{NS_SSD}\"\n    xmlns:ssc=\"{NS_SSC}\"\n    xmlns:ssv=\"{NS_SSV}\"\n    xmlns:osp=\"{NS_OSP}\"\n    xmlns:oms=\"{NS_OMS}\">\n"
    );
    x.push_str("  <ssd:System");
    attr(&mut x, "name", &system.name);
    x.push_str(">\n");

    if !system.components.is_empty() {
        x.push_str("    <ssd:Elements>\n");
        for (i, c) in system.components.iter().enumerate() {
            x.push_str("      <ssd:Component");
            attr(&mut x, "name", &c.name);
            attr(&mut x, "type", FMU_MIME_TYPE);
            attr(&mut x, "source", &fmu_sources(c));
            x.push_str(">\n");
            let connectors: Vec<&ScalarVariable> = mds[i]
                .model_variables
                .iter()
                .filter(|v| used[i].contains(v.name.as_str()))
                .collect();
            if !connectors.is_empty() {
                x.push_str("        <ssd:Connectors>\n");
                for v in connectors {
                    x.push_str("          <ssd:Connector");
                    attr(&mut x, "name", &v.name);
                    attr(&mut x, "kind", kind(v.causality).unwrap_or_default());
                    match v.kind.base_type() {
                        // ssc:Enumeration would need the enumeration declared in the SSD.
                        BaseType::Enumeration => x.push_str("/>\n"),
                        base => {
                            let _ = writeln!(x, "><ssc:{}/></ssd:Connector>", base.as_str());
                        }
                    }
                }
                x.push_str("        </ssd:Connectors>\n");
            }
            if !c.parameters.is_empty() {
                x.push_str("        <ssd:ParameterBindings>\n          <ssd:ParameterBinding>\n            <ssd:ParameterValues>\n");
                x.push_str("              <ssv:ParameterSet version=\"1.0\"");
                attr(&mut x, "name", &c.name);
                x.push_str(">\n                <ssv:Parameters>\n");
                for (name, value) in &c.parameters {
                    x.push_str("                  <ssv:Parameter");
                    attr(&mut x, "name", name);
                    let (ty, text) = match value {
                        Value::Real(r) => ("Real", format_f64(*r)),
                        Value::Integer(n) => ("Integer", n.to_string()),
                        Value::Boolean(b) => ("Boolean", b.to_string()),
                        Value::String(s) => ("String", s.clone()),
                    };
                    let _ = write!(x, "><ssv:{ty}");
                    attr(&mut x, "value", &text);
                    x.push_str("/></ssv:Parameter>\n");
                }
                x.push_str(
                    "                </ssv:Parameters>\n              </ssv:ParameterSet>\n",
                );
                x.push_str("            </ssd:ParameterValues>\n          </ssd:ParameterBinding>\n        </ssd:ParameterBindings>\n");
            }
            x.push_str("      </ssd:Component>\n");
        }
        x.push_str("    </ssd:Elements>\n");
    }

    if !system.connections.is_empty() {
        x.push_str("    <ssd:Connections>\n");
        for conn in &system.connections {
            x.push_str("      <ssd:Connection");
            attr(&mut x, "startElement", &conn.from.component);
            attr(&mut x, "startConnector", &conn.from.variable);
            attr(&mut x, "endElement", &conn.to.component);
            attr(&mut x, "endConnector", &conn.to.variable);
            match conn.transform {
                None => x.push_str("/>\n"),
                Some(t) => {
                    x.push_str(">\n        <ssc:LinearTransformation");
                    attr(&mut x, "factor", &format_f64(t.factor));
                    attr(&mut x, "offset", &format_f64(t.offset));
                    x.push_str("/>\n      </ssd:Connection>\n");
                }
            }
        }
        x.push_str("    </ssd:Connections>\n");
    }
    // The communication step: the system's, else the first FMU's default (what `run` uses).
    let step = system.experiment.step.or_else(|| {
        mds.first()
            .and_then(|md| md.default_experiment.as_ref())
            .and_then(|d| d.step_size)
    });
    if let Some(step) = step {
        let step = format_f64(step);
        x.push_str("    <ssd:Annotations>\n      <ssc:Annotation type=\"org.openmodelica\">\n        <oms:Annotations>\n          <oms:SimulationInformation>\n            <oms:FixedStepMaster description=\"oms-ma\"");
        attr(&mut x, "stepSize", &step);
        x.push_str(" absoluteTolerance=\"1e-4\" relativeTolerance=\"1e-4\"/>\n          </oms:SimulationInformation>\n        </oms:Annotations>\n      </ssc:Annotation>\n    </ssd:Annotations>\n");
    }
    x.push_str("  </ssd:System>\n");

    let e = &system.experiment;
    x.push_str("  <ssd:DefaultExperiment");
    attr(&mut x, "startTime", &format_f64(e.start));
    if let Some(stop) = e.stop {
        attr(&mut x, "stopTime", &format_f64(stop));
    }
    match step {
        None => x.push_str("/>\n"),
        Some(step) => {
            x.push_str(">\n    <ssd:Annotations>\n      <ssc:Annotation type=\"com.opensimulationplatform\">\n        <osp:Algorithm>\n          <osp:FixedStepAlgorithm");
            attr(&mut x, "baseStepSize", &format_f64(step));
            x.push_str("/>\n        </osp:Algorithm>\n      </ssc:Annotation>\n    </ssd:Annotations>\n  </ssd:DefaultExperiment>\n");
        }
    }
    x.push_str("</ssd:SystemStructureDescription>\n");
    Ok(x)
}
