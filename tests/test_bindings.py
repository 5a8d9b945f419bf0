"""The Python bindings (bindings/, `track_alignment`) against the FMU through fmpy and against
the command line: the estimator is the FMU bit for bit, the metrics are the CLI's, the band-pass
is scipy's, a vehicle run is fmpy's, and bad input raises with the library's message."""

from __future__ import annotations

import json
import threading

import fmpy
import numpy as np
import pytest
from fmpy.fmi2 import FMU2Slave
from scipy.signal import butter, sosfiltfilt

import orchestrator_cli as oc
from project import packaged_fmus

track_alignment = pytest.importorskip(
    "track_alignment", reason="the bindings are built into .venv by `cargo xtask test`"
)

H = 1e-3
SENSORS = ("ws_acc_y", "ws_yaw_rate", "frame_acc_y")


@pytest.fixture(scope="module")
def vehicle_signals() -> dict[str, np.ndarray]:
    """12 s of the vehicle's sensors (track seed 3) through the bindings' master run, with a
    speed that rises through the learned taps' 5 m/s lower bound so that both estimators act."""
    out = track_alignment.simulate(
        packaged_fmus()["RailVehicle"], 12.0, step=H, parameters={"track_seed": 3},
        variables=[*SENSORS, "ws_roll_rate", "distance", "alignment"],
    )
    n = len(out["time"]) - 1
    signals = {k: np.ascontiguousarray(v[1:]) for k, v in out.items()}
    signals["speed"] = 3.0 + 2.0 * np.arange(n) * H
    return signals


