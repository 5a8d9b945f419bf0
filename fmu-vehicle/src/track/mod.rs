//! Track irregularities: synthesis from a spectrum or reading a measured profile, and fast
//! evaluation of value and derivatives along the track.
//!
//! # Channels and units
//!
//! Following the paper's definition of irregularities (its equation for `xi_a`, `xi_cl`,
//! `xi_vp`; the gauge is constant here), with `u_y`, `u_z` the lateral and vertical deviation of
//! the left (`lr`) and right (`rr`) rail from their ideal position, all in metres:
//!
//! * alignment `xi_a = (u_y^lr + u_y^rr) / 2`;
//! * vertical profile `xi_vp = (u_z^lr + u_z^rr) / 2`;
//! * cross-level `xi_cl = u_z^lr - u_z^rr`, a **height difference** in metres (not an angle; the
//!   roll angle of the track is `xi_cl / (2 b)` with `b` half the contact-point distance).
//!
//! [`Track::at`] returns each with its first and second derivative along the track `s`; at speed
//! `V` the time derivatives are `V d/ds` and `V^2 d2/ds2`.
//!
//! # Spectra
//!
//! [`psd_alignment`], [`psd_vertical`] and [`psd_cross_level`] give one-sided PSDs in angular
//! wavenumber, m^2/(rad/m): German low/high disturbance (constants as in four public codes,
//! docs/references.md section 3) and FRA classes 5 and 6 (converted from cm^2/(rad/m)). The German
//! cross-level spectrum is published for the cross-level *angle* (units 1/(rad/m), `b = 0.75` m);
//! it is converted to the height difference by the factor `(2 b)^2`, which makes it agree in
//! form with the FRA cross-level spectrum (see [`psd_cross_level`]). Band RMS implied by the
//! spectra (quadrature, mm; D1 3-25 m, D2 25-70 m, D3 70-200 m):
//!
//! | channel | D1 | D2 | D3 |
//! |---|---|---|---|
//! | alignment, German low / high | 0.71 / 1.21 | 1.20 / 2.03 | 1.91 / 3.24 |
//! | vertical, German low / high | 0.98 / 1.61 | 1.65 / 2.70 | 2.63 / 4.30 |
//! | cross-level, German low / high | 1.37 / 2.24 | 1.05 / 1.72 | 0.65 / 1.06 |
//! | alignment, FRA 5 / 6 | 2.14 / 1.43 | 3.64 / 2.42 | 6.27 / 4.18 |
//!
//! # Synthesis
//!
//! Harmonic superposition `xi(s) = sum_k a_k cos(O_k s + phi_k)`, `a_k = sqrt(2 S(O_k) dO)`,
//! with [`COMPONENTS`] = 2048 components per channel. The band `[2 pi / max_wavelength, 2 pi /
//! min_wavelength]` (default 1-250 m; the FRA spectra grow as `1/O^2` towards long wavelengths,
//! with a divergent variance integral, and must be band-limited; the German ones are cut the
//! same way for consistency) is split into equal wavenumber bins of width `dO` (3.06e-3 rad/m by
//! default); each component's wavenumber is drawn uniformly *within its bin* and its phase
//! uniformly on `[0, 2 pi)`. Drawing the wavenumber breaks the exact period `2 pi / dO` (2.06 km)
//! that equally spaced components would have (the autocorrelation stays below 0.6 for all lags
//! of 0.5-10 km, in every band; see the unit tests). `S(O_k) dO` is taken as the integral of the
//! spectrum over the bin (Simpson, 8 panels): the same to first order, but the variance of every
//! bin is then exact whatever the draw.
//!
//! The amplitudes are deterministic (only phases and wavenumbers are random), so a stretch of
//! track longer than `2 pi / dO` carries nearly the spectrum's variance in every band, whatever
//! the seed; what remains is the finite length (components closer than `2 pi / L`, the band
//! edges). Measured over 80 seeds on 4096 m, the alignment band RMS deviates from the spectrum's
//! by rms 1.9 / 2.6 / 4.5 % (D1 / D2 / D3), no bias beyond 0.7 %. Equal spacing puts few
//! components at long wavelengths (19 in D3, 53 in D2, 603 in D1, 1371 below 3 m): D3 is where a
//! realization scatters most, the cost of following the brief's equal spacing with a component
//! budget that keeps generation fast.
//!
//! The three channels are independent, each drawn from its own stream: a `StdRng` seeded by
//! `seed_from_u64` with a 64-bit mix of the track seed and the channel number. The same seed
//! gives the same track with the same `rand` version (`StdRng`'s algorithm may change between
//! `rand` major versions).
//!
//! # Grid and interpolation
//!
//! The components are evaluated on a uniform grid of step [`GRID_STEP`] = 0.05 m, at the nodes
//! `s_i = i h` (`i` an integer, anchored at `s = 0` whatever range is generated), storing at
//! every node the value **and the exact first and second derivatives** of each channel. Between
//! nodes [`Track::at`] uses quintic Hermite interpolation of these six numbers per channel:
//! continuous value, slope and curvature (C2), error `O(h^6)` in the value and `O(h^4)` in the
//! second derivative, `O(1)` per call (one index computation, one basis, three six-term dot
//! products). Measured worst relative errors on a pure sinusoid (see `hermite` tests and the
//! `track_*` integration tests): at 0.05 m, 1 m wavelength: 2e-8 value, 5e-6 second derivative;
//! 3 m wavelength: 3e-11 / 6e-8. A cubic spline on the same grid would have a relative
//! second-derivative error of about `(O h)^2 / 12`, 9e-4 at 3 m, 8e-3 at 1 m. The grid step is
//! thus set by the brief's 0.05 m, not by accuracy: 0.1 m would still give 8e-5 at 1 m.
//! Memory: 72 bytes per node, 1.4 MB per km of grid.
//!
//! Evaluating `COMPONENTS` cosines at every node would cost about 20 ns each; instead each
//! component is a phasor `a exp(i (O s + phi))` that advances one node by one complex
//! multiplication with `exp(i O h)`, and value, slope and curvature are the sums of `Re z`,
//! `-O Im z` and `-O^2 Re z` (eight interleaved partial sums, 256-bit vectors when the CPU has
//! AVX2, bit-identical to the portable code). The phasors are set exactly (`sin_cos`) at the
//! start of every block of [`BLOCK`] nodes (51.2 m), whose start nodes are fixed multiples of
//! `BLOCK`; the grid always consists of whole blocks. Each node's value therefore depends only
//! on its index, so extending the grid ([`Track::ensure_covers`]) gives bit for bit the values a
//! longer initial generation would have given. The rotation drift over a block is below 1e-13
//! relative. The channels are evaluated on separate threads when there is enough work.
//! Measured (release, 2-core AMD EPYC VM): 1 km of all three channels in 32 ms (57 ms on one
//! thread), 0.5 ns per component and node; [`Track::at`] 40 ns per call.
//!
//! Outside its grid a synthesized track is still defined by its components: [`Track::at`] then
//! sums them directly (exact but `O(COMPONENTS)`, about 100 us per call), so callers should keep
//! the grid ahead of the wheelsets with [`Track::ensure_covers`].
//!
//! The harmonic alignment `A sin(2 pi s / lambda)` (the paper's resonance case: 1 mm at
//! 15.66 m) is added analytically in [`Track::at`], value and derivatives, never interpolated.
//!
//! # Measured profiles
//!
//! [`Track::from_csv`] reads `distance,alignment,vertical,cross_level` in metres (distance
//! strictly increasing, possibly non-uniform), fits a natural cubic spline through each channel
//! and samples it (value and derivatives) on a uniform grid of step `min(0.05 m, median data
//! spacing)` (at least 1 mm) from the first to the last distance; [`Track::at`] then interpolates as above.
//! Beyond the measured range the first/last value is **held with zero derivatives** (a step in
//! slope at the ends), and [`Track::ensure_covers`] cannot extend it (returns `false`). A profile
//! whose grid would exceed [`MAX_MEASURED_NODES`] nodes, or whose spline is not finite, is
//! refused with an error naming the file.

