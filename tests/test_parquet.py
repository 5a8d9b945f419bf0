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


# --- One Parquet dialect (issue 25): every codec pyarrow and pandas write, both directions. ---

CODECS = ["snappy", "zstd", "gzip", "lz4", "brotli", "none"]


@pytest.mark.parametrize("codec", CODECS)
def test_smooth_reads_every_codec_pyarrow_writes(recorded, tmp_path, codec):
    """pyarrow's default (snappy, also pandas'), the bindings' zstd and the other codecs it
    offers: `smooth` gives from each what it gives from the CSV, bit for bit."""
    csv, _, cols = recorded
    src = tmp_path / f"signals_{codec}.parquet"
    pq.write_table(pa.table(cols), src, compression=codec)
    assert pq.ParquetFile(src).metadata.row_group(0).column(0).compression == codec.upper().replace("NONE", "UNCOMPRESSED")
    oc.studies("smooth", csv, "--out", tmp_path / "want.csv")
    oc.studies("smooth", src, "--out", tmp_path / "got.csv")
    assert (tmp_path / "got.csv").read_bytes() == (tmp_path / "want.csv").read_bytes()


def test_simulate_reads_pandas_default_parquet(recorded, tmp_path):
    """pandas' `to_parquet` (snappy, a pandas index column left out) as the estimator's input."""
    import pandas as pd

    csv, _, cols = recorded
    src = tmp_path / "pandas.parquet"
    pd.DataFrame(cols).to_parquet(src, index=False)
    est = oc.fmus()["AlignmentEstimator"]
    outs = {}
    for s in (csv, src):
        oc.run("simulate", est, "--input", s, "--stop", "2", "--step", "0.001", "--quiet", "--replay",
               "--out", tmp_path / s.suffix[1:])
        outs[s.suffix] = oc.read_results(tmp_path / s.suffix[1:])
    np.testing.assert_array_equal(outs[".csv"]["AlignmentEstimator.alignment"], outs[".parquet"]["AlignmentEstimator.alignment"])


@pytest.fixture(scope="module")
def synthetic_pass(tmp_path_factory):
    """One pass of the synthetic fleet (track_alignment.synthetic: zstd, with the recording
    format's `distance` column), 150 m at 15-25 m/s."""
    synthetic = pytest.importorskip("track_alignment.synthetic", reason="the bindings are built into .venv by `cargo xtask test`")
    from project import packaged_fmus

    d = tmp_path_factory.mktemp("synthetic")
    [path] = synthetic.synthesize(d, packaged_fmus()["RailVehicle"], passes=1, length=150.0)
    return path


def test_a_synthetic_recording_through_simulate_equals_the_fleet_path_bit_for_bit(synthetic_pass, tmp_path):
    """The bindings' recording (zstd, `distance` column) through `orchestrator simulate` (the
    estimator FMU at its nominal step, 1 ms), results written as Parquet and read back by the
    bindings' reader; the fleet pipeline's estimate of the same recording is the FMU's bit for
    bit, because the step it infers is the nominal 1e-3 and not the neighbours' difference."""
    from track_alignment import fleet, recordings

    assert pq.ParquetFile(synthetic_pass).metadata.row_group(0).column(0).compression == "ZSTD"
    cols, step = recordings.read_recording(synthetic_pass)
    assert step == 1e-3, step
    # The time column as the FMU wrote it: the median neighbour difference is not the step.
    assert float(np.median(np.diff(cols["time"]))) != 1e-3
    n = len(cols["time"])
    p = oc.run("simulate", oc.fmus()["AlignmentEstimator"], "--input", synthetic_pass, "--replay",
               "--stop", repr(n * 1e-3), "--step", "0.001", "--quiet", "--out", tmp_path / "sim",
               "--results", "estimate.parquet")
    assert "input column 'distance' is not an input" in p.stderr and "ignored" in p.stderr, p.stderr
    fmu, _ = recordings.read_table(tmp_path / "sim" / "estimate.parquet")
    assert len(fmu["time"]) == n + 1  # row 0: t = 0, before the first sample
    _, out = fleet.estimate_recording(str(synthetic_pass))
    for name in ("alignment", "alignment_lagged", "distance"):
        assert fmu[f"AlignmentEstimator.{name}"][1:].tobytes() == out[name].tobytes(), name


def test_a_synthetic_recording_through_smooth(synthetic_pass, tmp_path):
    """`smooth` reads the bindings' zstd recording with its `distance` column, and the bindings'
    reader reads its Parquet output."""
    from track_alignment import recordings

    oc.studies("smooth", synthetic_pass, "--out", tmp_path / "s.parquet")
    got, provenance = recordings.read_table(tmp_path / "s.parquet")
    assert provenance["command"] == "alignment-studies smooth"
    assert {"time", "alignment_filtered", "alignment_smoothed"} <= set(got), list(got)
    assert np.isfinite(got["alignment_smoothed"]).all()
    n = len(recordings.read_table(synthetic_pass)[0]["time"])
    assert n - 1 <= len(got["time"]) <= n


def test_an_unknown_column_is_still_refused(recorded, tmp_path):
    """Only the recording format's `distance` is ignored: a typo is refused, not silently
    left at the input's start value."""
    _, _, cols = recorded
    src = tmp_path / "typo.parquet"
    pq.write_table(pa.table({**cols, "ws_acc_x": cols["ws_acc_y"]}), src)
    p = oc.run("simulate", oc.fmus()["AlignmentEstimator"], "--input", src, "--stop", "0.1", "--step", "0.001",
               "--quiet", "--out", tmp_path / "o", check=None)
    assert p.returncode == 2 and "input column 'ws_acc_x'" in p.stderr, p.stderr
