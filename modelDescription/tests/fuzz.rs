//! Property tests of the reader against hostile input: random bytes, token soup, and mutations of
//! valid files (truncation, byte flips, deleted and duplicated elements and attributes, huge and
//! odd attribute values, deep nesting, entities). The properties:
//!
//! - the reader never panics, and returns quickly (the whole file runs in a few seconds);
//! - an error points into the document: a line and column inside the text, shown in the message;
//! - whatever the reader accepts, the writer writes and the reader reads back to the same text
//!   (write -> read -> write is a fixed point), and any description the writer can express reads
//!   back equal (write -> read round trip).
//!
//! Case counts are small by default (CI); `PROPTEST_CASES=100000 cargo test -p model-description
//! --test fuzz --release` runs a larger campaign.

mod common;

use model_description::*;
use proptest::prelude::*;
use proptest::test_runner::Config;
use std::ops::Range;

/// The proptest configuration: `default_cases` unless PROPTEST_CASES is set.
fn config(default_cases: u32) -> Config {
    let mut c = Config::default();
    if std::env::var_os("PROPTEST_CASES").is_none() {
        c.cases = default_cases;
    }
    c
}

/// A third-party-styled description: prolog with DOCTYPE, comments, CDATA, namespaces, tool
/// annotations and every kind of element the reader reads.
const THIRD_PARTY: &str = include_str!("corpus/valid/third_party.xml");

fn seeds() -> Vec<String> {
    vec![common::valid().to_xml(), THIRD_PARTY.to_string()]
}

/// Checks the properties of one result; `text` is what was parsed.
fn check(text: &str, result: Result<ModelDescription, ParseError>) -> Result<(), TestCaseError> {
    match result {
        Ok(md) => {
            let written = md.to_xml();
            let back = ModelDescription::from_xml(&written).map_err(|e| {
                TestCaseError::fail(format!(
                    "the reader accepted a file whose rewrite it refuses: {e}\n{written}"
                ))
            })?;
            prop_assert_eq!(back.to_xml(), written, "write -> read -> write differs");
        }
        Err(e) => {
            let message = e.to_string();
            prop_assert!(!message.is_empty());
            let (line, column) = e
                .line_column()
                .ok_or_else(|| TestCaseError::fail(format!("no line and column: {message}")))?;
            let text = text.strip_prefix('\u{feff}').unwrap_or(text);
            let lines = text.split('\n').count();
            prop_assert!(
                line >= 1 && line <= lines && column >= 1,
                "line {} column {} outside the text ({} lines): {}",
                line,
                column,
                lines,
                message
            );
            let line_text = text.split('\n').nth(line - 1).unwrap_or("");
            prop_assert!(
                column <= line_text.chars().count() + 1,
                "column {} past the end of line {}: {}",
                column,
                line,
                message
            );
            let at = format!("line {line}, column {column}");
            prop_assert!(message.contains(&at), "'{}' not in: {}", at, message);
        }
    }
    Ok(())
}

// ---- spans of the valid seeds, found with quick-xml directly (not through the crate) --------

struct Spans {
    /// Whole elements, start tag to end tag.
    elements: Vec<Range<usize>>,
    /// ` name="value"` including the leading space.
    attributes: Vec<Range<usize>>,
    /// The value between the quotes.
    values: Vec<Range<usize>>,
}

fn spans(text: &str) -> Spans {
    use quick_xml::events::Event;
    let mut reader = quick_xml::Reader::from_str(text);
    let mut open = Vec::new();
    let mut out = Spans {
        elements: vec![],
        attributes: vec![],
        values: vec![],
    };
    loop {
        let start = reader.buffer_position() as usize;
        let event = reader.read_event().expect("the seeds are well-formed");
        let end = reader.buffer_position() as usize;
        match event {
            Event::Start(_) | Event::Empty(_) => {
                attribute_spans(text, start..end, &mut out);
                if matches!(event, Event::Start(_)) {
                    open.push(start);
                } else {
                    out.elements.push(start..end);
                }
            }
            Event::End(_) => out.elements.push(open.pop().unwrap()..end),
            Event::Eof => break,
            _ => {}
        }
    }
    out
}