mod csv;
mod hermite;
mod spectrum;
mod synth;

pub use spectrum::{HALF_CONTACT_DISTANCE, Spectrum, psd_alignment, psd_cross_level, psd_vertical};

use hermite::Basis;
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;
use std::path::Path;
use synth::{Components, Kernel, channel_rng};

/// Grid step of a synthesized track \[m\].
pub const GRID_STEP: f64 = 0.05;
/// Nodes per synthesis block (the phasors are re-anchored exactly at every block start).
pub const BLOCK: usize = 1024;
/// Harmonic components per channel.
pub const COMPONENTS: usize = 2048;
/// Blocks generated beyond a requested range when [`Track::ensure_covers`] extends the grid
/// (about 205 m), so that a vehicle moving along the track triggers few extensions.
const EXTEND_MARGIN_BLOCKS: i64 = 4;
/// Finest grid step for a measured profile \[m\] (bounds the memory for very dense files).
const MIN_MEASURED_STEP: f64 = 1e-3;
/// Most grid nodes of a measured profile (72 bytes each: 720 MB; 500 km at 0.05 m). A longer
/// profile (or distances like 0 and 1e300) is refused with an error instead of exhausting the
/// memory of the process that loaded the FMU.
pub const MAX_MEASURED_NODES: usize = 10_000_000;
/// Smallest synthesis (in blocks) worth spreading the channels over threads.
const PARALLEL_MIN_BLOCKS: usize = 4;

