"""Regenerates the golden references of tests/golden/ (README.md there): runs every case of
cases.toml through fmpy on the packaged FMUs and says, per case and column, how the new outputs
differ from the reference on disk (the largest absolute and relative difference, and how many
values fall outside the test's tolerance).

    python tests/golden/regenerate.py            # build the FMUs, compare, write nothing
    python tests/golden/regenerate.py --write    # the same, then replace the references that changed
    python tests/golden/regenerate.py --input    # also re-record the estimator's input from the vehicle

It writes only with `--write`, and only `*_ref.csv` files (with `--input` also
AlignmentEstimator_in.csv); a file whose text would not change is left untouched. Without
`--write` the exit status is 1 when any file would change (0: the FMUs reproduce every
reference bit for bit), so the same command checks that a change left the outputs identical.
The FMUs are built first with `cargo xtask fmu` (`--no-build`: use the packaged ones as they
are); their paths and GUIDs are printed.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import fmpy  # noqa: E402
import numpy as np  # noqa: E402

import golden_cases as g  # noqa: E402
from project import REPO, packaged_fmus  # noqa: E402

#: The estimator's input recording: (estimator input, vehicle output, decimals kept). The
#: decimals are a 16-bit logger's resolution (1e-4 m/s2, 1e-6 rad/s), 1 % or less of the
#: sensors' noise (0.01 m/s2, 5e-4 rad/s), and keep the file small; the FMU reads the
#: rounded values, so the rounding is part of the input, not an error of the reference.
ESTIMATOR_INPUT = [
    ("ws_acc_y", "ws_acc_y", 4),
    ("ws_yaw_rate", "ws_yaw_rate", 6),
    ("frame_acc_y", "frame_acc_y", 4),
    ("ws_roll_rate", "ws_roll_rate", 6),
    ("speed", "forward_speed", 4),
]
VEHICLE_CASE = "RailVehicle"
INPUT_FILE = g.GOLDEN / "AlignmentEstimator" / "AlignmentEstimator_in.csv"


def estimator_input(vehicle: g.Case, fmu: Path) -> str:
    """The estimator's input: the vehicle case's sensors and speed, rounded, the row of `t`
    holding the vehicle's outputs at `t + h`. That is what the estimator reads for its step
    from `t` in the Gauss-Seidel coupling of studies/standard.ssd (vehicle first), and what
    an importer that sets the row of `t` before the step from `t` (fmpy, `orchestrator
    simulate`) gives it; so the references are the estimator's outputs in that coupled run
    (up to the rounding), and the estimator never sees the vehicle at rest before its first
    step (speed 0)."""
    run = g.run_fmpy(vehicle, fmu, every_step=True)
    time = run.column("time")
    lines = ["time," + ",".join(name for name, _, _ in ESTIMATOR_INPUT)]
    for k in range(run.values.shape[0] - 1):
        fields = [repr(round(float(time[k]), 9))]
        fields += [repr(round(float(run.column(src)[k + 1]), d) + 0.0) for _, src, d in ESTIMATOR_INPUT]
        lines.append(",".join(fields))
    return "\n".join(lines) + "\n"


def report(label: str, old: g.Table | None, new: g.Table, discrete: set[str]) -> None:
    """Prints how `new` differs from `old`, per column."""
    if old is None:
        print(f"  {label}: new file ({new.values.shape[0]} rows, {len(new.names)} columns)")
        return
    added = [n for n in new.names if n not in old.names]
    removed = [n for n in old.names if n not in new.names]
    if added or removed:
        print(f"  {label}: columns added {added}, removed {removed}")
    if old.values.shape[0] != new.values.shape[0]:
        print(f"  {label}: {old.values.shape[0]} rows -> {new.values.shape[0]}")
        return
    common = [n for n in new.names if n in old.names]
    diffs = g.compare(g.Table(common, old.values[:, [old.names.index(n) for n in common]]),
                      g.Table(common, new.values[:, [new.names.index(n) for n in common]]), discrete)
    changed = [d for d in diffs if d.max_abs > 0 or np.isnan(d.max_abs)]
    if not changed and not added and not removed:
        print(f"  {label}: identical")
    for d in changed:
        print(f"  {label}: {d.name}: max |diff| {d.max_abs:.3g}, max relative {d.max_rel:.3g}, "
              f"{d.failed} of {old.values.shape[0]} outside the test's tolerance")


def update(path: Path, text: str, write: bool) -> bool:
    """Writes `text` to `path` when asked and different; True when the file would change."""
    if path.is_file() and path.read_text() == text:
        return False
    if write:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
        print(f"  wrote {path.relative_to(REPO)}")
    return True


def main(argv: list[str]) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--write", action="store_true", help="replace the files that changed (default: compare only)")
    p.add_argument("--input", action="store_true", help="re-record the estimator's input from the vehicle case first")
    p.add_argument("--no-build", action="store_true", help="do not run `cargo xtask fmu` first")
    args = p.parse_args(argv)

    if not args.no_build:
        print("cargo xtask fmu", flush=True)
        subprocess.run(["cargo", "xtask", "fmu"], cwd=REPO, check=True)
    fmus = packaged_fmus()
    for name in sorted({c.fmu for c in g.cases()}):
        md = fmpy.read_model_description(str(fmus[name]))
        print(f"{name}: {fmus[name]} (GUID {md.guid})")

    cases = g.cases()
    changes = 0
    if args.input:
        vehicle = next(c for c in cases if c.name == VEHICLE_CASE)
        text = estimator_input(vehicle, fmus[vehicle.fmu])
        old = g.read_table(INPUT_FILE) if INPUT_FILE.is_file() else None
        new = g.parse_table(text)
        print(f"{INPUT_FILE.relative_to(REPO)}:")
        report("input", old, new, set())
        if update(INPUT_FILE, text, args.write):
            changes += 1
        if not args.write:
            print("  (the cases below read the input on disk)")

    for case in cases:
        fmu = fmus[case.fmu]
        if case.input and not case.input.is_file():
            print(f"{case.ref.relative_to(REPO)} ({case.name}): its input {case.input.relative_to(REPO)} is missing (--input --write records it)")
            changes += 1
            continue
        _, discrete = g.outputs(fmu)
        new = g.run_fmpy(case, fmu)
        old = g.read_table(case.ref) if case.ref.is_file() else None
        print(f"{case.ref.relative_to(REPO)} ({case.name}):")
        report(case.name, old, new, discrete)
        if update(case.ref, g.table_text(new, discrete), args.write):
            changes += 1

    if args.write:
        print(f"{changes} file(s) written")
        return 0
    print(f"{changes} file(s) would change; nothing written (--write to write them)")
    return 1 if changes else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