/// Attributes of the tag `text[tag]` (`<name a="1" b='2'>`).
fn attribute_spans(text: &str, tag: Range<usize>, out: &mut Spans) {
    let bytes = text.as_bytes();
    let mut i = tag.start + 1;
    while i < tag.end && !bytes[i].is_ascii_whitespace() && bytes[i] != b'>' && bytes[i] != b'/' {
        i += 1;
    }
    loop {
        let space = i;
        while i < tag.end && bytes[i].is_ascii_whitespace() {
            i += 1;
        }
        if i >= tag.end || bytes[i] == b'>' || bytes[i] == b'/' {
            return;
        }
        while bytes[i] != b'=' {
            i += 1;
        }
        i += 1;
        let quote = bytes[i];
        let value_start = i + 1;
        i = value_start;
        while bytes[i] != quote {
            i += 1;
        }
        out.values.push(value_start..i);
        i += 1;
        out.attributes.push(space..i);
    }
}

// ---- mutations ------------------------------------------------------------------------------

/// Attribute values that stress number parsing, entities and sizes.
fn odd_value() -> impl Strategy<Value = String> {
    prop_oneof![
        Just("4294967296".to_string()),
        Just("-1".to_string()),
        Just("99999999999999999999999999999999".to_string()),
        Just("1e999999".to_string()),
        Just("-1e-999999".to_string()),
        Just("NaN".to_string()),
        Just("-INF".to_string()),
        Just("0x10".to_string()),
        Just("1,5".to_string()),
        Just(String::new()),
        Just("   ".to_string()),
        Just("&lol9;".to_string()),
        Just("&#0;".to_string()),
        Just("&#x110000;".to_string()),
        Just("&#99999999999999999999;".to_string()),
        Just("&amp;&lt;&gt;&quot;&apos;".to_string()),
        Just("<".to_string()),
        Just("\u{feff}".to_string()),
        Just("1".repeat(20_000)),
        Just("9".repeat(400) + "e-400"),
        "[0-9eE+.-]{1,40}",
        "\\PC{0,20}",
    ]
}

/// Fragments that make token soup look like XML.
fn token() -> impl Strategy<Value = String> {
    prop_oneof![
        Just("<".to_string()),
        Just(">".to_string()),
        Just("/>".to_string()),
        Just("</".to_string()),
        Just("=".to_string()),
        Just("\"".to_string()),
        Just("'".to_string()),
        Just("&".to_string()),
        Just(";".to_string()),
        Just(" ".to_string()),
        Just("\n".to_string()),
        Just("<!--".to_string()),
        Just("-->".to_string()),
        Just("<![CDATA[".to_string()),
        Just("]]>".to_string()),
        Just("<?xml version=\"1.0\"?>".to_string()),
        Just("<?".to_string()),
        Just("?>".to_string()),
        Just("<!DOCTYPE x [<!ENTITY e \"&e;&e;\">]>".to_string()),
        Just("&lt;".to_string()),
        Just("&#x41;".to_string()),
        Just("&e;".to_string()),
        Just("fmiModelDescription".to_string()),
        Just("fmiVersion=\"2.0\" modelName=\"m\" guid=\"g\"".to_string()),
        Just("ModelVariables".to_string()),
        Just("ScalarVariable".to_string()),
        Just("name=\"x\"".to_string()),
        Just("valueReference=\"1\"".to_string()),
        Just("Real".to_string()),
        Just("start=\"1\"".to_string()),
        Just("ModelStructure".to_string()),
        Just("Unknown index=\"1\" dependencies=\"1 2\"".to_string()),
        Just("xmlns:a=\"u\" a:".to_string()),
        "[a-zA-Z0-9]{1,8}",
        "\\PC{1,4}",
    ]
}

#[derive(Debug, Clone)]
enum Structural {
    None,
    DeleteElement(prop::sample::Index),
    DuplicateElement(prop::sample::Index),
    DeleteAttribute(prop::sample::Index),
    DuplicateAttribute(prop::sample::Index),
    ReplaceValue(prop::sample::Index, String),
    /// Wraps an element in `depth` nested elements.
    Nest(prop::sample::Index, usize),
}

#[derive(Debug, Clone)]
enum Bytes {
    Truncate(prop::sample::Index),
    Flip(prop::sample::Index, u8),
    Delete(prop::sample::Index, usize),
    Duplicate(prop::sample::Index, usize),
    Insert(prop::sample::Index, Vec<u8>),
}

