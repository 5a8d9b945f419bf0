"""The fleet pipeline: many passes of many trains over one line -> a map of alignment quality
per track segment, on ``dask.distributed`` (a ``LocalCluster`` by default, or any scheduler:
Slurm through dask-jobqueue, Kubernetes through dask-kubernetes; docs/python.md, "The fleet
pipeline").

Steps, each recording one task:

1. read the recording (Parquet or CSV, :mod:`track_alignment.recordings`) and run the
   estimator over it (:func:`track_alignment.estimate`, the FMU's estimator, bit for bit);
2. put the estimate on the line's distance grid (``ds``, default 0.25 m) at the recording's
   positions (``distance``; the integral of ``speed`` without it), by linear interpolation;
3. band-pass it in EN 13848 D1 (3-25 m) and D2 (25-70 m) with the metrics' zero-phase
   Butterworth filter and drop ``trim`` metres at both ends of the pass;
4. per segment (``segment`` metres, 200 by default): the pass's standard deviation in each
   band, where the pass covers at least half the segment, divided by the SD ratio the
   estimate's in-band gain and error give (:data:`SD_MODELS`, measured for the shipped tap
   files told nothing; the average's likewise). Other estimator settings: left uncorrected,
   with a warning (:class:`UncorrectedWarning`).

The passes' band-passed estimates are summed in a fixed binary tree of tasks (so the result
does not depend on the number of workers or the order tasks finish), and averaged: averaging
removes the passes' independent errors (sensor noise, speeds, wheel wear), so the segment's
standard deviation of the average approaches the track's as passes are added.

Output (``out_dir``):

| file | what |
|---|---|
| ``segments.parquet`` | per segment: ``segment``, ``start_m``, ``end_m``, ``passes``, ``d1_sd_mm`` and ``d2_sd_mm`` (of the average over passes), ``d1_pass_sd_mean_mm``, ``d1_pass_sd_spread_mm`` (mean and standard deviation over passes of each pass's own SD), the same for D2; with a truth, ``d1_truth_sd_mm``, ``d2_truth_sd_mm`` |
| ``passes.parquet`` | per pass and segment: ``pass``, ``file``, ``segment``, ``d1_sd_mm``, ``d2_sd_mm`` |
| ``map.png`` | segment index against D1 and D2 standard deviation, the passes' spread as error bars |
| ``manifest.json`` | the command, its settings, ``sd_model`` (the tap file whose SD model corrected the SDs; null: uncorrected) and the files above: a rerun into the directory replaces only these |

The output directory follows the commands' output policy (:mod:`track_alignment._output`): checked
before any work, files the command did not write and its inputs never replaced, each file
complete or not there.
"""

from __future__ import annotations

import argparse
import logging
import sys
import warnings
from dataclasses import dataclass
from glob import glob
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from . import _native
from ._args import whole
from ._output import OutputDir, OutputError
from .recordings import RecordingError, read_recording, read_table

COMMAND = "track-alignment-fleet"
OUTPUTS = ("segments.parquet", "passes.parquet", "map.png")

# The EN 13848 bands the map reports, with the edges the studies' metrics use (one definition,
# in Rust: track_alignment.BANDS); keys in lower case, as the output columns are named.
BANDS = {name.lower(): edges for name, edges in _native.BANDS if name in ("D1", "D2")}

#: The estimate's variance in each band as a fraction of the truth's, for the average of ``n``
#: passes: ``GAIN2 + SHARED + INDEPENDENT / n``, per shipped tap bank told nothing (the
#: ``tap_file`` setting; none: the default). ``GAIN2`` is the square of the in-band gain (the
#: regression slope of the estimate on the truth: the learned filter shrinks its estimate, as a
#: minimum-error filter does where the signal-to-noise ratio is finite), ``SHARED`` the error
#: every pass over a track shares, ``INDEPENDENT`` the one averaging removes. Measured on the
#: calibration and validation track seeds 101-106 (``tests/fleet_gain.py``, 50 passes each;
#: docs/python.md); the segment SDs are divided by its square root.
SD_MODELS = {
    "learned.taps": {"d1": (0.957, 0.0083, 0.0165), "d2": (0.959, 0.0006, 0.0016)},
    "learned-conicity.taps": {"d1": (0.992, 0.0299, 0.0310), "d2": (0.954, 0.0014, 0.0020)},
}
#: The default's model (no settings).
SD_MODEL = SD_MODELS["learned.taps"]
#: Settings the models hold with: the line's (the curved line's fleet meets the straight one's
#: tolerance, tests/test_fleet.py), and the fixed-lag output's, which the pipeline does not read.
NEUTRAL_SETTINGS = ("line_file", "line_rounding", "line_start", "design_response_file", "lag")


