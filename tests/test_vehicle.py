"""The RailVehicle FMU through fmpy: it validates, runs the standard case with signals of
plausible size, replays bit for bit from saved and serialized states (noise generator and
track included), resets to a fresh instance, runs in parallel threads, follows a speed input,
reads a measured track, and refuses impossible parameters with a message naming them."""

from __future__ import annotations

import threading
import uuid
from pathlib import Path

import fmpy
import numpy as np
import pytest
from fmpy.validation import validate_fmu

from fmi_harness import ERROR, OK, Slave, assert_another_builds_state_is_refused, slave_factory
from project import packaged_fmus

H = 1e-3
SENSORS = ["ws_acc_y", "ws_yaw_rate", "frame_acc_y"]
TRUTH = ["distance", "alignment", "vertical_profile", "cross_level", "ws_y", "ws_yaw", "ws_vy", "ws_yaw_rate_true", "frame_y", "frame_vy"]


@pytest.fixture(scope="module")
def vehicle_path() -> Path:
    return packaged_fmus()["RailVehicle"]


@pytest.fixture(scope="module")
def vehicle_md(vehicle_path):
    return fmpy.read_model_description(str(vehicle_path))


@pytest.fixture(scope="module")
def vehicle_dir(vehicle_path, tmp_path_factory) -> Path:
    return Path(fmpy.extract(str(vehicle_path), unzipdir=str(tmp_path_factory.mktemp("vehicle"))))


@pytest.fixture
def make_vehicle(vehicle_md, vehicle_dir):
    yield from slave_factory(vehicle_md, vehicle_dir, "vehicle")


def initialize(s: Slave, reals=None, integers=None, booleans=None, strings=None) -> int:
    s.fmu.setupExperiment(startTime=0.0)
    for name, value in (reals or {}).items():
        s.fmu.setReal([s.vr[name]], [value])
    for name, value in (integers or {}).items():
        s.fmu.setInteger([s.vr[name]], [value])
    for name, value in (booleans or {}).items():
        s.fmu.setBoolean([s.vr[name]], [value])
    for name, value in (strings or {}).items():
        s.fmu.setString([s.vr[name]], [value])
    s.fmu.enterInitializationMode()
    return s.call("fmi2ExitInitializationMode")


def run(s: Slave, steps: int, t0: float = 0.0, speed=20.0, names=SENSORS + TRUTH) -> np.ndarray:
    vrs = [s.vr[n] for n in names]
    out = np.empty((steps, len(names)))
    for k in range(steps):
        v = speed(t0 + k * H) if callable(speed) else speed
        s.fmu.setReal([s.vr["speed"]], [v])
        s.fmu.doStep(t0 + k * H, H)
        out[k] = s.fmu.getReal(vrs)
    return out


def rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(x))))


def test_fmpy_validation_finds_no_problems(vehicle_path):
    assert validate_fmu(str(vehicle_path)) == []


def test_declares_the_names_the_other_parts_rely_on(vehicle_md):
    by_name = {v.name: v for v in vehicle_md.modelVariables}
    assert by_name["speed"].causality == "input" and by_name["speed"].unit == "m/s" and float(by_name["speed"].start) == 20.0
    for name in SENSORS + TRUTH:
        assert by_name[name].causality == "output", name
    assert by_name["track_seed"].type == "Integer" and by_name["track_seed"].causality == "parameter"
    for name in ["conicity", "kalker_scale", "spectrum", "lateral_irregularity", "vertical_irregularity", "sensor_noise", "sigma_acc", "sigma_gyro", "harmonic_amplitude", "harmonic_wavelength"]:
        assert by_name[name].causality == "parameter", name
    estimator_guid = fmpy.read_model_description(str(packaged_fmus()["AlignmentEstimator"])).guid
    assert vehicle_md.guid != estimator_guid
    # Both are made by the build from what shapes the FMU (crate state-layout): RFC 9562
    # version 8 (custom) UUIDs, no braces.
    for g in (vehicle_md.guid, estimator_guid):
        assert uuid.UUID(g).version == 8 and str(uuid.UUID(g)) == g, g


