"""What the sensors allow: the non-causal multichannel Wiener estimate of the alignment, per
EN 13848 band, for each sensor grade's white noise, against the learned filter on the same
records. The second, independent formulation behind docs/accuracy.md's "Real sensors" limits.

Method (nothing here is taken from the estimator):
1. Noise-free runs of the vehicle FMU (`sensor_noise` off) on the training seeds at the
   standard case's speed, decimated to 50 Hz and shaped so that every channel is like an
   acceleration ([`SHAPE`]: the alignment differenced twice, the roll rate integrated once; the
   others are already), then the cross-spectral matrix (Welch, Hann windows of `--segment`
   metres, half overlap). Without the shaping, the window's main lobe spans transfers that
   change with frequency (the alignment's spectrum falls by decades across D3) and Welch's
   estimate loses coherence that is there: a floor of error no noise causes (exact derivatives
   of the alignment gave D3 0.12 instead of 0; `tests/test_wiener_bound.py`).
2. The sensors' noise is white with the grade's one-sided densities `N_i`, times the shaping's
   gain: per frequency, the Wiener weights `W = (S_xx + diag N)^-1 S_xy` (the normal equations
   of `E[(y - W x) x*] = 0`, with scipy's `csd(a, b) = E[a* b]`) and the error spectrum
   `S_yy - S_xy^H (S_xx + diag N)^-1 S_xy`, both mapped back to the alignment through the
   target's shaping (weights of waves longer than 500 m are left at 0: the metric's
   band-pass takes them out).
3. `bound`: the error spectrum weighted by the metric's band-pass (order-4 Butterworth run
   forward and backward: `|H|^4` on a power), over the truth's: a stationary Jrel per band.
4. `applied`: the weights as a two-sided FIR (the inverse FFT of `W`), run over the standard
   case's records (20 s at 20 m/s, held-out seeds, noise on, the grade's densities and no other
   error) and judged by `track_alignment.band_metrics`, the project's metric: the best linear
   estimate that may look both ways over the whole 400 m record, with its edges as they are.
5. `learned`: the shipped default (causal) on the same records, three and four sensors.
6. Per record: the held-out seeds with `--draws` noise draws each, the Wiener FIR against the
   default (the paper's sensors, three sensors): how much one 400 m record's D3 moves with the
   draw.
7. What a causal output of D3 alone can do with a long memory: a ridge least-squares FIR over
   the last `--memory` metres (and, for comparison, a two-sided one) fitted in the D3 band alone
   (regressors and truth band-passed alike by the metric's filter, then at 2 Hz; its response
   outside D3 is left free), on the first two thirds of the training runs with one draw of the
   grade's white noise added, the ridge chosen by two-fold cross-validation within them, judged
   on the rest;
   beside the default on noisy runs of those last seeds, as long (`band_metrics`, 200 m
   trimmed).

    XTASK_FMU_DIR=target/fmu .venv/bin/python tests/wiener_bound.py [--train-seeds 101-112] \
        [--seeds 1-5] [--duration 300] [--segment 1638.4]

Seeds: training 101-112 (calibration and validation), held out 1-5 (only judged). About 10 min
on 2 cores. Only the noise is modelled: biases, scale and misalignment are left out (the presets'
other errors are removed at a standstill or cost nothing: docs/accuracy.md).
"""

from __future__ import annotations

import argparse

import numpy as np
from scipy import linalg, signal