/// What a synthesized track looks like.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrackSpec {
    /// Spectrum of the stochastic channels.
    pub spectrum: Spectrum,
    /// Random seed: the same seed gives the same track.
    pub seed: u64,
    /// Stochastic alignment on/off.
    pub lateral: bool,
    /// Stochastic vertical profile and cross-level on/off.
    pub vertical: bool,
    /// \[m\] added to the alignment: `A sin(2 pi s / wavelength)`; 0 = off.
    pub harmonic_amplitude: f64,
    /// \[m\] default 15.66 (the paper's resonance case), inactive while the amplitude is 0.
    pub harmonic_wavelength: f64,
    /// \[m\] shortest wavelength synthesized, default 1 (at least 4 grid steps, 0.2 m).
    pub min_wavelength: f64,
    /// \[m\] longest wavelength synthesized, default 250.
    pub max_wavelength: f64,
}

impl Default for TrackSpec {
    fn default() -> Self {
        TrackSpec {
            spectrum: Spectrum::GermanLow,
            seed: 1,
            lateral: true,
            vertical: true,
            harmonic_amplitude: 0.0,
            harmonic_wavelength: 15.66,
            min_wavelength: 1.0,
            max_wavelength: 250.0,
        }
    }
}

impl TrackSpec {
    /// Checks the numbers; [`Track::generate`] panics on a spec this rejects.
    pub fn validate(&self) -> Result<(), String> {
        let (lo, hi) = (self.min_wavelength, self.max_wavelength);
        if !(lo.is_finite() && lo > 0.0) {
            return Err(format!(
                "min_wavelength must be a positive finite length in m; got {lo}"
            ));
        }
        if !(hi.is_finite() && hi > lo) {
            return Err(format!(
                "max_wavelength must be finite and greater than min_wavelength ({lo} m); got {hi}"
            ));
        }
        if lo < 4.0 * GRID_STEP {
            return Err(format!(
                "min_wavelength must be at least {} m (4 grid steps of {GRID_STEP} m); got {lo}",
                4.0 * GRID_STEP
            ));
        }
        if !self.harmonic_amplitude.is_finite() {
            return Err(format!(
                "harmonic_amplitude must be finite; got {}",
                self.harmonic_amplitude
            ));
        }
        if self.harmonic_amplitude != 0.0
            && !(self.harmonic_wavelength.is_finite() && self.harmonic_wavelength > 0.0)
        {
            return Err(format!(
                "harmonic_wavelength must be a positive finite length in m when harmonic_amplitude is not 0; got {}",
                self.harmonic_wavelength
            ));
        }
        Ok(())
    }
}