def test_standard_run_through_simulate_fmu_has_plausible_signals(vehicle_path):
    r = fmpy.simulate_fmu(str(vehicle_path), stop_time=20.0, output_interval=H, output=SENSORS + TRUTH)
    assert r.shape[0] == 20001
    assert abs(r["distance"][-1] - 400.0) < 1e-6
    for name in SENSORS + TRUTH:
        assert np.all(np.isfinite(r[name])), name
    settled = r[r["time"] > 1.0]
    # Sizes measured on this model (20 m/s, German low disturbance, seed 1): ws_acc_y 0.23 m/s2,
    # ws_yaw_rate 5.5e-3 rad/s, frame_acc_y 0.28 m/s2, alignment 2.8 mm; wide plausibility bounds.
    assert 0.02 < rms(settled["ws_acc_y"]) < 2.0
    assert 5e-4 < rms(settled["ws_yaw_rate"]) < 0.05
    assert 0.02 < rms(settled["frame_acc_y"]) < 2.0
    assert 1e-3 < rms(settled["alignment"]) < 1e-2
    assert rms(settled["ws_y"] - settled["alignment"]) < rms(settled["alignment"])


def test_noise_is_exactly_the_difference_to_the_clean_signal_and_has_its_sigma(make_vehicle):
    s = make_vehicle()
    assert initialize(s, reals={"sigma_acc": 0.02}) == OK
    out = run(s, 5000, names=["ws_acc_y", "ws_acc_y_clean", "ws_yaw_rate", "ws_yaw_rate_true"])
    noise_acc, noise_gyro = out[:, 0] - out[:, 1], out[:, 2] - out[:, 3]
    assert abs(np.std(noise_acc) / 0.02 - 1) < 0.05
    assert abs(np.std(noise_gyro) / 0.0005 - 1) < 0.05
    quiet = make_vehicle("quiet")
    assert initialize(quiet, booleans={"sensor_noise": False}) == OK
    out = run(quiet, 500, names=["ws_acc_y", "ws_acc_y_clean"])
    assert np.array_equal(out[:, 0], out[:, 1])


@pytest.mark.parametrize("integers", [{}, {"sensor_grade": 2}], ids=["ideal", "mems"])
def test_restored_and_deserialized_states_replay_bit_identically(make_vehicle, integers):
    """Also with the MEMS preset's sensor errors: drift generator, anti-alias filters and
    quantization are part of the state."""
    s = make_vehicle()
    assert initialize(s, integers=integers) == OK
    run(s, 1000)
    state = s.fmu.getFMUstate()
    blob = s.fmu.serializeFMUstate(state)
    first = run(s, 500, t0=1.0)
    s.fmu.setFMUstate(state)
    s.fmu.freeFMUstate(state)
    assert np.array_equal(run(s, 500, t0=1.0), first)
    other = make_vehicle("other")
    assert initialize(other, integers={"track_seed": 9, **integers}) == OK
    restored = other.fmu.deSerializeFMUstate(blob)
    other.fmu.setFMUstate(restored)
    other.fmu.freeFMUstate(restored)
    assert np.array_equal(run(other, 500, t0=1.0), first)


def test_a_state_of_another_build_is_refused_naming_its_layout(make_vehicle):
    s = make_vehicle("layout")
    assert initialize(s) == OK
    run(s, 100)
    assert_another_builds_state_is_refused(s)


def test_reset_gives_a_fresh_instance(make_vehicle):
    fresh = make_vehicle("fresh")
    assert initialize(fresh, integers={"track_seed": 3}) == OK
    expected = run(fresh, 300)
    used = make_vehicle("used")
    assert initialize(used, integers={"track_seed": 4}, reals={"kalker_scale": 0.5}) == OK
    run(used, 700)
    used.fmu.reset()
    assert initialize(used, integers={"track_seed": 3}) == OK
    assert np.array_equal(run(used, 300), expected)


def test_seeds_select_the_track(make_vehicle):
    a, b, c = make_vehicle("a"), make_vehicle("b"), make_vehicle("c")
    for s, seed in ((a, 5), (b, 5), (c, 6)):
        assert initialize(s, integers={"track_seed": seed}) == OK
    ra, rb, rc = (run(s, 1000, names=["alignment"]) for s in (a, b, c))
    assert np.array_equal(ra, rb)
    assert not np.array_equal(ra, rc)