SPEED = 20.0
STEP = 1e-3
DECIMATION = (4, 5)
CHANNELS = ("ws_yaw_rate", "ws_acc_y", "frame_acc_y", "ws_roll_rate")
BANDS = {"whole": (3.0, 200.0), "D1": (3.0, 25.0), "D2": (25.0, 70.0), "D3": (70.0, 200.0)}
# One-sided white-noise densities (unit^2/Hz) in CHANNELS' order. The paper's sensors are
# 0.01 m/s2 and 5e-4 rad/s per sample at 1 kHz (sigma^2 / 500 Hz); the presets are the vehicle
# FMU's `sensor_grade` 1 and 2 (docs/vehicle-fmu.md, with their datasheets).
GRADES = {
    "paper's sensors": (5e-10, 2e-7, 2e-7, 5e-10),
    "tactical (HG1700)": (3.64e-5**2, 3.3e-4**2, 3.3e-4**2, 3.64e-5**2),
    "MEMS (MTi-1)": (1.22e-4**2, 1.18e-3**2, 1.18e-3**2, 1.22e-4**2),
}
SETS = {"3": (0, 1, 2), "4 (+ roll gyro)": (0, 1, 2, 3)}
# The shaping per channel (CHANNELS, then the alignment): n > 0 integrates n times (leaky, corner
# LEAK), n < 0 differences -n times. The accelerometers and the yaw rate (`V psi'`, `psi = y'`)
# are like the alignment's second derivative; the roll rate is the cross-level's first, whose
# gravity the wheelset accelerometer carries as `g phi`.
SHAPE = (0, 0, 0, 1, -2)
LEAK = 0.005
# Waves longer than this carry no weight in the FIR [m]: the metric's longest band edge is 200 m.
LONGEST = 500.0
# The D3 FIR's ridges (relative to the mean diagonal of the normal equations), chosen by
# cross-validation within the fitted runs.
RIDGES = (1e-8, 1e-6, 1e-4, 1e-3, 1e-2, 1e-1)


def decimate(x: np.ndarray) -> np.ndarray:
    """To 50 Hz along the last axis, zero-phase: sample j is the input's sample 20 j."""
    for q in DECIMATION:
        x = signal.decimate(x, q, ftype="fir", axis=-1)
    return x


def shape(x: np.ndarray, order: int, fs: float) -> np.ndarray:
    """`x` integrated `order` times (leaky) or, for a negative order, differenced."""
    a = np.exp(-2 * np.pi * LEAK / fs)
    for _ in range(max(order, 0)):
        x = signal.lfilter([1 / fs], [1, -a], x)
    for _ in range(max(-order, 0)):
        x = np.diff(x, prepend=x[0]) * fs
    return x


def shape_response(order: int, f: np.ndarray, fs: float) -> np.ndarray:
    """The complex frequency response of `shape(., order)` at `f`."""
    z = np.exp(2j * np.pi * f / fs)
    a = np.exp(-2 * np.pi * LEAK / fs)
    step = (1 / fs) / (1 - a / z) if order > 0 else (1 - 1 / z) * fs
    return step ** abs(order)


def back_to_target(order: int, f: np.ndarray, fs: float, speed: float) -> np.ndarray:
    """The factor that takes a shaped target's weights (and, squared in magnitude, its spectra)
    back to the target: `1 / shape_response`, 0 for waves longer than LONGEST."""
    kept = f >= speed / LONGEST
    return np.where(kept, 1 / np.where(kept, shape_response(order, f, fs), 1), 0)


