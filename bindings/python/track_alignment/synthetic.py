"""A synthetic fleet: ``passes`` runs of the RailVehicle FMU over one track (the same
``track_seed``), each with its own sensor-noise seed, speed and Kalker scale (wheel and rail
wear), written as Parquet recordings, plus the track's true alignment for evaluation.

| file | columns |
|---|---|
| ``pass_NNNN.parquet`` | ``time``, ``speed``, ``distance``, ``ws_acc_y``, ``ws_yaw_rate``, ``frame_acc_y``, ``ws_roll_rate``; on a design line (``line_file``) also ``design_curvature``, ``design_cant`` |
| ``truth.parquet`` | ``distance``, ``alignment`` (the track's lateral alignment at the leading wheelset) |
| ``manifest.json`` | the command, its settings and the files above: a rerun into the directory replaces only these, and removes the passes of an earlier, larger fleet |

Pass ``i`` has the sensor-noise seed ``1000 + 100000 * seed + i`` (seed 0: ``1000 + i``), so
fleets of different ``seed`` share no noise; the speeds are drawn from ``seed`` too. Each
recording's provenance names the vehicle FMU and every parameter of its run. The output
directory follows the commands' output policy (:mod:`track_alignment._output`).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from . import _native
from ._args import positive, whole
from ._output import OutputDir
from .recordings import write_parquet

COMMAND = "python -m track_alignment.synthetic"
#: Passes per seed in the noise seeds' numbering; the FMU's Integer seeds stay within 32 bits.
SEED_STRIDE = 100_000
MAX_SEED = (2**31 - 1 - 1000) // SEED_STRIDE - 1

SIGNALS = ("forward_speed", "distance", "ws_acc_y", "ws_yaw_rate", "frame_acc_y", "ws_roll_rate", "alignment",
           "design_curvature", "design_cant")


def synthesize(
    out_dir: str | Path,
    vehicle_fmu: str | Path,
    *,
    passes: int = 50,
    track_seed: int = 1,
    length: float = 1000.0,
    speeds: tuple[float, float] = (15.0, 25.0),
    kalker_scales: tuple[float, ...] = (1.0, 0.75),
    seed: int = 0,
    step: float = 1e-3,
    line_file: str | None = None,
) -> list[Path]:
    """Writes the fleet into ``out_dir`` and returns the recordings' paths. Speeds are drawn
    uniformly from ``speeds`` (seeded by ``seed``); Kalker scales cycle through
    ``kalker_scales``; pass ``i`` has noise seed :func:`noise_seed` ``(seed, i)``. ``out_dir``
    is checked before the first run (``OutputError``); the files appear only when all are written.
    ``line_file``: the vehicle FMU's design line (its parameter of that name, e.g. ``metro-line.csv``
    in its resources); the recordings then carry ``design_curvature`` and ``design_cant``."""
    if not (1 <= passes <= SEED_STRIDE) or not length > 0 or not (0 < speeds[0] <= speeds[1] < float("inf")):
        raise ValueError(f"passes {passes} (1-{SEED_STRIDE}), length {length} m and speeds {speeds} must be positive")
    if not 0 <= seed <= MAX_SEED:
        raise ValueError(f"seed {seed}: expected 0-{MAX_SEED}")
    if not (step > 0 and np.isfinite(step)):
        raise ValueError(f"step {step}: expected a positive number of seconds")
    if not Path(vehicle_fmu).is_file():
        raise ValueError(f"{vehicle_fmu}: no such FMU")
    out = OutputDir(out_dir, COMMAND)
    names = [f"pass_{i:04d}.parquet" for i in range(passes)]
    out.check([*names, "truth.parquet"], inputs=[vehicle_fmu])
    rng = np.random.default_rng(seed)
    paths = []
    try:
        for i in range(passes):
            speed = float(rng.uniform(*speeds))
            parameters = {
                "track_seed": track_seed,
                "noise_seed": noise_seed(seed, i),
                "speed": speed,
                "kalker_scale": kalker_scales[i % len(kalker_scales)],
            }
            if line_file:
                parameters["line_file"] = line_file
            # Whole steps until the leading wheelset has passed `length`.
            stop = step * np.ceil(length / speed / step)
            run = _native.simulate(vehicle_fmu, float(stop), step=step, parameters=parameters, variables=list(SIGNALS))
            # Row 0 is t = 0, before any step; a recording's sample k ends step k.
            cols = {k: v[1:] for k, v in run.items()}
            recording = {
                "time": cols["time"],
                "speed": cols["forward_speed"],
                "distance": cols["distance"],
                **{k: cols[k] for k in ("ws_acc_y", "ws_yaw_rate", "frame_acc_y", "ws_roll_rate")},
                **({k: cols[k] for k in ("design_curvature", "design_cant")} if line_file else {}),
            }
            provenance = {"source": "track_alignment.synthetic", "vehicle_fmu": Path(vehicle_fmu).name,
                          "parameters": parameters, "step": step, "pass": i}
            out.stage(names[i], lambda tmp: write_parquet(tmp, recording, provenance))
            paths.append(out.path / names[i])
            if i == 0:
                out.stage("truth.parquet", lambda tmp: write_parquet(
                    tmp, {"distance": cols["distance"], "alignment": cols["alignment"]},
                    {"source": "track_alignment.synthetic", "track_seed": track_seed}))
        out.commit({"vehicle_fmu": str(vehicle_fmu), "line_file": line_file, "passes": passes, "track_seed": track_seed, "seed": seed,
                    "length_m": length, "speeds_m_s": list(speeds), "kalker_scales": list(kalker_scales), "step_s": step})
    except BaseException:
        out.abort()
        raise
    return paths


def noise_seed(seed: int, i: int) -> int:
    """Pass ``i``'s sensor-noise seed in the fleet of ``seed``: ``1000 + 100000 seed + i``."""
    return 1000 + SEED_STRIDE * seed + i