def fmu_outputs(signals, settings: dict, names: list[str], ints: list[str]) -> dict[str, np.ndarray]:
    """The estimator FMU stepped by fmpy: inputs set, then fmi2DoStep(t, h), then outputs read."""
    path = packaged_fmus()["AlignmentEstimator"]
    md = fmpy.read_model_description(str(path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    unzip = fmpy.extract(str(path))
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzip, modelIdentifier=md.coSimulation.modelIdentifier,
                    instanceName="bindings")
    fmu.instantiate()
    try:
        fmu.setupExperiment(startTime=0.0)
        for name, value in settings.items():
            if isinstance(value, bool):
                fmu.setBoolean([vr[name]], [value])
            elif isinstance(value, int):
                fmu.setInteger([vr[name]], [value])
            else:
                fmu.setReal([vr[name]], [value])
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        inputs = ["speed", *SENSORS, "ws_roll_rate"]
        in_vr = [vr[n] for n in inputs]
        real_vr, int_vr = [vr[n] for n in names], [vr[n] for n in ints]
        n = len(signals["speed"])
        out = {k: np.empty(n) for k in names} | {k: np.empty(n, dtype=np.int32) for k in ints}
        columns = np.column_stack([signals[k] for k in inputs])
        for k in range(n):
            fmu.setReal(in_vr, list(columns[k]))
            fmu.doStep(k * H, H)
            for name, x in zip(names, fmu.getReal(real_vr)):
                out[name][k] = x
            for name, x in zip(ints, fmu.getInteger(int_vr)):
                out[name][k] = x
        fmu.terminate()
    finally:
        fmu.freeInstance()
    return out


REALS = ["alignment", "alignment_std", "alignment_lagged", "alignment_lagged_std", "distance_lagged",
         "alignment_kalman", "contact_scale", "distance"]


@pytest.mark.parametrize(
    "settings",
    [{}, {"use_roll_rate": True}, {"estimator": 1, "alignment_model": 3, "gain": 1}],
    ids=["default-learned", "roll-rate", "paper-shaping-prior"],
)
def test_estimate_is_the_fmu_bit_for_bit(vehicle_signals, settings):
    s = vehicle_signals
    ours = track_alignment.estimate(
        s["speed"], s["ws_acc_y"], s["ws_yaw_rate"], s["frame_acc_y"], step=H,
        ws_roll_rate=s["ws_roll_rate"], settings=settings,
    )
    theirs = fmu_outputs(s, settings, REALS, ["active_estimator"])
    for name in [*REALS, "active_estimator"]:
        np.testing.assert_array_equal(ours[name], theirs[name], err_msg=name)
    active = set(np.unique(ours["active_estimator"]))
    assert active == ({1} if settings.get("estimator") == 1 else {1, 2})
    assert ours["skipped_updates"] == 0


def test_the_smoother_and_parameters_are_reachable(vehicle_signals):
    s = vehicle_signals
    speed = np.full_like(s["speed"], 20.0)
    out = track_alignment.estimate(speed, s["ws_acc_y"], s["ws_yaw_rate"], s["frame_acc_y"], step=H,
                                   settings={"estimator": 1}, smooth=True)
    # The smoother ends where the filter ends and never has a larger variance.
    assert out["alignment_smoothed"][-1] == out["alignment_kalman"][-1]
    kalman_std = track_alignment.estimate(speed, s["ws_acc_y"], s["ws_yaw_rate"], s["frame_acc_y"], step=H,
                                          settings={"estimator": 1})["alignment_std"]
    assert np.all(out["alignment_smoothed_std"] <= kalman_std + 1e-15)
    params = track_alignment.parameters()
    assert params["estimator"][:2] == ("Integer", 2)
    assert params["lag"][0] == "Real" and params["use_roll_rate"][:2] == ("Boolean", False)
    md = fmpy.read_model_description(str(packaged_fmus()["AlignmentEstimator"]))
    fmu_params = {v.name for v in md.modelVariables if v.causality == "parameter"}
    assert set(params) == fmu_params


def test_band_metrics_equal_the_command_lines(tmp_path):
    oc.studies("run", "--stop", "20", "--quiet", "--out", tmp_path, *oc.standard_fmu_args(),
           "--record", "vehicle.distance,vehicle.alignment,estimator.distance,estimator.alignment")
    cli = json.loads((tmp_path / "metrics.json").read_text())["bands"]
    r = oc.read_results(tmp_path)
    # The CLI leaves out the first row (t = 0, before any step; docs/studies.md).
    ours = track_alignment.band_metrics(r["estimator.distance"][1:], r["estimator.alignment"][1:],
                                        r["vehicle.distance"][1:], r["vehicle.alignment"][1:])
    assert set(ours) == {"whole", "D1", "D2", "D3"}
    for band, row in ours.items():
        assert row["J_mm"] == cli[band]["J_mm"], band
        assert row["Jrel"] == cli[band]["Jrel"], band


def test_the_bands_are_en_13848s():
    # EN 13848-5's D1-D3 wavelength ranges and the paper's whole range, in the metrics' order.
    assert track_alignment.BANDS == [("whole", (3.0, 200.0)), ("D1", (3.0, 25.0)),
                                     ("D2", (25.0, 70.0)), ("D3", (70.0, 200.0))]


def test_bandpass_is_scipys_zero_phase_butterworth():
    ds = 0.05
    x = np.random.default_rng(4).standard_normal(20_000)
    sos = butter(4, [1 / 25.0, 1 / 3.0], btype="bandpass", fs=1 / ds, output="sos")
    np.testing.assert_allclose(track_alignment.bandpass(x, ds, 3.0, 25.0), sosfiltfilt(sos, x),
                               rtol=0, atol=1e-9 * np.abs(x).max())


def test_a_vehicle_run_is_fmpys():
    path = packaged_fmus()["RailVehicle"]
    names = ["ws_acc_y", "frame_acc_y", "alignment"]
    ours = track_alignment.simulate(path, 1.0, step=H, variables=names)
    theirs = fmpy.simulate_fmu(str(path), stop_time=1.0, step_size=H, output_interval=H, output=names)
    n = min(len(ours["time"]), len(theirs))
    np.testing.assert_allclose(ours["time"][:n], theirs["time"][:n], rtol=0, atol=1e-12)
    # Not bit for bit: fmpy and the master round the communication points differently (1e-18 s
    # at first), which the vehicle's dynamics carry on to about 1e-6 of the signal in 1 s.
    for name in names:
        scale = np.abs(theirs[name][:n]).max()
        assert scale > 0, name
        np.testing.assert_allclose(ours[name][:n], theirs[name][:n], rtol=0, atol=1e-5 * scale, err_msg=name)


def test_strided_and_integer_inputs_give_the_contiguous_results(vehicle_signals):
    """A column of a 2-D array (strided) is copied once, a list or int array converted; the
    result is the contiguous float64 one."""
    s = vehicle_signals
    table = np.column_stack([s["speed"], s["ws_acc_y"], s["ws_yaw_rate"], s["frame_acc_y"]])
    assert not table[:, 1].flags["C_CONTIGUOUS"]
    want = track_alignment.estimate(s["speed"], s["ws_acc_y"], s["ws_yaw_rate"], s["frame_acc_y"], step=H)
    got = track_alignment.estimate(*(table[:, i] for i in range(4)), step=H)
    np.testing.assert_array_equal(got["alignment"], want["alignment"])
    ints = track_alignment.estimate(np.full(500, 20), [0] * 500, np.zeros(500), np.zeros(500), step=H)
    assert ints["alignment"].dtype == np.float64 and len(ints["alignment"]) == 500


def test_threads_give_the_sequential_results(vehicle_signals):
    """The GIL is released while Rust computes; concurrent calls share nothing."""
    s = vehicle_signals
    args = [s["speed"], s["ws_acc_y"], s["ws_yaw_rate"], s["frame_acc_y"]]
    want = [track_alignment.estimate(*args, step=H, settings={"lag": lag})["alignment_lagged"] for lag in (0.0, 10.0)]
    got: dict[int, np.ndarray] = {}

    def work(i: int, lag: float) -> None:
        got[i] = track_alignment.estimate(*args, step=H, settings={"lag": lag})["alignment_lagged"]

    threads = [threading.Thread(target=work, args=(i, lag)) for i, lag in enumerate((0.0, 10.0))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for i in range(2):
        np.testing.assert_array_equal(got[i], want[i])


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda z: track_alignment.estimate(z, z, z, z[1:], step=H), "column 'frame_acc_y' has 999 samples, 'speed' has 1000"),
        (lambda z: track_alignment.estimate(z, z, z, z, step=H, settings={"no_such": 1}), "the estimator has no variable 'no_such'"),
        (lambda z: track_alignment.estimate(z, z, z, z, step=H, settings={"m": "heavy"}), "'m' = 'heavy': not a number"),
        (lambda z: track_alignment.estimate(z, z, z, z, step=-1.0), "step -1 s must be a positive number"),
        (lambda z: track_alignment.estimate(z - 30.0, z, z, z, step=H), "sample 1:"),
        (lambda z: track_alignment.band_metrics(z, z, z, z[1:]), "truth has 999 samples but its distance 1000"),
        (lambda z: track_alignment.bandpass(z, 0.05, 25.0, 3.0), "need 2 ds < short < long"),
        (lambda z: track_alignment.simulate("/no/such.fmu", 1.0), "/no/such.fmu"),
    ],
    ids=["unequal-columns", "unknown-setting", "bad-value", "bad-step", "impossible-speed",
         "metrics-lengths", "bad-band", "missing-fmu"],
)
def test_bad_input_raises_with_the_librarys_message(call, message):
    z = np.full(1000, 20.0)
    with pytest.raises(ValueError) as e:
        call(z)
    assert message in str(e.value)


