"""What the sensors tell of the wheels' conicity, and how far the bank's estimate is from it.

The bank over conicities (`learned-conicity.taps`) told nothing loses most of its accuracy to
its conicity estimate (docs/learned-filter.md, "Conicity"). Until 2026-11-28 that was a linear
model of 35 scale-free moments of the band-passed sensors, `ln(conicity)` rms 0.07-0.09 after
200 m; this probe asked what the sensors allow, by a second formulation that shares nothing
with it, and its answer is now in the estimator (fmu-estimator/src/learned/spectral.rs, the
same likelihood in Rust, its model spectra from the bank's training runs). Against the bank of
today the printed `conicity_estimate` column is that estimator's; the docs' column is the
linear model's (the bank of commit 40f735e).

1. **Bound.** The sensors (`ws_acc_y`, `ws_yaw_rate`, `frame_acc_y`) at constant speed are a
   stationary Gaussian vector process whose cross-spectral matrix `S(f; c, K)` depends on the
   conicity `c` and the Kalker scale `K`. Whittle's approximation gives the Fisher information
   of `L` metres of track, `T / V * sum_f tr(S^-1 dS/da S^-1 dS/db) df`, `S` the noise-free
   runs' Welch matrix plus the sensors' white-noise densities (the paper's), the derivatives by
   central differences at `c e^(+-0.05)`, `K e^(+-0.05)` on the same tracks. The Cramer-Rao
   bound on `ln c` follows with `K` unknown, with the track spectrum's level known, or unknown in
   every frequency bin (a nuisance parameter per bin, taken out by its Schur complement).
2. **Estimate.** The maximum of Whittle's likelihood over the last `min(distance, 200 m)` of a
   run, every 10 m: a Hann-windowed FFT of the sensors at 50 Hz, the periodogram matrices
   `P_f` at wavelengths 3-40 m, against `a_o S(f; c, K) + N`, with the level `a_o` free per
   octave of wavelength, `S` interpolated linearly in `ln c` between the bank's seven
   conicities and in `K` between its three scales (from noise-free runs of the training seeds at
   each, Welch with the window's own length), searched on a grid and refined by a parabola.
   Its error is printed beside the bank's own `conicity_estimate` on the same records.
3. **What it would give.** The bank's estimate told the likelihood's conicity as it goes:
   causal, each estimate ramped in over the 10 m after it is made, the bank's outputs told a
   grid of conicities (0.02 apart in `ln c`) interpolated per sample; the bank's own output
   until the first estimate is in (40 m). Whole / D1 Jrel beside told nothing and told the
   truth, and, to show where the rest of the loss lies, told the truth over the first 100 m
   and the likelihood's after.

Seeds: the model spectra from noise-free runs of 101 and 107 (300 s each), the records are the
validation seeds 102-106 (the standard case, 20 s at 20 m/s, the paper's noise; nothing is
chosen here). About 8 min on 2 cores.

    XTASK_FMU_DIR=target/fmu .venv/bin/python tests/conicity_likelihood.py [--seeds 102-106]
"""

from __future__ import annotations

import argparse
import os

import numpy as np
from scipy import signal

from wiener_bound import CHANNELS as WIENER_CHANNELS
from wiener_bound import DECIMATION, GRADES, SPEED, STEP, decimate, noisy_record

