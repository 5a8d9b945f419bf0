"""The fleet pipeline (track_alignment.fleet) on a synthetic fleet of the vehicle FMU: 50 passes
over one track (seed 1, 1 km) at speeds of 15-25 m/s, with new and worn contact (Kalker 100 and
75 %), and 10 passes over each of four more held-out tracks (seeds 2-5). Oracles: the tracks'
true alignment processed the same way; the same result from 1 and 2 Dask workers; pyarrow
reading the recordings back."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from project import packaged_fmus

fleet = pytest.importorskip("track_alignment.fleet", reason="the bindings are built into .venv by `cargo xtask test`")
from track_alignment import recordings, synthetic  # noqa: E402

PASSES = 50
#: The stated tolerance (docs/python.md): every segment's D1 and D2 SD, of the average of the
#: passes, within this fraction of the truth's.
TOLERANCE = 0.05
#: Held-out track seeds besides 1, with fewer passes each (the error of the average is mostly
#: the one every pass shares: 10 passes show it).
MORE_SEEDS, MORE_PASSES = (2, 3, 4, 5), 10


@pytest.fixture(scope="module")
def fleet_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("fleet")
    synthetic.synthesize(out, packaged_fmus()["RailVehicle"], passes=PASSES, track_seed=1, length=1000.0)
    return out


def local_run(fleet_dir, out, workers: int) -> pd.DataFrame:
    from dask.distributed import Client, LocalCluster

    with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster, \
            Client(cluster) as client:
        assert len(client.scheduler_info()["workers"]) == workers
        return fleet.run([fleet_dir], out, client=client, truth=fleet_dir / "truth.parquet")


def test_one_and_two_workers_give_identical_segment_tables(fleet_dir, tmp_path):
    one = local_run(fleet_dir, tmp_path / "one", 1)
    two = local_run(fleet_dir, tmp_path / "two", 2)
    pd.testing.assert_frame_equal(one, two, check_exact=True)
    assert len(one) == 5 and (one["passes"] == PASSES).all()
    # Written as read back, and the map was drawn.
    pd.testing.assert_frame_equal(pd.read_parquet(tmp_path / "one" / "segments.parquet"), one, check_exact=True)
    assert len(pd.read_parquet(tmp_path / "one" / "passes.parquet")) == PASSES * 5
    assert (tmp_path / "one" / "map.png").stat().st_size > 10_000
    # The table's SDs are the corrected ones (fleet.SD_MODEL): within the stated tolerance of
    # the truth's.
    for k in fleet.BANDS:
        assert np.all(np.abs(one[f"{k}_sd_mm"] / one[f"{k}_truth_sd_mm"] - 1) < TOLERANCE), one


def first_passes(coverages, n: int):
    """The sum of the first `n` passes' coverages, by the pipeline's own reduction (fleet.tree_sum)."""
    import dask

    return dask.compute(fleet.tree_sum(coverages[:n]))[0]


def segment_errors(coverages, sds_truth, options, n: int) -> dict[str, np.ndarray]:
    """Relative error per segment of the SD of the first `n` passes' average, with the
    pipeline's correction for the estimate's in-band gain (fleet.SD_MODEL)."""
    total = first_passes(coverages, n)
    mean = {k: np.where(total.count > 0, x / np.maximum(total.count, 1), np.nan) for k, x in total.bands.items()}
    sds = fleet.corrected(fleet.segment_sds(total.start, mean, options), n)
    m = min(len(sds["d1"]), len(sds_truth["d1"]))
    return {k: sds[k][:m] / sds_truth[k][:m] - 1.0 for k in fleet.BANDS}


def test_segment_sds_agree_with_the_truth_and_the_average_is_the_passes_mean(fleet_dir):
    options = fleet.Options()
    files = fleet.expand([fleet_dir])
    coverages = [fleet.estimate_pass(f, options)[0] for f in files]
    truth = fleet.truth_sds(fleet_dir / "truth.parquet", options)
    curve = {n: segment_errors(coverages, truth, options, n) for n in (1, 5, 50)}
    rms = {n: {k: float(np.sqrt(np.nanmean(e[k] ** 2))) for k in e} for n, e in curve.items()}
    print("rms relative error of the segment SDs by number of passes:", rms)
    # Stated tolerance (docs/python.md), for the average of the 50 passes.
    for k in fleet.BANDS:
        assert np.nanmax(np.abs(curve[50][k])) < TOLERANCE, (k, curve[50][k])
    # The pipeline's average is the passes' mean, against numpy's on the stacked passes.
    total = first_passes(coverages, len(coverages))
    stacked = np.full((len(coverages), len(total.count)), np.nan)
    for row, c in zip(stacked, coverages):
        row[c.start - total.start:c.start - total.start + len(c.count)] = c.bands["d1"]
    covered = total.count > 0
    np.testing.assert_allclose(total.bands["d1"][covered] / total.count[covered],
                               np.nanmean(stacked[:, covered], axis=0), rtol=1e-9, atol=1e-15)
    assert (total.count == np.isfinite(stacked).sum(axis=0)).all()
    # Measured, not asserted (docs/python.md): the learned estimator's D1 error is nearly the
    # same on every pass over a track (it comes from the track's cross-level), so averaging
    # 5 or 50 passes moves the segment SDs' error by a fraction of a percent.
    signal = {n: d1_signal_error(coverages, fleet_dir / "truth.parquet", options, n) for n in (1, 5, 50)}
    print("rms D1 error of the passes' average against the truth [mm]:", signal)


@pytest.fixture(scope="module")
def more_fleets(tmp_path_factory):
    out = {}
    for seed in MORE_SEEDS:
        out[seed] = tmp_path_factory.mktemp(f"fleet{seed}")
        synthetic.synthesize(out[seed], packaged_fmus()["RailVehicle"], passes=MORE_PASSES, track_seed=seed,
                             length=1000.0, seed=seed)
    return out


def test_segment_sds_agree_with_the_truth_on_more_track_seeds(more_fleets):
    """The accuracy claim on four more held-out track seeds (their own speeds), 10 passes each:
    every segment's corrected D1 and D2 SD within the tolerance, and not all on one side."""
    options = fleet.Options()
    errors = {k: [] for k in fleet.BANDS}
    for seed, d in more_fleets.items():
        coverages = [fleet.estimate_pass(f, options)[0] for f in fleet.expand([d])]
        truth = fleet.truth_sds(d / "truth.parquet", options)
        e = segment_errors(coverages, truth, options, MORE_PASSES)
        for k in fleet.BANDS:
            errors[k].extend(e[k][np.isfinite(e[k])])
    print("segment SD errors, seeds", MORE_SEEDS, {k: np.round(np.array(v) * 100, 2).tolist() for k, v in errors.items()})
    for k, v in errors.items():
        v = np.array(v)
        assert len(v) == 5 * len(MORE_SEEDS)
        assert np.max(np.abs(v)) < TOLERANCE, (k, v)
        # Unbiased: the old SDs were low in 36 of 40 segment values.
        assert 0.2 < np.mean(v < 0) < 0.8, (k, v)


