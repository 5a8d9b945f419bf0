//! The helpers other crates call: `effective_initial`, `ModelStructure::derive`, lookups.

mod common;

use common::*;
use model_description::*;

#[test]
fn effective_initial_follows_the_spec_table() {
    use Causality::*;
    use Variability::*;
    let e = |c, v| real("x", 0, c, v, None).effective_initial();
    // Case A: constants and parameters default to exact.
    assert_eq!(e(Output, Constant), Some(Initial::Exact));
    assert_eq!(e(Local, Constant), Some(Initial::Exact));
    assert_eq!(e(Parameter, Fixed), Some(Initial::Exact));
    assert_eq!(e(Parameter, Tunable), Some(Initial::Exact));
    // Case B: calculatedParameter and fixed/tunable locals default to calculated.
    assert_eq!(e(CalculatedParameter, Fixed), Some(Initial::Calculated));
    assert_eq!(e(CalculatedParameter, Tunable), Some(Initial::Calculated));
    assert_eq!(e(Local, Fixed), Some(Initial::Calculated));
    // Case C: discrete/continuous outputs and locals default to calculated.
    assert_eq!(e(Output, Continuous), Some(Initial::Calculated));
    assert_eq!(e(Output, Discrete), Some(Initial::Calculated));
    assert_eq!(e(Local, Continuous), Some(Initial::Calculated));
    // Cases D and E: no initial at all.
    assert_eq!(e(Input, Continuous), None);
    assert_eq!(e(Input, Discrete), None);
    assert_eq!(e(Independent, Continuous), None);
    // A given attribute wins, except where initial is not allowed.
    assert_eq!(
        with_initial(real("x", 0, Output, Continuous, Some(1.0)), Initial::Exact)
            .effective_initial(),
        Some(Initial::Exact)
    );
    assert_eq!(
        with_initial(real("x", 0, Output, Continuous, Some(1.0)), Initial::Approx)
            .effective_initial(),
        Some(Initial::Approx)
    );
    assert_eq!(
        with_initial(real("x", 0, Input, Continuous, Some(1.0)), Initial::Exact)
            .effective_initial(),
        None
    );
    // Illegal combinations still get a sensible answer.
    assert_eq!(e(Parameter, Continuous), Some(Initial::Exact));
    assert_eq!(e(Output, Fixed), Some(Initial::Calculated));
}

#[test]
fn derive_builds_outputs_and_initial_unknowns() {
    let md = valid();
    let ms = ModelStructure::derive(&md.model_variables, |v| match v.name.as_str() {
        "y" => Some(vec![2]),
        "n" => None,
        _ => panic!("asked for the dependencies of non-output {}", v.name),
    });
    assert_eq!(
        ms.outputs,
        vec![
            Unknown {
                index: 4,
                dependencies: Some(vec![2]),
                dependencies_kind: None
            },
            Unknown {
                index: 5,
                dependencies: None,
                dependencies_kind: None
            },
        ]
    );
    assert!(ms.derivatives.is_empty());
    // y: output calculated; c: calculatedParameter. n is an exact output: not listed.
    assert_eq!(
        ms.initial_unknowns,
        vec![
            Unknown {
                index: 4,
                dependencies: None,
                dependencies_kind: None
            },
            Unknown {
                index: 6,
                dependencies: None,
                dependencies_kind: None
            },
        ]
    );
    let mut md = md;
    md.model_structure = ms;
    assert_eq!(md.validate(), vec![]);
}

#[test]
fn derive_of_a_structure_without_outputs_is_empty() {
    let vars = vec![real(
        "p",
        0,
        Causality::Parameter,
        Variability::Fixed,
        Some(1.0),
    )];
    assert_eq!(
        ModelStructure::derive(&vars, |_| unreachable!()),
        ModelStructure::default()
    );
}

#[test]
fn approx_outputs_are_initial_unknowns() {
    let vars = vec![
        with_initial(
            real(
                "a",
                0,
                Causality::Output,
                Variability::Continuous,
                Some(1.0),
            ),
            Initial::Approx,
        ),
        with_initial(
            real(
                "b",
                1,
                Causality::Output,
                Variability::Continuous,
                Some(1.0),
            ),
            Initial::Exact,
        ),
        real("c", 2, Causality::Output, Variability::Constant, Some(1.0)),
    ];
    let ms = ModelStructure::derive(&vars, |_| Some(vec![]));
    assert_eq!(
        ms.outputs.iter().map(|u| u.index).collect::<Vec<_>>(),
        [1, 2, 3]
    );
    assert_eq!(
        ms.initial_unknowns
            .iter()
            .map(|u| u.index)
            .collect::<Vec<_>>(),
        [1]
    );
}

#[test]
fn lookups_by_name() {
    let md = valid();
    assert_eq!(md.variable("y").unwrap().value_reference, 3);
    assert!(md.variable("nope").is_none());
    // 1-based, as in ModelStructure.
    assert_eq!(md.variable_index("time"), Some(1));
    assert_eq!(md.variable_index("y"), Some(4));
    assert_eq!(
        md.model_variables[md.variable_index("y").unwrap() - 1].name,
        "y"
    );
    assert_eq!(md.variable_index("nope"), None);
    assert!(
        md.model_structure
            .outputs
            .iter()
            .any(|u| u.index as usize == md.variable_index("y").unwrap())
    );
}