/// Irregularities at one position `s`, with derivatives along `s` (m, 1, 1/m).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Irregularity {
    /// Alignment `xi_a`, the mean lateral deviation of the two rails, left positive \[m\].
    pub alignment: f64,
    /// d(xi_a)/ds \[1\]; times `V` gives the rate seen by a wheelset.
    pub alignment_ds: f64,
    /// d2(xi_a)/ds2 \[1/m\]; times `V^2` gives the lateral acceleration the track imposes.
    pub alignment_ds2: f64,
    /// Vertical profile `xi_vp`, the mean height deviation of the two rails, up positive \[m\].
    pub vertical: f64,
    /// d(xi_vp)/ds \[1\].
    pub vertical_ds: f64,
    /// d2(xi_vp)/ds2 \[1/m\].
    pub vertical_ds2: f64,
    /// Height difference `u_z^lr - u_z^rr` \[m\].
    pub cross_level: f64,
    /// d(xi_cl)/ds \[1\]; `V xi_cl_s / (2 l)` is the track's roll rate.
    pub cross_level_ds: f64,
    /// d2(xi_cl)/ds2 \[1/m\].
    pub cross_level_ds2: f64,
}

impl Irregularity {
    fn from_node(n: &[f64; 9]) -> Irregularity {
        Irregularity {
            alignment: n[0],
            alignment_ds: n[1],
            alignment_ds2: n[2],
            vertical: n[3],
            vertical_ds: n[4],
            vertical_ds2: n[5],
            cross_level: n[6],
            cross_level_ds: n[7],
            cross_level_ds2: n[8],
        }
    }

    /// Values only (derivatives zero): what a measured track holds beyond its ends.
    fn held(n: &[f64; 9]) -> Irregularity {
        Irregularity {
            alignment: n[0],
            vertical: n[3],
            cross_level: n[6],
            ..Irregularity::default()
        }
    }
}

/// The source of the grid values.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
enum Source {
    /// Synthesized: the spec and the components of (alignment, vertical, cross-level), `None`
    /// for a channel switched off.
    Synthetic {
        spec: TrackSpec,
        channels: Box<[Option<Components>; 3]>,
    },
    /// Read from a file (its path, for messages).
    Measured { path: String },
}

/// An irregular track: a uniform grid of value and first and second derivative of the three
/// channels, interpolated by quintic Hermite polynomials (see the module documentation).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Track {
    source: Source,
    /// Grid step \[m\].
    step: f64,
    /// Position of global node index 0 \[m\]: 0 for a synthesized track, the first distance for a
    /// measured one. Global node `i` is at `zero + i step`.
    zero: f64,
    /// Global index of `nodes[0]`: a multiple of [`BLOCK`] for a synthesized track, 0 for a
    /// measured one.
    first_index: i64,
    /// Per node: alignment, its two derivatives, vertical (3), cross-level (3).
    nodes: Vec<[f64; 9]>,
}

