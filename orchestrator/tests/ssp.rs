//! SSP 1.0 reading and writing (`orchestrator::ssp`).
//!
//! FMUs here are fakes: zip archives holding only a modelDescription.xml, which is all the
//! reader (existence) and the writer (connector types) need.

use std::fs;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};

use orchestrator::ssp::{self, SspError};
use orchestrator::system::{Component, Connection, Endpoint, Experiment, Linear, System, Value};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/ssp")
        .join(name)
}

/// A modelDescription.xml with the given (name, causality, type) variables.
fn model_description(name: &str, variables: &[(&str, &str, &str)]) -> String {
    let mut x = format!(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<fmiModelDescription fmiVersion=\"2.0\" modelName=\"{name}\" guid=\"{{{name}}}\">\n  <CoSimulation modelIdentifier=\"{name}\"/>\n  <ModelVariables>\n"
    );
    for (i, (var, causality, ty)) in variables.iter().enumerate() {
        let (variability, start) = match (*causality, *ty) {
            ("parameter", "Real") => (" variability=\"fixed\"", " start=\"1\""),
            ("parameter", "Integer" | "Enumeration") => (" variability=\"fixed\"", " start=\"1\""),
            ("parameter", "Boolean") => (" variability=\"fixed\"", " start=\"false\""),
            ("parameter", "String") => (" variability=\"fixed\"", " start=\"\""),
            ("input", "Real") => ("", " start=\"0\""),
            (_, "Real") => ("", ""),
            _ => (" variability=\"discrete\"", ""),
        };
        let decl = if *ty == "Enumeration" {
            " declaredType=\"Mode\""
        } else {
            ""
        };
        x.push_str(&format!(
            "    <ScalarVariable name=\"{var}\" valueReference=\"{i}\" causality=\"{causality}\"{variability}><{ty}{decl}{start}/></ScalarVariable>\n"
        ));
    }
    x.push_str("  </ModelVariables>\n  <ModelStructure/>\n</fmiModelDescription>\n");
    x
}

fn fake_fmu(path: &Path, name: &str, variables: &[(&str, &str, &str)]) {
    fs::create_dir_all(path.parent().unwrap()).unwrap();
    let mut zip = zip::ZipWriter::new(fs::File::create(path).unwrap());
    zip.start_file(
        "modelDescription.xml",
        zip::write::SimpleFileOptions::default(),
    )
    .unwrap();
    zip.write_all(model_description(name, variables).as_bytes())
        .unwrap();
    zip.finish().unwrap();
}

const PLANT: &[(&str, &str, &str)] = &[
    ("x", "output", "Real"),
    ("w", "input", "Real"),
    ("k", "parameter", "Real"),
    ("n", "parameter", "Integer"),
    ("on", "parameter", "Boolean"),
    ("mode", "parameter", "String"),
    ("state", "local", "Real"),
    ("time", "independent", "Real"),
];
const OBSERVER: &[(&str, &str, &str)] = &[
    ("u", "input", "Real"),
    ("y", "output", "Real"),
    ("gain", "parameter", "Real"),
    ("label", "parameter", "String"),
    ("count", "output", "Integer"),
    ("flag", "input", "Boolean"),
    ("choice", "parameter", "Enumeration"),
];

/// A temporary directory with the fixture files and fake FMUs under resources/.
fn workspace() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    for f in ["two_fmus.ssd", "features.ssd", "plant.ssv", "system.ssv"] {
        fs::copy(data(f), dir.path().join(f)).unwrap();
    }
    fake_fmu(&dir.path().join("resources/Plant.fmu"), "Plant", PLANT);
    fake_fmu(
        &dir.path().join("resources/Observer.fmu"),
        "Observer",
        OBSERVER,
    );
    fake_fmu(
        &dir.path().join("resources/Sensor Unit.fmu"),
        "Sensor",
        &[("s", "output", "Real"), ("offset", "parameter", "Integer")],
    );
    dir
}

fn abs(dir: &Path, rel: &str) -> PathBuf {
    std::path::absolute(dir.join(rel)).unwrap()
}

fn component(name: &str, source: PathBuf, parameters: Vec<(&str, Value)>) -> Component {
    Component {
        name: name.into(),
        source,
        parameters: parameters
            .into_iter()
            .map(|(n, v)| (n.to_string(), v))
            .collect(),
    }
}

