//! `to_xml`: exact round trip, element order, omitted empty lists and defaults.

mod common;

use common::*;
use model_description::*;

const AWKWARD: [f64; 6] = [1e-20, 0.1, 1e300, -0.0, 5e-324, 123456789.123];
const NASTY: &str = "a <b> & \"c\" 'd'\nline two\ttab\r";

/// A description that sets every field of every type (validity is beside the point here).
fn everything() -> ModelDescription {
    let mut md = valid();
    md.description = Some(NASTY.into());
    md.author = Some("A. <Author> & Co".into());
    md.version = Some("1.2.3".into());
    md.copyright = Some("\u{a9} 2026 'us'".into());
    md.license = Some("MIT OR Apache-2.0".into());
    md.generation_tool = Some("xtask \"fmu\"".into());
    md.generation_date_and_time = Some("2026-01-02T03:04:05Z".into());
    md.variable_naming_convention = Some("structured".into());
    md.number_of_event_indicators = Some(3);
    md.model_exchange_identifier = Some("me_id".into());
    md.co_simulation = Some(CoSimulation {
        model_identifier: "cs_id".into(),
        needs_execution_tool: true,
        can_handle_variable_communication_step_size: true,
        can_interpolate_inputs: true,
        max_output_derivative_order: 2,
        can_run_asynchronuously: true,
        can_be_instantiated_only_once_per_process: true,
        can_not_use_memory_management_functions: true,
        can_get_and_set_fmu_state: true,
        can_serialize_fmu_state: true,
        provides_directional_derivative: true,
    });
    md.unit_definitions = vec![
        Unit {
            name: "weird<&>".into(),
            base_unit: Some(BaseUnit {
                kg: 1,
                m: -2,
                s: 3,
                a: -4,
                k: 5,
                mol: -6,
                cd: 7,
                rad: -8,
                factor: 1e-20,
                offset: -0.0,
            }),
            display_units: vec![
                DisplayUnit {
                    name: "d1".into(),
                    factor: 1e300,
                    offset: 5e-324,
                },
                DisplayUnit {
                    name: "d2".into(),
                    factor: 1.0,
                    offset: 0.0,
                },
            ],
        },
        Unit {
            name: "bare".into(),
            base_unit: None,
            display_units: vec![],
        },
        Unit {
            name: "only_base".into(),
            base_unit: Some(BaseUnit::default()),
            display_units: vec![],
        },
    ];
    md.type_definitions = vec![
        SimpleType {
            name: "Len".into(),
            description: Some(NASTY.into()),
            base_type: "Real".into(),
            quantity: Some("Length".into()),
            unit: Some("weird<&>".into()),
            display_unit: Some("d1".into()),
            items: vec![],
        },
        SimpleType {
            name: "Mode".into(),
            description: None,
            base_type: "Enumeration".into(),
            quantity: Some("q".into()),
            unit: None,
            display_unit: None,
            items: vec![
                ("neg".into(), -5),
                ("big".into(), i32::MAX),
                ("<&>".into(), 0),
            ],
        },
        SimpleType {
            name: "I".into(),
            description: None,
            base_type: "Integer".into(),
            quantity: None,
            unit: None,
            display_unit: None,
            items: vec![],
        },
        SimpleType {
            name: "B".into(),
            description: None,
            base_type: "Boolean".into(),
            quantity: None,
            unit: None,
            display_unit: None,
            items: vec![],
        },
        SimpleType {
            name: "S".into(),
            description: None,
            base_type: "String".into(),
            quantity: None,
            unit: None,
            display_unit: None,
            items: vec![],
        },
    ];
    md.log_categories = vec![
        Category {
            name: "a".into(),
            description: Some(NASTY.into()),
        },
        Category {
            name: "b".into(),
            description: None,
        },
    ];
    md.default_experiment = Some(DefaultExperiment {
        start_time: Some(-0.0),
        stop_time: Some(1e300),
        tolerance: Some(1e-20),
        step_size: Some(0.1),
    });

    let mut full_real = real(
        "full<&\"'>",
        100,
        Causality::Local,
        Variability::Continuous,
        Some(-0.0),
    );
    full_real.description = Some(NASTY.into());
    full_real.initial = Some(Initial::Approx);
    full_real.can_handle_multiple_set_per_time_instant = Some(false);
    full_real.kind = VariableKind::Real(RealAttributes {
        declared_type: Some("Len".into()),
        quantity: Some("Length".into()),
        unit: Some("weird<&>".into()),
        display_unit: Some("d1".into()),
        relative_quantity: Some(true),
        min: Some(5e-324),
        max: Some(1e300),
        nominal: Some(123456789.123),
        unbounded: Some(false),
        start: Some(-0.0),
        derivative: Some(1),
        reinit: Some(true),
    });
    md.model_variables.push(full_real);
    for (i, x) in AWKWARD.iter().enumerate() {
        md.model_variables.push(real(
            &format!("awkward{i}"),
            200 + i as u32,
            Causality::Parameter,
            Variability::Tunable,
            Some(*x),
        ));
    }
    md.model_variables.push(ScalarVariable {
        kind: VariableKind::Integer(IntegerAttributes {
            declared_type: Some("I".into()),
            quantity: Some("count".into()),
            min: Some(i32::MIN),
            max: Some(i32::MAX),
            start: Some(-7),
        }),
        can_handle_multiple_set_per_time_instant: Some(true),
        ..integer(
            "int",
            u32::MAX,
            Causality::Output,
            Variability::Discrete,
            None,
        )
    });
    md.model_variables.push(ScalarVariable {
        kind: VariableKind::Enumeration(IntegerAttributes {
            declared_type: Some("Mode".into()),
            quantity: Some("q".into()),
            min: Some(-5),
            max: Some(0),
            start: Some(-5),
        }),
        ..integer("enum", 300, Causality::Input, Variability::Discrete, None)
    });
    md.model_variables.push(ScalarVariable {
        kind: VariableKind::Boolean {
            declared_type: Some("B".into()),
            start: Some(false),
        },
        ..integer("bool", 301, Causality::Parameter, Variability::Fixed, None)
    });
    md.model_variables.push(ScalarVariable {
        kind: VariableKind::String {
            declared_type: Some("S".into()),
            start: Some(NASTY.into()),
        },
        ..integer(
            "string",
            302,
            Causality::Parameter,
            Variability::Fixed,
            None,
        )
    });
    md.model_variables.push(ScalarVariable {
        kind: VariableKind::String {
            declared_type: None,
            start: Some(String::new()),
        },
        initial: Some(Initial::Calculated),
        ..integer(
            "empty string",
            303,
            Causality::CalculatedParameter,
            Variability::Tunable,
            None,
        )
    });
    md.model_structure = ModelStructure {
        outputs: vec![
            Unknown {
                index: 4,
                dependencies: Some(vec![]),
                dependencies_kind: None,
            },
            Unknown {
                index: 5,
                dependencies: Some(vec![1, 2, 11]),
                dependencies_kind: Some(vec![
                    "dependent".into(),
                    "fixed".into(),
                    "constant".into(),
                ]),
            },
            Unknown {
                index: 6,
                dependencies: None,
                dependencies_kind: None,
            },
        ],
        derivatives: vec![Unknown {
            index: 12,
            dependencies: Some(vec![2]),
            dependencies_kind: Some(vec!["discrete".into()]),
        }],
        initial_unknowns: vec![Unknown {
            index: 4,
            dependencies: Some(vec![]),
            dependencies_kind: Some(vec![]),
        }],
    };
    md
}

