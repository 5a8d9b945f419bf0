//! Synthesized tracks: band RMS against docs/references.md's figures, reproducibility and extension,
//! interpolation accuracy, and the channel switches and harmonic alignment.

use fmu_vehicle::track::{Irregularity, Spectrum, Track, TrackSpec, psd_cross_level};
use std::f64::consts::{PI, TAU};

/// One-sided variance of `x` (samples every `dx` m) in the wavelength band `[lo, hi]` m, from
/// the DFT bins `j` with `L / hi <= j <= L / lo` (`L = x.len() dx`), each by Goertzel's
/// recurrence: `sum_j 2 |X_j|^2 / M^2`. A brick-wall band-pass on the sampled signal, no FFT
/// and nothing taken from the generator's internals.
fn band_variance(x: &[f64], dx: f64, lo: f64, hi: f64) -> f64 {
    let m = x.len();
    let len = m as f64 * dx;
    let (j0, j1) = ((len / hi).ceil() as usize, (len / lo).floor() as usize);
    (j0..=j1)
        .map(|j| {
            let c = 2.0 * (TAU * j as f64 / m as f64).cos();
            let (mut s1, mut s2) = (0.0, 0.0);
            for &v in x {
                let s0 = v + c * s1 - s2;
                s2 = s1;
                s1 = s0;
            }
            2.0 * (s1 * s1 + s2 * s2 - c * s1 * s2) / (m * m) as f64
        })
        .sum()
}

const BANDS: [(f64, f64); 3] = [(3.0, 25.0), (25.0, 70.0), (70.0, 200.0)];
/// Track length for the band tests [m] and sample spacing [m] (Nyquist wavelength 1 m, the
/// shortest synthesized).
const LEN: f64 = 20480.0;
const DX: f64 = 0.5;

fn band_rms_mm(track: &Track, channel: fn(&Irregularity) -> f64) -> [f64; 3] {
    let x: Vec<f64> = (0..(LEN / DX) as usize)
        .map(|i| channel(&track.at(i as f64 * DX)))
        .collect();
    BANDS.map(|(lo, hi)| 1e3 * band_variance(&x, DX, lo, hi).sqrt())
}

/// Bounds on `|rms / oracle - 1|` per band: the 10 % of the issue in every band. The amplitudes
/// are deterministic, so a stretch longer than `2 pi / dO` (2.06 km) carries close to the
/// spectrum's variance in every band; what remains is the finite length (unresolved pairs of
/// components, the band edges, leakage of the strong 200-250 m components through the
/// rectangular window). Over 80 seeds at 4096 m the relative deviation was rms 1.9 / 2.6 / 4.5 %
/// and worst 4.2 / 8.3 / 11 % in D1 / D2 / D3 (D3 holds few components); at 20 km the spread is
/// about 5 times smaller in variance, so 10 % is more than 4 sigma in every band. (The test
/// crates are built optimized, see the workspace Cargo.toml, so 20 km runs in well under a second.)
const TOLERANCE: [f64; 3] = [0.10, 0.10, 0.10];

fn check(name: &str, got: [f64; 3], oracle: [f64; 3]) {
    for b in 0..3 {
        let rel = got[b] / oracle[b] - 1.0;
        eprintln!(
            "{name} {}-{} m: {:.3} mm vs {:.3} mm ({:+.1} %)",
            BANDS[b].0,
            BANDS[b].1,
            got[b],
            oracle[b],
            100.0 * rel
        );
        assert!(
            rel.abs() < TOLERANCE[b],
            "{name} band {b}: {:.3} mm vs {:.3} mm",
            got[b],
            oracle[b]
        );
    }
}

