use super::*;
use serde_json::json;

/// A row as `alignment-studies variants` writes it; `whole` is also the first digit of the
/// other bands' figures, so a row taken in place of another shows.
fn row(name: &str, settings: &[(&str, &str)], lagged: bool, whole: f64) -> Value {
    let mut r = json!({
        "name": name,
        "settings": settings,
        "smooth": false,
        "bands": [["whole", whole, 0.01, 1.0], ["D1", whole + 0.001, 0.0, 0.0],
                  ["D2", whole + 0.002, 0.0, 0.0], ["D3", whole + 0.003, 0.0, 0.0]],
        "per_seed": [],
    });
    if lagged {
        r["output"] = json!("Lagged");
    }
    r
}

/// The estimator FMU's rows of the studies today, in another order, with names that do not
/// say which is which.
fn fixture() -> Value {
    let (three, nominal) = (
        ("use_roll_rate", "false"),
        ("tap_file", "learned-nominal.taps"),
    );
    let standard = json!([
        row("a", &[("estimator", "2"), nominal], true, 0.61),
        row(
            "b",
            &[("estimator", "2"), ("use_roll_rate", "true")],
            false,
            0.62
        ),
        row("c", &[three, ("estimator", "2")], true, 0.2),
        row("d", &[("estimator", "2"), ("gain", "1")], false, 0.63),
        row("e", &[("estimator", "1")], false, 0.3),
        row("f", &[("estimator", "2"), nominal], false, 0.4),
        row("g", &[("estimator", "2"), three], false, 0.1),
    ]);
    let mut smoothed = row("h", &[("estimator", "2"), three], false, 0.64);
    smoothed["smooth"] = json!(true);
    let mut standard = standard.as_array().unwrap().clone();
    standard.push(smoothed);
    json!({
        "seeds": [1, 2, 3, 4, 5],
        "estimator_fmu": {
            "standard": standard,
            "kalker_50": [
                row("x", &[("estimator", "2"), nominal], false, 0.385),
                row("y", &[("estimator", "2"), three], false, 0.128),
            ],
        },
    })
}

#[test]
fn picks_the_four_rows_by_settings_and_output() {
    let text = headline(&fixture()).unwrap();
    let table: Vec<&str> = text.lines().filter(|l| l.starts_with("| ")).collect();
    assert_eq!(
        table,
        [
            "| estimator | whole 3-200 m | D1 3-25 m | D2 25-70 m | D3 70-200 m |",
            "| learned filter, causal, contact-blended (default) | 0.100 | 0.101 | 0.102 | 0.103 |",
            "| learned, fixed lag 10 m (`alignment_lagged`) | 0.200 | 0.201 | 0.202 | 0.203 |",
            "| paper's filter on our vehicle (`estimator = 1`) | 0.300 | 0.301 | 0.302 | 0.303 |",
            "| the paper (its own vehicle) | 0.25 | 0.48 | 0.26 | 0.15 |",
        ]
    );
}

#[test]
fn says_what_the_figures_hold_for_and_why_nominal_taps_look_better() {
    let text = headline(&fixture()).unwrap();
    for fact in [
        "ML95-type metro car",
        "conicity 0.10",
        "nominal Kalker",
        "straight track",
        "sensors with white noise only",
        "20 m/s",
        "held-out track seeds 1-5:",
    ] {
        assert!(text.contains(fact), "{fact} missing from\n{text}");
    }
    let note = text.lines().last().unwrap();
    assert!(note.starts_with("Nominal-only taps (`tap_file = learned-nominal.taps`, whole 0.400)"));
    assert!(
        note.contains("default 0.128, nominal-only 0.385)"),
        "{note}"
    );
    // Without the worn-contact table the sentence stands without its figures.
    let mut v = fixture();
    v["estimator_fmu"]
        .as_object_mut()
        .unwrap()
        .remove("kalker_50");
    let note = headline(&v).unwrap().lines().last().unwrap().to_string();
    assert!(
        note.contains("when the contact differs, and pays"),
        "{note}"
    );
}

#[test]
fn a_missing_or_doubled_row_is_an_error_naming_it() {
    let mut v = fixture();
    let rows = v["estimator_fmu"]["standard"].as_array_mut().unwrap();
    rows.retain(|r| r["name"] != "c");
    let e = headline(&v).unwrap_err().to_string();
    assert!(e.starts_with("no row for \"learned, fixed lag 10 m"), "{e}");
    let mut v = fixture();
    let rows = v["estimator_fmu"]["standard"].as_array_mut().unwrap();
    let paper = rows.iter().find(|r| r["name"] == "e").unwrap().clone();
    rows.push(paper);
    let e = headline(&v).unwrap_err().to_string();
    assert_eq!(
        e,
        "two rows for \"paper's filter on our vehicle (`estimator = 1`)\""
    );
    let e = headline(&json!({"seeds": [1]})).unwrap_err().to_string();
    assert_eq!(e, "no estimator_fmu.standard table");
}

#[test]
fn seeds_as_a_range_when_consecutive() {
    assert_eq!(seed_list(&[1, 2, 3, 4, 5]), "1-5");
    assert_eq!(seed_list(&[1, 3, 8]), "1, 3, 8");
    assert_eq!(seed_list(&[7]), "7");
    assert_eq!(seed_list(&[]), "");
}