def d1_signal_error(coverages, truth_file, options, n: int) -> float:
    """Rms [mm] of the first `n` passes' average D1 band minus the truth's, where all `n` cover."""
    total = first_passes(coverages, n)
    first, bands = fleet.truth_bands(truth_file, options)
    truth = bands["d1"]
    lo, hi = max(first, total.start), min(first + len(truth), total.start + len(total.count))
    count = total.count[lo - total.start:hi - total.start]
    mean = total.bands["d1"][lo - total.start:hi - total.start] / np.maximum(count, 1)
    err = np.where(count == n, mean, np.nan) - truth[lo - first:hi - first]
    return float(np.sqrt(np.nanmean(err ** 2)) * 1e3)


def test_parquet_recordings_round_trip_with_units_and_provenance(fleet_dir, tmp_path):
    import pyarrow.parquet as pq

    cols, provenance = recordings.read_table(fleet_dir / "pass_0003.parquet")
    assert provenance["parameters"]["track_seed"] == 1 and provenance["pass"] == 3
    schema = pq.read_schema(fleet_dir / "pass_0003.parquet")
    assert schema.field("ws_yaw_rate").metadata[b"unit"] == b"rad/s"
    assert recordings.read_units(fleet_dir / "pass_0003.parquet")["frame_acc_y"] == "m/s2"
    again = tmp_path / "again.parquet"
    recordings.write_parquet(again, cols, provenance)
    back, prov = recordings.read_table(again)
    assert prov == provenance and list(back) == list(cols)
    for k in cols:
        assert back[k].tobytes() == cols[k].tobytes(), k
    # A CSV of the same recording gives the same estimate as the Parquet file.
    csv = tmp_path / "pass.csv"
    header = ",".join(cols)
    np.savetxt(csv, np.column_stack(list(cols.values())), delimiter=",", header=header, comments="", fmt="%.17g")
    a, b = fleet.estimate_pass(str(csv), fleet.Options()), fleet.estimate_pass(str(fleet_dir / "pass_0003.parquet"), fleet.Options())
    np.testing.assert_array_equal(a[0].bands["d1"], b[0].bands["d1"])