impl Track {
    /// Synthesizes the three channels on a uniform grid covering `[s_min, s_max]` (`s_min` may
    /// be negative: trailing wheelsets start behind the origin; the order of the bounds does not
    /// matter). The grid is rounded outwards to whole blocks of [`BLOCK`] nodes.
    ///
    /// # Panics
    /// If `spec` fails [`TrackSpec::validate`] or `s_min`, `s_max` are not finite.
    pub fn generate(spec: &TrackSpec, s_min: f64, s_max: f64) -> Track {
        if let Err(e) = spec.validate() {
            panic!("invalid track spec: {e}");
        }
        assert!(
            s_min.is_finite() && s_max.is_finite(),
            "track range must be finite: [{s_min}, {s_max}]"
        );
        let (s_min, s_max) = if s_min <= s_max {
            (s_min, s_max)
        } else {
            (s_max, s_min)
        };
        let omega_min = TAU / spec.max_wavelength;
        let omega_max = TAU / spec.min_wavelength;
        let draw = |on: bool, channel: u64, psd: fn(Spectrum, f64) -> f64| {
            on.then(|| {
                let mut rng = channel_rng(spec.seed, channel);
                Components::draw(
                    |o| psd(spec.spectrum, o),
                    omega_min,
                    omega_max,
                    COMPONENTS,
                    &mut rng,
                )
            })
        };
        let channels = Box::new([
            draw(spec.lateral, 0, psd_alignment),
            draw(spec.vertical, 1, psd_vertical),
            draw(spec.vertical, 2, psd_cross_level),
        ]);
        let (b_lo, b_hi) = block_range(s_min, s_max);
        let first_index = b_lo * BLOCK as i64;
        let mut track = Track {
            source: Source::Synthetic {
                spec: spec.clone(),
                channels,
            },
            step: GRID_STEP,
            zero: 0.0,
            first_index,
            nodes: Vec::new(),
        };
        track.nodes = track.synthesize(b_lo, b_hi);
        track
    }

    /// Reads a measured profile: CSV with the header `distance,alignment,vertical,cross_level`
    /// (metres; comma-separated; blank lines and lines starting with `#` ignored; other columns
    /// allowed and ignored; distance strictly increasing, possibly non-uniform), resampled onto
    /// a uniform grid (see the module documentation). Errors name the file, the line number and
    /// the column.
    pub fn from_csv(path: &Path) -> Result<Track, String> {
        let prof = csv::read(path)?;
        let x = &prof.distance;
        let n = x.len();
        let mut gaps: Vec<f64> = x.windows(2).map(|w| w[1] - w[0]).collect();
        gaps.sort_by(f64::total_cmp);
        let median = gaps[gaps.len() / 2];
        let target = GRID_STEP.min(median).max(MIN_MEASURED_STEP);
        let length = x[n - 1] - x[0];
        let wanted = (length / target).ceil();
        if !(wanted < MAX_MEASURED_NODES as f64) {
            // Plain digits up to a billion metres, exponent form beyond.
            let m = |x: f64| {
                if x.abs() < 1e9 {
                    format!("{x}")
                } else {
                    format!("{x:e}")
                }
            };
            return Err(format!(
                "{}: the profile spans {} m (distance {} to {} m), which on its {target} m grid needs {wanted:e} nodes, more than the limit of {MAX_MEASURED_NODES:e} ({} km at 0.05 m); split the file",
                path.display(),
                m(length),
                m(x[0]),
                m(x[n - 1]),
                MAX_MEASURED_NODES as f64 * GRID_STEP / 1000.0
            ));
        }
        let intervals = (wanted as usize).max(1);
        let step = length / intervals as f64;
        let splines: Vec<csv::Spline> = prof
            .channels
            .iter()
            .map(|y| csv::Spline::new(x, y))
            .collect();
        let mut nodes = Vec::with_capacity(intervals + 1);
        let mut seg = 0;
        for j in 0..=intervals {
            let s = if j == intervals {
                x[n - 1]
            } else {
                x[0] + j as f64 * step
            };
            while seg + 2 < n && s > x[seg + 1] {
                seg += 1;
            }
            let mut node = [0.0; 9];
            for (c, sp) in splines.iter().enumerate() {
                node[3 * c..3 * c + 3].copy_from_slice(&sp.eval(seg, s));
            }
            if let Some(bad) = node.iter().position(|v| !v.is_finite()) {
                const NAMES: [&str; 3] = ["alignment", "vertical", "cross_level"];
                return Err(format!(
                    "{}: the spline through the '{}' column is not finite near distance {s} m (data points too close together for their values?)",
                    path.display(),
                    NAMES[bad / 3]
                ));
            }
            nodes.push(node);
        }
        Ok(Track {
            source: Source::Measured {
                path: path.display().to_string(),
            },
            step,
            zero: x[0],
            first_index: 0,
            nodes,
        })
    }