FS = 1.0 / (STEP * np.prod(DECIMATION))  # 50 Hz
# In the order `track_alignment.estimate` takes them.
CHANNELS = ("ws_acc_y", "ws_yaw_rate", "frame_acc_y")
# The paper's sensors as one-sided white-noise densities, CHANNELS' order.
NOISE = np.array([dict(zip(WIENER_CHANNELS, GRADES["paper's sensors"]))[c] for c in CHANNELS])
# The bank's conditions (taps.rs: SHIPPED_CONICITIES and the Kalker scales).
CONICITIES = (0.05, 0.075, 0.1, 0.15, 0.2, 0.3, 0.4)
KALKER = (1.0, 0.75, 0.5)
WAVES = (3.0, 40.0)  # the wavelengths the likelihood reads [m]
MEMORY = 200.0
LENGTHS = (30, 40, 50, 60, 80, 100, 120, 150, 200)  # window lengths while the memory fills [m]
EVERY = 10.0  # metres between estimates
RUN_IN = 20.0  # seconds of a training run left out
DELTA = 0.05  # the bound's central differences in ln c, ln K
RECORDS = [(c, k) for c in (0.06, 0.075, 0.1, 0.125, 0.2, 0.3) for k in (1.0, 0.5)]
GRID_STEP = 0.02  # the emulation's grid of told conicities, in ln c
TAPS = "learned-conicity.taps"


def decimated(r: dict) -> np.ndarray:
    """The three sensors of a record (its first sample, at time 0, already left out) at 50 Hz."""
    return decimate(np.array([np.asarray(r[c], float) for c in CHANNELS]))


def clean_run(ta, vehicle, seed: int, c: float, k: float, duration: float) -> np.ndarray:
    out = ta.simulate(vehicle, duration, step=STEP, variables=list(CHANNELS),
                      parameters={"track_seed": seed, "sensor_noise": False, "conicity": c, "kalker_scale": k})
    return decimated({ch: out[ch][1:] for ch in CHANNELS})[:, int(RUN_IN * FS):]


def welch(x: np.ndarray, nperseg: int) -> tuple[np.ndarray, np.ndarray]:
    """The cross-spectral matrices, [i, j, f] = scipy's csd(x_i, x_j) = E[X_i* X_j]."""
    n = x.shape[0]
    out = None
    for i in range(n):
        for j in range(n):
            f, p = signal.csd(x[i], x[j], fs=FS, nperseg=nperseg, window="hann")
            if out is None:
                out = np.zeros((n, n, len(f)), complex)
            out[i, j] = p
    return f, out


def bound(ta, vehicle, seeds, c: float, k: float, duration: float) -> list[str]:
    """The Cramer-Rao bound on ln c at (c, K), K unknown, per record length."""
    runs = {}
    for name, (cc, kk) in {"0": (c, k), "c+": (c * np.exp(DELTA), k), "c-": (c * np.exp(-DELTA), k),
                           "k+": (c, k * np.exp(DELTA)), "k-": (c, k * np.exp(-DELTA))}.items():
        spectra = [welch(clean_run(ta, vehicle, s, cc, kk, duration), 1024) for s in seeds]
        f = spectra[0][0]
        runs[name] = np.mean([s for _, s in spectra], axis=0)
    dc = (runs["c+"] - runs["c-"]) / (2 * DELTA)
    dk = (runs["k+"] - runs["k-"]) / (2 * DELTA)
    lam = SPEED / np.maximum(f, 1e-12)
    df = f[1] - f[0]
    rows = []
    for lo, hi in ((0.5, 200.0), WAVES):
        m = np.where((lam >= lo) & (lam <= hi))[0]
        info = information(runs["0"][:, :, m], [dc[:, :, m], dk[:, :, m]], NOISE)
        for length in (100.0, 200.0, 400.0):
            sd = [cramer_rao(info, length / SPEED * df, level) for level in ("known", "free")]
            rows.append(f"| {c} | {k} | {length:g} m | {lo:g}-{hi:g} m | {sd[0]:.3f} | {sd[1]:.3f} |")
    return rows