class UncorrectedWarning(UserWarning):
    """The settings are not ones an SD model was measured for: the SDs are left uncorrected."""


def sd_model(settings: Mapping[str, Any] | None) -> tuple[str, dict] | None:
    """The SD model measured for the estimator ``settings`` and its name (the tap file), or None
    where none was: another tap file, or a setting that changes the estimate (told conicity or
    contact, the roll-rate gyroscope, the filter's parameters). A model measured for other
    settings would be wrong by their difference in gain and shared error: the bank over
    conicities' D1 segment SDs corrected with the default's model err by up to 19 %."""
    rest = {k: v for k, v in (settings or {}).items() if k not in NEUTRAL_SETTINGS}
    name = str(rest.pop("tap_file", "")).strip() or "learned.taps"
    if rest or name not in SD_MODELS:
        return None
    return name, SD_MODELS[name]


def sd_factor(band: str, passes, model: Mapping[str, tuple] = SD_MODEL) -> np.ndarray:
    """SD(estimate) / SD(truth) expected in ``band`` for an average of ``passes`` passes under
    ``model`` (one of :data:`SD_MODELS`; the default's unless given)."""
    gain2, shared, independent = model[band]
    return np.sqrt(gain2 + shared + independent / np.maximum(np.asarray(passes, dtype=np.float64), 1.0))


def corrected(sds: Mapping[str, np.ndarray], passes, model: Mapping[str, tuple] | None = SD_MODEL
              ) -> dict[str, np.ndarray]:
    """Segment SDs of an average of ``passes`` passes (per segment, or one number) divided by
    :func:`sd_factor`: unbiased estimates of the track's SDs. ``model`` None: as they are."""
    if model is None:
        return dict(sds)
    return {k: (x / sd_factor(k, passes, model) if k in model else x) for k, x in sds.items()}


@dataclass
class Options:
    segment: float = 200.0
    ds: float = 0.25
    trim: float = 10.0
    settings: Mapping[str, Any] | None = None
    #: The line's design is not known: fit it from each pass (:func:`track_alignment.fit_design`).
    fit_design: bool = False


@dataclass
class Coverage:
    """Band-passed estimates on the line grid from index ``start``; NaN where not covered;
    ``count`` is how many passes cover each point (summed passes: sums)."""

    start: int
    bands: dict[str, np.ndarray]
    count: np.ndarray


def estimate_pass(path: str, options: Options) -> tuple[Coverage, dict[str, np.ndarray]]:
    """One recording: its band-passed estimate on the line grid and its per-segment SDs [mm]."""
    cols, out = estimate_recording(path, options.settings, fit_design=options.fit_design)
    position = cols["distance"] if "distance" in cols else out["distance"]
    if np.any(np.diff(position) < 0):
        raise RecordingError(f"{path}: the position (distance) goes backwards; one pass per recording, one direction")
    ds = options.ds
    first, last = int(np.ceil(position[0] / ds)), int(np.floor(position[-1] / ds))
    n_trim = int(round(options.trim / ds))
    if last - first + 1 <= 2 * n_trim + 4 * int(BANDS["d2"][1] / ds):
        raise RecordingError(f"{path}: covers {position[-1] - position[0]:.0f} m, too short for the D2 band")
    bands = banded(np.interp(np.arange(first, last + 1) * ds, position, out["alignment"]), options)
    count = np.isfinite(bands["d1"]).astype(np.float64)
    return Coverage(first, bands, count), corrected(segment_sds(first, bands, options), 1, model_of(options))


def model_of(options: Options) -> dict | None:
    """The SD model of ``options``' settings (:func:`sd_model`), None where none was measured."""
    found = sd_model(options.settings)
    return found[1] if found else None