fn structural() -> impl Strategy<Value = Structural> {
    use prop::sample::Index;
    prop_oneof![
        Just(Structural::None),
        any::<Index>().prop_map(Structural::DeleteElement),
        any::<Index>().prop_map(Structural::DuplicateElement),
        any::<Index>().prop_map(Structural::DeleteAttribute),
        any::<Index>().prop_map(Structural::DuplicateAttribute),
        (any::<Index>(), odd_value()).prop_map(|(i, v)| Structural::ReplaceValue(i, v)),
        (
            any::<Index>(),
            prop_oneof![1usize..20, 990usize..1010, Just(50_000usize)]
        )
            .prop_map(|(i, d)| Structural::Nest(i, d)),
    ]
}

fn byte_mutation() -> impl Strategy<Value = Bytes> {
    use prop::sample::Index;
    prop_oneof![
        any::<Index>().prop_map(Bytes::Truncate),
        (any::<Index>(), 1u8..=255).prop_map(|(i, x)| Bytes::Flip(i, x)),
        (any::<Index>(), 1usize..64).prop_map(|(i, n)| Bytes::Delete(i, n)),
        (any::<Index>(), 1usize..256).prop_map(|(i, n)| Bytes::Duplicate(i, n)),
        (
            any::<Index>(),
            prop_oneof![
                token().prop_map(String::into_bytes),
                prop::collection::vec(any::<u8>(), 1..8),
                // Invalid UTF-8: a lone continuation byte, a truncated sequence, an overlong NUL.
                Just(vec![0x80]),
                Just(vec![0xe2, 0x82]),
                Just(vec![0xc0, 0x80]),
                Just(vec![0xff, 0xfe]),
            ]
        )
            .prop_map(|(i, b)| Bytes::Insert(i, b)),
    ]
}

fn apply_structural(seed: &str, m: &Structural) -> String {
    let s = spans(seed);
    let mut text = seed.to_string();
    match m {
        Structural::None => {}
        Structural::DeleteElement(i) => {
            text.replace_range(i.get(&s.elements).clone(), "");
        }
        Structural::DuplicateElement(i) => {
            let r = i.get(&s.elements).clone();
            let copy = seed[r.clone()].to_string();
            text.insert_str(r.end, &copy);
        }
        Structural::DeleteAttribute(i) => {
            text.replace_range(i.get(&s.attributes).clone(), "");
        }
        Structural::DuplicateAttribute(i) => {
            let r = i.get(&s.attributes).clone();
            let copy = seed[r.clone()].to_string();
            text.insert_str(r.end, &copy);
        }
        Structural::ReplaceValue(i, v) => {
            let quoted = v.replace('"', "&quot;").replace('\'', "&apos;");
            text.replace_range(i.get(&s.values).clone(), &quoted);
        }
        Structural::Nest(i, depth) => {
            let r = i.get(&s.elements).clone();
            text.insert_str(r.end, &"</n>".repeat(*depth));
            text.insert_str(r.start, &"<n>".repeat(*depth));
        }
    }
    text
}

fn apply_bytes(bytes: &mut Vec<u8>, m: &Bytes) {
    if bytes.is_empty() {
        return;
    }
    match m {
        Bytes::Truncate(i) => bytes.truncate(i.index(bytes.len())),
        Bytes::Flip(i, x) => {
            let i = i.index(bytes.len());
            bytes[i] ^= x;
        }
        Bytes::Delete(i, n) => {
            let i = i.index(bytes.len());
            let end = (i + n).min(bytes.len());
            bytes.drain(i..end);
        }
        Bytes::Duplicate(i, n) => {
            let i = i.index(bytes.len());
            let end = (i + n).min(bytes.len());
            let copy = bytes[i..end].to_vec();
            bytes.splice(end..end, copy);
        }
        Bytes::Insert(i, b) => {
            let i = i.index(bytes.len() + 1);
            bytes.splice(i..i, b.iter().copied());
        }
    }
}

/// Parses bytes as the importer does: invalid UTF-8 is refused before the reader (checked in
/// the corpus test), so the reader sees the lossy text.
fn parse_bytes(bytes: &[u8]) -> Result<(), TestCaseError> {
    let text = String::from_utf8_lossy(bytes);
    check(&text, ModelDescription::from_xml(&text))
}

