"""Monte-Carlo studies on Dask (track_alignment.montecarlo): each case a task, and each case's
figures equal to the studies' own (`alignment-studies variants`, the estimator FMU's table) for the same
seeds, conditions and estimators, to the last bit."""

from __future__ import annotations

import json

import pytest

import orchestrator_cli as oc
from project import packaged_fmus

mc = pytest.importorskip("track_alignment.montecarlo", reason="the bindings are built into .venv by `cargo xtask test`")

SEEDS = [1, 2]
#: study variants' condition key -> Kalker scale; its estimator names -> our estimator settings.
CONDITIONS = {"standard": 1.0, "kalker_75": 0.75, "kalker_50": 0.5}
ESTIMATORS = {"paper's filter (estimator 1)": {"estimator": 1}, "learned, causal (FMU default)": {}}


@pytest.fixture(scope="module")
def study(tmp_path_factory) -> dict:
    out = tmp_path_factory.mktemp("variants")
    oc.studies("variants", "--seeds", ",".join(map(str, SEEDS)), "--quiet", "--out", out, *oc.standard_fmu_args())
    return json.loads((out / "variants.json").read_text())


def test_dask_cases_equal_the_study(study):
    from dask.distributed import Client, LocalCluster

    cases = mc.grid(SEEDS, kalker_scales=list(CONDITIONS.values()))
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster, \
            Client(cluster) as client:
        table = mc.sweep(cases, packaged_fmus()["RailVehicle"], ESTIMATORS, client=client)
    assert len(table) == len(cases) * len(ESTIMATORS) * 4
    compared = 0
    for condition, scale in CONDITIONS.items():
        for entry in study["estimator_fmu"][condition]:
            if entry["name"] not in ESTIMATORS:
                continue
            for seed, theirs in zip(study["seeds"], entry["per_seed"]):
                for band, want in theirs.items():
                    row = table[(table.seed == seed) & (table.kalker_scale == scale)
                                & (table.estimator == entry["name"]) & (table.band == band)]
                    assert len(row) == 1
                    assert row.Jrel.iloc[0] == want["Jrel"], (condition, entry["name"], seed, band)
                    assert row.J_mm.iloc[0] == want["J_mm"], (condition, entry["name"], seed, band)
                    compared += 1
    assert compared == len(CONDITIONS) * len(ESTIMATORS) * len(SEEDS) * 4


def test_the_command_line_refuses_bad_arguments(tmp_path):
    import subprocess
    import sys

    base = [sys.executable, "-m", "track_alignment.montecarlo", "--seeds", "1", "--out", str(tmp_path / "r.parquet")]
    p = subprocess.run([*base, "--vehicle-fmu", str(tmp_path / "none.fmu")], capture_output=True, text=True)
    assert p.returncode == 2 and "none.fmu: no such FMU" in p.stderr, p.stderr
    p = subprocess.run([*base, "--vehicle-fmu", str(packaged_fmus()["RailVehicle"]), "--estimator", "x"],
                       capture_output=True, text=True)
    assert p.returncode == 2 and "expected label:name=value" in p.stderr, p.stderr