def test_parallel_instances_match_sequential_runs(make_vehicle):
    seeds = [11, 12]

    def fresh(name: str, seed: int) -> Slave:
        s = make_vehicle(name)
        assert initialize(s, integers={"track_seed": seed, "noise_seed": seed}) == OK
        return s

    sequential = [run(fresh(f"seq{i}", seed), 1500) for i, seed in enumerate(seeds)]
    slaves = [fresh(f"thr{i}", seed) for i, seed in enumerate(seeds)]
    results: list = [None, None]
    barrier = threading.Barrier(2)

    def work(i: int) -> None:
        barrier.wait()
        results[i] = run(slaves[i], 1500)

    threads = [threading.Thread(target=work, args=(i,)) for i in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=120)
    for i in range(2):
        assert np.array_equal(results[i], sequential[i])


def test_speed_input_drives_the_distance(make_vehicle):
    s = make_vehicle()
    assert initialize(s) == OK

    def profile(t: float) -> float:  # accelerate from rest, then brake to 10 m/s
        return min(2.0 * t, 20.0) if t < 15.0 else max(20.0 - 2.0 * (t - 15.0), 10.0)

    out = run(s, 20000, speed=profile, names=["distance", "ws_acc_y"])
    expected = sum(profile(k * H) * H if profile(k * H) >= 0.5 else 0.0 for k in range(20000))
    assert abs(out[-1, 0] - expected) < 1e-6
    assert np.all(np.isfinite(out))


def test_a_measured_track_is_followed(make_vehicle, tmp_path):
    d = np.arange(-30.0, 300.0, 0.1)
    alignment = 1e-3 * np.sin(2 * np.pi * d / 40.0)
    csv = tmp_path / "track.csv"
    csv.write_text("distance,alignment,vertical,cross_level\n" + "\n".join(f"{x},{a:.12e},0,0" for x, a in zip(d, alignment)))
    s = make_vehicle()
    assert initialize(s, reals={"ramp_length": 0.0}, strings={"track_file": str(csv)}) == OK
    out = run(s, 5000, names=["distance", "alignment"])
    assert np.allclose(out[:, 1], 1e-3 * np.sin(2 * np.pi * out[:, 0] / 40.0), atol=1e-8)


@pytest.mark.parametrize(
    "setting, word",
    [
        ({"integers": {"spectrum": 7}}, "spectrum"),
        ({"strings": {"vehicle": "no_such_vehicle.toml"}}, "vehicle"),
        ({"reals": {"min_wavelength": 300.0}}, "wavelength"),
        ({"strings": {"track_file": "/nonexistent/track.csv"}}, "/nonexistent/track.csv"),
        ({"strings": {"track_file": "/dev/zero"}}, "/dev/zero: the track file is not a regular file"),
        ({"strings": {"vehicle": "/dev/zero"}}, "/dev/zero: the vehicle file is not a regular file"),
        ({"reals": {"ws_acc_y_misalignment": 0.5}}, "ws_acc_y_misalignment"),
        ({"reals": {"ws_yaw_rate_bias_instability": 1e-4}}, "ws_yaw_rate_bias_tau"),
        ({"reals": {"frame_acc_y_scale_error": -1.0}}, "frame_acc_y_scale_error"),
    ],
)
def test_impossible_parameters_are_refused_naming_them(make_vehicle, setting, word):
    s = make_vehicle()
    assert initialize(s, **setting) == ERROR
    errors = [r.message for r in s.log.records if r.status == ERROR]
    assert any(word in m for m in errors), s.log.records


def test_a_vehicle_that_leaves_the_track_stops_with_an_error_naming_it(tmp_path):
    """A physically impossible state stops the run: with its Kalker coefficients halved the
    ML95 hunts at 30 m/s until its leading wheelset is 0.37 m off the track (the model's flange
    is a spring, so nothing else stops it). The FMU returns fmi2Error once the wheelset is past
    the flange clearance by a flange width (39 mm), the master exits 3 keeping the rows until
    then; at 25 m/s the same vehicle runs on."""
    import orchestrator_cli as oc

    fmu = oc.fmus()["RailVehicle"]
    out = tmp_path / "out"
    p = oc.run("simulate", fmu, "--stop", "20", "--quiet", "--set", "kalker_scale=0.5", "--set", "speed=30",
               "--out", out, "--record", "ws_y,alignment", check=3)
    assert "derailed" in p.stderr and "hunting" in p.stderr and "30 m/s" in p.stderr, p.stderr
    r = oc.read_results(out)
    relative = np.abs(r["RailVehicle.ws_y"] - r["RailVehicle.alignment"])
    assert 5.0 < r.time[-1] < 20.0 and relative.max() <= 0.039 + 1e-9
    oc.run("simulate", fmu, "--stop", "20", "--quiet", "--no-record", "--set", "kalker_scale=0.5", "--set", "speed=25")