fn link(from: &str, to: &str, transform: Option<Linear>) -> Connection {
    Connection {
        from: Endpoint::parse(from).unwrap(),
        to: Endpoint::parse(to).unwrap(),
        transform,
    }
}

/// Parses an .ssd text placed in a workspace; returns the error.
fn parse_err(ssd: &str) -> SspError {
    let dir = workspace();
    ssp::parse_ssd(ssd, dir.path()).expect_err("the document should be refused")
}

/// A minimal document around `system_body` (the content of <ssd:System>).
fn doc(system_body: &str) -> String {
    format!(
        r#"<?xml version="1.0" encoding="UTF-8"?>
<ssd:SystemStructureDescription version="1.0" name="t"
    xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription"
    xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon"
    xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues">
  <ssd:System name="root">
{system_body}
  </ssd:System>
</ssd:SystemStructureDescription>
"#
    )
}

const TWO_COMPONENTS: &str = r#"    <ssd:Elements>
      <ssd:Component name="plant" source="resources/Plant.fmu">
        <ssd:Connectors><ssd:Connector name="x" kind="output"/></ssd:Connectors>
      </ssd:Component>
      <ssd:Component name="observer" source="resources/Observer.fmu"/>
    </ssd:Elements>"#;

// ---------------------------------------------------------------------------------------------
// Reading

#[test]
fn the_minimal_two_fmu_ssd_reads_into_the_expected_system() {
    let dir = workspace();
    let loaded = ssp::read(&dir.path().join("two_fmus.ssd")).unwrap();
    assert!(loaded.extracted_dir().is_none());
    let expected = System {
        name: "two_fmus".into(),
        components: vec![
            component(
                "plant",
                abs(dir.path(), "resources/Plant.fmu"),
                vec![("k", Value::Real(0.5))],
            ),
            component(
                "observer",
                abs(dir.path(), "resources/Observer.fmu"),
                vec![],
            ),
        ],
        connections: vec![link("plant.x", "observer.u", None)],
        experiment: Experiment {
            start: 0.0,
            stop: Some(10.0),
            step: None,
        },
    };
    assert_eq!(loaded.system, expected);
    assert!(
        loaded
            .system
            .components
            .iter()
            .all(|c| c.source.is_absolute())
    );
    // A directory holding SystemStructure.ssd reads the same.
    fs::copy(data("two_fmus.ssd"), dir.path().join("SystemStructure.ssd")).unwrap();
    assert_eq!(ssp::read(dir.path()).unwrap().system, expected);
}

#[test]
fn parse_ssd_resolves_against_a_relative_base_dir() {
    let dir = workspace();
    let text = fs::read_to_string(data("two_fmus.ssd")).unwrap();
    let cwd = std::env::current_dir().unwrap();
    let rel = pathdiff(dir.path(), &cwd);
    let system = ssp::parse_ssd(&text, &rel).unwrap();
    assert_eq!(
        system.components[0].source,
        abs(dir.path(), "resources/Plant.fmu")
    );
}

/// `path` relative to `base` (both absolute), via enough `..`.
fn pathdiff(path: &Path, base: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for _ in base.components().skip(1) {
        out.push("..");
    }
    out.join(path.strip_prefix("/").unwrap())
}