def test_the_command_line_names_bad_recordings(fleet_dir, tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("time,speed,ws_acc_y,ws_yaw_rate\n0,20,0,0\n0.001,20,0,0\n")
    cmd = [sys.executable, "-m", "track_alignment.fleet", str(bad), "--out", str(tmp_path / "o"), "--workers", "1"]
    p = subprocess.run(cmd, capture_output=True, text=True)
    assert p.returncode == 2, p.stderr
    assert str(bad) in p.stderr and "missing column(s) frame_acc_y" in p.stderr
    p = subprocess.run([*cmd[:3], str(tmp_path / "none*.parquet"), *cmd[4:]], capture_output=True, text=True)
    assert p.returncode == 2 and "no such file, directory or match" in p.stderr, p.stderr
    jumpy = tmp_path / "jumpy.csv"
    jumpy.write_text("time,speed,ws_acc_y,ws_yaw_rate,frame_acc_y\n0,20,0,0,0\n0.001,20,0,0,0\n0.003,20,0,0,0\n")
    p = subprocess.run([*cmd[:3], str(jumpy), *cmd[4:]], capture_output=True, text=True)
    assert p.returncode == 2 and "time is not uniform at row" in p.stderr, p.stderr


def test_the_command_line_writes_the_map(fleet_dir, tmp_path):
    files = sorted(fleet_dir.glob("pass_000*.parquet"))[:4]
    out = tmp_path / "map"
    p = subprocess.run([sys.executable, "-m", "track_alignment.fleet", *map(str, files), "--out", str(out),
                        "--workers", "1", "--segment", "250"], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    seg = pd.read_parquet(out / "segments.parquet")
    assert list(seg["end_m"]) == [250.0, 500.0, 750.0, 1000.0] and (seg["passes"] == 4).all()
    assert "4 segments from 4 passes" in p.stdout
    assert json.loads((out / "manifest.json").read_text())["sd_model"] == "learned.taps"
    assert "warning" not in p.stderr, p.stderr
    # Told the contact, the estimate is another one, for which no SD model was measured: said
    # once, the SDs left as they are, and the manifest says so.
    told = tmp_path / "told"
    p = subprocess.run([sys.executable, "-m", "track_alignment.fleet", *map(str, files), "--out", str(told),
                        "--workers", "1", "--segment", "250", "--set", "kalker_scale=1"], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    assert p.stderr.count("warning: no SD model was measured for the estimator settings kalker_scale=1") == 1, p.stderr
    assert json.loads((told / "manifest.json").read_text())["sd_model"] is None


def test_the_sd_model_is_the_one_measured_for_the_settings():
    """The correction's model follows the tap file; settings that change the estimate have none
    and leave the SDs as they are; the line's settings keep the model."""
    assert fleet.sd_model(None) == ("learned.taps", fleet.SD_MODEL)
    assert fleet.sd_model({"line_file": "metro-line.csv", "lag": 0}) == ("learned.taps", fleet.SD_MODEL)
    bank = fleet.sd_model({"tap_file": "learned-conicity.taps"})
    assert bank is not None and bank[0] == "learned-conicity.taps" and bank[1] != fleet.SD_MODEL
    for other in ({"kalker_scale": 1.0}, {"tap_file": "learned-conicity.taps", "conicity": 0.2},
                  {"use_roll_rate": True}, {"tap_file": "/data/fitted.taps"}):
        assert fleet.sd_model(other) is None, other
    sds = {"d1": np.array([1.0, 2.0]), "d2": np.array([3.0, np.nan]), "segment": np.array([0, 1])}
    same = fleet.corrected(sds, 5, None)
    for k in sds:
        np.testing.assert_array_equal(same[k], sds[k])
    # The bank's model: SD(average of n) / SD(truth) = sqrt(g^2 + shared + independent / n).
    g2, shared, independent = bank[1]["d1"]
    out = fleet.corrected(sds, 5, bank[1])
    np.testing.assert_allclose(out["d1"], sds["d1"] / np.sqrt(g2 + shared + independent / 5), rtol=1e-15)
    np.testing.assert_array_equal(out["segment"], sds["segment"])


def test_recordings_at_2_ms_are_read_at_their_rate_and_meet_the_tolerance(tmp_path):
    """A fleet recorded every 2 ms (track seed 2, 10 passes): the pipeline takes the recordings'
    own step, and the segment SDs meet the same tolerance as at 1 ms (the Kalman filter runs on
    its 1 ms clock, the learned filter's grid is by distance)."""
    out = tmp_path / "fleet2ms"
    out.mkdir()
    synthetic.synthesize(out, packaged_fmus()["RailVehicle"], passes=MORE_PASSES, track_seed=2,
                         length=1000.0, seed=2, step=2e-3)
    files = fleet.expand([out])
    assert all(recordings.read_recording(f)[1] == 2e-3 for f in files)
    options = fleet.Options()
    coverages = [fleet.estimate_pass(f, options)[0] for f in files]
    e = segment_errors(coverages, fleet.truth_sds(out / "truth.parquet", options), options, MORE_PASSES)
    print("segment SD errors at 2 ms:", {k: np.round(v * 100, 2).tolist() for k, v in e.items()})
    for k in fleet.BANDS:
        assert np.nanmax(np.abs(e[k])) < TOLERANCE, (k, e[k])


def test_a_fleet_on_a_curved_line_meets_the_tolerance_with_the_design_in_its_recordings(tmp_path):
    """10 passes (track seed 3) over the first 1.1 km of the standard curved case's line (two
    curves, radius 600 and 1200 m), their recordings carrying the design line: the segment SDs
    meet the straight fleet's tolerance; the same passes without the design columns do not."""
    out = tmp_path / "curved"
    out.mkdir()
    synthetic.synthesize(out, packaged_fmus()["RailVehicle"], passes=MORE_PASSES, track_seed=3,
                         length=1100.0, seed=3, line_file="metro-line.csv")
    files = fleet.expand([out])
    cols, _ = recordings.read_recording(files[0])
    assert np.max(np.abs(cols["design_curvature"])) == pytest.approx(1 / 600, rel=1e-9)
    options = fleet.Options()
    truth = fleet.truth_sds(out / "truth.parquet", options)
    coverages = [fleet.estimate_pass(f, options)[0] for f in files]
    e = segment_errors(coverages, truth, options, MORE_PASSES)
    print("segment SD errors on the curved line:", {k: np.round(v * 100, 2).tolist() for k, v in e.items()})
    for k in fleet.BANDS:
        assert np.nanmax(np.abs(e[k])) < TOLERANCE, (k, e[k])
    # Without the design columns (a user who leaves them out), the curves swamp D2.
    blind = tmp_path / "blind"
    blind.mkdir()
    for f in files:
        c, _ = recordings.read_recording(f)
        recordings.write_parquet(blind / Path(f).name, {k: v for k, v in c.items() if not k.startswith("design")}, {})
    coverages = [fleet.estimate_pass(str(f), options)[0] for f in sorted(blind.iterdir())]
    e = segment_errors(coverages, truth, options, MORE_PASSES)
    assert np.nanmax(np.abs(e["d2"])) > 5 * TOLERANCE
