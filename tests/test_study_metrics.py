"""The studies' band metrics (metrics.json of `alignment-studies run`) against scipy: the same
procedure (common uniform distance grid of 0.05 m by linear interpolation, butter order 4
band-pass as second-order sections, sosfiltfilt, 10 m trimmed at each end, J and Jrel)
implemented independently with numpy and scipy must give the same numbers."""

from __future__ import annotations

import json
import subprocess

import numpy as np
from scipy.signal import butter, sosfiltfilt

from orchestrator_cli import studies_binary
from project import fmu_dir

BANDS = {"whole": (3.0, 200.0), "D1": (3.0, 25.0), "D2": (25.0, 70.0), "D3": (70.0, 200.0)}
DS, TRIM = 0.05, 10.0


def scipy_metrics(table) -> dict[str, tuple[float, float]]:
    de, e = table["estimator.distance"][1:], table["estimator.alignment"][1:]
    dt, t = table["vehicle.distance"][1:], table["vehicle.alignment"][1:]
    start, end = max(de[0], dt[0]), min(de[-1], dt[-1])
    grid = start + DS * np.arange(int(np.floor((end - start) / DS)) + 1)
    e, t = np.interp(grid, de, e), np.interp(grid, dt, t)
    out = {}
    n = int(round(TRIM / DS))
    for name, (short, long) in BANDS.items():
        sos = butter(4, [1 / long, 1 / short], btype="bandpass", fs=1 / DS, output="sos")
        fe, ft = sosfiltfilt(sos, e)[n:-n], sosfiltfilt(sos, t)[n:-n]
        j = np.sqrt(np.mean((fe - ft) ** 2))
        out[name] = (j * 1e3, j / np.sqrt(np.mean(ft**2)))
    return out


def test_band_metrics_match_scipy(tmp_path):
    subprocess.run(
        [str(studies_binary()), "run", "--stop", "20", "--quiet", "--out", str(tmp_path),
         "--vehicle", str(fmu_dir() / "RailVehicle.fmu"), "--estimator", str(fmu_dir() / "AlignmentEstimator.fmu"),
         "--record", "vehicle.distance,vehicle.alignment,estimator.distance,estimator.alignment"],
        check=True, capture_output=True,
    )
    ours = json.loads((tmp_path / "metrics.json").read_text())["bands"]
    table = np.genfromtxt(tmp_path / "results.csv", delimiter=",", names=True, deletechars="")
    theirs = scipy_metrics(table)
    for name, (j, jrel) in theirs.items():
        assert abs(ours[name]["J_mm"] - j) <= 1e-9 * j, (name, ours[name], j)
        assert abs(ours[name]["Jrel"] - jrel) <= 1e-9 * jrel, (name, ours[name], jrel)