def main(argv=None) -> int:
    """``python -m track_alignment.synthetic --vehicle-fmu F --out DIR [--passes N] [--seed S]``."""
    import sys

    from ._output import OutputError

    p = argparse.ArgumentParser(prog=COMMAND, description=__doc__.split("\n\n")[0],
                                epilog="Exit codes: 0 done, 1 the output cannot be written (checked before any "
                                       "run), 2 bad input, 3 a vehicle run failed, 130 interrupted. docs/python.md.")
    p.add_argument("--vehicle-fmu", required=True, help="the RailVehicle FMU")
    p.add_argument("--out", required=True, help="output directory; a rerun replaces only the files its manifest.json lists")
    p.add_argument("--passes", type=whole(1, SEED_STRIDE), default=50, help="number of passes (50)")
    p.add_argument("--track-seed", type=whole(0, 2**31 - 1), default=1, help="the track's seed, the same for every pass (1)")
    p.add_argument("--seed", type=whole(0, MAX_SEED), default=0,
                   help=f"seed of the passes' speeds and sensor noise: pass i has noise seed 1000 + {SEED_STRIDE} seed + i (0)")
    p.add_argument("--length", type=positive, default=1000.0, help="length of the line in m (1000)")
    p.add_argument("--line-file", default=None,
                   help="the vehicle FMU's design line (its line_file parameter, e.g. metro-line.csv): a curved line")
    a = p.parse_args(argv)
    try:
        paths = synthesize(a.out, a.vehicle_fmu, passes=a.passes, track_seed=a.track_seed, length=a.length, seed=a.seed,
                           line_file=a.line_file)
    except OutputError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    except ValueError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("error: interrupted; the output directory is as it was", file=sys.stderr)
        return 130
    except Exception as e:
        print(f"error: a vehicle run failed: {e}", file=sys.stderr)
        return 3
    print(f"{len(paths)} passes of {a.length:.0f} m over track seed {a.track_seed} (seed {a.seed}) -> {a.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
