//! Broken and hostile FMUs: each gives a clear error naming the file (and the entry, symbol or
//! position where that applies), and nothing panics or escapes the unpack directory.

mod common;

use common::*;
use fmi_import::{Fmu, ImportError};
use model_description::ModelDescription;
use std::path::{Path, PathBuf};

fn open_err(path: &Path) -> (ImportError, String) {
    let err = Fmu::open(path).unwrap_err();
    let text = err.to_string();
    assert!(
        text.contains(&path.display().to_string()),
        "error does not name the file: {text}"
    );
    assert_eq!(err.fmu_path(), path);
    (err, text)
}

/// The C test FMU's entries plus `extra`.
fn valid_entries() -> Vec<Entry> {
    let lib = std::fs::read(test_library(&[])).unwrap();
    vec![
        file("modelDescription.xml", test_model_description(TEST_GUID)),
        Entry::Mode(format!("binaries/{PLATFORM}/TestFmu.{EXT}"), lib, 0o755),
    ]
}

fn fmu_with(dir: &Path, name: &str, extra: Vec<Entry>) -> PathBuf {
    let path = dir.join(name);
    let mut entries = valid_entries();
    entries.extend(extra);
    write_zip(&path, &entries);
    path
}

#[test]
fn the_valid_test_fmu_opens() {
    let dir = scratch();
    let path = fmu_with(dir.path(), "Valid.fmu", vec![]);
    Fmu::open(&path).unwrap();
}

#[test]
fn missing_file() {
    let (err, text) = open_err(Path::new("/nonexistent/dir/Missing.fmu"));
    assert!(matches!(err, ImportError::Io { .. }), "{err:?}");
    assert!(text.contains("cannot open"), "{text}");
}

#[test]
fn corrupt_zip() {
    let dir = scratch();
    let path = dir.path().join("Random.fmu");
    let mut x: u64 = 0x9e37_79b9_7f4a_7c15;
    let bytes: Vec<u8> = (0..4096)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x as u8
        })
        .collect();
    std::fs::write(&path, bytes).unwrap();
    let (err, text) = open_err(&path);
    assert!(matches!(err, ImportError::Archive { .. }), "{err:?}");
    assert!(text.contains("not a valid FMU archive"), "{text}");

    // A truncated real FMU.
    let whole = std::fs::read(our_fmu("RailVehicle")).unwrap();
    let cut = dir.path().join("Truncated.fmu");
    std::fs::write(&cut, &whole[..whole.len() / 2]).unwrap();
    let (err, _) = open_err(&cut);
    assert!(matches!(err, ImportError::Archive { .. }), "{err:?}");
}

fn assert_unsafe(path: &Path, entry: &str, reason: &str) {
    let (err, text) = open_err(path);
    match &err {
        ImportError::UnsafeEntry {
            entry: e,
            reason: r,
            ..
        } => {
            assert_eq!(e, entry);
            assert!(r.contains(reason), "{r}");
        }
        other => panic!("expected UnsafeEntry, got {other:?}"),
    }
    assert!(text.contains(entry), "{text}");
}

#[test]
fn parent_dir_entry_is_refused_before_anything_is_written() {
    let dir = scratch();
    let parent = dir.path().join("a").join("b");
    std::fs::create_dir_all(&parent).unwrap();
    let path = fmu_with(dir.path(), "Evil.fmu", vec![file("../evil", "pwned")]);
    assert_unsafe(&path, "../evil", "..");
    let err = Fmu::open_in(&path, &parent).unwrap_err();
    assert!(matches!(err, ImportError::UnsafeEntry { .. }));
    assert!(!parent.join("evil").exists());
    assert_eq!(
        std::fs::read_dir(&parent).unwrap().count(),
        0,
        "left files behind"
    );

    let deeper = fmu_with(
        dir.path(),
        "Deeper.fmu",
        vec![file("resources/../../evil", "pwned")],
    );
    assert_unsafe(&deeper, "resources/../../evil", "..");
}