def spectra(runs: list[np.ndarray], fs: float, nperseg: int) -> tuple[np.ndarray, np.ndarray]:
    """Frequencies and the mean cross-spectral matrix `S[i, j, f] = E[X_i* X_j]` of the runs'
    channels (each run: channels x samples)."""
    total = None
    for x in runs:
        f, p = signal.csd(x[:, None, :], x[None, :, :], fs=fs, nperseg=nperseg,
                          noverlap=nperseg // 2, window="hann", axis=-1)
        total = p if total is None else total + p
    return f, total / len(runs)


def wiener(s: np.ndarray, target: int, sensors: tuple[int, ...], noise: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per frequency, the weights of `sensors` (their noise-free spectra in `s`, noise of
    densities `noise` added: one per channel, or channels x frequencies) that estimate channel
    `target`, and the error spectrum."""
    idx = list(sensors)
    nf = s.shape[-1]
    noise = np.broadcast_to(np.asarray(noise, float).reshape(len(noise), -1), (len(noise), nf))
    w = np.zeros((len(idx), nf), complex)
    err = np.zeros(nf)
    for k in range(nf):
        a = s[:, :, k][np.ix_(idx, idx)] + np.diag(noise[idx, k])
        b = s[idx, target, k]
        w[:, k] = np.linalg.solve(a, b)
        err[k] = s[target, target, k].real - np.real(np.conj(b) @ w[:, k])
    return w, err


def band_weight(f: np.ndarray, fs: float, band: tuple[float, float], speed: float) -> np.ndarray:
    """The metric's zero-phase band-pass on a power spectrum: `|H|^4` (forward and backward)."""
    sos = signal.butter(4, [speed / band[1], speed / band[0]], btype="band", fs=fs, output="sos")
    _, h = signal.sosfreqz(sos, worN=f, fs=fs)
    return np.abs(h) ** 4


def bound(err: np.ndarray, syy: np.ndarray, f: np.ndarray, fs: float, speed: float) -> dict[str, float]:
    """Stationary Jrel per band from the error and truth spectra."""
    out = {}
    for name, band in BANDS.items():
        g = band_weight(f, fs, band, speed)
        out[name] = float(np.sqrt(np.sum(err * g) / np.sum(syy * g)))
    return out


def fir(w: np.ndarray, nperseg: int) -> np.ndarray:
    """The weights as two-sided impulse responses of `nperseg` samples, lag 0 at the middle."""
    return np.roll(np.fft.irfft(w, n=nperseg, axis=-1), nperseg // 2, axis=-1)


def apply(h: np.ndarray, x: np.ndarray) -> np.ndarray:
    """`sum_i h_i * x_i` with each `h_i` centred (non-causal), as long as `x`."""
    half = h.shape[-1] // 2
    return sum(np.convolve(xi, hi)[half: half + x.shape[-1]] for xi, hi in zip(x, h))


def lag_fir(sxx: np.ndarray, sxy: np.ndarray, syy: np.ndarray, weight: np.ndarray, nperseg: int,
            lags: range, floor: float = 0.0, ridge: float = 1e-9) -> tuple[np.ndarray, float]:
    """The FIR over `lags` (samples, `k` reads the sensors `k` samples back: a causal filter has
    every `k >= 0`) with the least error under the power weight `weight + floor`, from one-sided
    spectra on `nperseg`'s grid: `sxx` sensors x sensors x frequencies (noise included), `sxy`
    sensors x frequencies (`E[X* Y]`), `syy`. Time domain normal equations, so a causal window
    is exact: `E[x_j(t-l) x_i(t-k)] = R_ij(k - l)` and `E[x_j(t-l) y(t)] = R_jy(l)`, the
    covariances the inverse FFT of the weighted spectra. Returns the taps (sensors x lags) and
    their Jrel under `weight` alone: the error's weighted variance, computed for the taps
    themselves (not assumed optimal), over the target's.

    `floor` asks the filter for a small error outside the weight too (a filter run on records,
    whose starts the stationary weight does not see); `ridge` only steadies the solve. A
    window as long as it needs to be (the error stops falling) makes the causal one the causal
    Wiener-Hopf bound of the spectra, and the two-sided one their non-causal bound."""
    ks = np.asarray(lags)
    if np.ptp(ks) >= nperseg // 2:
        raise ValueError(f"lags {ks[0]}..{ks[-1]} span {np.ptp(ks)} samples: the covariances of "
                         f"{nperseg}-sample spectra hold fewer than {nperseg // 2} without wrapping")
    m = len(sxy)
    diff = (ks[None, :] - ks[:, None]) % nperseg

    def normal(w: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
        rxx = np.fft.irfft(sxx * w, n=nperseg, axis=-1)
        rxy = np.fft.irfft(sxy * w, n=nperseg, axis=-1)
        a = np.block([[rxx[i, j][diff] for i in range(m)] for j in range(m)])
        b = np.concatenate([rxy[j][ks % nperseg] for j in range(m)])
        return a, b, float(np.fft.irfft(syy * w, n=nperseg)[0])

    a, b, ref = normal(weight)
    fa, fb = (a, b) if floor == 0 else normal(weight + floor)[:2]
    h = linalg.solve(fa + ridge * np.trace(fa) / len(fa) * np.eye(len(fa)), fb, assume_a="pos")
    return h.reshape(m, len(ks)), float(np.sqrt(max(ref - 2 * h @ b + h @ a @ h, 0.0) / ref))


def lagged(x: np.ndarray, lags: list[int]) -> np.ndarray:
    """The regressors: each channel of `x` shifted by each lag (positive: the past), zero-filled
    (all zeros for a lag beyond the record)."""
    n = x.shape[1]
    cols = []
    for c in x:
        for lag in lags:
            z = np.zeros(n)
            if 0 <= lag < n:
                z[lag:] = c[: n - lag]
            elif -n < lag < 0:
                z[:lag] = c[-lag:]
            cols.append(z)
    return np.array(cols).T


def with_noise(run: np.ndarray, density: np.ndarray, fs: float, rng: np.random.Generator) -> np.ndarray:
    """A noise-free run (sensors, then the target) with white noise of `density` on the sensors."""
    noisy = run.copy()
    noisy[:-1] += np.sqrt(density[:, None] * fs / 2) * rng.standard_normal(run[:-1].shape)
    return noisy


def d3_fir(runs: list[np.ndarray], sensors: tuple[int, ...], lags: list[int], fs: float) -> tuple[float, float]:
    """Jrel in D3 of a ridge least-squares FIR over `lags` (at 2 Hz) of the D3-band-passed
    sensors of `runs` (sensors, target last), fitted on the first two thirds of the runs and
    judged on the rest; the ridge chosen by two-fold cross-validation within the fitted runs.
    Returns (Jrel, ridge)."""
    sos = signal.butter(4, [SPEED / BANDS["D3"][1], SPEED / BANDS["D3"][0]], btype="band", fs=fs, output="sos")
    q = int(round(fs / 2.0))
    cut = max(abs(lag) for lag in lags) + 10
    data = []
    for r in runs:
        x = signal.sosfiltfilt(sos, r[list(sensors)], axis=-1)[:, ::q]
        y = signal.sosfiltfilt(sos, r[-1])[::q]
        data.append((lagged(x, lags)[cut:-cut], y[cut:-cut]))

    def fit(part, ridge):
        a = np.concatenate([x for x, _ in part])
        g = a.T @ a
        return np.linalg.solve(g + ridge * np.trace(g) / len(g) * np.eye(len(g)), a.T @ np.concatenate([y for _, y in part]))

    def jrel(w, part):
        return float(np.mean([np.sqrt(np.mean((x @ w - y) ** 2) / np.mean(y**2)) for x, y in part]))

    train = len(runs) * 2 // 3
    half = train // 2
    folds = [(data[:half], data[half:train]), (data[half:train], data[:half])]
    ridge = min(RIDGES, key=lambda k: sum(jrel(fit(a, k), b) for a, b in folds))
    return jrel(fit(data[:train], ridge), data[train:]), ridge


def noise_parameters(density) -> dict[str, float]:
    """The vehicle FMU's noise densities of a grade (`<sensor>_noise_psd`)."""
    return {f"{c}_noise_psd": n for c, n in zip(CHANNELS, density)}


def noisy_record(ta, vehicle, seed: int, duration: float, parameters: dict, noise_seed: int) -> dict[str, np.ndarray]:
    """A run of the vehicle FMU at the standard case's speed on track `seed`, with its noise
    drawn from `noise_seed` and `parameters` set: a grade's sensor noise ([`noise_parameters`];
    none: the FMU's default sigmas), the wheels (`conicity`, `kalker_scale`), another vehicle
    (`vehicle`)."""
    out = ta.simulate(vehicle, duration, step=STEP,
                      parameters={"track_seed": seed, "noise_seed": noise_seed, **parameters},
                      variables=[*CHANNELS, "alignment", "distance", "forward_speed"])
    return {k: np.ascontiguousarray(v[1:]) for k, v in out.items()}


def default_estimate(ta, r: dict[str, np.ndarray], sensors: int) -> dict[str, np.ndarray]:
    """The shipped default's outputs over a record, with the roll gyroscope for four sensors."""
    roll = sensors == 4
    return ta.estimate(r["forward_speed"], r["ws_acc_y"], r["ws_yaw_rate"], r["frame_acc_y"], step=STEP,
                       ws_roll_rate=r["ws_roll_rate"] if roll else None,
                       settings={"use_roll_rate": True} if roll else None)


def default_metrics(ta, r: dict[str, np.ndarray], sensors: int, trim: float = 10.0) -> dict:
    """The shipped default's band metrics over a record."""
    o = default_estimate(ta, r, sensors)
    return ta.band_metrics(o["distance"], o["alignment"], r["distance"], r["alignment"], trim=trim)


def wiener_fir(s: np.ndarray, f: np.ndarray, fs: float, nperseg: int, density,
               sensors: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray]:
    """The two-sided FIR of `sensors` (shaped) that estimates the alignment under a grade's
    noise, and its error spectrum in the alignment's units."""
    target = len(CHANNELS)
    gains = np.array([np.abs(shape_response(order, f, fs)) ** 2 for order in SHAPE[:target]])
    w, err = wiener(s, target, sensors, np.array(density)[:, None] * gains)
    to_alignment = back_to_target(SHAPE[target], f, fs, SPEED)
    return fir(w * to_alignment, nperseg), err * np.abs(to_alignment) ** 2


def wiener_metrics(ta, h: np.ndarray, r: dict[str, np.ndarray], sensors: tuple[int, ...], fs: float) -> dict:
    """The band metrics of the FIR `h` over a record's sensors (decimated, shaped)."""
    x = decimate(np.array([r[CHANNELS[i]] for i in sensors]))
    est = apply(h, np.array([shape(xi, SHAPE[i], fs) for xi, i in zip(x, sensors)]))
    at = np.ascontiguousarray(r["distance"][::int(np.prod(DECIMATION))][: len(est)])
    return ta.band_metrics(at, np.ascontiguousarray(est), r["distance"], r["alignment"])


def per_draw(ta, vehicle, s: np.ndarray, f: np.ndarray, fs: float, nperseg: int, seeds: list[int], draws: int) -> None:
    """The paper's sensors, three sensors: each held-out seed with `draws` noise draws
    (`noise_seed` = seed + 1000 k), D3 and whole of the Wiener FIR and of the default."""
    sensors = SETS["3"]
    density = GRADES["paper's sensors"]
    h, _ = wiener_fir(s, f, fs, nperseg, density, sensors)
    print(f"\nPer record: the paper's sensors, three sensors, {draws} noise draws per held-out seed "
          "(noise_seed = seed + 1000 k). Wiener FIR D3 / whole; default D3 / whole.\n")
    print("| seed | noise_seed | Wiener FIR | learned default |")
    print("|---|---|---|---|")
    rows = []
    for seed in seeds:
        for k in range(1, draws + 1):
            r = noisy_record(ta, vehicle, seed, 20.0, noise_parameters(density), seed + 1000 * k)
            m = wiener_metrics(ta, h, r, sensors, fs)
            d = default_metrics(ta, r, len(sensors))
            rows.append([m["D3"]["Jrel"], m["whole"]["Jrel"], d["D3"]["Jrel"], d["whole"]["Jrel"]])
            print(f"| {seed} | {seed + 1000 * k} | {rows[-1][0]:.3f} / {rows[-1][1]:.3f} | {rows[-1][2]:.3f} / {rows[-1][3]:.3f} |", flush=True)
    lo, hi, mean = np.min(rows, axis=0), np.max(rows, axis=0), np.mean(rows, axis=0)
    print(f"| range (mean) | | D3 {lo[0]:.3f}-{hi[0]:.3f} ({mean[0]:.3f}), whole ({mean[1]:.3f}) | "
          f"D3 {lo[2]:.3f}-{hi[2]:.3f} ({mean[2]:.3f}), whole ({mean[3]:.3f}) |")


def check_runs(ap: argparse.ArgumentParser, a: argparse.Namespace) -> None:
    """Before any run: training and held-out seeds disjoint, and training runs long enough for
    two Welch segments after the run-in."""
    if set(a.train_seeds) & set(a.seeds):
        ap.error(f"training and held-out seeds overlap: {sorted(set(a.train_seeds) & set(a.seeds))}")
    if a.duration < 2 * a.segment / SPEED + 20:
        ap.error(f"--duration {a.duration} s holds fewer than two --segment {a.segment} m windows")


def training_spectra(ta, vehicle, seeds: list[int], duration: float, fs: float, nperseg: int,
                     parameters: dict | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[np.ndarray]]:
    """The Welch spectra of noise-free runs on `seeds` (the vehicle's `parameters` added):
    frequencies, the shaped channels' cross-spectra (target last), the truth's own spectrum
    (no weight beyond LONGEST), and the runs decimated but not shaped. The first 20 s, the
    run-in ramp, are left out."""
    runs, plain = [], []
    for seed in seeds:
        out = ta.simulate(vehicle, duration, step=STEP,
                          parameters={"track_seed": seed, "sensor_noise": False, **(parameters or {})},
                          variables=[*CHANNELS, "alignment"])
        x = decimate(np.array([out[c][1:] for c in (*CHANNELS, "alignment")]))
        plain.append(x[:, int(20.0 * fs):])
        x = np.array([shape(xi, order, fs) for xi, order in zip(x, SHAPE)])
        runs.append(x[:, int(20.0 * fs):])
    f, s = spectra(runs, fs, nperseg)
    target = len(CHANNELS)
    syy = s[target, target].real * np.abs(back_to_target(SHAPE[target], f, fs, SPEED)) ** 2
    return f, s, syy, plain


def main() -> None:
    import track_alignment as ta
    from project import packaged_fmus, seed_list

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--train-seeds", type=seed_list, default=seed_list("101-112"))
    ap.add_argument("--seeds", type=seed_list, default=seed_list("1-5"))
    ap.add_argument("--duration", type=float, default=300.0, help="each training run [s]")
    ap.add_argument("--segment", type=float, default=1638.4, help="Welch segment [m]")
    ap.add_argument("--memory", type=float, default=600.0, help="the D3 FIR's window [m]")
    ap.add_argument("--draws", type=int, default=3, help="noise draws per held-out seed in the per-record table")
    a = ap.parse_args()
    check_runs(ap, a)
    if a.draws < 1:
        ap.error(f"--draws {a.draws}: at least one noise draw")
    vehicle = packaged_fmus()["RailVehicle"]
    fs = 1.0 / (STEP * np.prod(DECIMATION))
    nperseg = int(round(a.segment / SPEED * fs))
    f, s, syy, plain = training_spectra(ta, vehicle, a.train_seeds, a.duration, fs, nperseg)
    print(f"Training: seeds {a.train_seeds[0]}-{a.train_seeds[-1]}, {a.duration:g} s each at {SPEED:g} m/s; "
          f"held out: {a.seeds}. Jrel whole / D1 / D2 / D3.\n")
    print("| sensors (noise only) | sensor set | Wiener bound (stationary) | Wiener FIR, non-causal, on the records | learned default, causal |")
    print("|---|---|---|---|---|")
    fmt = lambda d: " / ".join(f"{d[k]:.3f}" for k in BANDS)  # noqa: E731
    for grade, density in GRADES.items():
        records = [noisy_record(ta, vehicle, seed, 20.0, noise_parameters(density), seed + 1000) for seed in a.seeds]
        for name, sensors in SETS.items():
            h, err = wiener_fir(s, f, fs, nperseg, density, sensors)
            applied = [wiener_metrics(ta, h, r, sensors, fs) for r in records]
            learned = [default_metrics(ta, r, len(sensors)) for r in records]
            mean = lambda ms: {k: float(np.mean([m[k]["Jrel"] for m in ms])) for k in BANDS}  # noqa: E731
            stationary = bound(err, syy, f, fs, SPEED)
            print(f"| {grade} | {name} | {fmt(stationary)} | {fmt(mean(applied))} | {fmt(mean(learned))} |", flush=True)

    per_draw(ta, vehicle, s, f, fs, nperseg, a.seeds, a.draws)

    checked = a.train_seeds[len(a.train_seeds) * 2 // 3:]
    steps = int(round(a.memory / SPEED * 2.0))
    print(f"\nD3 only, least-squares FIR at 2 Hz over {a.memory:g} m (fitted on seeds {a.train_seeds[0]}-"
          f"{a.train_seeds[len(a.train_seeds) * 2 // 3 - 1]}, judged on {checked[0]}-{checked[-1]}), beside the default "
          f"on {a.duration:g} s noisy runs of {checked[0]}-{checked[-1]}. D3 Jrel.\n")
    print("| sensors (noise only) | sensor set | FIR, causal (ridge) | FIR, two-sided (ridge) | learned default, causal |")
    print("|---|---|---|---|---|")
    rng = np.random.default_rng(2)
    for grade, density in GRADES.items():
        # One noise draw per grade, shared by both windows.
        noisy = [with_noise(r, np.array(density), fs, rng) for r in plain]
        long_runs = [noisy_record(ta, vehicle, seed, a.duration, noise_parameters(density), seed + 1000)
                     for seed in checked]
        for name, sensors in SETS.items():
            causal, causal_ridge = d3_fir(noisy, sensors, list(range(0, steps + 1)), fs)
            both, both_ridge = d3_fir(noisy, sensors, list(range(-steps, steps + 1)), fs)
            d3 = [default_metrics(ta, r, len(sensors), trim=200.0)["D3"]["Jrel"] for r in long_runs]
            print(f"| {grade} | {name} | {causal:.3f} ({causal_ridge:g}) | {both:.3f} ({both_ridge:g}) | {np.mean(d3):.3f} |", flush=True)


if __name__ == "__main__":
    main()