def estimate_recording(path: str, settings: Mapping[str, Any] | None = None, *,
                       fit_design: bool = False) -> tuple[dict[str, np.ndarray], dict]:
    """The recording's columns and the estimator's outputs over them, at the recording's
    nominal step (:func:`track_alignment.recordings.nominal_step`): the FMU's, bit for bit.
    With ``fit_design``, told the design :func:`track_alignment.fit_design` fits from the
    recording (it needs ``ws_roll_rate``, and no design columns of its own)."""
    cols, step = read_recording(path)
    design = {"design_curvature": cols.get("design_curvature"), "design_cant": cols.get("design_cant")}
    if fit_design:
        if design["design_curvature"] is not None:
            raise RecordingError(f"{path}: has design_curvature and design_cant, and fit_design asks to fit them: give one")
        if cols.get("ws_roll_rate") is None:
            raise RecordingError(f"{path}: fit_design needs the column ws_roll_rate (the cant ramps place the transitions)")
        try:
            fitted = _native.fit_design(cols["speed"], cols["ws_yaw_rate"], cols["ws_roll_rate"], cols["ws_acc_y"],
                                        step=step,
                                        design_response_file=(settings or {}).get("design_response_file"))
        except ValueError as e:
            raise RecordingError(f"{path}: {e}") from None
        design = {k: fitted[k] for k in design}
    out = _native.estimate(cols["speed"], cols["ws_acc_y"], cols["ws_yaw_rate"], cols["frame_acc_y"],
                           step=step, ws_roll_rate=cols.get("ws_roll_rate"), **design,
                           settings=dict(settings or {}))
    return cols, out


def banded(aligned: np.ndarray, options: Options) -> dict[str, np.ndarray]:
    """``aligned`` (on the line grid) band-passed in D1 and D2, ``trim`` metres at each end
    set to NaN (where the zero-phase filter starts and stops)."""
    n_trim = int(round(options.trim / options.ds))
    bands = {}
    for name, (short, long) in BANDS.items():
        x = _native.bandpass(aligned, options.ds, short, long)
        x[:n_trim] = np.nan
        x[len(x) - n_trim:] = np.nan
        bands[name] = x
    return bands


def segment_sds(start: int, bands: Mapping[str, np.ndarray], options: Options) -> dict[str, np.ndarray]:
    """Per segment: the SD [mm] of each band where at least half the segment is covered (NaN
    elsewhere), for the segments from 0 to the last one the signal reaches."""
    per = int(round(options.segment / options.ds))
    n = len(next(iter(bands.values())))
    n_segments = (start + n + per - 1) // per
    out = {}
    for name, x in bands.items():
        full = np.full(n_segments * per, np.nan)
        full[start:start + n] = x
        seg = full.reshape(n_segments, per)
        valid = np.isfinite(seg).sum(axis=1)
        with np.errstate(invalid="ignore"):
            sd = np.nanstd(np.where(valid[:, None] > 0, seg, 0.0), axis=1) * 1e3
        sd[valid < per / 2] = np.nan
        out[name] = sd
    out["segment"] = np.arange(n_segments, dtype=np.float64)
    return out


def add(a: Coverage, b: Coverage) -> Coverage:
    """The sum of two coverages on the union of their ranges (NaN counts as not covered)."""
    start = min(a.start, b.start)
    end = max(a.start + len(a.count), b.start + len(b.count))
    total = Coverage(start, {k: np.zeros(end - start) for k in a.bands}, np.zeros(end - start))
    for c in (a, b):
        i = slice(c.start - start, c.start - start + len(c.count))
        total.count[i] += c.count
        for k, x in c.bands.items():
            total.bands[k][i] += np.nan_to_num(x, nan=0.0)
    return total


def tree_sum(items: list) -> Any:
    """A fixed binary tree of delayed :func:`add` over ``items``: its shape depends only on
    their number, so the floating-point sums do not depend on scheduling."""
    import dask

    level = list(items)
    while len(level) > 1:
        nxt = [dask.delayed(add)(level[i], level[i + 1]) for i in range(0, len(level) - 1, 2)]
        if len(level) % 2:
            nxt.append(level[-1])
        level = nxt
    return level[0]


