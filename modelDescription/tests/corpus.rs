//! The corpus of malformed files (`tests/corpus/*.xml`): inputs that once broke a reader, or
//! that stand for a class of hostile input. Each is read with `from_file` and must give the
//! exact error listed here: the file, the line and column, and what is wrong.

use model_description::{ModelDescription, ParseError};
use std::path::{Path, PathBuf};

fn corpus() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/corpus")
}

/// (file, line and column or None, substrings the message must contain).
type Expected = (
    &'static str,
    Option<(usize, usize)>,
    &'static [&'static str],
);

const EXPECTED: &[Expected] = &[
    ("empty.xml", Some((1, 1)), &["no root element"]),
    ("only_prolog.xml", Some((3, 1)), &["no root element"]),
    (
        "truncated.xml",
        Some((3, 5)),
        &["<ScalarVariable> is never closed (the input ends first)"],
    ),
    (
        "not_model_description.xml",
        Some((1, 1)),
        &["the root element is <html>, expected <fmiModelDescription>"],
    ),
    (
        "second_root.xml",
        Some((8, 1)),
        &["a second root element <fmiModelDescription> after the first one"],
    ),
    (
        "text_outside_root.xml",
        Some((1, 1)),
        &["text outside the root element"],
    ),
    (
        "mismatched_end_tag.xml",
        Some((3, 3)),
        &["expected `</ModelVariables>`, but `</ModelStructure>` was found"],
    ),
    (
        "duplicate_attribute.xml",
        Some((3, 49)),
        &["in <ScalarVariable>: an attribute is given twice"],
    ),
    (
        "unquoted_attribute.xml",
        Some((3, 26)),
        &["in <ScalarVariable>: an attribute value is not in quotes"],
    ),
    (
        "unclosed_comment.xml",
        Some((2, 1)),
        &["comment not closed"],
    ),
    ("unclosed_cdata.xml", Some((2, 4)), &["CDATA not closed"]),
    (
        "missing_name.xml",
        Some((3, 5)),
        &["<ScalarVariable> has no 'name' attribute, which is required"],
    ),
    (
        "missing_guid.xml",
        Some((1, 1)),
        &["<fmiModelDescription> has no 'guid' attribute, which is required"],
    ),
    (
        "missing_type_element.xml",
        Some((3, 5)),
        &[
            "<ScalarVariable> (variable 'x') has no Real, Integer, Boolean, String or Enumeration element",
        ],
    ),
    (
        "huge_value_reference.xml",
        Some((3, 30)),
        &[
            "attribute 'valueReference' of <ScalarVariable> (variable 'x') is \"4294967296\", expected a non-negative 32-bit integer",
        ],
    ),
    (
        "negative_value_reference.xml",
        Some((3, 30)),
        &[
            "attribute 'valueReference' of <ScalarVariable> (variable 'x') is \"-1\", expected a non-negative 32-bit integer",
        ],
    ),
    (
        "huge_integer_start.xml",
        Some((4, 16)),
        &[
            "attribute 'start' of <Integer> (variable 'x') is \"99999999999999999999\", expected a 32-bit integer",
        ],
    ),
    (
        "bad_real_start.xml",
        Some((4, 13)),
        &[
            "attribute 'start' of <Real> (variable 'x') is \"1,5\", expected a floating-point number",
        ],
    ),
    (
        "hex_real_start.xml",
        Some((4, 13)),
        &[
            "attribute 'start' of <Real> (variable 'x') is \"0x10\", expected a floating-point number",
        ],
    ),
    (
        "bad_boolean.xml",
        Some((4, 16)),
        &["attribute 'start' of <Boolean> (variable 'x') is \"yes\", expected true or false"],
    ),
    (
        "bad_causality.xml",
        Some((3, 49)),
        &[
            "attribute 'causality' of <ScalarVariable> (variable 'x') is \"sideways\", expected one of parameter",
        ],
    ),
    (
        "bad_dependencies.xml",
        Some((5, 26)),
        &[
            "attribute 'dependencies' of <Unknown> is \"1 two 3\", expected a non-negative 32-bit integer",
        ],
    ),
    (
        "unknown_entity.xml",
        Some((3, 21)),
        &[
            "in attribute 'name' of <ScalarVariable>",
            "unrecognized entity `nope`",
        ],
    ),
    (
        "bad_char_reference.xml",
        Some((3, 21)),
        &[
            "in attribute 'name' of <ScalarVariable>",
            "`1114112` is not a valid codepoint",
        ],
    ),
    // Entities declared in a DOCTYPE are never expanded: no memory or time is spent on them.
    (
        "billion_laughs.xml",
        Some((14, 62)),
        &[
            "in attribute 'description' of <fmiModelDescription>",
            "unrecognized entity `lol9`",
        ],
    ),
    (
        "external_entity.xml",
        Some((5, 39)),
        &[
            "in attribute 'modelName' of <fmiModelDescription>",
            "unrecognized entity `secret`",
        ],
    ),
    (
        "deep_nesting.xml",
        Some((2, 3016)),
        &["elements are nested more than 1000 levels deep (<a> inside <a>)"],
    ),
    (
        "nul_byte.xml",
        Some((3, 28)),
        &["the character U+0000 is not allowed in XML"],
    ),
    (
        "bad_utf8.xml",
        Some((3, 30)),
        &[
            "byte 0xE9 (offset",
            "is not UTF-8; modelDescription.xml must be UTF-8",
        ],
    ),
    (
        "utf16.xml",
        Some((1, 1)),
        &["byte 0xFF (offset 0) is not UTF-8 (the file starts with a UTF-16 byte-order mark)"],
    ),
];

