//! Shared by the integration tests and the bench: our packaged FMUs (built on demand), a C
//! test FMU compiled at test time, zip writing, and a capturing log sink.
#![allow(dead_code)]

use fmi_import::{LogConfig, LogRecord, fmi2Status};
use std::collections::HashMap;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::{Arc, Mutex, OnceLock};
use zip::write::SimpleFileOptions;

pub const PLATFORM: &str = if cfg!(target_os = "linux") {
    "linux64"
} else if cfg!(target_os = "macos") {
    "darwin64"
} else {
    "win64"
};
pub const EXT: &str = if cfg!(target_os = "linux") {
    "so"
} else if cfg!(target_os = "macos") {
    "dylib"
} else {
    "dll"
};

pub fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .unwrap()
        .to_path_buf()
}

/// The directory of the packaged FMUs: `$XTASK_FMU_DIR` (set by `cargo xtask test` to the FMUs it
/// packaged, as for every other crate's tests), else `<target>/fmu` where `cargo xtask fmu` puts
/// them.
pub fn fmu_dir() -> PathBuf {
    if let Some(d) = std::env::var_os("XTASK_FMU_DIR") {
        return PathBuf::from(d);
    }
    // CARGO_TARGET_TMPDIR is <target>/tmp, whatever CARGO_TARGET_DIR says.
    Path::new(env!("CARGO_TARGET_TMPDIR"))
        .parent()
        .unwrap()
        .join("fmu")
}

/// One of our packaged FMUs ("AlignmentEstimator", "RailVehicle"). Without `$XTASK_FMU_DIR`, runs
/// `cargo xtask fmu` once per test binary when they are missing; with it (`cargo xtask test`),
/// they must be there.
pub fn our_fmu(model_identifier: &str) -> PathBuf {
    static BUILT: OnceLock<()> = OnceLock::new();
    let path = |id: &str| fmu_dir().join(format!("{id}.fmu"));
    BUILT.get_or_init(|| {
        if std::env::var_os("XTASK_FMU_DIR").is_some()
            || ["AlignmentEstimator", "RailVehicle"]
                .iter()
                .all(|id| path(id).is_file())
        {
            return;
        }
        let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
        let status = Command::new(cargo)
            .args(["xtask", "fmu"])
            .current_dir(workspace_root())
            .status()
            .expect("cannot run `cargo xtask fmu`");
        assert!(status.success(), "`cargo xtask fmu` failed ({status})");
    });
    let p = path(model_identifier);
    assert!(
        p.is_file(),
        "{} not found (packaged by `cargo xtask fmu`, or by `cargo xtask test` into \
         $XTASK_FMU_DIR)",
        p.display()
    );
    p
}

/// A fresh directory under cargo's per-package test scratch space.
pub fn scratch() -> tempfile::TempDir {
    let base = Path::new(env!("CARGO_TARGET_TMPDIR")).join("fmi-import");
    std::fs::create_dir_all(&base).unwrap();
    tempfile::tempdir_in(base).unwrap()
}

/// An archive entry to write.
pub enum Entry {
    File(String, Vec<u8>),
    /// A file with an explicit unix mode (e.g. a symlink type in the mode bits).
    Mode(String, Vec<u8>, u32),
    Symlink(String, String),
    Dir(String),
}

pub fn file(name: &str, data: impl Into<Vec<u8>>) -> Entry {
    Entry::File(name.to_string(), data.into())
}

pub fn write_zip(path: &Path, entries: &[Entry]) {
    let mut zip = zip::ZipWriter::new(std::fs::File::create(path).unwrap());
    let opts = SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated);
    for e in entries {
        match e {
            Entry::File(name, data) => {
                zip.start_file(name.as_str(), opts).unwrap();
                zip.write_all(data).unwrap();
            }
            Entry::Mode(name, data, mode) => {
                zip.start_file(name.as_str(), opts.unix_permissions(*mode))
                    .unwrap();
                zip.write_all(data).unwrap();
            }
            Entry::Symlink(name, target) => {
                zip.add_symlink(name.as_str(), target.as_str(), opts)
                    .unwrap();
            }
            Entry::Dir(name) => {
                zip.add_directory(name.as_str(), opts).unwrap();
            }
        }
    }
    zip.finish().unwrap();
}

/// Rewrites the central-directory record of `entry` so that it says "made on unix, with
/// this mode" (the zip writer only lets us choose permission bits, not the file type).
pub fn set_unix_mode(path: &Path, entry: &str, mode: u32) {
    let mut bytes = std::fs::read(path).unwrap();
    let mut i = 0;
    let mut patched = false;
    while i + 46 <= bytes.len() {
        if bytes[i..i + 4] == [0x50, 0x4b, 0x01, 0x02] {
            let name_len = u16::from_le_bytes([bytes[i + 28], bytes[i + 29]]) as usize;
            if bytes.get(i + 46..i + 46 + name_len) == Some(entry.as_bytes()) {
                bytes[i + 5] = 3; // version made by: unix
                bytes[i + 38..i + 42].copy_from_slice(&(mode << 16).to_le_bytes());
                patched = true;
            }
        }
        i += 1;
    }
    assert!(patched, "no central directory record for {entry}");
    std::fs::write(path, bytes).unwrap();
}

/// Every file entry of an archive: (name, bytes).
pub fn read_entries(path: &Path) -> Vec<(String, Vec<u8>)> {
    let mut zip = zip::ZipArchive::new(std::fs::File::open(path).unwrap()).unwrap();
    let mut out = Vec::new();
    for i in 0..zip.len() {
        let mut f = zip.by_index(i).unwrap();
        if f.is_dir() {
            continue;
        }
        let mut data = Vec::new();
        f.read_to_end(&mut data).unwrap();
        out.push((f.name().unwrap().into_owned(), data));
    }
    out
}

