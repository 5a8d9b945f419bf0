"""A synthetic fleet: ``passes`` runs of the RailVehicle FMU over one track (the same
``track_seed``), each with its own sensor-noise seed, speed and Kalker scale (wheel and rail
wear), written as Parquet recordings, plus the track's true alignment for evaluation.

| file | columns |
|---|---|
| ``pass_NNNN.parquet`` | ``time``, ``speed``, ``distance``, ``ws_acc_y``, ``ws_yaw_rate``, ``frame_acc_y``, ``ws_roll_rate`` |
| ``truth.parquet`` | ``distance``, ``alignment`` (the track's lateral alignment at the leading wheelset) |

Each recording's provenance names the vehicle FMU and every parameter of its run.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from . import _native
from .recordings import write_parquet

SIGNALS = ("forward_speed", "distance", "ws_acc_y", "ws_yaw_rate", "frame_acc_y", "ws_roll_rate", "alignment")


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
) -> list[Path]:
    """Writes the fleet into ``out_dir`` and returns the recordings' paths. Speeds are drawn
    uniformly from ``speeds`` (seeded by ``seed``); Kalker scales cycle through
    ``kalker_scales``; pass ``i`` has noise seed ``1000 + i``."""
    if passes < 1 or length <= 0 or not (0 < speeds[0] <= speeds[1]):
        raise ValueError(f"passes {passes}, length {length} m and speeds {speeds} must be positive")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    paths = []
    for i in range(passes):
        speed = float(rng.uniform(*speeds))
        parameters = {
            "track_seed": track_seed,
            "noise_seed": 1000 + i,
            "speed": speed,
            "kalker_scale": kalker_scales[i % len(kalker_scales)],
        }
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
        }
        provenance = {"source": "track_alignment.synthetic", "vehicle_fmu": Path(vehicle_fmu).name,
                      "parameters": parameters, "step": step, "pass": i}
        path = out / f"pass_{i:04d}.parquet"
        write_parquet(path, recording, provenance)
        paths.append(path)
        if i == 0:
            write_parquet(out / "truth.parquet", {"distance": cols["distance"], "alignment": cols["alignment"]},
                          {"source": "track_alignment.synthetic", "track_seed": track_seed})
    return paths


def main(argv=None) -> int:
    """``python -m track_alignment.synthetic --vehicle-fmu F --out DIR [--passes N]``."""
    import argparse
    import sys

    p = argparse.ArgumentParser(prog="python -m track_alignment.synthetic", description=__doc__.split("\n\n")[0])
    p.add_argument("--vehicle-fmu", required=True)
    p.add_argument("--out", required=True)
    p.add_argument("--passes", type=int, default=50)
    p.add_argument("--track-seed", type=int, default=1)
    p.add_argument("--length", type=float, default=1000.0, help="m")
    a = p.parse_args(argv)
    try:
        paths = synthesize(a.out, a.vehicle_fmu, passes=a.passes, track_seed=a.track_seed, length=a.length)
    except (ValueError, OSError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except RuntimeError as e:
        print(f"error: a vehicle run failed: {e}", file=sys.stderr)
        return 3
    print(f"{len(paths)} passes of {a.length:.0f} m over track seed {a.track_seed} -> {a.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
