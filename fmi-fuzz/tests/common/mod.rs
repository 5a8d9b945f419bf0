//! Shared by the fmi-fuzz tests: the packaged FMUs, the fuzzer binary, and the C test FMU.
#![allow(dead_code)]

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The directory of the packaged FMUs: `$XTASK_FMU_DIR` (set by `cargo xtask test`), else
/// `<target>/fmu` where `cargo xtask fmu` puts them.
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

/// One of our packaged FMUs; fails (never skips) with instructions when it is missing.
pub fn fmu(model_identifier: &str) -> PathBuf {
    let p = fmu_dir().join(format!("{model_identifier}.fmu"));
    assert!(
        p.is_file(),
        "{} not found. Package the FMUs first with `cargo xtask fmu` (they land in \
         <target>/fmu; with CARGO_TARGET_DIR set, run the tests with \
         XTASK_FMU_DIR=$CARGO_TARGET_DIR/fmu), or run everything with `cargo xtask test`.",
        p.display()
    );
    p
}

/// Runs the fmi-fuzz binary with `args`.
pub fn fuzzer(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_fmi-fuzz"))
        .args(args)
        .output()
        .expect("cannot run fmi-fuzz")
}

pub fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

pub const STRICT_GUID: &str = "{fmi-fuzz-strict-0001}";

const STRICT_MD: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="2.0" modelName="StrictFmu" guid="{fmi-fuzz-strict-0001}" variableNamingConvention="flat" numberOfEventIndicators="0">
  <CoSimulation modelIdentifier="StrictFmu" canHandleVariableCommunicationStepSize="true" canGetAndSetFMUstate="true" canSerializeFMUstate="true"/>
  <LogCategories>
    <Category name="logStatusError"/>
  </LogCategories>
  <ModelVariables>
    <ScalarVariable name="u" valueReference="0" causality="input" variability="continuous"><Real start="0"/></ScalarVariable>
    <ScalarVariable name="y" valueReference="1" causality="output" variability="continuous"><Real/></ScalarVariable>
    <ScalarVariable name="k" valueReference="2" causality="parameter" variability="fixed" initial="exact"><Real start="1"/></ScalarVariable>
    <ScalarVariable name="g" valueReference="3" causality="parameter" variability="tunable" initial="exact"><Real start="1"/></ScalarVariable>
    <ScalarVariable name="n" valueReference="0" causality="output" variability="discrete"><Integer/></ScalarVariable>
    <ScalarVariable name="mode" valueReference="1" causality="parameter" variability="tunable" initial="exact"><Integer start="0"/></ScalarVariable>
    <ScalarVariable name="flag" valueReference="0" causality="parameter" variability="tunable" initial="exact"><Boolean start="false"/></ScalarVariable>
    <ScalarVariable name="label" valueReference="0" causality="parameter" variability="fixed" initial="exact"><String start=""/></ScalarVariable>
  </ModelVariables>
  <ModelStructure>
    <Outputs>
      <Unknown index="2"/>
      <Unknown index="5"/>
    </Outputs>
    <InitialUnknowns>
      <Unknown index="2"/>
      <Unknown index="5"/>
    </InitialUnknowns>
  </ModelStructure>
</fmiModelDescription>
"#;

/// tests/c/strictfmu.c compiled with `-D<define>` (if any) and packaged as an FMU in a fresh
/// scratch directory.
pub fn strict_fmu(define: Option<&str>) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("fmi-fuzz")
        .join(define.unwrap_or("correct"));
    std::fs::create_dir_all(&dir).unwrap();
    let lib = dir.join("StrictFmu.so");
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/c/strictfmu.c");
    let cc = std::env::var_os("CC").unwrap_or_else(|| "cc".into());
    let mut cmd = Command::new(cc);
    cmd.args(["-shared", "-fPIC", "-O1", "-Wall", "-Wextra", "-o"])
        .arg(&lib)
        .arg(&src);
    if let Some(d) = define {
        cmd.arg(format!("-D{d}"));
    }
    let out = cmd.output().expect("cannot run the C compiler (cc)");
    assert!(
        out.status.success(),
        "compiling tests/c/strictfmu.c failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let fmu = dir.join("StrictFmu.fmu");
    let mut zip = zip::ZipWriter::new(std::fs::File::create(&fmu).unwrap());
    let opts = zip::write::SimpleFileOptions::default();
    zip.start_file("modelDescription.xml", opts).unwrap();
    zip.write_all(STRICT_MD.as_bytes()).unwrap();
    zip.start_file(
        "binaries/linux64/StrictFmu.so",
        opts.unix_permissions(0o755),
    )
    .unwrap();
    zip.write_all(&std::fs::read(&lib).unwrap()).unwrap();
    zip.add_directory("resources/", opts).unwrap();
    zip.finish().unwrap();
    fmu
}
