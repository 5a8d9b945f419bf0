//! `validate`: one test per rule, each building a violating description and checking that the
//! violation is reported and names the variable.

mod common;

use common::*;
use model_description::*;

/// Asserts that exactly the expected kind of violation is present: one naming `variable` whose
/// message contains `needle`.
#[track_caller]
fn assert_violation(md: &ModelDescription, variable: Option<&str>, needle: &str) {
    let found = md.validate();
    assert!(
        found
            .iter()
            .any(|v| v.variable.as_deref() == variable && v.message.contains(needle)),
        "expected a violation for {variable:?} containing {needle:?}, got:\n{}",
        found.iter().map(|v| format!("  {v}\n")).collect::<String>()
    );
}

#[track_caller]
fn assert_valid(md: &ModelDescription) {
    let found = md.validate();
    assert!(
        found.is_empty(),
        "unexpected violations:\n{}",
        found.iter().map(|v| format!("  {v}\n")).collect::<String>()
    );
}

fn var<'a>(md: &'a mut ModelDescription, name: &str) -> &'a mut ScalarVariable {
    md.model_variables
        .iter_mut()
        .find(|v| v.name == name)
        .unwrap()
}

/// Re-derives ModelStructure so that a test only breaks the rule it is about.
fn rederive(md: &mut ModelDescription) {
    md.model_structure = ModelStructure::derive(&md.model_variables, |_| Some(vec![]));
}

#[test]
fn the_valid_description_has_no_violations() {
    assert_valid(&valid());
}

#[test]
fn display_names_the_variable() {
    let v = Violation {
        variable: Some("x".into()),
        message: "input must not have an initial attribute".into(),
    };
    assert_eq!(
        v.to_string(),
        "variable 'x': input must not have an initial attribute"
    );
    let v = Violation {
        variable: None,
        message: "guid is empty".into(),
    };
    assert_eq!(v.to_string(), "guid is empty");
}

// ---- model-level -------------------------------------------------------------------------

#[test]
fn fmi_version_must_be_2_0() {
    let mut md = valid();
    md.fmi_version = "3.0".into();
    assert_violation(&md, None, "fmiVersion is \"3.0\", expected \"2.0\"");
}

#[test]
fn guid_and_model_name_must_not_be_empty() {
    let mut md = valid();
    md.guid = String::new();
    md.model_name = " ".into();
    assert_violation(&md, None, "guid is empty");
    assert_violation(&md, None, "modelName is empty");
}

#[test]
fn co_simulation_is_required() {
    let mut md = valid();
    md.co_simulation = None;
    assert_violation(
        &md,
        None,
        "no CoSimulation element: this toolkit only runs co-simulation FMUs",
    );
}

#[test]
fn model_identifier_must_be_a_non_empty_c_identifier() {
    let mut md = valid();
    md.co_simulation.as_mut().unwrap().model_identifier = String::new();
    assert_violation(&md, None, "CoSimulation modelIdentifier is empty");
    md.co_simulation.as_mut().unwrap().model_identifier = "my-fmu".into();
    assert_violation(&md, None, "\"my-fmu\" is not a C identifier");
}

#[test]
fn serializing_state_requires_get_and_set_state() {
    let mut md = valid();
    md.co_simulation.as_mut().unwrap().can_get_and_set_fmu_state = false;
    assert_violation(
        &md,
        None,
        "canSerializeFMUstate=\"true\" requires canGetAndSetFMUstate=\"true\"",
    );
}

#[test]
fn default_experiment_must_be_sensible() {
    let mut md = valid();
    md.default_experiment = Some(DefaultExperiment {
        start_time: Some(5.0),
        stop_time: Some(1.0),
        tolerance: Some(0.0),
        step_size: Some(-0.1),
    });
    assert_violation(&md, None, "startTime 5 is after stopTime 1");
    assert_violation(&md, None, "stepSize -0.1 must be > 0");
    assert_violation(&md, None, "tolerance 0 must be > 0");
}

#[test]
fn unit_and_type_definitions_are_unique_and_well_formed() {
    let mut md = valid();
    md.unit_definitions.push(md.unit_definitions[0].clone());
    md.type_definitions.push(SimpleType {
        items: vec![],
        ..md.type_definitions[0].clone()
    });
    md.type_definitions.push(SimpleType {
        name: "Odd".into(),
        base_type: "Float".into(),
        ..md.type_definitions[0].clone()
    });
    assert_violation(&md, None, "unit 'm' is defined twice");
    assert_violation(&md, None, "type 'Mode' is defined twice");
    assert_violation(
        &md,
        None,
        "type 'Mode': an Enumeration needs at least one Item",
    );
    assert_violation(&md, None, "type 'Odd': base type \"Float\" is not Real");
}