def truth_bands(path: str | Path, options: Options) -> tuple[int, dict[str, np.ndarray]]:
    """A truth file (``distance``, ``alignment``) on the line grid from index ``first``,
    band-passed as a pass is: ``(first, bands)``."""
    cols, _ = read_table(path)
    missing = [c for c in ("distance", "alignment") if c not in cols]
    if missing or len(cols["distance"]) < 2:
        raise RecordingError(f"{path}: a truth file needs the columns distance and alignment, 2 rows or more")
    ds = options.ds
    first, last = int(np.ceil(cols["distance"][0] / ds)), int(np.floor(cols["distance"][-1] / ds))
    aligned = np.interp(np.arange(first, last + 1) * ds, cols["distance"], cols["alignment"])
    return first, banded(aligned, options)


def truth_sds(path: str | Path, options: Options) -> dict[str, np.ndarray]:
    """Per-segment SDs of a truth file (``distance``, ``alignment``), processed as a pass."""
    return segment_sds(*truth_bands(path, options), options)


def expand(inputs: Sequence[str | Path]) -> list[str]:
    """Files named, matched by a glob, or inside a directory (*.parquet and *.csv), sorted,
    without ``truth.parquet``."""
    found: set[str] = set()
    for item in inputs:
        p = Path(item)
        if p.is_dir():
            matches = [*p.glob("*.parquet"), *p.glob("*.csv")]
        elif p.exists():
            matches = [p]
        else:
            matches = [Path(m) for m in glob(str(item))]
            if not matches:
                raise RecordingError(f"{item}: no such file, directory or match")
        found.update(str(m) for m in matches if m.name != "truth.parquet")
    if not found:
        raise RecordingError(f"no recordings in {', '.join(map(str, inputs))}")
    return sorted(found)


def run(
    recordings: Sequence[str | Path],
    out_dir: str | Path,
    *,
    options: Options | None = None,
    client=None,
    truth: str | Path | None = None,
    plot: bool = True,
):
    """The pipeline over ``recordings`` on ``client`` (a ``dask.distributed.Client``; a
    ``LocalCluster`` with the machine's cores when None). Returns the segments table (pandas).
    The recordings, the truth, the settings and ``out_dir`` are checked before any task starts
    (:class:`RecordingError`, ``ValueError``, :class:`OutputError`)."""
    import dask

    options = options or Options()
    files = expand(recordings)
    check_settings(options.settings or {}, options.fit_design)
    if sd_model(options.settings) is None:
        warnings.warn(uncorrected_message(options.settings), UncorrectedWarning, stacklevel=2)
    out = OutputDir(out_dir, COMMAND)
    out.check(OUTPUTS if plot else OUTPUTS[:2], inputs=[*files, *([truth] if truth is not None else [])])
    truth_sd = truth_sds(truth, options) if truth is not None else None
    own = None
    if client is None:
        from dask.distributed import Client, LocalCluster

        own = Client(LocalCluster(threads_per_worker=1, processes=True, dashboard_address=":0"))
        client = own
    try:
        per_pass = [dask.delayed(estimate_pass, pure=True)(f, options) for f in files]
        total = tree_sum([p[0] for p in per_pass])
        sds = [p[1] for p in per_pass]
        total, sds = client.compute([total, sds], sync=True)
    finally:
        if own is not None:
            own.close()
            own.cluster.close()
    return write(files, total, sds, options, out, truth_sd, plot)


def uncorrected_message(settings: Mapping[str, Any] | None) -> str:
    """Why the segment SDs are left uncorrected, naming the settings."""
    given = ", ".join(f"{k}={v}" for k, v in (settings or {}).items())
    return (f"no SD model was measured for the estimator settings {given} (only for the shipped tap files "
            f"{', '.join(SD_MODELS)} told nothing): the segment SDs are the estimate's own, not corrected for "
            "its in-band gain and shared error (manifest.json: sd_model null)")


