"""Monte-Carlo studies on Dask: the studies' cases (a vehicle run on a seeded track, the
estimator over its sensors, the band metrics against the track's truth) as one task each, over
seeds x vehicles x speeds x Kalker scales, for sweeps larger than one machine.

A case is computed exactly as the studies compute it (``alignment-studies variants``):
the RailVehicle FMU alone through the master for ``stop`` seconds at 1 ms with ``track_seed =
seed`` and ``noise_seed = seed + 1000``; row 0 (before any step) dropped; the estimator over the
samples; :func:`track_alignment.band_metrics` of its ``alignment`` at its own ``distance``
against the vehicle's ``alignment`` at the vehicle's ``distance`` (ds 0.05 m, trim 10 m).
So a case's figures equal the study's for the same seed and conditions.

Output: one row per case, estimator and band: ``seed``, ``vehicle``, ``speed``,
``kalker_scale``, ``estimator``, ``band``, ``Jrel``, ``J_mm``, ``truth_rms_mm``. ``--out`` follows
the commands' output policy (:mod:`track_alignment._output`): checked before any case runs, an
existing file replaced only with ``--force`` (never an input, a symlink, a FIFO or a directory),
written to a temporary file and renamed.
"""

from __future__ import annotations

import argparse
import logging
import itertools
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping, Sequence

from . import _native
from ._args import positive, whole
from ._output import OutputError, check_file, write_file

RECORDED = ["forward_speed", "ws_acc_y", "ws_yaw_rate", "frame_acc_y", "distance", "alignment"]
STEP = 1e-3


@dataclass(frozen=True)
class Case:
    seed: int
    speed: float = 20.0
    kalker_scale: float = 1.0
    vehicle: str = "default"
    #: vehicle parameters of this vehicle variant, as (name, value) pairs.
    vehicle_parameters: tuple[tuple[str, Any], ...] = field(default=())


def run_case(case: Case, vehicle_fmu: str, estimators: Mapping[str, Mapping[str, Any]], stop: float = 20.0) -> list[dict]:
    """One case: the vehicle run, then every estimator over the same samples."""
    parameters = {"track_seed": case.seed, "noise_seed": case.seed + 1000, **dict(case.vehicle_parameters)}
    if case.speed != 20.0:
        parameters["speed"] = case.speed
    if case.kalker_scale != 1.0:
        parameters["kalker_scale"] = case.kalker_scale
    run = _native.simulate(vehicle_fmu, stop, step=STEP, parameters=parameters, variables=RECORDED)
    c = {k: v[1:] for k, v in run.items()}
    rows = []
    for label, settings in estimators.items():
        out = _native.estimate(c["forward_speed"], c["ws_acc_y"], c["ws_yaw_rate"], c["frame_acc_y"],
                               step=STEP, settings=dict(settings))
        m = _native.band_metrics(out["distance"], out["alignment"], c["distance"], c["alignment"])
        for band, a in m.items():
            rows.append({"seed": case.seed, "vehicle": case.vehicle, "speed": case.speed,
                         "kalker_scale": case.kalker_scale, "estimator": label, "band": band, **a})
    return rows


def sweep(cases: Sequence[Case], vehicle_fmu: str | Path, estimators: Mapping[str, Mapping[str, Any]], *,
          client=None, stop: float = 20.0):
    """Every case as a Dask task on ``client`` (a LocalCluster when None); a pandas table in
    case order, whatever the order the tasks finish."""
    import dask
    import pandas as pd

    own = None
    if client is None:
        from dask.distributed import Client, LocalCluster

        own = client = Client(LocalCluster(threads_per_worker=1, processes=True, dashboard_address=":0"))
    try:
        tasks = [dask.delayed(run_case, pure=True)(c, str(vehicle_fmu), dict(estimators), stop) for c in cases]
        results = client.compute(tasks, sync=True)
    finally:
        if own is not None:
            own.close()
            own.cluster.close()
    return pd.DataFrame([row for rows in results for row in rows])


def grid(seeds: Sequence[int], speeds: Sequence[float] = (20.0,), kalker_scales: Sequence[float] = (1.0,),
         vehicles: Mapping[str, Mapping[str, Any]] | None = None) -> list[Case]:
    """The product seeds x vehicles x speeds x Kalker scales."""
    vehicles = vehicles or {"default": {}}
    return [Case(seed, speed, k, name, tuple(sorted(p.items())))
            for seed, (name, p), speed, k in itertools.product(seeds, vehicles.items(), speeds, kalker_scales)]


def _numbers(text: str, kind=float) -> list:
    out = []
    for part in text.split(","):
        a, sep, b = part.partition("-")
        if sep and kind is int:
            out.extend(range(int(a), int(b) + 1))
        else:
            out.append(kind(part))
    return out


