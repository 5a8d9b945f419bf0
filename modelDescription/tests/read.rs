//! `from_xml` / `from_file`: third-party files, defaults, tolerance, and error locations.

mod common;

use model_description::*;

/// Written by hand after the Modelica Reference-FMUs' BouncingBall (FMI 2.0), with a few
/// things other tools add (VendorAnnotations, Annotations, SourceFiles, xmlns attributes).
const BOUNCING_BALL: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription
  xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
  fmiVersion="2.0"
  modelName="BouncingBall"
  description="This model calculates the trajectory, over time, of a ball dropped from a height of 1 m."
  guid="{1AE5E10D-9521-4DE3-80B9-D0EAAA7D5AF1}"
  generationTool="Reference FMUs (development build)"
  numberOfEventIndicators="1">

  <ModelExchange
    modelIdentifier="BouncingBall"
    canNotUseMemoryManagementFunctions="true"
    canGetAndSetFMUstate="true"
    canSerializeFMUstate="true">
    <SourceFiles>
      <File name="all.c"/>
    </SourceFiles>
  </ModelExchange>

  <CoSimulation
    modelIdentifier="BouncingBall"
    canHandleVariableCommunicationStepSize="true"
    canNotUseMemoryManagementFunctions="true"
    canGetAndSetFMUstate="true"
    canSerializeFMUstate="true">
    <SourceFiles>
      <File name="all.c"/>
    </SourceFiles>
  </CoSimulation>

  <UnitDefinitions>
    <Unit name="m">
      <BaseUnit m="1"/>
    </Unit>
    <Unit name="m/s">
      <BaseUnit m="1" s="-1"/>
    </Unit>
    <Unit name="m/s2">
      <BaseUnit m="1" s="-2"/>
    </Unit>
  </UnitDefinitions>

  <TypeDefinitions>
    <SimpleType name="Position">
      <Real quantity="Position" unit="m"/>
    </SimpleType>
    <SimpleType name="Velocity">
      <Real quantity="Velocity" unit="m/s"/>
    </SimpleType>
    <SimpleType name="Acceleration">
      <Real quantity="Acceleration" unit="m/s2"/>
    </SimpleType>
  </TypeDefinitions>

  <LogCategories>
    <Category name="logEvents" description="Log events"/>
    <Category name="logStatusError" description="Log error messages"/>
  </LogCategories>

  <DefaultExperiment startTime="0" stopTime="3" stepSize="1e-2"/>

  <VendorAnnotations>
    <Tool name="SomeTool"><Anything goes="here"/></Tool>
  </VendorAnnotations>

  <ModelVariables>
    <ScalarVariable name="time" valueReference="0" causality="independent" variability="continuous" description="Simulation time">
      <Real/>
    </ScalarVariable>
    <ScalarVariable name="h" valueReference="1" description="Position of the ball" causality="output" variability="continuous" initial="exact">
      <Real start="1" declaredType="Position"/>
    </ScalarVariable>
    <ScalarVariable name="der(h)" valueReference="2" description="Derivative of h" causality="local" variability="continuous" initial="calculated">
      <Real derivative="2" declaredType="Velocity"/>
    </ScalarVariable>
    <ScalarVariable name="v" valueReference="3" description="Velocity of the ball" causality="output" variability="continuous" initial="exact">
      <Real start="0" reinit="true" declaredType="Velocity"/>
      <Annotations>
        <Tool name="SomeTool"><Extra/></Tool>
      </Annotations>
    </ScalarVariable>
    <ScalarVariable name="der(v)" valueReference="4" description="Derivative of v" causality="local" variability="continuous" initial="calculated">
      <Real derivative="4" declaredType="Acceleration"/>
    </ScalarVariable>
    <ScalarVariable name="g" valueReference="5" description="Gravity acting on the ball" causality="parameter" variability="fixed" initial="exact">
      <Real start="-9.81" declaredType="Acceleration"/>
    </ScalarVariable>
    <ScalarVariable name="e" valueReference="6" description="Coefficient of restitution" causality="parameter" variability="tunable" initial="exact">
      <Real start="0.7" min="0.5" max="1"/>
    </ScalarVariable>
    <ScalarVariable name="v_min" valueReference="7" description="Velocity below which the ball stops bouncing" variability="constant" initial="exact">
      <Real start="0.1" declaredType="Velocity"/>
    </ScalarVariable>
  </ModelVariables>

  <ModelStructure>
    <Outputs>
      <Unknown index="2"/>
      <Unknown index="4"/>
    </Outputs>
    <Derivatives>
      <Unknown index="3"/>
      <Unknown index="5"/>
    </Derivatives>
    <InitialUnknowns>
      <Unknown index="3"/>
      <Unknown index="5"/>
    </InitialUnknowns>
  </ModelStructure>