#[test]
fn round_trip_keeps_every_field() {
    let md = everything();
    let xml = md.to_xml();
    let back = ModelDescription::from_xml(&xml).unwrap_or_else(|e| panic!("{e}\n{xml}"));
    assert_eq!(back, md, "\n{xml}");
    // PartialEq treats -0.0 == 0.0 and cannot see the bits; check the awkward values exactly.
    for (i, x) in AWKWARD.iter().enumerate() {
        let v = back.variable(&format!("awkward{i}")).unwrap();
        let VariableKind::Real(r) = &v.kind else {
            panic!()
        };
        assert_eq!(
            r.start.unwrap().to_bits(),
            x.to_bits(),
            "awkward{i} = {x:?}"
        );
    }
    let VariableKind::Real(r) = &back.variable("full<&\"'>").unwrap().kind else {
        panic!()
    };
    assert!(
        r.start.unwrap().is_sign_negative(),
        "-0.0 start lost its sign"
    );
    assert_eq!(r.min.unwrap().to_bits(), 5e-324f64.to_bits());
    let base = back.unit_definitions[0].base_unit.as_ref().unwrap();
    assert!(
        base.offset == 0.0 && base.offset.is_sign_negative(),
        "BaseUnit offset -0.0 must be written"
    );
    assert_eq!(
        back.default_experiment
            .as_ref()
            .unwrap()
            .start_time
            .unwrap()
            .to_bits(),
        (-0.0f64).to_bits()
    );
    // Writing again gives the same text.
    assert_eq!(back.to_xml(), xml);
}

#[test]
fn floats_are_short_and_exact_in_the_text() {
    let xml = everything().to_xml();
    for expected in [
        "start=\"1e-20\"",
        "start=\"0.1\"",
        "start=\"1e300\"",
        "start=\"-0\"",
        "start=\"5e-324\"",
        "start=\"123456789.123\"",
    ] {
        assert!(xml.contains(expected), "missing {expected}");
    }
    // No number is written with a long tail of digits.
    let numbers: Vec<&str> = xml
        .split('"')
        .skip(1)
        .step_by(2)
        .filter(|v| v.parse::<f64>().is_ok())
        .collect();
    assert!(numbers.len() > 40, "{numbers:?}");
    for value in numbers {
        assert!(value.len() <= 24, "long number {value}");
    }
}