def check_settings(settings: Mapping[str, Any], fit_design: bool = False) -> None:
    """The estimator's own check of ``settings`` (names and values), on two samples in this
    process, so that a bad ``--set`` is one line here and not a traceback from every worker."""
    if fit_design and str(settings.get("line_file", "")).strip():
        raise ValueError("--set line_file gives the design and --fit-design asks to fit it: give one")
    if fit_design and "design_response_file" in settings and not str(settings["design_response_file"]).strip():
        raise ValueError("--fit-design needs design_response_file (the vehicle's response to the design), "
                         "which --set makes empty")
    if not settings:
        return
    z = np.zeros(2)
    try:
        _native.estimate(z + 20.0, z, z, z, step=1e-3, ws_roll_rate=z, settings=dict(settings))
    except ValueError as e:
        raise ValueError(f"--set {', '.join(f'{k}={v}' for k, v in settings.items())}: {e}") from None


def write(files, total: Coverage, sds, options: Options, out: OutputDir, truth_sd, plot: bool):
    import pandas as pd

    with np.errstate(invalid="ignore", divide="ignore"):
        mean = {k: np.where(total.count > 0, x / total.count, np.nan) for k, x in total.bands.items()}
    averaged = segment_sds(total.start, mean, options)
    n_segments = max(len(averaged["segment"]), *(len(s["segment"]) for s in sds))

    def pad(x):
        return np.concatenate([x, np.full(max(0, n_segments - len(x)), np.nan)])[:n_segments]

    rows = {"segment": np.arange(n_segments), "start_m": np.arange(n_segments) * options.segment,
            "end_m": (np.arange(n_segments) + 1) * options.segment}
    per_pass = {k: np.vstack([pad(s[k]) for s in sds]) for k in BANDS}
    rows["passes"] = np.isfinite(per_pass["d1"]).sum(axis=0)
    averaged = corrected({k: pad(averaged[k]) for k in BANDS}, rows["passes"], model_of(options))
    for k in BANDS:
        rows[f"{k}_sd_mm"] = averaged[k]
        # Segments no pass covers: numpy's 'mean of empty slice' warnings, NaN as wanted.
        with np.errstate(invalid="ignore"), warnings.catch_warnings(action="ignore", category=RuntimeWarning):
            rows[f"{k}_pass_sd_mean_mm"] = np.nanmean(per_pass[k], axis=0)
            rows[f"{k}_pass_sd_spread_mm"] = np.nanstd(per_pass[k], axis=0)
    if truth_sd is not None:
        for k in BANDS:
            rows[f"{k}_truth_sd_mm"] = pad(truth_sd[k])
    segments = pd.DataFrame(rows)
    # Segments past the last one any pass covers are not part of the line.
    covered = np.flatnonzero(segments["passes"].to_numpy() > 0)
    segments = segments.iloc[: covered[-1] + 1 if covered.size else 0]
    passes = pd.DataFrame([
        {"pass": i, "file": Path(f).name, "segment": j, "d1_sd_mm": s["d1"][j], "d2_sd_mm": s["d2"][j]}
        for i, (f, s) in enumerate(zip(files, sds)) for j in range(len(s["segment"])) if np.isfinite(s["d1"][j])
    ])
    out.stage("segments.parquet", lambda tmp: segments.to_parquet(tmp, index=False))
    out.stage("passes.parquet", lambda tmp: passes.to_parquet(tmp, index=False))
    if plot:
        out.stage("map.png", lambda tmp: plot_map(segments, tmp))
    out.commit({"recordings": [str(f) for f in files], "segment_m": options.segment, "ds_m": options.ds,
                "trim_m": options.trim, "settings": {k: str(v) for k, v in (options.settings or {}).items()},
                "fit_design": options.fit_design,
                "sd_model": (sd_model(options.settings) or [None])[0]})
    return segments