proptest! {
    #![proptest_config(config(256))]

    #[test]
    fn random_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..2048)) {
        parse_bytes(&bytes)?;
    }

    #[test]
    fn token_soup_never_panics(tokens in prop::collection::vec(token(), 0..200)) {
        let text: String = tokens.concat();
        check(&text, ModelDescription::from_xml(&text))?;
        // The same soup inside a root element, so the reader gets past the first tag.
        let wrapped = format!("<fmiModelDescription fmiVersion=\"2.0\" modelName=\"m\" guid=\"g\"><ModelVariables>{text}</ModelVariables></fmiModelDescription>");
        check(&wrapped, ModelDescription::from_xml(&wrapped))?;
    }

    #[test]
    fn mutated_valid_files_never_panic(
        seed in 0usize..2,
        s in structural(),
        bytes in prop::collection::vec(byte_mutation(), 0..4),
    ) {
        let seed = &seeds()[seed];
        let text = apply_structural(seed, &s);
        // Structural mutations alone keep the text UTF-8; check them before the byte-level ones.
        check(&text, ModelDescription::from_xml(&text))?;
        if let Structural::DuplicateAttribute(_) = s {
            let e = ModelDescription::from_xml(&text).unwrap_err();
            prop_assert!(e.to_string().contains("given twice"), "{}", e);
        }
        if let Structural::Nest(_, depth) = s && depth >= xml::MAX_DEPTH {
            let e = ModelDescription::from_xml(&text).unwrap_err();
            prop_assert!(e.to_string().contains("nested more than 1000 levels"), "{}", e);
        }
        let mut b = text.into_bytes();
        for m in &bytes {
            apply_bytes(&mut b, m);
        }
        parse_bytes(&b)?;
    }
}

// ---- write -> read round trip of arbitrary descriptions --------------------------------------

/// Text the writer must carry through an attribute: any non-control character, the markup
/// characters, and the whitespace that attribute-value normalization would otherwise eat.
fn text() -> impl Strategy<Value = String> {
    "[\\PC<>&\"' \t\n\r]{0,12}"
}

fn float() -> impl Strategy<Value = f64> {
    use prop::num::f64::*;
    prop_oneof![
        (POSITIVE | NEGATIVE | NORMAL | SUBNORMAL | ZERO | INFINITE),
        Just(-0.0),
        Just(5e-324),
        Just(1e300),
        Just(0.1),
    ]
}

fn opt<T: std::fmt::Debug + Clone>(
    s: impl Strategy<Value = T>,
) -> impl Strategy<Value = Option<T>> {
    prop::option::of(s)
}

fn causality() -> impl Strategy<Value = Causality> {
    prop_oneof![
        Just(Causality::Parameter),
        Just(Causality::CalculatedParameter),
        Just(Causality::Input),
        Just(Causality::Output),
        Just(Causality::Local),
        Just(Causality::Independent),
    ]
}

fn variability() -> impl Strategy<Value = Variability> {
    prop_oneof![
        Just(Variability::Constant),
        Just(Variability::Fixed),
        Just(Variability::Tunable),
        Just(Variability::Discrete),
        Just(Variability::Continuous),
    ]
}

fn initial() -> impl Strategy<Value = Initial> {
    prop_oneof![
        Just(Initial::Exact),
        Just(Initial::Approx),
        Just(Initial::Calculated)
    ]
}

fn integer_attributes() -> impl Strategy<Value = IntegerAttributes> {
    (
        opt(text()),
        opt(text()),
        opt(any::<i32>()),
        opt(any::<i32>()),
        opt(any::<i32>()),
    )
        .prop_map(
            |(declared_type, quantity, min, max, start)| IntegerAttributes {
                declared_type,
                quantity,
                min,
                max,
                start,
            },
        )
}

fn real_attributes() -> impl Strategy<Value = RealAttributes> {
    (
        (opt(text()), opt(text()), opt(text()), opt(text())),
        (opt(any::<bool>()), opt(float()), opt(float()), opt(float())),
        (
            opt(any::<bool>()),
            opt(float()),
            opt(any::<u32>()),
            opt(any::<bool>()),
        ),
    )
        .prop_map(
            |(
                (declared_type, quantity, unit, display_unit),
                (relative_quantity, min, max, nominal),
                (unbounded, start, derivative, reinit),
            )| RealAttributes {
                declared_type,
                quantity,
                unit,
                display_unit,
                relative_quantity,
                min,
                max,
                nominal,
                unbounded,
                start,
                derivative,
                reinit,
            },
        )
}