/// Copies an FMU, letting `edit` replace (Some) or drop (None... keep as is) entries.
pub fn rewrite_fmu(
    src: &Path,
    dst: &Path,
    mut edit: impl FnMut(&str, &[u8]) -> Option<Option<Vec<u8>>>,
) {
    let mut entries = Vec::new();
    for (name, data) in read_entries(src) {
        match edit(&name, &data) {
            None => entries.push(file(&name, data)),
            Some(Some(new)) => entries.push(file(&name, new)),
            Some(None) => {}
        }
    }
    write_zip(dst, &entries);
}

/// The C test FMU compiled with `defines`, cached per test binary.
pub fn test_library(defines: &[&str]) -> PathBuf {
    static CACHE: OnceLock<Mutex<HashMap<String, PathBuf>>> = OnceLock::new();
    let key = defines.join(" ");
    let mut cache = CACHE.get_or_init(Default::default).lock().unwrap();
    if let Some(p) = cache.get(&key) {
        return p.clone();
    }
    let dir = scratch().keep();
    let out = dir.join(format!("TestFmu.{EXT}"));
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/c/testfmu.c");
    let cc = std::env::var_os("CC").unwrap_or_else(|| "cc".into());
    let mut cmd = Command::new(cc);
    cmd.args(["-shared", "-fPIC", "-O2", "-Wall", "-o"])
        .arg(&out)
        .arg(&src);
    for d in defines {
        cmd.arg(format!("-D{d}"));
    }
    let result = cmd.output().expect("cannot run the C compiler");
    assert!(
        result.status.success(),
        "compiling the test FMU failed:\n{}",
        String::from_utf8_lossy(&result.stderr)
    );
    cache.insert(key, out.clone());
    out
}

pub const TEST_GUID: &str = "{5f1c0e2a-test-fmu-0001}";

pub fn test_model_description(guid: &str) -> String {
    format!(
        r#"<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="2.0" modelName="TestFmu" guid="{guid}" variableNamingConvention="flat" numberOfEventIndicators="0">
  <CoSimulation modelIdentifier="TestFmu" canHandleVariableCommunicationStepSize="true" canGetAndSetFMUstate="true" canSerializeFMUstate="true"/>
  <LogCategories>
    <Category name="logInfo"/>
    <Category name="logStep"/>
  </LogCategories>
  <ModelVariables>
    <ScalarVariable name="x" valueReference="0" causality="output" variability="continuous" initial="exact"><Real start="0"/></ScalarVariable>
    <ScalarVariable name="u" valueReference="1" causality="input" variability="continuous"><Real start="0"/></ScalarVariable>
    <ScalarVariable name="time" valueReference="2" causality="output" variability="continuous" initial="exact"><Real start="0"/></ScalarVariable>
    <ScalarVariable name="mode" valueReference="0" causality="parameter" variability="tunable" initial="exact"><Integer start="0"/></ScalarVariable>
    <ScalarVariable name="steps" valueReference="1" causality="output" variability="discrete" initial="exact"><Integer start="0"/></ScalarVariable>
    <ScalarVariable name="flag" valueReference="0" causality="parameter" variability="tunable" initial="exact"><Boolean start="false"/></ScalarVariable>
    <ScalarVariable name="label" valueReference="0" causality="parameter" variability="tunable" initial="exact"><String start=""/></ScalarVariable>
  </ModelVariables>
  <ModelStructure>
    <Outputs>
      <Unknown index="1"/>
      <Unknown index="3"/>
      <Unknown index="5"/>
    </Outputs>
  </ModelStructure>
</fmiModelDescription>
"#
    )
}

/// A packaged C test FMU at `dir/<name>.fmu`, built with `defines`.
pub fn test_fmu(dir: &Path, name: &str, defines: &[&str]) -> PathBuf {
    let lib = std::fs::read(test_library(defines)).unwrap();
    let path = dir.join(format!("{name}.fmu"));
    write_zip(
        &path,
        &[
            file("modelDescription.xml", test_model_description(TEST_GUID)),
            Entry::Mode(format!("binaries/{PLATFORM}/TestFmu.{EXT}"), lib, 0o755),
            file(
                "resources/readme.txt",
                "calls.txt is written next to this file\n",
            ),
        ],
    );
    path
}

/// The lifecycle calls the C test FMU recorded.
pub fn recorded_calls(fmu: &fmi_import::Fmu) -> Vec<String> {
    std::fs::read_to_string(fmu.unpacked_dir().join("resources/calls.txt"))
        .unwrap_or_default()
        .lines()
        .map(str::to_string)
        .collect()
}

pub type Records = Arc<Mutex<Vec<LogRecord>>>;

/// A log configuration whose sink collects records.
pub fn capture(min_status: fmi2Status) -> (LogConfig, Records) {
    let records: Records = Arc::default();
    let r = Arc::clone(&records);
    let config = LogConfig {
        min_status,
        sink: Arc::new(move |rec: &LogRecord| r.lock().unwrap().push(rec.clone())),
        ..LogConfig::default()
    };
    (config, records)
}

/// A LogConfig that prints nothing.
pub fn quiet() -> LogConfig {
    LogConfig {
        sink: Arc::new(|_: &LogRecord| {}),
        ..LogConfig::default()
    }
}
