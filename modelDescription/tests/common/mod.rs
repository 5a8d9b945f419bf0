//! Builders shared by the integration tests.
#![allow(dead_code)]

use model_description::*;

pub fn real(
    name: &str,
    vr: u32,
    causality: Causality,
    variability: Variability,
    start: Option<f64>,
) -> ScalarVariable {
    ScalarVariable {
        name: name.into(),
        value_reference: vr,
        description: None,
        causality,
        variability,
        initial: None,
        can_handle_multiple_set_per_time_instant: None,
        kind: VariableKind::Real(RealAttributes {
            start,
            ..RealAttributes::default()
        }),
    }
}

pub fn integer(
    name: &str,
    vr: u32,
    causality: Causality,
    variability: Variability,
    start: Option<i32>,
) -> ScalarVariable {
    ScalarVariable {
        kind: VariableKind::Integer(IntegerAttributes {
            start,
            ..IntegerAttributes::default()
        }),
        ..real(name, vr, causality, variability, None)
    }
}

pub fn with_initial(mut v: ScalarVariable, initial: Initial) -> ScalarVariable {
    v.initial = Some(initial);
    v
}

pub fn real_attrs(v: &mut ScalarVariable) -> &mut RealAttributes {
    match &mut v.kind {
        VariableKind::Real(r) => r,
        other => panic!("not Real: {other:?}"),
    }
}

/// A valid co-simulation description using every causality and base type.
///
/// Indices: 1 time, 2 u, 3 k, 4 y, 5 n, 6 c, 7 flag, 8 label, 9 mode, 10 z, 11 K.
pub fn valid() -> ModelDescription {
    use Causality::*;
    use Variability::*;
    let mut u = real("u", 1, Input, Continuous, Some(0.0));
    real_attrs(&mut u).unit = Some("m".into());
    let mut k = with_initial(real("k", 2, Parameter, Fixed, Some(2.0)), Initial::Exact);
    {
        let r = real_attrs(&mut k);
        r.unit = Some("s".into());
        r.min = Some(0.0);
        r.max = Some(10.0);
    }
    let mut y = with_initial(real("y", 3, Output, Continuous, None), Initial::Calculated);
    {
        let r = real_attrs(&mut y);
        r.unit = Some("m".into());
        r.display_unit = Some("mm".into());
    }
    let n = with_initial(integer("n", 0, Output, Discrete, Some(0)), Initial::Exact);
    let c = real("c", 4, CalculatedParameter, Fixed, None);
    let flag = ScalarVariable {
        kind: VariableKind::Boolean {
            declared_type: None,
            start: Some(true),
        },
        ..real("flag", 0, Parameter, Fixed, None)
    };
    let label = ScalarVariable {
        kind: VariableKind::String {
            declared_type: None,
            start: Some("track A".into()),
        },
        ..real("label", 0, Parameter, Tunable, None)
    };
    let mode = ScalarVariable {
        kind: VariableKind::Enumeration(IntegerAttributes {
            declared_type: Some("Mode".into()),
            start: Some(2),
            ..IntegerAttributes::default()
        }),
        ..real("mode", 1, Parameter, Fixed, None)
    };
    let z = real("z", 5, Local, Continuous, None);
    let big_k = real("K", 6, Local, Constant, Some(3.0));
    let time = real("time", 0, Independent, Continuous, None);
    let model_variables = vec![time, u, k, y, n, c, flag, label, mode, z, big_k];
    let model_structure = ModelStructure::derive(&model_variables, |v| match v.name.as_str() {
        "y" => Some(vec![2]),
        _ => Some(vec![]),
    });
    ModelDescription {
        fmi_version: "2.0".into(),
        model_name: "Test".into(),
        guid: "0b6e6f0a-5b1e-4d59-9a49-3f1c7d4f2a10".into(),
        co_simulation: Some(CoSimulation {
            model_identifier: "test_fmu".into(),
            can_handle_variable_communication_step_size: true,
            can_get_and_set_fmu_state: true,
            can_serialize_fmu_state: true,
            can_not_use_memory_management_functions: true,
            ..CoSimulation::default()
        }),
        unit_definitions: vec![
            Unit {
                name: "m".into(),
                base_unit: Some(BaseUnit {
                    m: 1,
                    ..BaseUnit::default()
                }),
                display_units: vec![DisplayUnit {
                    name: "mm".into(),
                    factor: 0.001,
                    offset: 0.0,
                }],
            },
            Unit {
                name: "s".into(),
                base_unit: Some(BaseUnit {
                    s: 1,
                    ..BaseUnit::default()
                }),
                display_units: vec![],
            },
        ],
        type_definitions: vec![SimpleType {
            name: "Mode".into(),
            description: None,
            base_type: "Enumeration".into(),
            quantity: None,
            unit: None,
            display_unit: None,
            items: vec![("off".into(), 1), ("on".into(), 2)],
        }],
        log_categories: vec![Category {
            name: "logAll".into(),
            description: Some("everything".into()),
        }],
        default_experiment: Some(DefaultExperiment {
            start_time: Some(0.0),
            stop_time: Some(10.0),
            tolerance: None,
            step_size: Some(0.01),
        }),
        model_variables,
        model_structure,
        ..ModelDescription::default()
    }
}

/// The names of the direct children of the root element, in document order, read with
/// quick-xml independently of the crate's reader.
pub fn top_level_elements(xml: &str) -> Vec<String> {
    use quick_xml::events::Event;
    let mut reader = quick_xml::Reader::from_str(xml);
    let mut depth = 0usize;
    let mut names = Vec::new();
    loop {
        match reader.read_event().expect("well-formed") {
            Event::Start(e) => {
                if depth == 1 {
                    names.push(e.name().0.to_string());
                }
                depth += 1;
            }
            Event::Empty(e) if depth == 1 => {
                names.push(e.name().0.to_string());
            }
            Event::End(_) => depth -= 1,
            Event::Eof => break,
            _ => {}
        }
    }
    names
}