/// Files that must parse, and quickly: entity references in text are skipped, not expanded.
#[test]
fn entity_references_in_text_are_not_expanded() {
    let path = corpus().join("valid/billion_laughs_in_text.xml");
    let started = std::time::Instant::now();
    let md = ModelDescription::from_file(&path).unwrap();
    assert!(started.elapsed().as_secs_f64() < 1.0);
    assert_eq!(md.model_variables.len(), 1);
    ModelDescription::from_file(&corpus().join("valid/third_party.xml")).unwrap();
}

#[test]
fn every_corpus_file_gives_its_error() {
    let mut seen = vec![];
    let mut report = String::new();
    for entry in std::fs::read_dir(corpus()).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "xml") {
            continue;
        }
        let name = path.file_name().unwrap().to_str().unwrap().to_string();
        let started = std::time::Instant::now();
        let result = ModelDescription::from_file(&path);
        let elapsed = started.elapsed();
        let err = match result {
            Ok(_) => {
                report.push_str(&format!("{name}: parsed without error\n"));
                continue;
            }
            Err(e) => e,
        };
        let text = err.to_string();
        report.push_str(&format!("{name}: {:?} {text}\n", err.line_column()));
        seen.push(name.clone());
        assert!(elapsed.as_secs_f64() < 2.0, "{name} took {elapsed:?}");
        let Some((_, at, parts)) = EXPECTED.iter().find(|(n, ..)| *n == name) else {
            continue;
        };
        assert!(
            text.starts_with(&format!("{}: ", path.display())),
            "{name}: the message does not start with the file: {text}"
        );
        assert_eq!(err.line_column(), *at, "{name}: {text}");
        if let Some((line, column)) = at {
            assert!(
                text.contains(&format!("line {line}, column {column}")),
                "{name}: {text}"
            );
        }
        for p in *parts {
            assert!(text.contains(p), "{name}: '{p}' not in: {text}");
        }
        if let ParseError::InFile { source, .. } = &err {
            assert!(!matches!(**source, ParseError::InFile { .. }));
        }
    }
    let missing: Vec<_> = EXPECTED
        .iter()
        .filter(|(n, ..)| !seen.iter().any(|s| s == n))
        .map(|(n, ..)| *n)
        .collect();
    assert!(
        missing.is_empty(),
        "not in the corpus or parsed: {missing:?}\n{report}"
    );
    let unlisted: Vec<_> = seen
        .iter()
        .filter(|s| !EXPECTED.iter().any(|(n, ..)| n == s))
        .collect();
    assert!(
        unlisted.is_empty(),
        "corpus files without an expectation: {unlisted:?}\n{report}"
    );
}