/// German low: alignment and vertical against docs/references.md section 3 (0.71 / 1.20 / 1.91 mm and
/// 0.98 / 1.65 / 2.63 mm), cross-level against quadrature of its PSD.
#[test]
fn band_rms_german_low() {
    let track = Track::generate(&TrackSpec::default(), 0.0, LEN);
    check(
        "alignment low",
        band_rms_mm(&track, |i| i.alignment),
        [0.71, 1.20, 1.91],
    );
    check(
        "vertical low",
        band_rms_mm(&track, |i| i.vertical),
        [0.98, 1.65, 2.63],
    );
    let cl = BANDS.map(|(lo, hi)| {
        let (a, b, n) = (TAU / hi, TAU / lo, 20_000);
        let h = (b - a) / n as f64;
        let trapz: f64 = (0..=n)
            .map(|i| {
                psd_cross_level(Spectrum::GermanLow, a + i as f64 * h)
                    * if i == 0 || i == n { 0.5 } else { 1.0 }
            })
            .sum();
        1e3 * (trapz * h).sqrt()
    });
    check(
        "cross-level low",
        band_rms_mm(&track, |i| i.cross_level),
        cl,
    );
}

/// German high alignment, another seed: 1.21 / 2.03 / 3.24 mm (docs/references.md).
#[test]
fn band_rms_german_high() {
    let spec = TrackSpec {
        spectrum: Spectrum::GermanHigh,
        seed: 2,
        vertical: false,
        ..TrackSpec::default()
    };
    let track = Track::generate(&spec, 0.0, LEN);
    check(
        "alignment high",
        band_rms_mm(&track, |i| i.alignment),
        [1.21, 2.03, 3.24],
    );
}

fn samples(track: &Track, from: f64, to: f64, n: usize) -> Vec<Irregularity> {
    (0..n)
        .map(|i| track.at(from + (to - from) * (i as f64 + 0.37) / n as f64))
        .collect()
}

/// Same seed, same track (bit for bit); another seed, another track (uncorrelated).
#[test]
fn seeds() {
    let spec = TrackSpec::default();
    let a = samples(&Track::generate(&spec, 0.0, 150.0), 0.0, 150.0, 3000);
    let b = samples(&Track::generate(&spec, 0.0, 150.0), 0.0, 150.0, 3000);
    assert_eq!(a, b);
    let other = TrackSpec { seed: 2, ..spec };
    let c = samples(&Track::generate(&other, 0.0, 150.0), 0.0, 150.0, 3000);
    for ch in [
        |i: &Irregularity| i.alignment,
        |i: &Irregularity| i.vertical,
        |i: &Irregularity| i.cross_level,
    ] {
        let (x, y): (Vec<f64>, Vec<f64>) = a.iter().zip(&c).map(|(p, q)| (ch(p), ch(q))).unzip();
        assert!(x.iter().zip(&y).all(|(p, q)| p != q));
        let dot = |u: &[f64], v: &[f64]| u.iter().zip(v).map(|(p, q)| p * q).sum::<f64>();
        let corr = dot(&x, &y) / (dot(&x, &x) * dot(&y, &y)).sqrt();
        assert!(corr.abs() < 0.5, "seeds 1 and 2 correlate: {corr}");
    }
    // The channels of one track are independent too.
    let (x, y): (Vec<f64>, Vec<f64>) = a.iter().map(|p| (p.alignment, p.vertical)).unzip();
    let dot = |u: &[f64], v: &[f64]| u.iter().zip(v).map(|(p, q)| p * q).sum::<f64>();
    assert!((dot(&x, &y) / (dot(&x, &x) * dot(&y, &y)).sqrt()).abs() < 0.5);
}

/// Extending the grid forwards and backwards gives exactly the values of a longer initial
/// generation; a covered range does not extend. (Alignment only, to keep the unoptimized test
/// fast: the channels share the code path.)
#[test]
fn extension_is_bit_identical() {
    let spec = TrackSpec {
        vertical: false,
        ..TrackSpec::default()
    };
    let mut short = Track::generate(&spec, 0.0, 100.0);
    let (lo, hi) = short.range();
    assert!(!short.ensure_covers(lo, hi));
    assert!(!short.ensure_covers(10.0, 90.0));
    assert!(short.ensure_covers(0.0, 400.0));
    assert!(short.ensure_covers(-150.0, 400.0));
    let (lo2, hi2) = short.range();
    assert!(lo2 <= -150.0 && hi2 >= 400.0, "{lo2} {hi2}");
    let long = Track::generate(&spec, -150.0, 400.0);
    let n = 55_000;
    for i in 0..n {
        let s = -150.0 + 550.0 * i as f64 / n as f64;
        assert_eq!(short.at(s), long.at(s), "s = {s}");
    }
}