def _named(items: Sequence[str], what: str) -> dict[str, dict[str, str]]:
    """``label:name=value,name=value`` (or ``label:`` for the defaults)."""
    out: dict[str, dict[str, str]] = {}
    for item in items:
        label, sep, rest = item.partition(":")
        if not sep or not label:
            raise ValueError(f"--{what} {item!r}: expected label:name=value,...")
        pairs = [p for p in rest.split(",") if p]
        settings = {}
        for p in pairs:
            k, eq, v = p.partition("=")
            if not eq:
                raise ValueError(f"--{what} {item!r}: {p!r} is not name=value")
            settings[k.strip()] = v.strip()
        out[label] = settings
    return out


def main(argv: Sequence[str] | None = None) -> int:
    """``track-alignment-montecarlo --vehicle-fmu F --seeds 1-100 --out results.parquet``."""
    p = argparse.ArgumentParser(prog="track-alignment-montecarlo", description=__doc__.split("\n\n")[0],
                                epilog="Exit codes: 0 done, 1 the output cannot be written (checked before any case), "
                                       "2 bad input, 3 the sweep failed, 130 interrupted. docs/python.md.")
    p.add_argument("--vehicle-fmu", required=True, help="the RailVehicle FMU")
    p.add_argument("--seeds", required=True, help="track seeds: 1-100 or 1,2,5")
    p.add_argument("--speeds", default="20", help="m/s, comma-separated (20)")
    p.add_argument("--kalker-scales", default="1", help="comma-separated (1)")
    p.add_argument("--vehicle", action="append", default=[], metavar="LABEL:NAME=VALUE,...",
                   help="a vehicle variant by its parameters (default: the FMU's vehicle)")
    p.add_argument("--estimator", action="append", default=[], metavar="LABEL:NAME=VALUE,...",
                   help="an estimator by its parameters (default: 'default:', the FMU's default)")
    p.add_argument("--stop", type=positive, default=20.0, help="run length in s (20)")
    p.add_argument("--out", required=True, help="results table (.parquet or .csv); an existing file only with --force")
    p.add_argument("--force", action="store_true",
                   help="replace an existing --out file (never an input, a symlink, a FIFO or a directory)")
    p.add_argument("--scheduler", help="address of a running dask scheduler (default: a LocalCluster)")
    p.add_argument("--workers", type=whole(1), help="LocalCluster workers, 1 or more (default: the machine's cores)")
    a = p.parse_args(argv)
    client = None
    try:
        seeds = _numbers(a.seeds, int)
        speeds, scales = _numbers(a.speeds), _numbers(a.kalker_scales)
        if not seeds or not all(0 < x < float("inf") for x in [*speeds, *scales]):
            raise ValueError(f"--speeds {a.speeds} and --kalker-scales {a.kalker_scales} must be positive")
        cases = grid(seeds, speeds, scales, _named(a.vehicle, "vehicle") or None)
        estimators = _named(a.estimator, "estimator") or {"default": {}}
        if not Path(a.vehicle_fmu).is_file():
            raise ValueError(f"{a.vehicle_fmu}: no such FMU")
        out = Path(a.out)
        if out.suffix not in (".parquet", ".csv"):
            raise ValueError(f"--out {out}: expected a name ending in .parquet or .csv")
        check_file(out, inputs=[a.vehicle_fmu], force=a.force)
        from dask.distributed import Client, LocalCluster

        # A failed case reaches the user as one error line, not as the workers' logs.
        client = Client(a.scheduler) if a.scheduler else Client(
            LocalCluster(n_workers=a.workers, threads_per_worker=1, processes=True, dashboard_address=":0",
                         silence_logs=logging.CRITICAL))
        table = sweep(cases, a.vehicle_fmu, estimators, client=client, stop=a.stop)
        check_file(out, inputs=[a.vehicle_fmu], force=a.force)
        try:
            write_file(out, lambda tmp: table.to_csv(tmp, index=False) if out.suffix == ".csv"
                       else table.to_parquet(tmp, index=False))
        except OSError as e:
            raise OutputError(f"{out}: cannot be written ({e.strerror or e})") from e
    except OutputError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    except ValueError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("error: interrupted; nothing written", file=sys.stderr)
        return 130
    except Exception as e:
        print(f"error: the sweep failed: {e}", file=sys.stderr)
        return 3
    finally:
        if client is not None:
            client.close()
    summary = table.groupby(["estimator", "band"])["Jrel"].mean().unstack()
    print(f"{len(cases)} cases -> {out}\nmean Jrel:\n{summary.to_string()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