    /// Value and first and second derivatives along `s` at `s`: quintic Hermite interpolation of
    /// the grid (C2, `O(1)`), plus the analytic harmonic alignment. Outside the grid: a
    /// synthesized track sums its components directly (exact, slow: extend the grid with
    /// [`Track::ensure_covers`]); a measured track holds its first/last value with zero
    /// derivatives.
    pub fn at(&self, s: f64) -> Irregularity {
        // Global grid coordinate; `x - floor(x)` is exact, so the interpolation weights at a
        // given `s` do not depend on which part of the grid is stored.
        let x = (s - self.zero) / self.step;
        let g = x.floor();
        let mut u = x - g;
        let mut j = (g as i64).saturating_sub(self.first_index);
        let last = self.nodes.len() as i64 - 1;
        if j == last && u == 0.0 {
            j = last - 1;
            u = 1.0;
        }
        let mut irr = if (0..last).contains(&j) {
            let basis = Basis::new(u);
            let inv = 1.0 / self.step;
            let (a, b) = (&self.nodes[j as usize], &self.nodes[j as usize + 1]);
            let mut n = [0.0; 9];
            for c in 0..3 {
                let r = 3 * c..3 * c + 3;
                n[r.clone()].copy_from_slice(&basis.eval(self.step, inv, &a[r.clone()], &b[r]));
            }
            Irregularity::from_node(&n)
        } else {
            match &self.source {
                Source::Synthetic { channels, .. } => {
                    let mut n = [0.0; 9];
                    for (c, comps) in channels.iter().enumerate() {
                        if let Some(comps) = comps {
                            n[3 * c..3 * c + 3].copy_from_slice(&comps.eval(s));
                        }
                    }
                    Irregularity::from_node(&n)
                }
                Source::Measured { .. } => {
                    Irregularity::held(&self.nodes[if j < 0 { 0 } else { last as usize }])
                }
            }
        };
        if let Source::Synthetic { spec, .. } = &self.source
            && spec.harmonic_amplitude != 0.0
        {
            let [v, d, dd] = harmonic(spec.harmonic_amplitude, spec.harmonic_wavelength, s);
            irr.alignment += v;
            irr.alignment_ds += d;
            irr.alignment_ds2 += dd;
        }
        irr
    }

    /// Makes the grid cover `[s_min, s_max]`, extending it (with a margin of about 200 m in the
    /// direction of growth) if needed; returns whether it extended. A synthesized track is
    /// defined everywhere by its components, and the new nodes are exactly those a longer
    /// initial generation would have had. A measured track cannot be extended: returns `false`
    /// (beyond its ends it holds the end values).
    pub fn ensure_covers(&mut self, s_min: f64, s_max: f64) -> bool {
        if !(matches!(self.source, Source::Synthetic { .. })
            && s_min.is_finite()
            && s_max.is_finite())
        {
            return false;
        }
        let (s_min, s_max) = if s_min <= s_max {
            (s_min, s_max)
        } else {
            (s_max, s_min)
        };
        let (lo, hi) = self.range();
        if s_min >= lo && s_max <= hi {
            return false;
        }
        let (need_lo, need_hi) = block_range(s_min, s_max);
        let cur_lo = self.first_index / BLOCK as i64;
        let cur_hi = cur_lo + (self.nodes.len() / BLOCK) as i64 - 1;
        let mut extended = false;
        if need_hi > cur_hi {
            let new_hi = need_hi + EXTEND_MARGIN_BLOCKS;
            let tail = self.synthesize(cur_hi + 1, new_hi);
            self.nodes.extend_from_slice(&tail);
            extended = true;
        }
        if need_lo < cur_lo {
            let new_lo = need_lo - EXTEND_MARGIN_BLOCKS;
            let mut head = self.synthesize(new_lo, cur_lo - 1);
            head.extend_from_slice(&self.nodes);
            self.nodes = head;
            self.first_index = new_lo * BLOCK as i64;
            extended = true;
        }
        extended
    }