</fmiModelDescription>
"#;

#[test]
fn reads_the_reference_bouncing_ball() {
    let md = ModelDescription::from_xml(BOUNCING_BALL).unwrap();
    assert_eq!(md.fmi_version, "2.0");
    assert_eq!(md.model_name, "BouncingBall");
    assert_eq!(md.guid, "{1AE5E10D-9521-4DE3-80B9-D0EAAA7D5AF1}");
    assert_eq!(
        md.generation_tool.as_deref(),
        Some("Reference FMUs (development build)")
    );
    assert_eq!(md.number_of_event_indicators, Some(1));
    assert_eq!(md.author, None);
    assert_eq!(
        md.model_exchange_identifier.as_deref(),
        Some("BouncingBall")
    );
    let cs = md.co_simulation.as_ref().unwrap();
    assert_eq!(
        *cs,
        CoSimulation {
            model_identifier: "BouncingBall".into(),
            can_handle_variable_communication_step_size: true,
            can_not_use_memory_management_functions: true,
            can_get_and_set_fmu_state: true,
            can_serialize_fmu_state: true,
            ..CoSimulation::default()
        }
    );
    assert_eq!(md.unit_definitions.len(), 3);
    assert_eq!(md.unit_definitions[1].name, "m/s");
    assert_eq!(
        md.unit_definitions[1].base_unit,
        Some(BaseUnit {
            m: 1,
            s: -1,
            ..BaseUnit::default()
        })
    );
    assert_eq!(md.type_definitions.len(), 3);
    assert_eq!(md.type_definitions[2].name, "Acceleration");
    assert_eq!(md.type_definitions[2].base_type, "Real");
    assert_eq!(
        md.type_definitions[2].quantity.as_deref(),
        Some("Acceleration")
    );
    assert_eq!(md.type_definitions[2].unit.as_deref(), Some("m/s2"));
    assert_eq!(
        md.log_categories[1],
        Category {
            name: "logStatusError".into(),
            description: Some("Log error messages".into())
        }
    );
    assert_eq!(
        md.default_experiment,
        Some(DefaultExperiment {
            start_time: Some(0.0),
            stop_time: Some(3.0),
            tolerance: None,
            step_size: Some(0.01)
        })
    );

    assert_eq!(md.model_variables.len(), 8);
    let time = &md.model_variables[0];
    assert_eq!(
        (time.causality, time.variability, time.initial),
        (Causality::Independent, Variability::Continuous, None)
    );
    let der_h = md.variable("der(h)").unwrap();
    let VariableKind::Real(r) = &der_h.kind else {
        panic!("{der_h:?}")
    };
    assert_eq!(r.derivative, Some(2));
    assert_eq!(r.declared_type.as_deref(), Some("Velocity"));
    let v = md.variable("v").unwrap();
    assert_eq!(
        v.kind,
        VariableKind::Real(RealAttributes {
            declared_type: Some("Velocity".into()),
            start: Some(0.0),
            reinit: Some(true),
            ..Default::default()
        })
    );
    let e = md.variable("e").unwrap();
    assert_eq!(
        (e.causality, e.variability, e.initial),
        (
            Causality::Parameter,
            Variability::Tunable,
            Some(Initial::Exact)
        )
    );
    let VariableKind::Real(r) = &e.kind else {
        panic!()
    };
    assert_eq!((r.start, r.min, r.max), (Some(0.7), Some(0.5), Some(1.0)));
    // v_min has no causality attribute: the default is local.
    let v_min = md.variable("v_min").unwrap();
    assert_eq!(
        (v_min.causality, v_min.variability),
        (Causality::Local, Variability::Constant)
    );
    assert_eq!(md.variable_index("v_min"), Some(8));

    let ms = &md.model_structure;
    let indices = |l: &[Unknown]| l.iter().map(|u| u.index).collect::<Vec<_>>();
    assert_eq!(indices(&ms.outputs), [2, 4]);
    assert_eq!(indices(&ms.derivatives), [3, 5]);
    assert_eq!(indices(&ms.initial_unknowns), [3, 5]);
    assert!(
        ms.outputs
            .iter()
            .all(|u| u.dependencies.is_none() && u.dependencies_kind.is_none())
    );

    // A correct third-party file passes validation, including the state/derivative rule
    // for InitialUnknowns.
    assert_eq!(md.validate(), vec![]);
    // What we write from it reads back the same.
    assert_eq!(ModelDescription::from_xml(&md.to_xml()).unwrap(), md);
}

