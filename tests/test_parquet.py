"""Parquet recordings through the Rust commands (issue 16.2): `orchestrator simulate --input
x.parquet` and `alignment-studies smooth` read Parquet by extension and give what the same
signals in CSV give, bit for bit; `smooth --out x.parquet` and `orchestrator run/simulate
--results results.parquet` write the same values as their CSV, with units and provenance that
pyarrow (an independent reader) sees; bad files are named."""

from __future__ import annotations

import json

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

import orchestrator_cli as oc


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    """2 s of the vehicle's sensors (the standard case), as CSV and as Parquet written by
    pyarrow with nullable columns (pyarrow's default: OPTIONAL, the path other tools take)."""
    d = tmp_path_factory.mktemp("parquet")
    oc.studies("run", "--stop", "2", "--quiet", "--out", d / "run", *oc.standard_fmu_args(),
               "--record", "vehicle.forward_speed,vehicle.ws_acc_y,vehicle.ws_yaw_rate,vehicle.frame_acc_y")
    rec = oc.read_results(d / "run")
    names = {"time": "time", "speed": "vehicle.forward_speed", "ws_acc_y": "vehicle.ws_acc_y",
             "ws_yaw_rate": "vehicle.ws_yaw_rate", "frame_acc_y": "vehicle.frame_acc_y"}
    cols = {k: np.asarray(rec[v], dtype=np.float64) for k, v in names.items()}
    csv = d / "signals.csv"
    csv.write_text(",".join(cols) + "\n" + "\n".join(",".join(repr(float(x)) for x in row) for row in zip(*cols.values())) + "\n")
    parquet = d / "signals.parquet"
    pq.write_table(pa.table(cols), parquet)
    return csv, parquet, cols


def test_simulate_reads_parquet_input_as_csv(recorded, tmp_path):
    csv, parquet, _ = recorded
    est = oc.fmus()["AlignmentEstimator"]
    outs = {}
    for src in (csv, parquet):
        out = tmp_path / src.suffix[1:]
        oc.run("simulate", est, "--input", src, "--stop", "2", "--step", "0.001", "--quiet", "--replay", "--out", out)
        outs[src.suffix] = oc.read_results(out)
    a, b = outs[".csv"], outs[".parquet"]
    for col in ("AlignmentEstimator.alignment", "AlignmentEstimator.alignment_kalman"):
        np.testing.assert_array_equal(a[col], b[col], err_msg=col)


def test_smooth_reads_and_writes_parquet(recorded, tmp_path):
    csv, parquet, _ = recorded
    oc.studies("smooth", csv, "--out", tmp_path / "s.csv")
    oc.studies("smooth", parquet, "--out", tmp_path / "s.parquet")
    want = np.genfromtxt(tmp_path / "s.csv", delimiter=",", names=True)
    table = pq.read_table(tmp_path / "s.parquet")
    assert table.column_names == list(want.dtype.names)
    for name in want.dtype.names:
        np.testing.assert_array_equal(table.column(name).to_numpy(), want[name], err_msg=name)
    meta = table.schema.metadata
    assert json.loads(meta[b"units"]) == {n: ("s" if n == "time" else "m") for n in want.dtype.names}
    provenance = json.loads(meta[b"provenance"])
    assert provenance["command"] == "alignment-studies smooth" and provenance["input"] == str(parquet)
    assert not list(tmp_path.glob("*.partial"))