#[test]
fn strings_are_escaped() {
    let xml = everything().to_xml();
    assert!(
        xml.contains(
            "description=\"a &lt;b&gt; &amp; &quot;c&quot; &apos;d&apos;&#10;line two&#9;tab&#13;\""
        ),
        "{xml}"
    );
    assert!(xml.contains("name=\"full&lt;&amp;&quot;&apos;&gt;\""));
}

#[test]
fn header_root_and_element_order() {
    let xml = everything().to_xml();
    assert!(xml.starts_with("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<fmiModelDescription fmiVersion=\"2.0\" modelName=\"Test\" guid=\""));
    assert_eq!(
        top_level_elements(&xml),
        [
            "ModelExchange",
            "CoSimulation",
            "UnitDefinitions",
            "TypeDefinitions",
            "LogCategories",
            "DefaultExperiment",
            "ModelVariables",
            "ModelStructure"
        ]
    );
    // Inside ModelStructure: Outputs, Derivatives, InitialUnknowns.
    let o = xml.find("<Outputs>").unwrap();
    let d = xml.find("<Derivatives>").unwrap();
    let i = xml.find("<InitialUnknowns>").unwrap();
    assert!(o < d && d < i);
    // Index comments map the 1-based indices.
    assert!(xml.contains("<!-- index 1 -->\n    <ScalarVariable name=\"time\""));
    assert!(xml.contains("<!-- index 12 -->\n    <ScalarVariable name=\"full&lt;"));
}

#[test]
fn empty_lists_and_default_flags_are_not_written() {
    let mut md = valid();
    md.unit_definitions.clear();
    md.type_definitions.clear();
    md.log_categories.clear();
    md.default_experiment = None;
    md.model_structure.initial_unknowns.clear();
    md.co_simulation = Some(CoSimulation {
        model_identifier: "m".into(),
        ..CoSimulation::default()
    });
    let xml = md.to_xml();
    assert_eq!(
        top_level_elements(&xml),
        ["CoSimulation", "ModelVariables", "ModelStructure"]
    );
    for absent in [
        "UnitDefinitions",
        "TypeDefinitions",
        "LogCategories",
        "InitialUnknowns",
        "Derivatives",
        "DefaultExperiment",
        "ModelExchange",
    ] {
        assert!(!xml.contains(absent), "{absent} written:\n{xml}");
    }
    assert!(
        xml.contains("  <CoSimulation modelIdentifier=\"m\"/>\n"),
        "flags at their default are omitted:\n{xml}"
    );
    assert!(!xml.contains("maxOutputDerivativeOrder"));
    assert_eq!(ModelDescription::from_xml(&xml).unwrap(), md);

    md.model_structure = ModelStructure::default();
    md.model_variables.clear();
    let xml = md.to_xml();
    assert!(xml.contains("  <ModelVariables/>\n"), "{xml}");
    assert!(xml.contains("  <ModelStructure/>\n"), "{xml}");
    assert!(!xml.contains("<Outputs"));
    assert_eq!(ModelDescription::from_xml(&xml).unwrap(), md);
}

#[test]
fn dependencies_attribute_forms() {
    let xml = everything().to_xml();
    assert!(
        xml.contains("<Unknown index=\"4\" dependencies=\"\"/>"),
        "Some(vec![]) writes dependencies=\"\""
    );
    assert!(xml.contains("<Unknown index=\"5\" dependencies=\"1 2 11\" dependenciesKind=\"dependent fixed constant\"/>"));
    assert!(
        xml.contains("<Unknown index=\"6\"/>"),
        "None writes no attribute"
    );
}

#[test]
fn valid_description_is_written_as_our_fmus_need() {
    let xml = valid().to_xml();
    assert!(xml.contains(
        "<CoSimulation modelIdentifier=\"test_fmu\" canHandleVariableCommunicationStepSize=\"true\" canNotUseMemoryManagementFunctions=\"true\" canGetAndSetFMUstate=\"true\" canSerializeFMUstate=\"true\"/>"
    ), "{xml}");
    assert!(xml.contains(
        "    <ScalarVariable name=\"u\" valueReference=\"1\" causality=\"input\" variability=\"continuous\">\n      <Real unit=\"m\" start=\"0\"/>\n    </ScalarVariable>\n"
    ), "{xml}");
    assert!(xml.contains("<Boolean start=\"true\"/>"));
    assert!(xml.contains("<BaseUnit m=\"1\"/>"));
    assert!(xml.contains("<DisplayUnit name=\"mm\" factor=\"0.001\"/>"));
    assert!(
        ModelDescription::from_xml(&xml)
            .unwrap()
            .validate()
            .is_empty()
    );
}