#[test]
fn reads_a_minimal_dahlquist_and_fills_defaults() {
    let xml = r#"<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="2.0" modelName="Dahlquist" guid="{221063D2-EF4A-45FE-B954-B5BFEEA9A59B}">
  <CoSimulation modelIdentifier="Dahlquist"/>
  <DefaultExperiment startTime="0" stopTime="10" stepSize="0.1"/>
  <ModelVariables>
    <ScalarVariable name="time" valueReference="0" causality="independent"><Real/></ScalarVariable>
    <ScalarVariable name="x" valueReference="1" causality="output" initial="exact"><Real start="1"/></ScalarVariable>
    <ScalarVariable name="der(x)" valueReference="2"><Real derivative="2"/></ScalarVariable>
    <ScalarVariable name="k" valueReference="3" causality="parameter" variability="fixed"><Real start="1"/></ScalarVariable>
  </ModelVariables>
  <ModelStructure>
    <Outputs><Unknown index="2" dependencies=""/></Outputs>
    <Derivatives><Unknown index="3" dependencies="2 4" dependenciesKind="dependent  dependent"/></Derivatives>
    <InitialUnknowns><Unknown index="3"/></InitialUnknowns>
  </ModelStructure>
</fmiModelDescription>"#;
    let md = ModelDescription::from_xml(xml).unwrap();
    let cs = md.co_simulation.as_ref().unwrap();
    assert_eq!(
        *cs,
        CoSimulation {
            model_identifier: "Dahlquist".into(),
            ..CoSimulation::default()
        }
    );
    let der = md.variable("der(x)").unwrap();
    assert_eq!(
        (der.causality, der.variability, der.initial),
        (Causality::Local, Variability::Continuous, None)
    );
    assert_eq!(der.effective_initial(), Some(Initial::Calculated));
    assert_eq!(md.model_structure.outputs[0].dependencies, Some(vec![]));
    assert_eq!(
        md.model_structure.derivatives[0].dependencies,
        Some(vec![2, 4])
    );
    assert_eq!(
        md.model_structure.derivatives[0].dependencies_kind,
        Some(vec!["dependent".to_string(), "dependent".to_string()])
    );
    assert_eq!(md.validate(), vec![]);
}