#[test]
fn transformations_parameter_types_ssv_files_prefixes_and_precedence() {
    let dir = workspace();
    let system = ssp::read(&dir.path().join("features.ssd")).unwrap().system;
    let expected = System {
        name: "features".into(),
        components: vec![
            // Own bindings: k=1, n=4, on=true, mode; then plant.ssv: k=2, n=-7, on=0; then the
            // system's prefixed binding: k=3. One entry per variable, in order of first mention.
            component(
                "plant",
                abs(dir.path(), "resources/Plant.fmu"),
                vec![
                    ("k", Value::Real(3.0)),
                    ("n", Value::Integer(-7)),
                    ("on", Value::Boolean(false)),
                    ("mode", Value::String("fast & \"exact\"".into())),
                ],
            ),
            // Own gain=2; system names: label; system.ssv with prefix (last): gain=5, label.
            component(
                "observer",
                abs(dir.path(), "resources/Observer.fmu"),
                vec![
                    ("gain", Value::Real(5.0)),
                    ("label", Value::String("from system.ssv".into())),
                ],
            ),
            component(
                "sensor",
                abs(dir.path(), "resources/Sensor Unit.fmu"),
                vec![("offset", Value::Integer(12))],
            ),
            // "sensor.hf.cutoff" goes to the component "sensor.hf", the longest matching name.
            component(
                "sensor.hf",
                abs(dir.path(), "resources/Observer.fmu"),
                vec![("cutoff", Value::Real(2.5e-3))],
            ),
        ],
        connections: vec![
            link(
                "plant.x",
                "observer.u",
                Some(Linear {
                    factor: 2.5,
                    offset: -1.0,
                }),
            ),
            // Written plant.w (input) -> sensor.s (output): read the other way round.
            link(
                "sensor.s",
                "plant.w",
                Some(Linear {
                    factor: 0.001,
                    offset: 0.0,
                }),
            ),
            Connection {
                from: Endpoint::new("observer", "y"),
                to: Endpoint::new("sensor.hf", "u"),
                transform: None,
            },
        ],
        experiment: Experiment {
            start: 1.5,
            stop: Some(20.0),
            step: None,
        },
    };
    assert_eq!(system, expected);
}

#[test]
fn any_prefix_or_none_and_file_uris() {
    let dir = workspace();
    let plant = abs(dir.path(), "resources/Plant.fmu");
    let uri = format!("file://{}", plant.display()).replace(' ', "%20");
    let text = format!(
        r#"<SystemStructureDescription xmlns="http://ssp-standard.org/SSP1/SystemStructureDescription"
    xmlns:c="http://ssp-standard.org/SSP1/SystemStructureCommon" xmlns:v="http://ssp-standard.org/SSP1/SystemStructureParameterValues"
    version="1.0" name="plain">
  <System name="s">
    <Elements>
      <Component name="a" source="{uri}">
        <ParameterBindings><ParameterBinding><ParameterValues>
          <v:ParameterSet version="1.0" name="p"><v:Parameters>
            <v:Parameter name="k"><v:Real value=" -INF "/></v:Parameter>
          </v:Parameters></v:ParameterSet>
        </ParameterValues></ParameterBinding></ParameterBindings>
      </Component>
      <Component name="b" source="file:{}"/>
    </Elements>
    <Connections><Connection startElement="a" startConnector="x" endElement="b" endConnector="w"><c:LinearTransformation offset="4"/></Connection></Connections>
  </System>
</SystemStructureDescription>"#,
        plant.display()
    );
    let system = ssp::parse_ssd(&text, Path::new("/nonexistent")).unwrap();
    assert_eq!(system.name, "plain");
    assert_eq!(system.components[0].source, plant);
    assert_eq!(system.components[1].source, plant);
    assert_eq!(
        system.components[0].parameters,
        vec![("k".to_string(), Value::Real(f64::NEG_INFINITY))]
    );
    assert_eq!(
        system.connections[0].transform,
        Some(Linear {
            factor: 1.0,
            offset: 4.0
        })
    );
    assert_eq!(system.experiment, Experiment::default());
}

// ---------------------------------------------------------------------------------------------
// Errors

#[test]
fn malformed_xml_gives_file_line_and_column() {
    let dir = workspace();
    let path = dir.path().join("broken.ssd");
    fs::write(&path, doc("    <ssd:Elements>\n      <ssd:Component name=\"a\" source=\"resources/Plant.fmu\">\n    </ssd:Elements>")).unwrap();
    let err = ssp::read(&path).unwrap_err();
    let text = err.to_string();
    assert!(text.contains("broken.ssd"), "{text}");
    assert!(matches!(err.innermost(), SspError::Xml { .. }), "{err:?}");
    // The </ssd:Elements> where </ssd:Component> was due: line 9, column 5.
    assert_eq!(err.line_column(), Some((9, 5)), "{text}");
    assert!(text.contains("line 9, column 5"), "{text}");
}