def _write_recording(path, out, offset: float, scale: float) -> None:
    """A vehicle run as an instrumented train records it: speed and distance `scale` times the
    true ones, the distance from `offset` (the recording format of docs/python.md)."""
    n = len(out["time"]) - 1
    cols = {
        "time": (np.arange(n) + 1) * H,
        "speed": out["forward_speed"][1:] * scale,
        **{s: out[s][1:] for s in SENSORS},
        "distance": offset + scale * out["distance"][1:],
    }
    np.savetxt(path, np.column_stack(list(cols.values())), delimiter=",", header=",".join(cols), comments="")


def test_fit_from_recordings_is_the_command_lines(tmp_path):
    """track_alignment.fit runs `alignment-studies fit` with its parser and checks: a pass
    placed on the reference (its odometry errors recovered), a bank written; bad input raises
    ValueError naming the file, and leaves nothing at `out`."""
    run = track_alignment.simulate(
        packaged_fmus()["RailVehicle"], 100.0, step=H, parameters={"track_seed": 101},
        variables=[*SENSORS, "forward_speed", "distance", "alignment"],
    )
    keep = np.searchsorted(run["distance"], np.arange(0.0, run["distance"][-1], 0.25))
    np.savetxt(tmp_path / "reference.csv", np.column_stack([run["distance"][keep], run["alignment"][keep]]),
               delimiter=",", header="distance,alignment", comments="")
    _write_recording(tmp_path / "pass.csv", run, offset=11.0, scale=1.004)
    report = track_alignment.fit(tmp_path / "fitted", recordings=[tmp_path / "pass.csv"],
                                 reference=tmp_path / "reference.csv")
    row = next(line for line in report.splitlines() if line.startswith("| ") and "pass.csv" in line)
    offset, scale = (float(c) for c in row.split("|")[2:4])
    # Recorded odometry = 11 + 1.004 x true position: true = start - 11 + (odometry - start) / 1.004.
    assert abs(offset - (-11.0)) < 0.5, row
    assert abs(scale - (1 / 1.004 - 1) * 100) < 0.02, row
    assert sorted(p.name for p in (tmp_path / "fitted").iterdir()) == ["fitted.taps", "report.md"]
    assert (tmp_path / "fitted" / "report.md").read_text() == report

    # A reference with a gap: named, with its line; nothing written.
    lines = (tmp_path / "reference.csv").read_text().splitlines()
    (tmp_path / "gap.csv").write_text("\n".join(lines[:2000] + lines[2100:]) + "\n")
    with pytest.raises(ValueError) as e:
        track_alignment.fit(tmp_path / "gap-out", recordings=[tmp_path / "pass.csv"], reference=tmp_path / "gap.csv")
    assert "gap.csv" in str(e.value) and "gap of" in str(e.value), e.value
    assert not (tmp_path / "gap-out").exists()
    # An option the command refuses, by the command's own parser.
    with pytest.raises(ValueError) as e:
        track_alignment.fit(tmp_path / "x", recordings=[tmp_path / "pass.csv"])
    assert "--reference" in str(e.value), e.value