fn kind() -> impl Strategy<Value = VariableKind> {
    prop_oneof![
        real_attributes().prop_map(VariableKind::Real),
        integer_attributes().prop_map(VariableKind::Integer),
        integer_attributes().prop_map(VariableKind::Enumeration),
        (opt(text()), opt(any::<bool>())).prop_map(|(declared_type, start)| {
            VariableKind::Boolean {
                declared_type,
                start,
            }
        }),
        (opt(text()), opt(text())).prop_map(|(declared_type, start)| VariableKind::String {
            declared_type,
            start
        }),
    ]
}

fn variable() -> impl Strategy<Value = ScalarVariable> {
    (
        text(),
        any::<u32>(),
        opt(text()),
        causality(),
        variability(),
        opt(initial()),
        opt(any::<bool>()),
        kind(),
    )
        .prop_map(
            |(
                name,
                value_reference,
                description,
                causality,
                variability,
                initial,
                multiple,
                kind,
            )| {
                ScalarVariable {
                    name,
                    value_reference,
                    description,
                    causality,
                    variability,
                    initial,
                    can_handle_multiple_set_per_time_instant: multiple,
                    kind,
                }
            },
        )
}

fn unknown() -> impl Strategy<Value = Unknown> {
    let kinds = prop::collection::vec(
        prop_oneof![
            Just("dependent".to_string()),
            Just("constant".to_string()),
            Just("fixed".to_string()),
            Just("tunable".to_string()),
            Just("discrete".to_string()),
        ],
        0..4,
    );
    (
        any::<u32>(),
        opt(prop::collection::vec(any::<u32>(), 0..4)),
        opt(kinds),
    )
        .prop_map(|(index, dependencies, dependencies_kind)| Unknown {
            index,
            dependencies,
            dependencies_kind,
        })
}

fn unit() -> impl Strategy<Value = Unit> {
    let base =
        (prop::array::uniform8(any::<i32>()), float(), float()).prop_map(|(e, factor, offset)| {
            BaseUnit {
                kg: e[0],
                m: e[1],
                s: e[2],
                a: e[3],
                k: e[4],
                mol: e[5],
                cd: e[6],
                rad: e[7],
                factor,
                offset,
            }
        });
    let display = (text(), float(), float()).prop_map(|(name, factor, offset)| DisplayUnit {
        name,
        factor,
        offset,
    });
    (text(), opt(base), prop::collection::vec(display, 0..3)).prop_map(
        |(name, base_unit, display_units)| Unit {
            name,
            base_unit,
            display_units,
        },
    )
}

fn simple_type() -> impl Strategy<Value = SimpleType> {
    (
        text(),
        opt(text()),
        prop_oneof![
            Just("Real".to_string()),
            Just("Integer".to_string()),
            Just("Boolean".to_string()),
            Just("String".to_string()),
            Just("Enumeration".to_string()),
        ],
        (opt(text()), opt(text()), opt(text())),
        prop::collection::vec((text(), any::<i32>()), 0..3),
    )
        .prop_map(
            |(name, description, base_type, (quantity, unit, display_unit), items)| {
                let items = if base_type == "Enumeration" {
                    items
                } else {
                    vec![]
                };
                SimpleType {
                    name,
                    description,
                    base_type,
                    quantity,
                    unit,
                    display_unit,
                    items,
                }
            },
        )
}

fn co_simulation() -> impl Strategy<Value = CoSimulation> {
    (text(), prop::array::uniform10(any::<bool>()), any::<u32>()).prop_map(|(id, f, order)| {
        CoSimulation {
            model_identifier: id,
            needs_execution_tool: f[0],
            can_handle_variable_communication_step_size: f[1],
            can_interpolate_inputs: f[2],
            max_output_derivative_order: order,
            can_run_asynchronuously: f[3],
            can_be_instantiated_only_once_per_process: f[4],
            can_not_use_memory_management_functions: f[5],
            can_get_and_set_fmu_state: f[6],
            can_serialize_fmu_state: f[7],
            provides_directional_derivative: f[8],
        }
    })
}

