"""Two instances stepped in parallel threads must not see each other (no global state in the
FMU): each gives exactly what it gives when the instances run one after the other. ctypes
releases the GIL during each FMI call, so the two threads do run inside the library at once."""

from __future__ import annotations

import threading

import numpy as np

from fmi_harness import run_steps, step_samples

H = 1e-3
#: An alpha other than the default is another Kalman channel than the tap bank's: allowed here.
OTHER_KALMAN = {"allow_other_kalman": True}


def run_alone(make_slave, name: str, samples: np.ndarray, alpha: float) -> np.ndarray:
    s = make_slave(name)
    assert s.initialize({"alpha": alpha, **OTHER_KALMAN}) == 0
    return run_steps(s, samples, 0.0, H)


def test_parallel_instances_match_sequential_runs(make_slave, short_runs):
    inputs = [step_samples(r.signals) for r in short_runs]
    alphas = [0.1, 0.11]
    sequential = [run_alone(make_slave, f"seq{i}", inputs[i], alphas[i]) for i in range(2)]
    assert not np.array_equal(sequential[0], sequential[1])

    slaves = [make_slave(f"thread{i}") for i in range(2)]  # created here: fmpy's loader chdirs
    for s, alpha in zip(slaves, alphas):
        assert s.initialize({"alpha": alpha, **OTHER_KALMAN}) == 0
    results: list[np.ndarray | None] = [None, None]
    errors: list[BaseException] = []
    barrier = threading.Barrier(2)

    def work(i: int) -> None:
        try:
            barrier.wait()
            results[i] = run_steps(slaves[i], inputs[i], 0.0, H)
        except BaseException as e:  # reported by the main thread
            errors.append(e)

    threads = [threading.Thread(target=work, args=(i,)) for i in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=120)
    assert errors == []
    for i in range(2):
        assert np.array_equal(results[i], sequential[i]), f"instance {i} differs when run in parallel"