// ---- names and value references ------------------------------------------------------------

#[test]
fn variable_names_are_unique() {
    let mut md = valid();
    var(&mut md, "z").name = "y".into();
    assert_violation(
        &md,
        Some("y"),
        "the name is used twice (variables 4 and 10)",
    );
}

#[test]
fn value_references_are_unique_per_base_type() {
    let mut md = valid();
    var(&mut md, "z").value_reference = 3; // y is Real vr 3
    assert_violation(
        &md,
        Some("z"),
        "value reference 3 (Real) is also used by variable 'y'",
    );

    // Enumeration shares the Integer space: mode (Enumeration, vr 1) vs a new Integer vr 1.
    let mut md = valid();
    md.model_variables.push(integer(
        "count",
        1,
        Causality::Local,
        Variability::Discrete,
        None,
    ));
    rederive(&mut md);
    assert_violation(
        &md,
        Some("count"),
        "value reference 1 (Integer) is also used by variable 'mode'",
    );

    // Different base types may share a number: u is Real vr 1, mode is Enumeration vr 1.
    assert_valid(&valid());
    assert_eq!(
        valid().variable("u").unwrap().value_reference,
        valid().variable("mode").unwrap().value_reference
    );
}

// ---- causality / variability / initial ---------------------------------------------------

#[test]
fn parameter_must_be_fixed_or_tunable() {
    let mut md = valid();
    var(&mut md, "k").variability = Variability::Continuous;
    assert_violation(
        &md,
        Some("k"),
        "causality parameter with variability continuous is not allowed",
    );
}

#[test]
fn parameter_initial_must_be_exact() {
    let mut md = valid();
    var(&mut md, "k").initial = Some(Initial::Approx);
    assert_violation(
        &md,
        Some("k"),
        "initial=\"approx\" is not allowed for causality parameter with variability fixed (allowed: exact)",
    );
    // Absent is fine: the default is exact.
    let mut md = valid();
    var(&mut md, "k").initial = None;
    assert_valid(&md);
}

#[test]
fn calculated_parameter_rules() {
    let mut md = valid();
    var(&mut md, "c").variability = Variability::Discrete;
    assert_violation(
        &md,
        Some("c"),
        "causality calculatedParameter with variability discrete is not allowed",
    );

    let mut md = valid();
    let c = var(&mut md, "c");
    c.initial = Some(Initial::Exact);
    real_attrs(c).start = Some(1.0);
    assert_violation(
        &md,
        Some("c"),
        "initial=\"exact\" is not allowed for causality calculatedParameter with variability fixed (allowed: approx or calculated)",
    );

    // approx with a start value is legal.
    let mut md = valid();
    let c = var(&mut md, "c");
    c.initial = Some(Initial::Approx);
    real_attrs(c).start = Some(1.0);
    assert_valid(&md);
}

#[test]
fn input_must_not_have_initial() {
    let mut md = valid();
    var(&mut md, "u").initial = Some(Initial::Exact);
    assert_violation(&md, Some("u"), "input must not have an initial attribute");
    let text = md
        .validate()
        .iter()
        .map(|v| v.to_string())
        .find(|s| s.contains("initial attribute"))
        .unwrap();
    assert_eq!(
        text,
        "variable 'u': input must not have an initial attribute (found initial=\"exact\")"
    );
}

#[test]
fn input_must_have_a_start_value() {
    let mut md = valid();
    real_attrs(var(&mut md, "u")).start = None;
    assert_violation(&md, Some("u"), "input needs a start value");
}

#[test]
fn input_must_be_discrete_or_continuous() {
    let mut md = valid();
    var(&mut md, "u").variability = Variability::Tunable;
    assert_violation(
        &md,
        Some("u"),
        "causality input with variability tunable is not allowed",
    );
    let mut md = valid();
    var(&mut md, "u").variability = Variability::Constant;
    assert_violation(
        &md,
        Some("u"),
        "causality input with variability constant is not allowed",
    );
}

#[test]
fn output_may_be_constant_but_not_fixed() {
    let mut md = valid();
    md.model_variables.push(real(
        "c_out",
        50,
        Causality::Output,
        Variability::Constant,
        Some(1.0),
    ));
    rederive(&mut md);
    assert_valid(&md);
    // A constant output is exact: it must not claim calculated.
    var(&mut md, "c_out").initial = Some(Initial::Calculated);
    assert_violation(
        &md,
        Some("c_out"),
        "initial=\"calculated\" is not allowed for causality output with variability constant (allowed: exact)",
    );

    let mut md = valid();
    var(&mut md, "y").variability = Variability::Fixed;
    assert_violation(
        &md,
        Some("y"),
        "causality output with variability fixed is not allowed",
    );
}

