"""The learned FIR smoother through the command line: `alignment-studies learn` fits it on the
calibration seed, `alignment-studies smooth --learned` applies it to a recorded run of another seed,
and the accuracy is measured here with scipy's Butterworth filters (tests/evaluation.py), a
second implementation of the study's metrics."""

from __future__ import annotations

import numpy as np

import evaluation as ev
import orchestrator_cli as oc


def test_learned_smoother_from_the_command_line_beats_the_paper_in_d1(tmp_path):
    learned = tmp_path / "learned.json"
    # A shorter training run than the default 1000 s keeps the test quick.
    oc.studies("learn", "--stop", "200", "--out", learned, *oc.standard_fmu_args())
    run_dir = tmp_path / "run"
    oc.run(
        "run", "--out", run_dir, "--quiet", *oc.standard_case_args(),
        "--record", "vehicle.forward_speed,vehicle.ws_acc_y,vehicle.ws_yaw_rate,vehicle.frame_acc_y,vehicle.distance,vehicle.alignment",
    )
    smoothed = tmp_path / "smoothed.csv"
    oc.studies("smooth", run_dir / "results.csv", "--learned", learned, "--out", smoothed)
    run = oc.read_results(run_dir)
    out = oc.read_results(smoothed)
    assert out.columns[-2:] == ["alignment_learned", "alignment_hybrid"]
    # A row per row of results.csv, the first one too; each estimate is at its own distance.
    assert len(out["time"]) == len(run["time"])
    distance, truth = run["vehicle.distance"], run["vehicle.alignment"]
    ds = 0.05
    grid = np.arange(out["distance"][1], distance[-1], ds)

    # Row 0 (the vehicle at rest before its first step, speed 0) has no learned estimate.
    assert np.isnan(out["alignment_learned"][0]) and np.all(np.isfinite(out["alignment_learned"][1:]))

    def jrel(column: str, band: str) -> float:
        moving = np.isfinite(out[column])
        est = np.interp(grid, out["distance"][moving], out[column][moving])
        return ev.accuracy(est, np.interp(grid, distance, truth), ds, ev.BANDS[band]).Jrel

    # The paper's D1 Jrel is 0.48; the Kalman smoother (the paper's model, this command's
    # default) misses it on our vehicle (docs/cross-level.md), the learned one does not.
    assert jrel("alignment_learned", "D1") < 0.48
    assert jrel("alignment_hybrid", "D1") < 0.48
    assert jrel("alignment_hybrid", "whole") < 0.5 * jrel("alignment_smoothed", "whole")


def test_a_corrupt_learned_file_is_named(tmp_path):
    csv = tmp_path / "recorded.csv"
    rows = ["time,speed,ws_acc_y,ws_yaw_rate,frame_acc_y"] + [f"{k * 1e-3},20,0,0,0" for k in range(3000)]
    csv.write_text("\n".join(rows) + "\n")
    bad = tmp_path / "learned.json"
    bad.write_text('{"format": 1, "speed": 20}')
    p = oc.studies("smooth", csv, "--learned", bad, "--out", tmp_path / "out.csv", check=None)
    assert p.returncode != 0
    assert str(bad) in p.stderr and "not a learned smoother file" in p.stderr, p.stderr
    assert not (tmp_path / "out.csv").exists()


def test_the_default_estimate_does_not_drift_over_6_km(tmp_path):
    """Issue 13: the FMU's default `alignment` (learned, causal) stays within a few times the
    truth's rms over a run of several km, where the Kalman filter's random-walk estimate wanders
    (its long waves are unobservable). 300 s at 20 m/s, track seed 7 (neither a training,
    validation nor study evaluation seed). The drift is mostly the random walk the sensors'
    noise leaves, so the bounds come from several noise draws: 1.35 times the largest over the
    validation tracks 102-106 each with its own draw (`noise_seed` = track + 1000, as the
    studies run them): per 500 m the mean error 5.9 and the estimate's rms 6.3 times the truth's
    rms, the error's rms 3.3 times, the Kalman filter's largest error at least 2.1 times the
    default's. This run (one draw, the default noise seed) gives 3.2, 5.5, 3.0 and 2.4. The
    bounds are wider than the high-pass alone gave (3.3, 3.8, 2.2, 3.3 on the validation
    draws): the shelf after it lets more of the random walk through for the bands' sake
    (`KALMAN_SHELF`, studies/src/study/learned/taps.rs)."""
    run_dir = tmp_path / "run"
    oc.run(
        "run", "--out", run_dir, "--quiet", "--stop", "300", *oc.standard_case_args(),
        "--set", "vehicle.track_seed=7", "--interval", "0.01",
        "--record", "vehicle.distance,vehicle.alignment,estimator.distance,estimator.alignment,"
        "estimator.alignment_kalman,estimator.active_estimator",
    )
    r = oc.read_results(run_dir)
    assert r["estimator.distance"][-1] > 5900.0
    assert np.all(r["estimator.active_estimator"][200:] == 2), "the learned filter is active"
    truth = np.interp(r["estimator.distance"], r["vehicle.distance"], r["vehicle.alignment"])
    truth_rms = np.sqrt(np.mean(truth**2))
    learned_error = r["estimator.alignment"] - truth
    kalman_error = r["estimator.alignment_kalman"] - truth
    # Per 500 m: the mean error (the drift) and the estimate's rms.
    edges = np.arange(0.0, 6000.0, 500.0)
    for a in edges:
        m = (r["estimator.distance"] >= a) & (r["estimator.distance"] < a + 500.0)
        assert abs(np.mean(learned_error[m])) < 8.0 * truth_rms, f"drift at {a} m"
        assert np.sqrt(np.mean(r["estimator.alignment"][m] ** 2)) < 8.5 * truth_rms, f"rms at {a} m"
    assert np.sqrt(np.mean(learned_error**2)) < 4.5 * truth_rms
    # The test can fail: the Kalman filter alone drifts beyond these bounds on the same run.
    assert np.max(np.abs(kalman_error)) > 1.5 * np.max(np.abs(learned_error))