fn model_description() -> impl Strategy<Value = ModelDescription> {
    let strings = (
        (text(), text(), text()),
        prop::collection::vec(opt(text()), 8),
        opt(any::<u32>()),
    );
    let parts = (
        opt(co_simulation()),
        opt(text()),
        prop::collection::vec(unit(), 0..3),
        prop::collection::vec(simple_type(), 0..3),
        prop::collection::vec((text(), opt(text())), 0..3),
        opt((opt(float()), opt(float()), opt(float()), opt(float()))),
        prop::collection::vec(variable(), 0..6),
        (
            prop::collection::vec(unknown(), 0..3),
            prop::collection::vec(unknown(), 0..3),
            prop::collection::vec(unknown(), 0..3),
        ),
    );
    (strings, parts).prop_map(
        |(
            ((fmi_version, model_name, guid), o, events),
            (cs, me, units, types, categories, de, vars, (outputs, derivatives, initial_unknowns)),
        )| ModelDescription {
            fmi_version,
            model_name,
            guid,
            description: o[0].clone(),
            author: o[1].clone(),
            version: o[2].clone(),
            copyright: o[3].clone(),
            license: o[4].clone(),
            generation_tool: o[5].clone(),
            generation_date_and_time: o[6].clone(),
            variable_naming_convention: o[7].clone(),
            number_of_event_indicators: events,
            co_simulation: cs,
            model_exchange_identifier: me,
            unit_definitions: units,
            type_definitions: types,
            log_categories: categories
                .into_iter()
                .map(|(name, description)| Category { name, description })
                .collect(),
            default_experiment: de.map(|(start_time, stop_time, tolerance, step_size)| {
                DefaultExperiment {
                    start_time,
                    stop_time,
                    tolerance,
                    step_size,
                }
            }),
            model_variables: vars,
            model_structure: ModelStructure {
                outputs,
                derivatives,
                initial_unknowns,
            },
        },
    )
}

proptest! {
    #![proptest_config(config(256))]

    /// Everything the types can hold (except NaN, which PartialEq cannot compare) comes back
    /// equal, and the text is a fixed point.
    #[test]
    fn write_read_round_trip(md in model_description()) {
        let xml = md.to_xml();
        let back = ModelDescription::from_xml(&xml)
            .map_err(|e| TestCaseError::fail(format!("{e}\n{xml}")))?;
        prop_assert_eq!(&back, &md, "\n{}", xml);
        prop_assert_eq!(back.to_xml(), xml);
    }
}

#[test]
fn the_seeds_are_valid_and_their_spans_cover_every_element() {
    for seed in seeds() {
        let md = ModelDescription::from_xml(&seed).unwrap();
        assert!(!md.model_variables.is_empty());
        let s = spans(&seed);
        assert!(s.elements.len() > 10 && s.attributes.len() > 20);
        for r in &s.elements {
            assert!(seed[r.clone()].starts_with('<') && seed[r.clone()].ends_with('>'));
        }
        for r in &s.attributes {
            assert!(seed[r.clone()].starts_with(char::is_whitespace));
        }
    }
}

/// A million nested elements: an error, not a stack overflow, and fast.
#[test]
fn a_million_nested_elements_is_an_error() {
    let depth = 1_000_000;
    let text = format!(
        "<fmiModelDescription fmiVersion=\"2.0\" modelName=\"m\" guid=\"g\">{}{}</fmiModelDescription>",
        "<a>".repeat(depth),
        "</a>".repeat(depth)
    );
    let started = std::time::Instant::now();
    let e = ModelDescription::from_xml(&text).unwrap_err();
    assert!(started.elapsed().as_secs_f64() < 5.0);
    assert_eq!(e.line_column(), Some((1, 3059)), "{e}");
    assert!(
        e.to_string()
            .contains("elements are nested more than 1000 levels deep (<a> inside <a>)"),
        "{e}"
    );
    // Exactly at the limit it parses.
    let ok = format!(
        "<fmiModelDescription fmiVersion=\"2.0\" modelName=\"m\" guid=\"g\">{}{}</fmiModelDescription>",
        "<a>".repeat(xml::MAX_DEPTH - 1),
        "</a>".repeat(xml::MAX_DEPTH - 1)
    );
    ModelDescription::from_xml(&ok).unwrap();
}