#[test]
fn independent_rules() {
    let mut md = valid();
    var(&mut md, "time").variability = Variability::Discrete;
    assert_violation(
        &md,
        Some("time"),
        "causality independent with variability discrete is not allowed",
    );

    let mut md = valid();
    real_attrs(var(&mut md, "time")).start = Some(0.0);
    assert_violation(
        &md,
        Some("time"),
        "the independent variable must not have a start value",
    );

    let mut md = valid();
    var(&mut md, "time").initial = Some(Initial::Exact);
    assert_violation(
        &md,
        Some("time"),
        "the independent variable must not have an initial attribute",
    );

    let mut md = valid();
    md.model_variables.push(integer(
        "step",
        9,
        Causality::Independent,
        Variability::Continuous,
        None,
    ));
    rederive(&mut md);
    assert_violation(&md, Some("step"), "the independent variable must be Real");
    assert_violation(
        &md,
        Some("step"),
        "there can be at most one independent variable, 'time' is one already",
    );
}

#[test]
fn constants_need_a_start_value() {
    let mut md = valid();
    real_attrs(var(&mut md, "K")).start = None;
    assert_violation(&md, Some("K"), "a constant needs a start value");
}

#[test]
fn only_real_variables_can_be_continuous() {
    let mut md = valid();
    var(&mut md, "n").variability = Variability::Continuous;
    assert_violation(&md, Some("n"), "a Integer variable cannot be continuous");
    let mut md = valid();
    let flag = var(&mut md, "flag");
    flag.causality = Causality::Local;
    flag.variability = Variability::Continuous;
    assert_violation(&md, Some("flag"), "a Boolean variable cannot be continuous");
}

#[test]
fn start_required_for_exact_and_approx() {
    let mut md = valid();
    real_attrs(var(&mut md, "k")).start = None;
    assert_violation(
        &md,
        Some("k"),
        "initial is exact, so it needs a start value",
    );

    let mut md = valid();
    var(&mut md, "k").initial = None;
    real_attrs(var(&mut md, "k")).start = None;
    assert_violation(
        &md,
        Some("k"),
        "initial defaults to exact here, so it needs a start value",
    );

    let mut md = valid();
    var(&mut md, "y").initial = Some(Initial::Approx);
    rederive(&mut md);
    assert_violation(
        &md,
        Some("y"),
        "initial is approx, so it needs a start value",
    );
}

#[test]
fn start_forbidden_when_calculated() {
    let mut md = valid();
    real_attrs(var(&mut md, "y")).start = Some(0.0);
    assert_violation(
        &md,
        Some("y"),
        "initial is calculated, so it must not have a start value",
    );

    // Local continuous defaults to calculated.
    let mut md = valid();
    real_attrs(var(&mut md, "z")).start = Some(0.0);
    assert_violation(
        &md,
        Some("z"),
        "initial defaults to calculated, so it must not have a start value",
    );
}

// ---- bounds, units, types ----------------------------------------------------------------

#[test]
fn start_within_min_and_max() {
    let mut md = valid();
    real_attrs(var(&mut md, "k")).start = Some(-1.0);
    assert_violation(&md, Some("k"), "start -1 is below min 0");

    let mut md = valid();
    real_attrs(var(&mut md, "k")).start = Some(10.5);
    assert_violation(&md, Some("k"), "start 10.5 is above max 10");

    let mut md = valid();
    real_attrs(var(&mut md, "k")).min = Some(20.0);
    assert_violation(&md, Some("k"), "min 20 is greater than max 10");

    let mut md = valid();
    var(&mut md, "n").kind = VariableKind::Integer(IntegerAttributes {
        min: Some(1),
        max: Some(5),
        start: Some(7),
        ..Default::default()
    });
    assert_violation(&md, Some("n"), "start 7 is above max 5");
}

#[test]
fn units_must_be_defined() {
    let mut md = valid();
    real_attrs(var(&mut md, "u")).unit = Some("km".into());
    assert_violation(
        &md,
        Some("u"),
        "unit 'km' is not defined in UnitDefinitions",
    );
}

#[test]
fn display_units_must_belong_to_the_unit() {
    let mut md = valid();
    real_attrs(var(&mut md, "k")).display_unit = Some("ms".into());
    assert_violation(
        &md,
        Some("k"),
        "displayUnit 'ms' is not a DisplayUnit of unit 's' in UnitDefinitions",
    );

    let mut md = valid();
    let z = real_attrs(var(&mut md, "z"));
    z.display_unit = Some("mm".into());
    assert_violation(&md, Some("z"), "displayUnit 'mm' is given without a unit");
}