#[test]
fn absolute_entry_is_refused() {
    let dir = scratch();
    let path = fmu_with(
        dir.path(),
        "Abs.fmu",
        vec![file("/tmp/evil-fmi-import", "x")],
    );
    assert_unsafe(&path, "/tmp/evil-fmi-import", "absolute");
    assert!(!Path::new("/tmp/evil-fmi-import").exists());
    let drive = fmu_with(dir.path(), "Drive.fmu", vec![file("C:/evil", "x")]);
    assert_unsafe(&drive, "C:/evil", "Windows");
}

#[test]
fn symlink_entry_is_refused() {
    let dir = scratch();
    let path = fmu_with(
        dir.path(),
        "Link.fmu",
        vec![Entry::Symlink(
            "resources/link".into(),
            "/etc/passwd".into(),
        )],
    );
    assert_unsafe(&path, "resources/link", "symbolic link");
    // The same by mode bits on an ordinary-looking entry.
    let mode = fmu_with(dir.path(), "Mode.fmu", vec![file("resources/l", "/etc")]);
    set_unix_mode(&mode, "resources/l", 0o120_777);
    assert_unsafe(&mode, "resources/l", "symbolic link");
    let fifo = fmu_with(dir.path(), "Fifo.fmu", vec![file("resources/f", "")]);
    set_unix_mode(&fifo, "resources/f", 0o010_644);
    assert_unsafe(&fifo, "resources/f", "special file");
}

#[test]
fn backslash_and_nul_entries_are_refused() {
    let dir = scratch();
    let path = fmu_with(dir.path(), "Back.fmu", vec![file("..\\evil", "x")]);
    assert_unsafe(&path, "..\\evil", "backslash");
    let nul = fmu_with(dir.path(), "Nul.fmu", vec![file("resources/a\0b", "x")]);
    assert_unsafe(&nul, "resources/a\\0b", "NUL");
}

#[test]
fn missing_model_description() {
    let dir = scratch();
    let path = dir.path().join("NoMd.fmu");
    write_zip(&path, &[file("resources/x.txt", "x")]);
    let (err, text) = open_err(&path);
    assert!(
        matches!(err, ImportError::MissingModelDescription { .. }),
        "{err:?}"
    );
    assert!(text.contains("modelDescription.xml"), "{text}");
}

#[test]
fn malformed_xml_gives_line_and_column() {
    let dir = scratch();
    let xml = "<?xml version=\"1.0\"?>\n<fmiModelDescription fmiVersion=\"2.0\" modelName=\"m\" guid=\"g\">\n  <CoSimulation modelIdentifier=\"TestFmu\">\n  </Oops>\n</fmiModelDescription>\n";
    let (line, column) = ModelDescription::from_xml(xml)
        .unwrap_err()
        .line_column()
        .unwrap();
    let path = dir.path().join("BadXml.fmu");
    write_zip(&path, &[file("modelDescription.xml", xml)]);
    let (err, text) = open_err(&path);
    assert!(
        matches!(err, ImportError::ModelDescription { .. }),
        "{err:?}"
    );
    assert!(
        text.contains(&format!("line {line}, column {column}")),
        "{text}"
    );
    assert_eq!(line, 4, "{text}");
}

#[test]
fn no_co_simulation_element() {
    let dir = scratch();
    let xml = test_model_description(TEST_GUID).replace(
        "<CoSimulation modelIdentifier=\"TestFmu\"",
        "<ModelExchange modelIdentifier=\"TestFmu\"",
    );
    let path = dir.path().join("Me.fmu");
    write_zip(&path, &[file("modelDescription.xml", xml)]);
    let (err, text) = open_err(&path);
    assert!(
        matches!(
            err,
            ImportError::NotCoSimulation {
                model_exchange: true,
                ..
            }
        ),
        "{err:?}"
    );
    assert!(text.contains("CoSimulation"), "{text}");
}