def information(s: np.ndarray, derivatives: list[np.ndarray], noise: np.ndarray) -> np.ndarray:
    """Whittle's Fisher information per frequency bin, `[bin, a, b] = tr(C^-1 dC/da C^-1 dC/db)`
    with `C = s + diag(noise)` (`s[i, j, bin]`: the noise-free cross-spectra), for the parameters
    whose `dC` are `derivatives` and, last, the level of `s` (`dC = s`: the track spectrum's level
    as a nuisance parameter)."""
    out = []
    for m in range(s.shape[-1]):
        si = np.linalg.inv(s[:, :, m] + np.diag(noise))
        g = [si @ d[:, :, m] for d in derivatives] + [si @ s[:, :, m]]
        out.append([[np.trace(a @ b).real for b in g] for a in g])
    return np.array(out)


def cramer_rao(info: np.ndarray, seconds_hz: float, level: str) -> float:
    """The bound on the first parameter's standard deviation from [`information`] summed over the
    bins, times `seconds_hz` (the record's duration times the bins' spacing: the number of
    independent bins per bin); the level `known`, or `free` in every bin (its Schur
    complement per bin)."""
    if level == "known":
        total = info[:, :-1, :-1].sum(0)
    else:
        total = sum(a[:-1, :-1] - np.outer(a[:-1, -1], a[-1, :-1]) / a[-1, -1] for a in info)
    return float(np.sqrt(np.linalg.inv(total * seconds_hz)[0, 0]))


def whittle_nll(p: np.ndarray, model: np.ndarray, noise: np.ndarray, levels: np.ndarray) -> np.ndarray:
    """Whittle's negative log-likelihood of periodogram matrices `p[bin, i, j]` (one-sided
    densities, `X_i* X_j`) under each model `model[..., bin, i, j]` times a level, plus the white
    noise: `sum_bins ln det C + tr(C^-1 p)`, `C = a model + diag(noise)`, minimised over the
    `levels` `a` (one level for all the bins given)."""
    per_level = []
    for a in levels:
        c = a * model + np.diag(noise)
        per_level.append((np.linalg.slogdet(c)[1] + np.einsum("...nij,nji->...n", np.linalg.inv(c), p).real).sum(-1))
    return np.min(per_level, axis=0)


class Likelihood:
    """Whittle's likelihood of the sensors over a window of `length` metres."""

    def __init__(self, spectra: dict, length: float):
        self.n = int(round(length / SPEED * FS))
        f = np.fft.rfftfreq(self.n, 1 / FS)
        lam = SPEED / np.maximum(f, 1e-12)
        self.bins = np.where((lam >= WAVES[0]) & (lam <= WAVES[1]))[0]
        edges = [WAVES[0] * 2.0**i for i in range(12) if WAVES[0] * 2.0**i < WAVES[1]] + [WAVES[1]]
        octaves = [np.where((lam[self.bins] >= a) & (lam[self.bins] < b))[0] for a, b in zip(edges, edges[1:])]
        self.octaves = [o for o in octaves if len(o)]
        model = {key: welch(x, self.n)[1][:, :, self.bins] for key, x in spectra.items()}
        self.lnc = np.linspace(np.log(CONICITIES[0]), np.log(CONICITIES[-1]), 36)
        self.kalker = np.linspace(0.5, 1.0, 6)
        self.model = np.array([[np.moveaxis(interpolated(model, l, k), -1, 0) for k in self.kalker] for l in self.lnc])
        self.window = signal.get_window("hann", self.n)
        self.scale = 2.0 / (FS * (self.window**2).sum())  # one-sided density, as Welch's
        self.levels = np.exp(np.linspace(np.log(0.25), np.log(4.0), 9))

    def ln_conicity(self, x: np.ndarray) -> float:
        spec = np.fft.rfft((x - x.mean(1, keepdims=True)) * self.window, axis=1)[:, self.bins]
        p = np.einsum("if,jf->fij", spec.conj(), spec) * self.scale
        nll = sum(whittle_nll(p[o], self.model[:, :, o], NOISE, self.levels) for o in self.octaves)
        i, j = np.unravel_index(np.argmin(nll), nll.shape)
        if 0 < i < len(self.lnc) - 1:
            y0, y1, y2 = nll[i - 1, j], nll[i, j], nll[i + 1, j]
            if y0 - 2 * y1 + y2 > 0:
                return self.lnc[i] + 0.5 * (y0 - y2) / (y0 - 2 * y1 + y2) * (self.lnc[1] - self.lnc[0])
        return self.lnc[i]