def test_sensor_errors_compose_as_documented_against_the_true_signals(make_vehicle):
    """Without noise and vertical irregularities (so the vertical specific force is g), every
    sample is the documented chain of the true signals: misalignment, scale, bias."""
    s = make_vehicle()
    m, k, b = 0.004, 0.03, 0.02
    assert initialize(s, booleans={"sensor_noise": False, "vertical_irregularity": False}, reals={
        "ws_acc_y_misalignment": m, "ws_acc_y_scale_error": k, "ws_acc_y_bias": b,
        "ws_yaw_rate_misalignment": m, "ws_yaw_rate_scale_error": k, "ws_yaw_rate_bias": 1e-3,
    }) == OK
    out = run(s, 2000, names=["ws_acc_y", "ws_acc_y_clean", "ws_yaw_rate", "ws_yaw_rate_true",
                              "ws_roll_rate_true"])
    acc = (1 + k) * (np.cos(m) * out[:, 1] + np.sin(m) * 9.81) + b
    gyro = (1 + k) * (np.cos(m) * out[:, 3] + np.sin(m) * out[:, 4]) + 1e-3
    assert np.allclose(out[:, 0], acc, rtol=0, atol=1e-12)
    assert np.allclose(out[:, 2], gyro, rtol=0, atol=1e-15)


def test_a_noise_density_gives_the_sigma_of_the_step(make_vehicle):
    """sigma = sqrt(psd / (2 h)): 5e-4 rad/s at 1 kHz from psd 5e-10 rad2/s, as sigma_gyro's
    default; quantized to 1e-4 rad/s the samples are multiples of it."""
    s = make_vehicle()
    assert initialize(s, reals={"ws_yaw_rate_noise_psd": 5e-10, "ws_yaw_rate_resolution": 1e-4}) == OK
    out = run(s, 5000, names=["ws_yaw_rate", "ws_yaw_rate_true"])
    assert abs(np.std(out[:, 0] - out[:, 1]) / 5e-4 - 1) < 0.05
    assert np.allclose(out[:, 0] / 1e-4, np.round(out[:, 0] / 1e-4), rtol=0, atol=1e-9)


def test_the_anti_alias_filters_follow_a_stop_and_a_start_at_2_ms(make_vehicle):
    """The MEMS preset at 2 ms: moving, standing, moving again. The filtered samples stay
    within their errors' size of the true signal throughout (the filters redesigned for each
    substep used to jump, and standing at 2 ms made them unstable: 16 g)."""
    s = make_vehicle()
    assert initialize(s, integers={"sensor_grade": 2}) == OK
    names = ["ws_acc_y", "ws_acc_y_clean", "frame_acc_y", "frame_acc_y_clean", "ws_yaw_rate",
             "ws_yaw_rate_true"]
    vrs = [s.vr[n] for n in names]
    h, rows = 2e-3, []
    for k in range(750):
        t = k * h
        s.fmu.setReal([s.vr["speed"]], [0.0 if 250 <= k < 500 else 20.0])
        s.fmu.doStep(t, h)
        rows.append(s.fmu.getReal(vrs))
    out = np.array(rows)
    # Bias 9.8e-3, tilt 0.017, noise sigma 0.019 m/s2 (0.0023 rad/s): 10 sigma and the offsets.
    assert np.max(np.abs(out[:, 0] - out[:, 1])) < 0.25
    assert np.max(np.abs(out[:, 2] - out[:, 3])) < 0.25
    assert np.max(np.abs(out[:, 4] - out[:, 5])) < 0.03
    assert np.all(out[260:500, 5] == 0.0), "standing, the true yaw rate is 0"