#[test]
fn units_of_simple_types_must_be_defined() {
    let mut md = valid();
    md.type_definitions.push(SimpleType {
        name: "Speed".into(),
        description: None,
        base_type: "Real".into(),
        quantity: None,
        unit: Some("km/h".into()),
        display_unit: None,
        items: vec![],
    });
    assert_violation(
        &md,
        None,
        "type 'Speed': unit 'km/h' is not defined in UnitDefinitions",
    );
    // A variable inheriting the unit through declaredType is reported too.
    real_attrs(var(&mut md, "z")).declared_type = Some("Speed".into());
    assert_violation(
        &md,
        Some("z"),
        "unit 'km/h' is not defined in UnitDefinitions",
    );
}

#[test]
fn declared_type_must_be_defined_and_match() {
    let mut md = valid();
    real_attrs(var(&mut md, "z")).declared_type = Some("Nope".into());
    assert_violation(
        &md,
        Some("z"),
        "declaredType 'Nope' is not defined in TypeDefinitions",
    );

    let mut md = valid();
    real_attrs(var(&mut md, "z")).declared_type = Some("Mode".into());
    assert_violation(
        &md,
        Some("z"),
        "declaredType 'Mode' is a Enumeration type but the variable is Real",
    );
}

#[test]
fn enumeration_variables_need_a_declared_type_and_a_valid_start() {
    let mut md = valid();
    let VariableKind::Enumeration(e) = &mut var(&mut md, "mode").kind else {
        panic!()
    };
    e.start = Some(3);
    assert_violation(
        &md,
        Some("mode"),
        "start 3 is not a value of enumeration 'Mode'",
    );
    let VariableKind::Enumeration(e) = &mut var(&mut md, "mode").kind else {
        panic!()
    };
    e.declared_type = None;
    assert_violation(
        &md,
        Some("mode"),
        "an Enumeration variable needs a declaredType",
    );
}

#[test]
fn derivative_must_refer_to_a_real_variable() {
    let mut md = valid();
    real_attrs(var(&mut md, "z")).derivative = Some(99);
    assert_violation(
        &md,
        Some("z"),
        "derivative index 99 is not a variable (valid indices are 1..=11)",
    );
    let mut md = valid();
    real_attrs(var(&mut md, "z")).derivative = Some(5);
    assert_violation(
        &md,
        Some("z"),
        "derivative index 5 refers to 'n', which is not Real",
    );
}

// ---- ModelStructure ------------------------------------------------------------------------

#[test]
fn outputs_must_list_every_output() {
    let mut md = valid();
    md.model_structure.outputs.retain(|u| u.index != 5);
    assert_violation(&md, Some("n"), "missing from ModelStructure/Outputs");
}

#[test]
fn outputs_must_list_only_outputs() {
    let mut md = valid();
    md.model_structure.outputs.push(Unknown {
        index: 10,
        ..Unknown::default()
    });
    assert_violation(
        &md,
        Some("z"),
        "listed in ModelStructure/Outputs but is not an output: its causality is local, not output",
    );
}

#[test]
fn outputs_must_be_ascending_and_unique() {
    let mut md = valid();
    md.model_structure.outputs.reverse();
    assert_violation(
        &md,
        Some("y"),
        "ModelStructure/Outputs is not in ascending order (index 4 after 5)",
    );
    let mut md = valid();
    let first = md.model_structure.outputs[0].clone();
    md.model_structure.outputs.insert(1, first);
    assert_violation(
        &md,
        Some("y"),
        "listed more than once in ModelStructure/Outputs",
    );
}

#[test]
fn unknown_indices_must_be_valid() {
    let mut md = valid();
    md.model_structure.outputs.push(Unknown {
        index: 12,
        ..Unknown::default()
    });
    md.model_structure.initial_unknowns.push(Unknown {
        index: 0,
        ..Unknown::default()
    });
    assert_violation(
        &md,
        None,
        "ModelStructure/Outputs: index 12 is not a variable (valid indices are 1..=11)",
    );
    assert_violation(
        &md,
        None,
        "ModelStructure/InitialUnknowns: index 0 is not a variable (valid indices are 1..=11)",
    );
}

#[test]
fn dependency_indices_must_be_valid() {
    let mut md = valid();
    md.model_structure.outputs[0].dependencies = Some(vec![2, 0, 40]);
    assert_violation(
        &md,
        Some("y"),
        "ModelStructure/Outputs dependency index 0 is not a variable",
    );
    assert_violation(
        &md,
        Some("y"),
        "ModelStructure/Outputs dependency index 40 is not a variable",
    );
}

