"""The packaged .fmu as an importer sees it: schema-valid XML, the declared interface, the
archive layout, and a binary that exports every FMI 2.0 function (fmpy's validation reads only
the XML, so a missing symbol would otherwise surface only when someone simulates)."""

from __future__ import annotations

import ctypes
import zipfile
from pathlib import Path

from fmpy.validation import validate_fmu

from project import MODEL_IDENTIFIER, REPO

#: fmi_abi::export::FUNCTION_NAMES: the 25 common and 9 co-simulation functions of FMI 2.0.
FMI2_FUNCTIONS = [
    "fmi2GetTypesPlatform", "fmi2GetVersion", "fmi2SetDebugLogging", "fmi2Instantiate", "fmi2FreeInstance",
    "fmi2SetupExperiment", "fmi2EnterInitializationMode", "fmi2ExitInitializationMode", "fmi2Terminate", "fmi2Reset",
    "fmi2GetReal", "fmi2GetInteger", "fmi2GetBoolean", "fmi2GetString", "fmi2SetReal", "fmi2SetInteger",
    "fmi2SetBoolean", "fmi2SetString", "fmi2GetFMUstate", "fmi2SetFMUstate", "fmi2FreeFMUstate",
    "fmi2SerializedFMUstateSize", "fmi2SerializeFMUstate", "fmi2DeSerializeFMUstate", "fmi2GetDirectionalDerivative",
    "fmi2SetRealInputDerivatives", "fmi2GetRealOutputDerivatives", "fmi2DoStep", "fmi2CancelStep", "fmi2GetStatus",
    "fmi2GetRealStatus", "fmi2GetIntegerStatus", "fmi2GetBooleanStatus", "fmi2GetStringStatus",
]  # fmt: skip


def test_fmpy_validation_finds_no_problems(fmu_path):
    assert validate_fmu(str(fmu_path)) == []


def test_declares_the_sensor_inputs_and_estimate_outputs(model_description):
    md = model_description
    assert md.fmiVersion == "2.0"
    assert md.coSimulation is not None and md.coSimulation.modelIdentifier == MODEL_IDENTIFIER
    assert md.modelExchange is None
    variables = {v.name: v for v in md.modelVariables}
    inputs = {"ws_acc_y": "m/s2", "ws_yaw_rate": "rad/s", "frame_acc_y": "m/s2", "speed": "m/s"}
    for name, unit in inputs.items():
        v = variables[name]
        assert (v.causality, v.type, v.unit) == ("input", "Real", unit), name
    for name in ("alignment", "alignment_std", "distance"):
        v = variables[name]
        assert (v.causality, v.type, v.unit) == ("output", "Real", "m"), name
    assert variables["skipped_updates"].causality == "output"
    # every output is listed once in ModelStructure/Outputs
    assert sorted(u.variable.name for u in md.outputs) == sorted(v.name for v in md.modelVariables if v.causality == "output")


def test_archive_holds_exactly_the_expected_entries(fmu_path):
    resources = sorted(
        "resources/" + p.relative_to(REPO / "fmu-estimator" / "resources").as_posix()
        for p in (REPO / "fmu-estimator" / "resources").rglob("*")
        if p.is_file() and not p.name.startswith(".")
    )
    assert resources, "fmu-estimator/resources should ship at least calibration.toml"
    expected = sorted(
        ["modelDescription.xml", f"binaries/linux64/{MODEL_IDENTIFIER}.so", "documentation/index.html", *resources]
    )
    with zipfile.ZipFile(fmu_path) as z:
        infos = z.infolist()
        assert [i.filename for i in infos] == expected  # sorted, files only, forward slashes
        for i in infos:
            assert i.compress_type == zipfile.ZIP_DEFLATED, i.filename
            assert i.date_time == (1980, 1, 1, 0, 0, 0), i.filename
            mode = (i.external_attr >> 16) & 0o777
            assert mode == (0o755 if i.filename.endswith(".so") else 0o644), i.filename
        assert z.testzip() is None
        html = z.read("documentation/index.html").decode()
        assert "ws_acc_y" in html and "alignment_std" in html  # the generated variable table


def test_binary_exports_all_34_fmi2_functions(unzip_dir):
    assert len(FMI2_FUNCTIONS) == 34 and len(set(FMI2_FUNCTIONS)) == 34
    lib = ctypes.CDLL(str(Path(unzip_dir) / "binaries" / "linux64" / f"{MODEL_IDENTIFIER}.so"))
    missing = []
    for name in FMI2_FUNCTIONS:
        try:
            getattr(lib, name)
        except AttributeError:
            missing.append(name)
    assert missing == []
    lib.fmi2GetVersion.restype = ctypes.c_char_p
    lib.fmi2GetTypesPlatform.restype = ctypes.c_char_p
    assert lib.fmi2GetVersion() == b"2.0"
    assert lib.fmi2GetTypesPlatform() == b"default"