def interpolated(model: dict, lnc: float, k: float) -> np.ndarray:
    """The model spectrum at (ln c, K): linear in ln c between the bank's conicities, in K between
    its scales."""
    nodes = np.log(CONICITIES)
    i = int(np.clip(np.searchsorted(nodes, lnc) - 1, 0, len(nodes) - 2))
    t = (lnc - nodes[i]) / (nodes[i + 1] - nodes[i])
    hi = 1.0 if k >= 0.75 else 0.75
    u = (k - (hi - 0.25)) / 0.25

    def at(c):
        return u * model[(c, hi)] + (1 - u) * model[(c, hi - 0.25)]

    return (1 - t) * at(CONICITIES[i]) + t * at(CONICITIES[i + 1])


def track(likelihoods: dict, x: np.ndarray, distance: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The likelihood's ln c every EVERY metres from the first window on (causal)."""
    at = np.arange(LENGTHS[0], distance[-1] + 1e-9, EVERY)
    out = []
    for d in at:
        length = max(n for n in LENGTHS if n <= d)
        end = int(np.searchsorted(distance, d))
        lk = likelihoods[length]
        out.append(lk.ln_conicity(x[:, end - lk.n:end]))
    return at, np.clip(out, np.log(CONICITIES[0]), np.log(CONICITIES[-1]))


def emulated(ta, r: dict, tap: str, at: np.ndarray, lnc: np.ndarray, nothing: dict, truth_until: float = 0.0,
             truth: float = 0.0) -> np.ndarray:
    """The bank told the likelihood's conicity as it goes (see the module docs); before
    `truth_until` metres, told `truth` (the diagnostic of where the rest of the loss is)."""
    d = nothing["distance"]
    current = np.where(d >= at[0] + EVERY, np.interp(d - EVERY, at, lnc), np.nan)
    if truth_until > 0:
        current = np.where(d < truth_until, np.log(truth), current)
    ok = np.isfinite(current)
    lo = int(np.floor(np.nanmin(current) / GRID_STEP))
    hi = max(lo + 1, int(np.ceil(np.nanmax(current) / GRID_STEP)))
    grid = np.array([ta.estimate(r["forward_speed"], *(r[c] for c in CHANNELS), step=STEP,
                                 settings={"tap_file": tap, "conicity": float(np.exp(g * GRID_STEP))})["alignment"]
                     for g in range(lo, hi + 1)])
    pos = np.clip(current[ok] / GRID_STEP - lo, 0, hi - lo - 1e-9)
    i0 = np.floor(pos).astype(int)
    w = pos - i0
    cols = np.where(ok)[0]
    out = nothing["alignment"].copy()
    out[ok] = (1 - w) * grid[i0, cols] + w * grid[np.minimum(i0 + 1, hi - lo), cols]
    return out


def main() -> None:
    import track_alignment as ta
    from project import packaged_fmus, seed_list, REPO

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=seed_list, default=seed_list("102-106"), help="the records' track seeds")
    ap.add_argument("--train-seeds", type=seed_list, default=seed_list("101,107"), help="the model spectra's")
    ap.add_argument("--duration", type=float, default=300.0, help="each noise-free run [s]")
    a = ap.parse_args()
    if set(a.seeds) & set(a.train_seeds):
        ap.error(f"the records' and the model's seeds overlap: {sorted(set(a.seeds) & set(a.train_seeds))}")
    if a.duration < RUN_IN + 2 * 1024 / FS:
        ap.error(f"--duration {a.duration} s: too short for the bound's Welch windows")
    vehicle = packaged_fmus()["RailVehicle"]
    tap = str(REPO / "fmu-estimator" / "resources" / TAPS)

    print("Cramer-Rao bound on ln(conicity), the Kalker scale unknown (three sensors, the paper's noise):\n")
    print("| conicity | Kalker | track | wavelengths | track spectrum known | its level unknown per bin |")
    print("|---|---|---|---|---|---|")
    for c, k in ((0.1, 1.0), (0.06, 0.5), (0.3, 1.0)):
        print("\n".join(bound(ta, vehicle, a.train_seeds, c, k, a.duration)), flush=True)

    spectra = {(c, k): np.concatenate([clean_run(ta, vehicle, s, c, k, a.duration) for s in a.train_seeds], axis=1)
               for c in CONICITIES for k in KALKER}
    likelihoods = {n: Likelihood(spectra, n) for n in LENGTHS}
    errors = {"likelihood": [], "bank": []}
    scores = {"told nothing": [], "told the likelihood's": [], "told the truth": [],
              "told the truth over the first 100 m, then the likelihood's": []}
    for c, k in RECORDS:
        per = {name: [] for name in scores}
        for seed in a.seeds:
            r = noisy_record(ta, vehicle, seed, 20.0, {"conicity": c, "kalker_scale": k}, seed + 1000)
            x = decimated(r)
            at, lnc = track(likelihoods, x, r["distance"][:: int(np.prod(DECIMATION))][: x.shape[1]])
            nothing = ta.estimate(r["forward_speed"], *(r[ch] for ch in CHANNELS), step=STEP, settings={"tap_file": tap})
            told = ta.estimate(r["forward_speed"], *(r[ch] for ch in CHANNELS), step=STEP,
                               settings={"tap_file": tap, "conicity": c})
            errors["likelihood"].append(lnc - np.log(c))
            errors["bank"].append(np.log(np.interp(at, nothing["distance"], nothing["conicity_estimate"]) / c))
            for name, est in (("told nothing", nothing["alignment"]), ("told the truth", told["alignment"]),
                              ("told the likelihood's", emulated(ta, r, tap, at, lnc, nothing)),
                              ("told the truth over the first 100 m, then the likelihood's",
                               emulated(ta, r, tap, at, lnc, nothing, 100.0, c))):
                m = ta.band_metrics(nothing["distance"], est, r["distance"], r["alignment"], trim=10.0)
                per[name].append([m["whole"]["Jrel"], m["D1"]["Jrel"]])
        for name in scores:
            scores[name].append(np.mean(per[name], axis=0))
        print(f"conicity {c}, Kalker {k}: " + "; ".join(f"{n} {v[-1][0]:.3f} / {v[-1][1]:.3f}" for n, v in scores.items()),
              flush=True)

    print(f"\nln(conicity) rms error (mean) on seeds {a.seeds}, {len(RECORDS)} conditions:\n")
    print("| distance | likelihood | bank's `conicity_estimate` |")
    print("|---|---|---|")
    at = np.arange(LENGTHS[0], 400.0, EVERY)
    for d in (30, 50, 100, 150, 200, 300, 390):
        i = int(np.argmin(np.abs(at - d)))
        cells = [np.array([e[i] for e in errors[name]]) for name in ("likelihood", "bank")]
        print(f"| {d} m | " + " | ".join(f"{np.sqrt(np.mean(e**2)):.3f} ({np.mean(e):+.3f})" for e in cells) + " |")
    print("\nThe bank over conicities, whole / D1 Jrel, mean over the conditions (worst condition's whole):\n")
    print("| bank told | whole | D1 | worst whole |")
    print("|---|---|---|---|")
    for name, v in scores.items():
        v = np.array(v)
        print(f"| {name} | {v[:, 0].mean():.3f} | {v[:, 1].mean():.3f} | {v[:, 0].max():.3f} |")


if __name__ == "__main__":
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    main()