    /// The covered range `(first node, last node)` \[m\]: for a measured track the first and last
    /// distance of the file.
    pub fn range(&self) -> (f64, f64) {
        let first = self.first_index as f64;
        let last = (self.first_index + self.nodes.len() as i64 - 1) as f64;
        (self.zero + first * self.step, self.zero + last * self.step)
    }

    /// Grid step \[m\].
    pub fn step(&self) -> f64 {
        self.step
    }

    /// The spec of a synthesized track; `None` for a measured one.
    pub fn spec(&self) -> Option<&TrackSpec> {
        match &self.source {
            Source::Synthetic { spec, .. } => Some(spec),
            Source::Measured { .. } => None,
        }
    }

    /// Evaluates the components on blocks `b_lo ..= b_hi`. With two or more channels and
    /// enough work, the channels are evaluated on separate threads (the values do not depend
    /// on it: each channel's nodes come from the same code in the same order).
    fn synthesize(&self, b_lo: i64, b_hi: i64) -> Vec<[f64; 9]> {
        let Source::Synthetic { channels, .. } = &self.source else {
            unreachable!("only synthesized tracks are synthesized")
        };
        let blocks = (b_hi - b_lo + 1).max(0) as usize;
        let step = self.step;
        let channel = |comps: &Components| {
            let mut kernel = Kernel::new(comps, step);
            let mut out = vec![[0.0; 3]; blocks * BLOCK];
            for (k, chunk) in out.chunks_exact_mut(BLOCK).enumerate() {
                kernel.fill((b_lo + k as i64) * BLOCK as i64, step, chunk);
            }
            out
        };
        let active: Vec<(usize, &Components)> = channels
            .iter()
            .enumerate()
            .filter_map(|(c, comps)| comps.as_ref().map(|x| (c, x)))
            .collect();
        let parallel = active.len() > 1
            && blocks >= PARALLEL_MIN_BLOCKS
            && std::thread::available_parallelism().is_ok_and(|n| n.get() > 1);
        let results: Vec<(usize, Vec<[f64; 3]>)> = if parallel {
            std::thread::scope(|scope| {
                let spawned: Vec<_> = active[1..]
                    .iter()
                    .map(|&(c, comps)| {
                        (
                            c,
                            comps,
                            std::thread::Builder::new().spawn_scoped(scope, move || channel(comps)),
                        )
                    })
                    .collect();
                let mut results = vec![(active[0].0, channel(active[0].1))];
                for (c, comps, handle) in spawned {
                    let values = match handle {
                        Ok(h) => h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)),
                        Err(_) => channel(comps), // could not spawn: do it here
                    };
                    results.push((c, values));
                }
                results
            })
        } else {
            active
                .iter()
                .map(|&(c, comps)| (c, channel(comps)))
                .collect()
        };
        let mut nodes = vec![[0.0; 9]; blocks * BLOCK];
        for (c, values) in results {
            for (node, v) in nodes.iter_mut().zip(values) {
                node[3 * c..3 * c + 3].copy_from_slice(&v);
            }
        }
        nodes
    }
}

/// The blocks `(first, last)` whose nodes cover `[s_min, s_max]`.
fn block_range(s_min: f64, s_max: f64) -> (i64, i64) {
    let i_lo = (s_min / GRID_STEP).floor() as i64;
    let i_hi = (s_max / GRID_STEP).ceil() as i64;
    (i_lo.div_euclid(BLOCK as i64), i_hi.div_euclid(BLOCK as i64))
}

/// `A sin(2 pi s / lambda)` and its first and second derivatives along `s`.
fn harmonic(amplitude: f64, wavelength: f64, s: f64) -> [f64; 3] {
    let k = TAU / wavelength;
    let (sin, cos) = (TAU * s / wavelength).sin_cos();
    [
        amplitude * sin,
        amplitude * k * cos,
        -amplitude * k * k * sin,
    ]
}

#[cfg(test)]
mod tests;