#[test]
fn accepts_schema_spellings_of_booleans_and_numbers() {
    let xml = r#"<fmiModelDescription fmiVersion="2.0" modelName="m" guid="g">
  <CoSimulation modelIdentifier="m" canInterpolateInputs="1" needsExecutionTool="0"/>
  <ModelVariables>
    <ScalarVariable name="a" valueReference=" 7 " causality="parameter" variability="fixed">
      <Real start=" 1E3 " min="-INF" max="INF" relativeQuantity="false"/>
    </ScalarVariable>
  </ModelVariables>
</fmiModelDescription>"#;
    let md = ModelDescription::from_xml(xml).unwrap();
    let cs = md.co_simulation.as_ref().unwrap();
    assert!(cs.can_interpolate_inputs && !cs.needs_execution_tool);
    let a = &md.model_variables[0];
    assert_eq!(a.value_reference, 7);
    let VariableKind::Real(r) = &a.kind else {
        panic!()
    };
    assert_eq!(
        (r.start, r.min, r.max),
        (Some(1000.0), Some(f64::NEG_INFINITY), Some(f64::INFINITY))
    );
    assert_eq!(r.relative_quantity, Some(false));
    assert_eq!(
        md.model_structure,
        ModelStructure::default(),
        "a missing ModelStructure reads as empty"
    );
}

#[test]
fn a_byte_order_mark_is_skipped() {
    let xml = format!("\u{feff}{}", BOUNCING_BALL);
    assert_eq!(
        ModelDescription::from_xml(&xml).unwrap().model_name,
        "BouncingBall"
    );
}

// ---- errors ------------------------------------------------------------------------------

fn break_line(line: usize, from: &str, to: &str) -> String {
    let mut lines: Vec<String> = BOUNCING_BALL.lines().map(str::to_string).collect();
    assert!(
        lines[line - 1].contains(from),
        "line {line} is {:?}",
        lines[line - 1]
    );
    lines[line - 1] = lines[line - 1].replacen(from, to, 1);
    lines.join("\n")
}

/// The 1-based line of the first line containing `needle`.
fn line_of(needle: &str) -> usize {
    BOUNCING_BALL
        .lines()
        .position(|l| l.contains(needle))
        .unwrap()
        + 1
}

#[test]
fn mismatched_end_tag_reports_line_and_column() {
    let line = line_of("<Real start=\"-9.81\"") + 1;
    let xml = break_line(line, "</ScalarVariable>", "</ScalarVariabel>");
    let err = ModelDescription::from_xml(&xml).unwrap_err();
    let ParseError::Xml {
        line: l,
        column,
        message,
    } = &err
    else {
        panic!("{err:?}")
    };
    assert_eq!((*l, *column), (line, 5), "{err}");
    assert!(message.contains("ScalarVariabel"), "{message}");
    assert!(
        err.to_string()
            .starts_with(&format!("malformed XML at line {line}, column 5:")),
        "{err}"
    );
}

#[test]
fn unquoted_attribute_reports_line_and_column() {
    // `    <ScalarVariable name="h" valueReference=1 ...`: 4 spaces, `<ScalarVariable` ends at
    // column 19, ` name="h"` at 28, ` valueReference=` at 44, so the value is at column 45.
    let line = line_of("name=\"h\"");
    let xml = break_line(line, "valueReference=\"1\"", "valueReference=1");
    let err = ModelDescription::from_xml(&xml).unwrap_err();
    assert_eq!(err.line_column(), Some((line, 45)), "{err}");
    assert!(matches!(err, ParseError::Xml { .. }), "{err:?}");
}

#[test]
fn unclosed_element_reports_where_it_was_opened() {
    let xml = "<?xml version=\"1.0\"?>\n<fmiModelDescription fmiVersion=\"2.0\" modelName=\"m\" guid=\"g\">\n  <ModelVariables>\n";
    let err = ModelDescription::from_xml(xml).unwrap_err();
    assert_eq!(err.line_column(), Some((3, 3)), "{err}");
    assert!(
        err.to_string().contains("<ModelVariables> is never closed"),
        "{err}"
    );
}

#[test]
fn truncated_tag_reports_its_start() {
    let xml = "<fmiModelDescription fmiVersion=\"2.0\" modelName=\"m\" guid=\"g\">\n  <ModelVariables>\n    <ScalarVariable name=\"x";
    let err = ModelDescription::from_xml(xml).unwrap_err();
    assert_eq!(err.line_column(), Some((3, 5)), "{err}");
}