/// Inside the grid, `at` interpolates; outside, a synthesized track sums its components
/// directly (exact). Comparing the two on the same stretch of one track measures the
/// interpolation error on the real multi-component signal, relative to each quantity's RMS.
#[test]
fn interpolation_matches_direct_sum() {
    let spec = TrackSpec::default();
    let gridded = Track::generate(&spec, 0.0, 60.0);
    let far = Track::generate(&spec, 5000.0, 5010.0); // does not cover [0, 60]: direct sums
    let n = 600;
    let a = samples(&gridded, 0.0, 60.0, n);
    let b = samples(&far, 0.0, 60.0, n);
    type Field = (&'static str, fn(&Irregularity) -> f64);
    let fields: [Field; 9] = [
        ("alignment", |i| i.alignment),
        ("alignment_ds", |i| i.alignment_ds),
        ("alignment_ds2", |i| i.alignment_ds2),
        ("vertical", |i| i.vertical),
        ("vertical_ds", |i| i.vertical_ds),
        ("vertical_ds2", |i| i.vertical_ds2),
        ("cross_level", |i| i.cross_level),
        ("cross_level_ds", |i| i.cross_level_ds),
        ("cross_level_ds2", |i| i.cross_level_ds2),
    ];
    for (name, f) in fields {
        let rms = (b.iter().map(|i| f(i).powi(2)).sum::<f64>() / n as f64).sqrt();
        let err = a
            .iter()
            .zip(&b)
            .map(|(p, q)| (f(p) - f(q)).abs())
            .fold(0.0, f64::max)
            / rms;
        eprintln!("{name}: max |interpolated - exact| / rms = {err:.1e}");
        // Second derivatives are dominated by the 1-2 m components, where the quintic Hermite
        // error is largest (5e-6 of their amplitude at 1 m).
        assert!(err < 1e-5, "{name}: {err:e}");
    }
}

/// Switches: lateral off leaves the alignment exactly zero, vertical off the vertical profile
/// and cross-level, inside and outside the grid.
#[test]
fn channel_switches() {
    let lateral_off = TrackSpec {
        lateral: false,
        ..TrackSpec::default()
    };
    let vertical_off = TrackSpec {
        vertical: false,
        ..TrackSpec::default()
    };
    let t1 = Track::generate(&lateral_off, -20.0, 80.0);
    let t2 = Track::generate(&vertical_off, -20.0, 80.0);
    // Mostly inside the grid, a few points outside it (direct sums, slow unoptimized).
    for i in 0..1000 {
        let s = if i % 100 == 0 {
            -300.0 + i as f64
        } else {
            -20.0 + 0.1 * i as f64
        };
        let a = t1.at(s);
        assert_eq!(
            (a.alignment, a.alignment_ds, a.alignment_ds2),
            (0.0, 0.0, 0.0),
            "s = {s}"
        );
        assert!(a.vertical != 0.0 && a.cross_level != 0.0);
        let b = t2.at(s);
        assert_eq!(
            (b.vertical, b.vertical_ds, b.vertical_ds2),
            (0.0, 0.0, 0.0),
            "s = {s}"
        );
        assert_eq!(
            (b.cross_level, b.cross_level_ds, b.cross_level_ds2),
            (0.0, 0.0, 0.0),
            "s = {s}"
        );
        assert!(b.alignment != 0.0);
    }
    // The stochastic channels do not depend on the other switch.
    let both = Track::generate(&TrackSpec::default(), -20.0, 80.0);
    for s in [-7.3, 0.0, 33.3, 79.9] {
        assert_eq!(both.at(s).alignment, t2.at(s).alignment);
        assert_eq!(both.at(s).vertical, t1.at(s).vertical);
    }
}

/// The paper's resonance case 2: harmonic alignment only, 1 mm at 15.66 m. The alignment is
/// exactly `1e-3 sin(2 pi s / 15.66)` with its analytic derivatives (added, not interpolated),
/// and the harmonic adds to the stochastic alignment unchanged otherwise (case 3).
#[test]
fn harmonic_alignment() {
    let (amp, wl) = (1e-3, 15.66);
    let spec = TrackSpec {
        lateral: false,
        vertical: false,
        harmonic_amplitude: amp,
        harmonic_wavelength: wl,
        ..TrackSpec::default()
    };
    let track = Track::generate(&spec, 0.0, 400.0);
    let k = 2.0 * PI / wl;
    for i in 0..4000 {
        let s = -50.0 + 0.123 * i as f64;
        let irr = track.at(s);
        let phase = 2.0 * PI * s / wl;
        assert_eq!(irr.alignment, amp * phase.sin(), "s = {s}");
        assert!(
            (irr.alignment_ds - amp * k * phase.cos()).abs() <= 1e-16 * amp * k,
            "s = {s}"
        );
        assert!(
            (irr.alignment_ds2 + amp * k * k * phase.sin()).abs() <= 1e-16 * amp * k * k,
            "s = {s}"
        );
    }
    let with = Track::generate(
        &TrackSpec {
            lateral: true,
            ..spec.clone()
        },
        0.0,
        400.0,
    );
    let without = Track::generate(
        &TrackSpec {
            lateral: true,
            harmonic_amplitude: 0.0,
            ..spec
        },
        0.0,
        400.0,
    );
    for s in [1.0, 77.7, 399.0] {
        let h = amp * (2.0 * PI * s / wl).sin();
        assert!((with.at(s).alignment - without.at(s).alignment - h).abs() < 1e-18);
        let dd = with.at(s).alignment_ds2 - without.at(s).alignment_ds2;
        assert!((dd - harmonic_ds2(amp, wl, s)).abs() < 1e-15, "{dd}");
    }
}

fn harmonic_ds2(amp: f64, wl: f64, s: f64) -> f64 {
    let k = 2.0 * PI / wl;
    -amp * k * k * (2.0 * PI * s / wl).sin()
}

/// Invalid specs are rejected with a message; the default is valid and is the documented one.
#[test]
fn spec_validation_and_default() {
    let d = TrackSpec::default();
    assert_eq!(
        (
            d.spectrum,
            d.seed,
            d.lateral,
            d.vertical,
            d.harmonic_amplitude,
            d.min_wavelength,
            d.max_wavelength
        ),
        (Spectrum::GermanLow, 1, true, true, 0.0, 1.0, 250.0)
    );
    assert!(d.validate().is_ok());
    let bad = [
        TrackSpec {
            min_wavelength: 0.0,
            ..d.clone()
        },
        TrackSpec {
            max_wavelength: 0.5,
            ..d.clone()
        },
        TrackSpec {
            max_wavelength: f64::NAN,
            ..d.clone()
        },
        TrackSpec {
            harmonic_amplitude: 1e-3,
            harmonic_wavelength: 0.0,
            ..d.clone()
        },
    ];
    for spec in bad {
        assert!(spec.validate().is_err(), "{spec:?}");
    }
}

/// Non-finite positions give non-finite values, never a panic.
#[test]
fn non_finite_positions() {
    let track = Track::generate(&TrackSpec::default(), -60.0, 10.0);
    for s in [f64::INFINITY, f64::NEG_INFINITY, f64::NAN] {
        assert!(track.at(s).alignment.is_nan(), "{s}");
    }
    let mut t = track.clone();
    assert!(!t.ensure_covers(f64::NAN, 5.0));
}

/// A serialized track (FMU state) round-trips to an identical track.
#[test]
fn serde_round_trip() {
    let track = Track::generate(&TrackSpec::default(), 0.0, 20.0);
    let text = toml::to_string(&Wrapper {
        track: track.clone(),
    })
    .expect("serialize");
    let back: Wrapper = toml::from_str(&text).expect("deserialize");
    assert_eq!(back.track, track);
    assert_eq!(back.track.at(3.3), track.at(3.3));
}

#[derive(serde::Serialize, serde::Deserialize)]
struct Wrapper {
    track: Track,
}