#[test]
fn dependencies_kind_must_pair_with_dependencies() {
    let mut md = valid();
    md.model_structure.outputs[0].dependencies_kind =
        Some(vec!["dependent".into(), "sometimes".into()]);
    assert_violation(&md, Some("y"), "2 dependenciesKind for 1 dependencies");
    assert_violation(
        &md,
        Some("y"),
        "dependenciesKind \"sometimes\" is not one of",
    );
    md.model_structure.outputs[0].dependencies = None;
    assert_violation(&md, Some("y"), "dependenciesKind without dependencies");
}

#[test]
fn initial_unknowns_must_list_calculated_parameters() {
    let mut md = valid();
    md.model_structure.initial_unknowns.retain(|u| u.index != 6);
    assert_violation(
        &md,
        Some("c"),
        "missing from ModelStructure/InitialUnknowns (every calculatedParameter is)",
    );
}

#[test]
fn initial_unknowns_must_list_calculated_and_approx_outputs() {
    let mut md = valid();
    md.model_structure.initial_unknowns.retain(|u| u.index != 4);
    assert_violation(
        &md,
        Some("y"),
        "missing from ModelStructure/InitialUnknowns (an output with initial calculated)",
    );

    // Default initial of a continuous output is calculated.
    let mut md = valid();
    var(&mut md, "y").initial = None;
    md.model_structure.initial_unknowns.retain(|u| u.index != 4);
    assert_violation(
        &md,
        Some("y"),
        "(an output with initial calculated (the default))",
    );
}

#[test]
fn initial_unknowns_must_not_list_exact_outputs_or_others() {
    let mut md = valid();
    md.model_structure.initial_unknowns.insert(
        1,
        Unknown {
            index: 5,
            ..Unknown::default()
        },
    );
    assert_violation(
        &md,
        Some("n"),
        "listed in ModelStructure/InitialUnknowns but is not an initial unknown: it is an output with initial exact",
    );
    let mut md = valid();
    md.model_structure.initial_unknowns.push(Unknown {
        index: 10,
        ..Unknown::default()
    });
    assert_violation(
        &md,
        Some("z"),
        "listed in ModelStructure/InitialUnknowns but is not an initial unknown: its causality is local",
    );
}

#[test]
fn initial_unknowns_must_be_ascending() {
    let mut md = valid();
    md.model_structure.initial_unknowns.reverse();
    assert_violation(
        &md,
        Some("y"),
        "ModelStructure/InitialUnknowns is not in ascending order (index 4 after 6)",
    );
}

#[test]
fn initial_unknowns_include_calculated_states_and_derivatives() {
    // x (local, continuous, approx with start) is a state, der_x its derivative.
    let mut md = valid();
    let x = with_initial(
        real(
            "x",
            60,
            Causality::Local,
            Variability::Continuous,
            Some(1.0),
        ),
        Initial::Approx,
    );
    let mut der_x = real("der_x", 61, Causality::Local, Variability::Continuous, None);
    real_attrs(&mut der_x).derivative = Some(12);
    md.model_variables.push(x);
    md.model_variables.push(der_x);
    rederive(&mut md);
    assert_eq!(
        md.model_structure
            .derivatives
            .iter()
            .map(|u| u.index)
            .collect::<Vec<_>>(),
        [13]
    );
    assert_eq!(
        md.model_structure
            .initial_unknowns
            .iter()
            .map(|u| u.index)
            .collect::<Vec<_>>(),
        [4, 6, 12, 13]
    );
    assert_valid(&md);

    md.model_structure
        .initial_unknowns
        .retain(|u| u.index != 12);
    assert_violation(
        &md,
        Some("x"),
        "missing from ModelStructure/InitialUnknowns",
    );

    // Derivatives may only list Real variables with a derivative attribute.
    let mut md2 = valid();
    md2.model_structure.derivatives.push(Unknown {
        index: 10,
        ..Unknown::default()
    });
    assert_violation(
        &md2,
        Some("z"),
        "listed in ModelStructure/Derivatives but is not a state derivative: it is not a Real variable with a derivative attribute",
    );
}

#[test]
fn every_violation_of_a_broken_variable_names_it() {
    let mut md = valid();
    let y = var(&mut md, "y");
    y.causality = Causality::Input;
    y.initial = Some(Initial::Approx);
    let found = md.validate();
    assert!(!found.is_empty());
    for v in &found {
        assert_eq!(v.variable.as_deref(), Some("y"), "{v}");
    }
}