#[test]
fn no_binary_for_this_platform_lists_what_there_is() {
    let dir = scratch();
    let path = dir.path().join("WinOnly.fmu");
    write_zip(
        &path,
        &[
            file("modelDescription.xml", test_model_description(TEST_GUID)),
            file("binaries/win64/TestFmu.dll", "MZ"),
            file("binaries/win32/TestFmu.dll", "MZ"),
        ],
    );
    let (err, text) = open_err(&path);
    assert!(matches!(err, ImportError::MissingBinary { .. }), "{err:?}");
    let expected = format!("binaries/{PLATFORM}/TestFmu.{EXT}");
    assert!(text.contains(&expected), "{text}");
    if PLATFORM != "win64" {
        assert!(text.contains("win32, win64"), "{text}");
    }

    let none = dir.path().join("NoBinaries.fmu");
    write_zip(
        &none,
        &[file(
            "modelDescription.xml",
            test_model_description(TEST_GUID),
        )],
    );
    let (_, text) = open_err(&none);
    assert!(text.contains("no binaries/ folder"), "{text}");
}

#[test]
fn missing_functions_are_listed_in_one_error() {
    let dir = scratch();
    let path = test_fmu(dir.path(), "Partial", &["OMIT_SOME"]);
    let (err, text) = open_err(&path);
    let ImportError::MissingFunctions { missing, .. } = &err else {
        panic!("expected MissingFunctions, got {err:?}");
    };
    let mut missing = missing.clone();
    missing.sort_unstable();
    assert_eq!(
        missing,
        ["fmi2CancelStep", "fmi2DoStep", "fmi2GetRealStatus"]
    );
    assert!(text.contains("3 of the 34"), "{text}");
    assert!(
        text.contains(&format!("binaries/{PLATFORM}/TestFmu.{EXT}")),
        "{text}"
    );
}

#[test]
fn undefined_symbol_fails_at_load_with_the_loaders_message() {
    let dir = scratch();
    let path = test_fmu(dir.path(), "Undefined", &["UNDEFINED_REF"]);
    let (err, text) = open_err(&path);
    assert!(matches!(err, ImportError::Load { .. }), "{err:?}");
    assert!(text.contains("testfmu_undefined_function"), "{text}");
}

#[test]
fn not_a_shared_library() {
    let dir = scratch();
    let path = dir.path().join("Garbage.fmu");
    write_zip(
        &path,
        &[
            file("modelDescription.xml", test_model_description(TEST_GUID)),
            file(
                &format!("binaries/{PLATFORM}/TestFmu.{EXT}"),
                vec![0x42u8; 4096],
            ),
        ],
    );
    let (err, text) = open_err(&path);
    assert!(matches!(err, ImportError::Load { .. }), "{err:?}");
    assert!(text.contains("cannot load"), "{text}");
}

#[test]
fn wrong_fmi_version_reported_by_the_library() {
    let dir = scratch();
    let path = test_fmu(dir.path(), "V3", &["FMI_VERSION=\"3.0\""]);
    let (err, text) = open_err(&path);
    assert!(matches!(err, ImportError::Incompatible { .. }), "{err:?}");
    assert!(
        text.contains("fmi2GetVersion") && text.contains("\"3.0\""),
        "{text}"
    );
}

#[test]
fn model_identifier_cannot_point_outside() {
    let dir = scratch();
    let xml = test_model_description(TEST_GUID).replace(
        "modelIdentifier=\"TestFmu\"",
        "modelIdentifier=\"../../../tmp/x\"",
    );
    let path = dir.path().join("Ident.fmu");
    write_zip(&path, &[file("modelDescription.xml", xml)]);
    let (err, text) = open_err(&path);
    assert!(
        matches!(err, ImportError::InvalidModelIdentifier { .. }),
        "{err:?}"
    );
    assert!(text.contains("../../../tmp/x"), "{text}");
}

#[test]
fn fmi3_model_description_is_refused() {
    let dir = scratch();
    let xml = test_model_description(TEST_GUID).replace("fmiVersion=\"2.0\"", "fmiVersion=\"3.0\"");
    let path = dir.path().join("Fmi3.fmu");
    write_zip(&path, &[file("modelDescription.xml", xml)]);
    let (err, text) = open_err(&path);
    assert!(
        matches!(err, ImportError::UnsupportedFmiVersion { .. }),
        "{err:?}"
    );
    assert!(text.contains("3.0"), "{text}");
}