def plot_map(segments, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
    for ax, (k, (short, long)) in zip(axes, BANDS.items()):
        label = f"{k.upper()} {short:g}-{long:g} m"
        ax.errorbar(segments["segment"], segments[f"{k}_pass_sd_mean_mm"], yerr=segments[f"{k}_pass_sd_spread_mm"],
                    fmt="o", color="0.6", capsize=3, label="single passes: mean and spread")
        ax.plot(segments["segment"], segments[f"{k}_sd_mm"], "s-", color="C0", label="average of the passes")
        if f"{k}_truth_sd_mm" in segments:
            ax.plot(segments["segment"], segments[f"{k}_truth_sd_mm"], "k--", label="truth")
        ax.set_ylabel(f"alignment SD, {label} [mm]")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    from matplotlib.ticker import MaxNLocator

    axes[1].xaxis.set_major_locator(MaxNLocator(integer=True))
    axes[1].set_xlabel(f"segment ({segments['end_m'][0] - segments['start_m'][0]:.0f} m each)")
    fig.tight_layout()
    fig.savefig(path, dpi=110, format="png")
    plt.close(fig)


def parse_settings(items: Sequence[str]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not name:
            raise ValueError(f"--set {item!r}: expected name=value")
        out[name.strip()] = value.strip()
    return out


def main(argv: Sequence[str] | None = None) -> int:
    """``track-alignment-fleet RECORDINGS... --out DIR``: exit 0 done, 1 the output cannot be
    written, 2 bad input, 3 the pipeline failed, 130 interrupted."""
    p = argparse.ArgumentParser(prog=COMMAND, description=__doc__.split("\n\n")[0],
                                epilog="Exit codes: 0 done, 1 the output cannot be written (checked before any work), "
                                       "2 bad input, 3 the pipeline failed, 130 interrupted. docs/python.md, "
                                       "'The fleet pipeline'.")
    p.add_argument("recordings", nargs="+", help="recording files, directories or globs (Parquet or CSV)")
    p.add_argument("--out", required=True,
                   help="output directory; a rerun replaces only the files its manifest.json lists")
    p.add_argument("--segment", type=float, default=200.0, help="segment length in m (200)")
    p.add_argument("--ds", type=float, default=0.25, help="line grid step in m (0.25)")
    p.add_argument("--scheduler", help="address of a running dask scheduler (default: a LocalCluster)")
    p.add_argument("--workers", type=whole(1), help="LocalCluster workers, 1 or more (default: the machine's cores)")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE", help="estimator parameter")
    p.add_argument("--truth", help="a truth file (distance, alignment) to add the true SDs")
    p.add_argument("--fit-design", action="store_true",
                   help="the line's design is not known: fit it from each pass (needs ws_roll_rate)")
    p.add_argument("--no-plot", action="store_true", help="no map.png")
    a = p.parse_args(argv)
    client = None
    try:
        settings = parse_settings(a.set)
        if not (a.segment > 0 and 0 < a.ds < 1.5):
            raise ValueError(f"--segment {a.segment} must be positive and --ds {a.ds} within 0-1.5 m (D1 starts at 3 m)")
        if a.scheduler and a.workers:
            raise ValueError("--workers sets up a LocalCluster; a --scheduler has its own workers")
        options = Options(segment=a.segment, ds=a.ds, settings=settings, fit_design=a.fit_design)
        files = expand(a.recordings)
        check_settings(settings, a.fit_design)
        plot = not a.no_plot
        OutputDir(a.out, COMMAND).check(OUTPUTS if plot else OUTPUTS[:2],
                                       inputs=[*files, *([a.truth] if a.truth else [])])
        if a.truth:
            truth_sds(a.truth, options)
        if plot:
            import matplotlib  # noqa: F401  (before the computing: the [fleet] extra installs it)
        from dask.distributed import Client, LocalCluster

        if a.scheduler:
            client = Client(a.scheduler)
        else:
            # A failed task reaches the user as one error line, not as the workers' logs.
            client = Client(LocalCluster(n_workers=a.workers, threads_per_worker=1, processes=True,
                                         dashboard_address=":0", silence_logs=logging.CRITICAL))
        with warnings.catch_warnings():
            # Said once, as a line of its own.
            warnings.simplefilter("ignore", UncorrectedWarning)
            if sd_model(settings) is None:
                print(f"warning: {uncorrected_message(settings)}", file=sys.stderr)
            segments = run(files, a.out, options=options, client=client, truth=a.truth, plot=plot)
    except OutputError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    except (RecordingError, ValueError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except ImportError as e:
        hint = ", or give --no-plot" if e.name == "matplotlib" else ""
        print(f"error: {e.name or e} is not installed (pip install 'track-alignment[fleet]'){hint}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("error: interrupted; the output directory is as it was", file=sys.stderr)
        return 130
    except Exception as e:
        print(f"error: the pipeline failed: {e}", file=sys.stderr)
        return 3
    finally:
        if client is not None:
            client.close()
    print(f"{len(segments)} segments from {int(segments['passes'].max())} passes -> {Path(a.out) / 'segments.parquet'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