#[test]
fn missing_name_names_the_element() {
    let line = line_of("name=\"g\"");
    let xml = break_line(line, "name=\"g\" ", "");
    let err = ModelDescription::from_xml(&xml).unwrap_err();
    match &err {
        ParseError::MissingAttribute {
            line: l,
            column,
            element,
            attribute,
            variable,
        } => {
            assert_eq!((*l, *column), (line, 5));
            assert_eq!(element, "ScalarVariable");
            assert_eq!(*attribute, "name");
            assert_eq!(*variable, None);
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(
        err.to_string(),
        format!(
            "line {line}, column 5: <ScalarVariable> has no 'name' attribute, which is required"
        )
    );

    // Elsewhere: a Unit without a name, and a Category.
    let err = ModelDescription::from_xml(&break_line(
        line_of("<Unit name=\"m/s\""),
        "name=\"m/s\"",
        "",
    ))
    .unwrap_err();
    assert!(
        err.to_string().contains("<Unit> has no 'name' attribute"),
        "{err}"
    );
    let err =
        ModelDescription::from_xml(&break_line(line_of("logEvents"), "name=\"logEvents\"", ""))
            .unwrap_err();
    assert!(
        err.to_string()
            .contains("<Category> has no 'name' attribute"),
        "{err}"
    );
}

#[test]
fn missing_attribute_inside_a_variable_names_the_variable() {
    let line = line_of("name=\"g\"");
    let xml = break_line(line, "valueReference=\"5\" ", "");
    let err = ModelDescription::from_xml(&xml).unwrap_err();
    assert_eq!(
        err.to_string(),
        format!(
            "line {line}, column 5: <ScalarVariable> (variable 'g') has no 'valueReference' attribute, which is required"
        )
    );
    let xml = BOUNCING_BALL.replace("<fmiModelDescription\n  xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\"\n  fmiVersion=\"2.0\"", "<fmiModelDescription");
    let err = ModelDescription::from_xml(&xml).unwrap_err();
    assert!(
        matches!(&err, ParseError::MissingAttribute { element, attribute, .. } if element == "fmiModelDescription" && *attribute == "fmiVersion"),
        "{err:?}"
    );
}

#[test]
fn bad_numbers_name_attribute_and_value() {
    let line = line_of("<Real start=\"-9.81\"");
    let xml = break_line(line, "start=\"-9.81\"", "start=\"-9,81\"");
    let err = ModelDescription::from_xml(&xml).unwrap_err();
    match &err {
        ParseError::InvalidValue {
            line: l,
            column,
            element,
            attribute,
            value,
            variable,
            ..
        } => {
            assert_eq!((*l, *column), (line, 13), "points at the attribute");
            assert_eq!(
                (element.as_str(), *attribute, value.as_str()),
                ("Real", "start", "-9,81")
            );
            assert_eq!(variable.as_deref(), Some("g"));
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(
        err.to_string(),
        format!(
            "line {line}, column 13: attribute 'start' of <Real> (variable 'g') is \"-9,81\", expected a floating-point number"
        )
    );

    let err = ModelDescription::from_xml(
        &BOUNCING_BALL.replace("valueReference=\"6\"", "valueReference=\"-6\""),
    )
    .unwrap_err();
    assert!(err.to_string().contains("attribute 'valueReference' of <ScalarVariable> (variable 'e') is \"-6\", expected a non-negative 32-bit integer"), "{err}");
    let err = ModelDescription::from_xml(
        &BOUNCING_BALL.replace("<Unknown index=\"4\"/>", "<Unknown index=\"four\"/>"),
    )
    .unwrap_err();
    assert!(
        err.to_string()
            .contains("attribute 'index' of <Unknown> is \"four\""),
        "{err}"
    );
    let err = ModelDescription::from_xml(&BOUNCING_BALL.replace(
        "<Unknown index=\"3\"/>\n      <Unknown index=\"5\"/>\n    </Derivatives>",
        "<Unknown index=\"3\" dependencies=\"1 x\"/>\n    </Derivatives>",
    ))
    .unwrap_err();
    assert!(
        err.to_string()
            .contains("attribute 'dependencies' of <Unknown> is \"1 x\""),
        "{err}"
    );
    let err = ModelDescription::from_xml(&BOUNCING_BALL.replace(
        "causality=\"parameter\" variability=\"tunable\"",
        "causality=\"parameter\" variability=\"Tunable\"",
    ))
    .unwrap_err();
    assert!(err.to_string().contains("attribute 'variability' of <ScalarVariable> (variable 'e') is \"Tunable\", expected one of constant, fixed, tunable, discrete, continuous"), "{err}");
    let err =
        ModelDescription::from_xml(&BOUNCING_BALL.replace("reinit=\"true\"", "reinit=\"yes\""))
            .unwrap_err();
    assert!(
        err.to_string().contains(
            "attribute 'reinit' of <Real> (variable 'v') is \"yes\", expected true or false"
        ),
        "{err}"
    );
    let err = ModelDescription::from_xml(&BOUNCING_BALL.replace(
        "<BaseUnit m=\"1\" s=\"-2\"/>",
        "<BaseUnit m=\"1\" s=\"-2.5\"/>",
    ))
    .unwrap_err();
    assert!(
        err.to_string()
            .contains("attribute 's' of <BaseUnit> is \"-2.5\", expected a 32-bit integer"),
        "{err}"
    );
}

#[test]
fn a_variable_without_a_type_element_is_an_error() {
    let xml = BOUNCING_BALL.replace(
        "<Real start=\"0.7\" min=\"0.5\" max=\"1\"/>",
        "<Annotations/>",
    );
    let err = ModelDescription::from_xml(&xml).unwrap_err();
    assert!(err.to_string().contains("<ScalarVariable> (variable 'e') has no Real, Integer, Boolean, String or Enumeration element"), "{err}");
}

#[test]
fn wrong_root_element() {
    let err = ModelDescription::from_xml(
        "<?xml version=\"1.0\"?>\n<fmiModelDescriptio fmiVersion=\"2.0\"/>",
    )
    .unwrap_err();
    assert!(
        matches!(&err, ParseError::NotModelDescription { line: 2, column: 1, found } if found == "fmiModelDescriptio"),
        "{err:?}"
    );
    let err = ModelDescription::from_xml("").unwrap_err();
    assert!(err.to_string().contains("no root element"), "{err}");
}

#[test]
fn from_file_names_the_path() {
    let dir = std::env::temp_dir().join(format!("model-description-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();

    let good = dir.join("good.xml");
    std::fs::write(&good, BOUNCING_BALL).unwrap();
    assert_eq!(
        ModelDescription::from_file(&good).unwrap(),
        ModelDescription::from_xml(BOUNCING_BALL).unwrap()
    );

    let bad = dir.join("bad.xml");
    std::fs::write(
        &bad,
        BOUNCING_BALL.replace("<Real start=\"0.7\"", "<Real start=\"0.7.1\""),
    )
    .unwrap();
    let err = ModelDescription::from_file(&bad).unwrap_err();
    let text = err.to_string();
    assert!(
        text.starts_with(&format!(
            "{}: line {}, column",
            bad.display(),
            line_of("<Real start=\"0.7\"")
        )),
        "{text}"
    );
    assert!(text.contains("\"0.7.1\""), "{text}");
    assert_eq!(
        err.line_column().map(|(l, _)| l),
        Some(line_of("<Real start=\"0.7\""))
    );

    let missing = dir.join("missing.xml");
    let err = ModelDescription::from_file(&missing).unwrap_err();
    assert!(matches!(err, ParseError::Io { .. }), "{err:?}");
    assert!(
        err.to_string()
            .starts_with(&format!("cannot read {}:", missing.display())),
        "{err}"
    );
    assert!(std::error::Error::source(&err).is_some());

    std::fs::remove_dir_all(&dir).unwrap();
}
