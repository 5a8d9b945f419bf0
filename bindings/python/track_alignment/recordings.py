"""Recordings of one train pass: reading them (Parquet or CSV, chosen by extension) and writing
them as Parquet with units and provenance.

A recording is a table with one row per sample, taken every ``step`` seconds:

| column | unit | required | meaning |
|---|---|---|---|
| ``time`` | s | yes | sample time, uniform |
| ``speed`` | m/s | yes | forward speed over the step ending at the sample |
| ``ws_acc_y`` | m/s2 | yes | wheelset lateral acceleration |
| ``ws_yaw_rate`` | rad/s | yes | wheelset yaw rate |
| ``frame_acc_y`` | m/s2 | yes | bogie-frame lateral acceleration |
| ``distance`` | m | no | position along the line (odometry, GNSS map-matching); without it the position is the integral of ``speed`` from 0 |
| ``ws_roll_rate`` | rad/s | no | wheelset roll rate, for the four-sensor taps |
| ``design_curvature``, ``design_cant`` | 1/m, m | no (both or neither) | the design line at the wheelset, from the line's data and the position; the estimator removes its response (curves) |

Parquet files carry, in the file's key-value metadata, ``units`` (JSON ``{column: unit}``) and
``provenance`` (JSON: what produced the file, from which inputs and settings), the convention the
Rust side (``orchestrator run``/``simulate``, ``smooth``) writes too; this module also puts each
unit in the Arrow field metadata (``unit``) for Arrow tools.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Mapping

import numpy as np

REQUIRED = ("time", "speed", "ws_acc_y", "ws_yaw_rate", "frame_acc_y")
OPTIONAL = ("distance", "ws_roll_rate", "design_curvature", "design_cant")
UNITS = {
    "time": "s",
    "speed": "m/s",
    "distance": "m",
    "ws_acc_y": "m/s2",
    "ws_yaw_rate": "rad/s",
    "frame_acc_y": "m/s2",
    "ws_roll_rate": "rad/s",
    "design_curvature": "1/m",
    "design_cant": "m",
    "alignment": "m",
}
PROVENANCE_KEY = b"provenance"
UNITS_KEY = b"units"


class RecordingError(ValueError):
    """A recording that cannot be used; the message names the file and what is wrong."""


def read_units(path: str | Path) -> dict[str, str]:
    """The ``units`` of a Parquet file's metadata (empty for a file without them)."""
    import pyarrow.parquet as pq

    meta = pq.read_schema(path).metadata or {}
    return json.loads(meta[UNITS_KEY]) if UNITS_KEY in meta else {}


def read_table(path: str | Path) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    """Every column of a Parquet or CSV file as float64 arrays, and the Parquet provenance."""
    path = Path(path)
    suffix = path.suffix.lower()
    try:
        if suffix == ".parquet":
            import pyarrow.parquet as pq

            table = pq.read_table(path)
            columns = {n: table.column(n).to_numpy().astype(np.float64, copy=False) for n in table.column_names}
            meta = table.schema.metadata or {}
            provenance = json.loads(meta[PROVENANCE_KEY]) if PROVENANCE_KEY in meta else {}
            return columns, provenance
        if suffix == ".csv":
            data = np.genfromtxt(path, delimiter=",", names=True, deletechars="", dtype=np.float64)
            if data.dtype.names is None:
                raise RecordingError(f"{path}: no header row")
            return {n: np.ascontiguousarray(data[n]) for n in data.dtype.names}, {}
    except RecordingError:
        raise
    except Exception as e:  # a corrupt file: name it
        raise RecordingError(f"{path}: cannot be read ({e})") from e
    raise RecordingError(f"{path}: unknown format '{suffix}' (.parquet or .csv)")


def read_recording(path: str | Path) -> tuple[dict[str, np.ndarray], float]:
    """The recording's columns (required and optional ones) and its step [s]; refuses a missing
    column, unequal lengths, fewer than 2 rows, a non-finite or non-uniform time, naming the
    file and the row."""
    columns, _ = read_table(path)
    missing = [c for c in REQUIRED if c not in columns]
    if missing:
        raise RecordingError(f"{path}: missing column(s) {', '.join(missing)} (has {', '.join(columns)})")
    keep = {c: columns[c] for c in (*REQUIRED, *OPTIONAL) if c in columns}
    if ("design_curvature" in keep) != ("design_cant" in keep):
        raise RecordingError(f"{path}: design_curvature and design_cant come together (the design line); it has only one")
    time = keep["time"]
    if len(time) < 2:
        raise RecordingError(f"{path}: {len(time)} row(s), at least 2 needed")
    if not np.isfinite(time).all():
        raise RecordingError(f"{path}: the time column is not finite")
    dt = np.diff(time)
    step = nominal_step(time)
    if not step > 0:
        raise RecordingError(f"{path}: the time column is not increasing")
    bad = np.flatnonzero(np.abs(dt - step) > 1e-6 * step)
    if bad.size:
        k = int(bad[0])
        raise RecordingError(
            f"{path}: time is not uniform at row {k + 2}: {time[k]} -> {time[k + 1]} (step {step})"
        )
    return keep, step


#: A step is snapped to its 9-significant-digit decimal when the mean step is this close to it.
SNAP = 1e-10


def nominal_step(time: np.ndarray) -> float:
    """The step of a uniform time column, as the FMU was stepped: the mean step over the whole
    column (the rounding of each time cancels, where a difference of neighbours is off by up to
    an ulp of the time, 1e-11 of a 1 ms step after 50 s), snapped to the decimal with 9
    significant digits when within :data:`SNAP` of it: a recording made at ``1e-3`` gives
    exactly ``1e-3``, so the estimate equals the FMU's at its nominal step bit for bit; a step
    that is no short decimal (1/3 ms) keeps the mean."""
    mean = float((time[-1] - time[0]) / (len(time) - 1))
    if not (np.isfinite(mean) and mean > 0):
        return mean
    snapped = float(f"{mean:.9g}")
    return snapped if abs(mean - snapped) <= SNAP * snapped else mean


def write_parquet(path: str | Path, columns: Mapping[str, np.ndarray], provenance: Mapping[str, Any]) -> None:
    """Columns as float64 Parquet (zstd), units in the field metadata, provenance in the file's."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    fields = [
        pa.field(name, pa.float64(), nullable=False,
                 metadata={b"unit": UNITS[name].encode()} if name in UNITS else None)
        for name in columns
    ]
    units = {name: UNITS[name] for name in columns if name in UNITS}
    schema = pa.schema(fields, metadata={
        UNITS_KEY: json.dumps(units, sort_keys=True).encode(),
        PROVENANCE_KEY: json.dumps(dict(provenance), sort_keys=True).encode(),
    })
    arrays = [pa.array(np.asarray(v, dtype=np.float64)) for v in columns.values()]
    pq.write_table(pa.Table.from_arrays(arrays, schema=schema), path, compression="zstd")