#[test]
fn a_bad_value_names_the_attribute_parameter_and_position() {
    let err = parse_err(&doc(r#"    <ssd:Elements>
      <ssd:Component name="plant" source="resources/Plant.fmu">
        <ssd:ParameterBindings><ssd:ParameterBinding><ssd:ParameterValues>
          <ssv:ParameterSet version="1.0" name="p"><ssv:Parameters>
            <ssv:Parameter name="n"><ssv:Integer value="4.5"/></ssv:Parameter>
          </ssv:Parameters></ssv:ParameterSet>
        </ssd:ParameterValues></ssd:ParameterBinding></ssd:ParameterBindings>
      </ssd:Component>
    </ssd:Elements>"#));
    let text = err.to_string();
    assert!(
        matches!(
            &err,
            SspError::InvalidValue {
                attribute: "value",
                ..
            }
        ),
        "{err:?}"
    );
    assert_eq!(err.line_column(), Some((11, 50)), "{text}");
    assert!(
        text.contains("parameter 'n'")
            && text.contains("\"4.5\"")
            && text.contains("32-bit integer"),
        "{text}"
    );
}

#[test]
fn a_connection_to_an_unknown_component_names_it() {
    let err = parse_err(&doc(&format!(
        "{TWO_COMPONENTS}\n    <ssd:Connections>\n      <ssd:Connection startElement=\"plant\" startConnector=\"x\" endElement=\"obsrver\" endConnector=\"u\"/>\n    </ssd:Connections>"
    )));
    match &err {
        SspError::UnknownComponent {
            component,
            connection,
            ..
        } => {
            assert_eq!(component, "obsrver");
            assert_eq!(connection, "plant.x -> obsrver.u");
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(err.line_column(), Some((14, 63)), "{err}");
    assert!(err.to_string().contains("'obsrver'"), "{err}");
}

#[test]
fn an_undeclared_connector_names_component_and_connector() {
    let err = parse_err(&doc(&format!(
        "{TWO_COMPONENTS}\n    <ssd:Connections>\n      <ssd:Connection startElement=\"plant\" startConnector=\"xx\" endElement=\"observer\" endConnector=\"anything\"/>\n    </ssd:Connections>"
    )));
    match &err {
        SspError::UndeclaredConnector {
            component,
            connector,
            ..
        } => {
            assert_eq!((component.as_str(), connector.as_str()), ("plant", "xx"));
        }
        other => panic!("{other:?}"),
    }
    let text = err.to_string();
    assert!(text.contains("'xx'") && text.contains("'plant'"), "{text}");
    // The observer declares no connectors: "anything" is accepted there.
    let ok = doc(&format!(
        "{TWO_COMPONENTS}\n    <ssd:Connections>\n      <ssd:Connection startElement=\"plant\" startConnector=\"x\" endElement=\"observer\" endConnector=\"anything\"/>\n    </ssd:Connections>"
    ));
    let dir = workspace();
    assert_eq!(
        ssp::parse_ssd(&ok, dir.path()).unwrap().connections,
        vec![link("plant.x", "observer.anything", None)]
    );
}

#[test]
fn nested_systems_are_refused() {
    let err = parse_err(&doc(r#"    <ssd:Elements>
      <ssd:Component name="plant" source="resources/Plant.fmu"/>
      <ssd:System name="inner"><ssd:Elements><ssd:Component name="c" source="resources/Plant.fmu"/></ssd:Elements></ssd:System>
    </ssd:Elements>"#));
    assert!(matches!(&err, SspError::Unsupported { .. }), "{err:?}");
    let text = err.to_string();
    assert!(
        text.contains("sub-system 'inner'") && text.contains("not supported"),
        "{text}"
    );
    assert_eq!(err.line_column(), Some((9, 7)));
}

#[test]
fn connections_to_system_connectors_are_refused_by_name() {
    let err = parse_err(&doc(&format!(
        "    <ssd:Connectors><ssd:Connector name=\"in\" kind=\"input\"/></ssd:Connectors>\n{TWO_COMPONENTS}\n    <ssd:Connections>\n      <ssd:Connection startConnector=\"in\" endElement=\"observer\" endConnector=\"u\"/>\n    </ssd:Connections>"
    )));
    assert!(matches!(&err, SspError::Unsupported { .. }), "{err:?}");
    let text = err.to_string();
    assert!(
        text.contains("connection in -> observer.u")
            && text.contains("system's own connector 'in'"),
        "{text}"
    );
}

#[test]
fn a_missing_source_is_refused() {
    let err = parse_err(&doc(
        "    <ssd:Elements>\n      <ssd:Component name=\"plant\"/>\n    </ssd:Elements>",
    ));
    match &err {
        SspError::MissingAttribute {
            attribute, context, ..
        } => {
            assert_eq!(*attribute, "source");
            assert_eq!(context.as_deref(), Some("component 'plant'"));
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(err.line_column(), Some((8, 7)));
    // A source that points at no file.
    let err = parse_err(&doc(
        "    <ssd:Elements>\n      <ssd:Component name=\"plant\" source=\"resources/Nope.fmu\"/>\n    </ssd:Elements>",
    ));
    let text = err.to_string();
    assert!(
        text.contains("component 'plant'") && text.contains("resources/Nope.fmu"),
        "{text}"
    );
    assert_eq!(err.line_column(), Some((8, 35)));
}

#[test]
fn other_unsupported_features_say_what() {
    let cases = [
        (
            "<ssd:Elements><ssd:Component name=\"sub\" type=\"application/x-ssp-package\" source=\"resources/Plant.fmu\"/></ssd:Elements>",
            "application/x-ssp-package",
        ),
        (
            "<ssd:Elements><ssd:Component name=\"p\" source=\"resources/Plant.fmu\"><ssd:ParameterBindings><ssd:ParameterBinding source=\"p.ssm\"><ssd:ParameterMapping/></ssd:ParameterBinding></ssd:ParameterBindings></ssd:Component></ssd:Elements>",
            "<ParameterMapping>",
        ),
        (
            "<ssd:Elements><ssd:Component name=\"p\" source=\"http://example.com/Plant.fmu\"/></ssd:Elements>",
            "'http:'",
        ),
        (
            "<ssd:Elements><ssd:Component name=\"p\" source=\"resources/Plant.fmu\"/><ssd:Component name=\"q\" source=\"resources/Plant.fmu\"/></ssd:Elements><ssd:Connections><ssd:Connection startElement=\"p\" startConnector=\"n\" endElement=\"q\" endConnector=\"n\"><ssc:IntegerMappingTransformation><ssc:MapEntry source=\"1\" target=\"2\"/></ssc:IntegerMappingTransformation></ssd:Connection></ssd:Connections>",
            "IntegerMappingTransformation",
        ),
    ];
    for (body, needle) in cases {
        let err = parse_err(&doc(body));
        assert!(matches!(err, SspError::Unsupported { .. }), "{err:?}");
        assert!(err.to_string().contains(needle), "{err}");
    }
}

#[test]
fn system_level_parameters_must_name_a_component() {
    let err = parse_err(&doc(&format!(
        "    <ssd:ParameterBindings><ssd:ParameterBinding><ssd:ParameterValues><ssv:ParameterSet version=\"1.0\" name=\"s\"><ssv:Parameters>\n      <ssv:Parameter name=\"plnt.k\"><ssv:Real value=\"1\"/></ssv:Parameter>\n    </ssv:Parameters></ssv:ParameterSet></ssd:ParameterValues></ssd:ParameterBinding></ssd:ParameterBindings>\n{TWO_COMPONENTS}"
    )));
    match &err {
        SspError::UnknownParameterTarget { parameter, .. } => assert_eq!(parameter, "plnt.k"),
        other => panic!("{other:?}"),
    }
    assert_eq!(err.line_column(), Some((8, 7)));
}

#[test]
fn errors_in_an_ssv_file_name_that_file() {
    let dir = workspace();
    fs::write(dir.path().join("bad.ssv"), "<ssv:ParameterSet xmlns:ssv=\"x\" version=\"1.0\" name=\"b\">\n  <ssv:Parameters>\n    <ssv:Parameter name=\"k\"><ssv:Real value=\"fast\"/></ssv:Parameter>\n  </ssv:Parameters>\n</ssv:ParameterSet>\n").unwrap();
    let ssd = dir.path().join("s.ssd");
    fs::write(&ssd, doc("    <ssd:Elements>\n      <ssd:Component name=\"plant\" source=\"resources/Plant.fmu\">\n        <ssd:ParameterBindings><ssd:ParameterBinding source=\"bad.ssv\"/></ssd:ParameterBindings>\n      </ssd:Component>\n    </ssd:Elements>")).unwrap();
    let err = ssp::read(&ssd).unwrap_err();
    let text = err.to_string();
    assert!(
        text.contains("s.ssd") && text.contains("bad.ssv") && text.contains("line 3, column 39"),
        "{text}"
    );
    assert!(text.contains("\"fast\""), "{text}");
    // A missing .ssv is reported at the binding that names it.
    fs::remove_file(dir.path().join("bad.ssv")).unwrap();
    let err = ssp::read(&ssd).unwrap_err();
    assert_eq!(err.line_column(), Some((9, 54)), "{err}");
    assert!(err.to_string().contains("bad.ssv"), "{err}");
}

// ---------------------------------------------------------------------------------------------
// Archives and writing

fn round_trip_system(dir: &Path) -> System {
    fake_fmu(&dir.join("build/plant.fmu"), "Plant", PLANT);
    fake_fmu(&dir.join("build/observer.fmu"), "Observer", OBSERVER);
    System {
        name: "round <trip> & \"back\"".into(),
        components: vec![
            component(
                "plant",
                dir.join("build/plant.fmu"),
                vec![
                    ("k", Value::Real(0.1 + 0.2)),
                    ("n", Value::Integer(i32::MIN)),
                    ("on", Value::Boolean(true)),
                    (
                        "mode",
                        Value::String("tab\there\nand 'quotes' \"too\" <&>".into()),
                    ),
                    ("state", Value::Real(-1e-300)),
                ],
            ),
            component(
                "observer",
                dir.join("build/observer.fmu"),
                vec![
                    ("gain", Value::Real(f64::INFINITY)),
                    ("choice", Value::Integer(2)),
                ],
            ),
            component("second observer", dir.join("build/observer.fmu"), vec![]),
        ],
        connections: vec![
            link(
                "plant.x",
                "observer.u",
                Some(Linear {
                    factor: 1.0 / 3.0,
                    offset: -273.15,
                }),
            ),
            link("observer.y", "plant.w", None),
            link("observer.count", "second observer.choice", None),
            link("plant.x", "second observer.u", None),
        ],
        experiment: Experiment {
            start: 0.25,
            stop: Some(12.5),
            step: None,
        },
    }
}

fn zip_names(path: &Path) -> Vec<String> {
    let zip = zip::ZipArchive::new(fs::File::open(path).unwrap()).unwrap();
    zip.file_names().map(|n| n.unwrap().to_string()).collect()
}

fn zip_text(path: &Path, name: &str) -> String {
    let mut zip = zip::ZipArchive::new(fs::File::open(path).unwrap()).unwrap();
    let mut text = String::new();
    zip.by_name(name)
        .unwrap()
        .read_to_string(&mut text)
        .unwrap();
    text
}

#[test]
fn write_then_read_gives_the_same_system() {
    let dir = tempfile::tempdir().unwrap();
    let system = round_trip_system(dir.path());
    let out = dir.path().join("out/model.ssp");
    fs::create_dir_all(out.parent().unwrap()).unwrap();
    ssp::write_ssp(&system, &out).unwrap();

    let mut names = zip_names(&out);
    names.sort();
    assert_eq!(
        names,
        [
            "SystemStructure.ssd",
            "resources/",
            "resources/observer.fmu",
            "resources/plant.fmu",
            "resources/second_observer.fmu"
        ]
    );
    // No temporary file left beside the output.
    assert_eq!(fs::read_dir(out.parent().unwrap()).unwrap().count(), 1);

    let ssd = zip_text(&out, "SystemStructure.ssd");
    for needle in [
        r#"<ssd:Component name="plant" type="application/x-fmu-sharedlibrary" source="resources/plant.fmu">"#,
        r#"<ssd:Connector name="x" kind="output"><ssc:Real/></ssd:Connector>"#,
        r#"<ssd:Connector name="n" kind="parameter"><ssc:Integer/></ssd:Connector>"#,
        r#"<ssd:Connector name="on" kind="parameter"><ssc:Boolean/></ssd:Connector>"#,
        r#"<ssd:Connector name="mode" kind="parameter"><ssc:String/></ssd:Connector>"#,
        r#"<ssd:Connector name="count" kind="output"><ssc:Integer/></ssd:Connector>"#,
        r#"<ssd:Connector name="choice" kind="parameter"/>"#,
        r#"<ssv:Parameter name="n"><ssv:Integer value="-2147483648"/></ssv:Parameter>"#,
        r#"<ssv:Parameter name="gain"><ssv:Real value="INF"/></ssv:Parameter>"#,
        r#"<ssc:LinearTransformation factor="0.3333333333333333" offset="-273.15"/>"#,
        r#"<ssd:DefaultExperiment startTime="0.25" stopTime="12.5"/>"#,
    ] {
        assert!(ssd.contains(needle), "missing {needle} in\n{ssd}");
    }
    // Connectors only for what connections and bindings use (a local needs none); an
    // enumeration's has no type element.
    for unused in ["label", "flag", "time", "state"] {
        assert!(
            !ssd.contains(&format!("<ssd:Connector name=\"{unused}\"")),
            "{unused} in\n{ssd}"
        );
    }
    assert_eq!(
        ssd.matches(r#"<ssd:Connector name="choice" kind="parameter"/>"#)
            .count(),
        2,
        "{ssd}"
    );
    assert_eq!(ssd.matches("<ssd:Connector ").count(), 6 + 5 + 2, "{ssd}");

    let loaded = ssp::read(&out).unwrap();
    let extracted = loaded.extracted_dir().unwrap().to_path_buf();
    let mut back = loaded.system.clone();
    for (c, file) in
        back.components
            .iter_mut()
            .zip(["plant.fmu", "observer.fmu", "second_observer.fmu"])
    {
        assert_eq!(c.source, extracted.join("resources").join(file));
        assert_eq!(
            fs::read(&c.source).unwrap(),
            fs::read(&system.component(&c.name).unwrap().source).unwrap()
        );
    }
    for (b, s) in back.components.iter_mut().zip(&system.components) {
        b.source = s.source.clone();
    }
    assert_eq!(back, system);
    // The extraction lives as long as the LoadedSystem.
    drop(loaded);
    assert!(!extracted.exists());
}

#[test]
fn to_ssd_works_without_fmus_and_keeps_the_step_in_the_annotations() {
    let system = System {
        name: "s".into(),
        components: vec![component("a", PathBuf::from("/x/a.fmu"), vec![])],
        connections: vec![],
        experiment: Experiment {
            start: 0.0,
            stop: None,
            step: Some(1e-3),
        },
    };
    let md = model_description_from(&[("y", "output", "Real")]);
    let ssd = ssp::to_ssd(&system, &|c| format!("fmus/{}.fmu", c.name), &|_| {
        Ok(md.clone())
    })
    .unwrap();
    assert!(ssd.contains(r#"source="fmus/a.fmu""#), "{ssd}");
    // SSP 1.0 has no step: it goes in the annotations libcosim and OMSimulator read.
    assert!(
        ssd.contains(r#"<ssd:DefaultExperiment startTime="0">"#),
        "{ssd}"
    );
    assert!(
        ssd.contains(r#"<osp:FixedStepAlgorithm baseStepSize="0.001"/>"#),
        "{ssd}"
    );
    assert!(ssd.contains(r#"stepSize="0.001""#), "{ssd}");
    assert!(!ssd.contains("<ssd:Connections"), "{ssd}");
    // And reads back (with the FMU where the source says).
    let dir = tempfile::tempdir().unwrap();
    fake_fmu(
        &dir.path().join("fmus/a.fmu"),
        "A",
        &[("y", "output", "Real")],
    );
    let back = ssp::parse_ssd(&ssd, dir.path()).unwrap();
    assert_eq!(
        back.experiment,
        Experiment {
            start: 0.0,
            stop: None,
            step: Some(1e-3)
        }
    );
    assert_eq!(back.components[0].name, "a");
}

fn model_description_from(variables: &[(&str, &str, &str)]) -> model_description::ModelDescription {
    model_description::ModelDescription::from_xml(&model_description("M", variables)).unwrap()
}

#[test]
fn the_writer_checks_against_the_model_descriptions() {
    let dir = tempfile::tempdir().unwrap();
    let base = round_trip_system(dir.path());
    let md = |c: &Component| {
        Ok(model_description_from(if c.name == "plant" {
            PLANT
        } else {
            OBSERVER
        }))
    };
    let src = |c: &Component| format!("resources/{}.fmu", c.name);
    let fails = |system: &System, needle: &str| {
        let err = ssp::to_ssd(system, &src, &md).unwrap_err();
        assert!(matches!(err, SspError::NotWritable { .. }), "{err:?}");
        assert!(
            err.to_string().contains(needle),
            "expected '{needle}' in: {err}"
        );
    };
    let mut s = base.clone();
    s.connections.push(link("plant.nope", "observer.u", None));
    fails(&s, "component 'plant'");
    fails(&s, "no variable 'nope'");
    let mut s = base.clone();
    s.connections.push(link("plant.x", "ghost.u", None));
    fails(&s, "'ghost'");
    let mut s = base.clone();
    s.components[0]
        .parameters
        .push(("k".into(), Value::Integer(1)));
    fails(
        &s,
        "parameter 'k' of component 'plant': a Integer value for a variable of type Real",
    );
    let mut s = base.clone();
    s.connections.push(link("plant.state", "observer.u", None));
    fails(&s, "causality local");
    let mut s = base.clone();
    s.connections.push(link("observer.u", "plant.x", None));
    fails(&s, "from an input to an output");
    let mut s = base.clone();
    s.components.push(s.components[0].clone());
    fails(&s, "two components are named 'plant'");
    // A source that is not an FMU: named with its component.
    let mut s = base;
    s.components[1].source = dir.path().join("build");
    let err = ssp::write_ssp(&s, &dir.path().join("x.ssp")).unwrap_err();
    assert!(err.to_string().contains("component 'observer'"), "{err}");
    assert!(!dir.path().join("x.ssp").exists());
}

fn write_zip(path: &Path, entries: &[(&str, &[u8])]) {
    let mut zip = zip::ZipWriter::new(fs::File::create(path).unwrap());
    for (name, bytes) in entries {
        zip.start_file(*name, zip::write::SimpleFileOptions::default())
            .unwrap();
        zip.write_all(bytes).unwrap();
    }
    zip.finish().unwrap();
}

#[test]
fn an_archive_with_a_parent_dir_entry_is_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let ssd = fs::read(data("two_fmus.ssd")).unwrap();
    for bad in ["../evil.fmu", "resources/../../evil.fmu", "/etc/evil.fmu"] {
        let path = dir.path().join("evil.ssp");
        write_zip(&path, &[("SystemStructure.ssd", &ssd), (bad, b"x")]);
        let err = ssp::read(&path).unwrap_err();
        match &err {
            SspError::UnsafeEntry { entry, .. } => assert_eq!(entry, bad),
            other => panic!("{other:?}"),
        }
        let text = err.to_string();
        assert!(text.contains(bad) && text.contains("evil.ssp"), "{text}");
    }
    assert!(!dir.path().parent().unwrap().join("evil.fmu").exists());
}

#[test]
fn archive_problems_name_the_archive() {
    let dir = tempfile::tempdir().unwrap();
    // No SystemStructure.ssd at the root.
    let path = dir.path().join("empty.ssp");
    write_zip(&path, &[("other/SystemStructure.ssd", b"<x/>")]);
    let err = ssp::read(&path).unwrap_err();
    assert!(
        matches!(err, SspError::Archive { .. }) && err.to_string().contains("empty.ssp"),
        "{err}"
    );
    // Not a zip.
    let path = dir.path().join("text.ssp");
    fs::write(&path, "hello").unwrap();
    let err = ssp::read(&path).unwrap_err();
    assert!(
        matches!(err, SspError::Archive { .. }) && err.to_string().contains("text.ssp"),
        "{err}"
    );
    // An error inside the archive's .ssd names archive and entry.
    let path = dir.path().join("bad.ssp");
    write_zip(&path, &[("SystemStructure.ssd", b"<ssd:SystemStructureDescription xmlns:ssd=\"x\" version=\"1.0\" name=\"n\">\n<ssd:System name=\"s\"><ssd:Elements><ssd:Component name=\"c\" source=\"../outside.fmu\"/></ssd:Elements></ssd:System></ssd:SystemStructureDescription>")]);
    let err = ssp::read(&path).unwrap_err();
    let text = err.to_string();
    assert!(
        text.contains("bad.ssp/SystemStructure.ssd")
            && text.contains("outside the .ssp archive")
            && text.contains("component 'c'"),
        "{text}"
    );
    assert_eq!(err.line_column(), Some((2, 60)));
}

#[test]
fn errors_can_cross_threads_and_go_into_anyhow() {
    fn check<T: Send + Sync + std::error::Error + 'static>() {}
    check::<SspError>();
    let err: anyhow::Error = SspError::NotWritable {
        message: "x".into(),
    }
    .into();
    assert!(err.to_string().contains('x'));
}