def test_bad_parquet_files_are_named(recorded, tmp_path):
    corrupt = tmp_path / "corrupt.parquet"
    corrupt.write_bytes(b"PAR1 not a parquet file PAR1")
    p = oc.studies("smooth", corrupt, "--out", tmp_path / "s.parquet", check=None)
    assert p.returncode == 2 and str(corrupt) in p.stderr and "not a readable Parquet file" in p.stderr, p.stderr
    holed = tmp_path / "holed.parquet"
    _, _, cols = recorded
    with_null = dict(cols)
    with_null["ws_acc_y"] = pa.array([*cols["ws_acc_y"][:5], None, *cols["ws_acc_y"][6:]], pa.float64())
    pq.write_table(pa.table(with_null), holed)
    p = oc.studies("smooth", holed, "--out", tmp_path / "h.csv", check=None)
    assert p.returncode == 2 and "column 'ws_acc_y' row 6: null" in p.stderr, p.stderr
    assert not (tmp_path / "s.parquet").exists() and not (tmp_path / "h.csv").exists()


def test_run_and_simulate_write_parquet_results_equal_to_csv(recorded, tmp_path):
    """The standard case's results as Parquet: pyarrow reads the CSV run's values bit for bit,
    its units file as the `units` metadata and its manifest.json as the `provenance`; `simulate`
    of the estimator on the recorded sensors writes as Parquet what it writes as CSV."""
    runs = {}
    for name in ("results.csv", "results.parquet"):
        out = tmp_path / name.split(".")[1]
        oc.run("run", *oc.standard_case_args(), "--stop", "1.5", "--quiet", "--out", out, "--results", name)
        runs[name] = out
    csv = oc.read_results(runs["results.csv"])
    table = pq.read_table(runs["results.parquet"] / "results.parquet")
    assert table.column_names == csv.columns
    for i, name in enumerate(csv.columns):
        np.testing.assert_array_equal(table.column(name).to_numpy(), csv.values[:, i], err_msg=name)
    names, units = oc.read_units(runs["results.csv"] / "results.units.csv")
    assert json.loads(table.schema.metadata[b"units"]) == {n: u for n, u in zip(names, units) if u}
    manifest = json.loads((runs["results.parquet"] / "manifest.json").read_text())
    assert json.loads(table.schema.metadata[b"provenance"]) == manifest
    assert manifest["files"] == ["results.parquet"] and [f["component"] for f in manifest["fmus"]] == ["vehicle", "estimator"]
    assert sorted(p.name for p in runs["results.parquet"].iterdir()) == ["manifest.json", "results.parquet"]

    # simulate: the estimator on the recorded sensors, results as Parquet and as CSV.
    signals, _, _ = recorded
    est = oc.fmus()["AlignmentEstimator"]
    for name in ("estimate.csv", "estimate.parquet"):
        oc.run("simulate", est, "--input", signals, "--replay", "--stop", "2", "--step", "0.001", "--quiet",
               "--out", tmp_path / "simulate", "--results", name)
        if name.endswith(".csv"):
            want = oc.read_results(tmp_path / "simulate" / name)
    got = pq.read_table(tmp_path / "simulate" / "estimate.parquet")
    assert got.column_names == want.columns and got.num_rows == 2001
    for i, name in enumerate(want.columns):
        np.testing.assert_array_equal(got.column(name).to_numpy(), want.values[:, i], err_msg=name)
    # The second run into the directory removed the first one's CSV and units (its manifest's).
    assert sorted(p.name for p in (tmp_path / "simulate").iterdir()) == ["estimate.parquet", "manifest.json"]

    # The next run into the directory, as CSV, removes the Parquet file its manifest lists.
    oc.run("run", *oc.standard_case_args(), "--stop", "0.1", "--quiet", "--out", runs["results.parquet"])
    assert not (runs["results.parquet"] / "results.parquet").exists()


@pytest.mark.parametrize("name", ["sub/results.parquet", "results.txt", "../results.csv"])
def test_a_results_name_that_is_not_a_plain_csv_or_parquet_name_is_refused(name, tmp_path):
    p = oc.run("run", *oc.standard_case_args(), "--stop", "0.1", "--quiet", "--out", tmp_path / "o",
               "--results", name, check=None)
    assert p.returncode == 2 and f"--results {name}: expected a plain file name ending in .csv or .parquet" in p.stderr, p.stderr
    assert not (tmp_path / "o").exists()
