//! Figures and time series of the studies, written as SVG (plotters' SVG backend, no font
//! library: text is emitted as SVG `<text>` elements with an estimated layout, rendered by the
//! viewer's own fonts).
//!
//! - [`estimate_vs_truth`]: estimated and true alignment \[mm\] over distance, whole band and
//!   D1, D2, D3 (each band-passed as the metrics do: common 0.05 m grid, zero-phase Butterworth,
//!   10 m trimmed at each end);
//! - [`spectra`]: amplitude spectra of estimate and truth over wavelength, log-log, 1-250 m;
//! - [`model_adjustment`]: the vehicle's wheelset `y`, `psi` against the identified simplified
//!   model's, over time;
//! - [`case_bars`]: Jrel per band for each case, grouped bars with the seeds' standard deviation
//!   and the paper's figure as a marker;
//! - [`TimeSeries`]: distance, true alignment and estimate of one run, as CSV.

use super::identify::Identification;
use super::metrics::{BANDS, bandpass, common_grid, resample};
use super::standard::{DS, TRIM};
use crate::Error;
use orchestrator::master::Table;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

use super::cases::CaseResult;

const TRUTH: RGBColor = RGBColor(0, 0, 0);
const ESTIMATE: RGBColor = RGBColor(214, 39, 40);
const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
];
/// At most this many points per drawn line (the SVG stays small; 0.2 m at 400 m).
const MAX_POINTS: usize = 2000;

fn err<E: std::fmt::Display>(path: &Path) -> impl Fn(E) -> Error + '_ {
    move |e| Error::Draw {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

/// Every `k`-th point so that at most [`MAX_POINTS`] remain (the last one kept).
fn decimate(x: &[f64], y: &[f64]) -> Vec<(f64, f64)> {
    let n = x.len().min(y.len());
    let k = n.div_ceil(MAX_POINTS).max(1);
    let mut out: Vec<(f64, f64)> = (0..n).step_by(k).map(|i| (x[i], y[i])).collect();
    if n > 0 && !(n - 1).is_multiple_of(k) {
        out.push((x[n - 1], y[n - 1]));
    }
    out
}

/// `[lo, hi]` of the values with a 5 % margin (never empty).
/// An SVG drawing area of `size` pixels on a white background.
fn white_svg(path: &Path, size: (u32, u32)) -> Result<DrawingArea<SVGBackend<'_>, Shift>, Error> {
    let root = SVGBackend::new(path, size).into_drawing_area();
    root.fill(&WHITE).map_err(err(path))?;
    Ok(root)
}

/// One panel of two lines over the same x values: `a` in black, `b` in red, with a legend.
#[allow(clippy::too_many_arguments)]
fn two_lines(
    area: &DrawingArea<SVGBackend<'_>, Shift>,
    path: &Path,
    caption: Option<String>,
    x: &[f64],
    (a, a_label): (&[f64], &str),
    (b, b_label): (&[f64], &str),
    (x_desc, y_desc): (&str, &str),
    y_label_size: u32,
) -> Result<(), Error> {
    let (y0, y1) = range(a.iter().chain(b).copied());
    let mut builder = ChartBuilder::on(area);
    if let Some(c) = caption {
        builder.caption(c, ("sans-serif", 15));
    }
    let mut chart = builder
        .margin(8)
        .x_label_area_size(30)
        .y_label_area_size(y_label_size)
        .build_cartesian_2d(x[0]..x[x.len() - 1], y0..y1)
        .map_err(err(path))?;
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .light_line_style(WHITE)
        .draw()
        .map_err(err(path))?;
    chart
        .draw_series(LineSeries::new(decimate(x, a), TRUTH.stroke_width(1)))
        .map_err(err(path))?
        .label(a_label)
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], TRUTH));
    chart
        .draw_series(LineSeries::new(decimate(x, b), ESTIMATE.stroke_width(1)))
        .map_err(err(path))?
        .label(b_label)
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], ESTIMATE));
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(err(path))?;
    Ok(())
}

fn range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (-1.0, 1.0);
    }
    let pad = if hi > lo { 0.05 * (hi - lo) } else { 1.0 };
    (lo - pad, hi + pad)
}

/// Estimate and truth (both sampled at `distance`) on the metrics' uniform grid.
fn on_grid(distance: &[f64], estimate: &[f64], truth: &[f64]) -> Result<Grid, Error> {
    if distance.len() < 2 || estimate.len() != distance.len() || truth.len() != distance.len() {
        return Err(Error::Input(format!(
            "distance, estimate and truth need equal lengths of at least 2 ({}, {}, {})",
            distance.len(),
            estimate.len(),
            truth.len()
        )));
    }
    let s = common_grid(distance, distance, DS);
    Ok(Grid {
        e: resample(distance, estimate, &s),
        t: resample(distance, truth, &s),
        s,
    })
}

struct Grid {
    s: Vec<f64>,
    e: Vec<f64>,
    t: Vec<f64>,
}

/// Estimated against true alignment \[mm\] over distance \[m\] in four stacked panels: the whole
/// band and D1, D2, D3. `estimate` and `truth` are sampled at the same `distance` \[m\] (values in
/// m); each panel band-passes both on a 0.05 m grid and drops the first and last 10 m.
pub fn estimate_vs_truth(
    path: &Path,
    distance: &[f64],
    estimate: &[f64],
    truth: &[f64],
    title: &str,
) -> Result<(), Error> {
    let g = on_grid(distance, estimate, truth)?;
    let n = (TRIM / DS).round() as usize;
    let root = white_svg(path, (1000, 1100))?;
    let root = root.titled(title, ("sans-serif", 20)).map_err(err(path))?;
    let panels = root.split_evenly((BANDS.len(), 1));
    for (band, area) in BANDS.iter().zip(&panels) {
        let e = bandpass(&g.e, DS, band)?;
        let t = bandpass(&g.t, DS, band)?;
        if 2 * n >= e.len() {
            return Err(Error::Input(format!(
                "{} m is too short to trim {TRIM} m at each end",
                e.len() as f64 * DS
            )));
        }
        let s = &g.s[n..g.s.len() - n];
        let mm = |x: &[f64]| {
            x[n..x.len() - n]
                .iter()
                .map(|v| v * 1e3)
                .collect::<Vec<_>>()
        };
        let (e, t) = (mm(&e), mm(&t));
        two_lines(
            area,
            path,
            Some(band.label()),
            s,
            (&t, "truth"),
            (&e, "estimate"),
            ("distance [m]", "alignment [mm]"),
            55,
        )?;
    }
    root.present().map_err(err(path))
}

/// In-place iterative radix-2 FFT (`re.len()` a power of two).
pub fn fft(re: &mut [f64], im: &mut [f64]) {
    let n = re.len();
    assert!(
        n.is_power_of_two() && im.len() == n,
        "FFT length must be a power of two"
    );
    let mut j = 0;
    for i in 1..n {
        let mut bit = n >> 1;
        while j & bit != 0 {
            j ^= bit;
            bit >>= 1;
        }
        j |= bit;
        if i < j {
            re.swap(i, j);
            im.swap(i, j);
        }
    }
    let mut len = 2;
    while len <= n {
        let angle = -2.0 * std::f64::consts::PI / len as f64;
        for start in (0..n).step_by(len) {
            for k in 0..len / 2 {
                let (wr, wi) = ((angle * k as f64).cos(), (angle * k as f64).sin());
                let (a, b) = (start + k, start + k + len / 2);
                let (xr, xi) = (re[b] * wr - im[b] * wi, re[b] * wi + im[b] * wr);
                re[b] = re[a] - xr;
                im[b] = im[a] - xi;
                re[a] += xr;
                im[a] += xi;
            }
        }
        len <<= 1;
    }
}

/// One-sided amplitude spectrum of `x` sampled every `ds` metres: mean removed, Hann window
/// (amplitude-corrected), zero-padded to a power of two. Returns `(wavelength [m], amplitude)`
/// from the longest wavelength down, without the zero frequency; a sinusoid of amplitude `a` on
/// a bin gives a peak of about `a`.
pub fn amplitude_spectrum(x: &[f64], ds: f64) -> Vec<(f64, f64)> {
    let n = x.len();
    if n < 2 {
        return vec![];
    }
    let mean = x.iter().sum::<f64>() / n as f64;
    let w = |i: usize| 0.5 - 0.5 * (2.0 * std::f64::consts::PI * i as f64 / (n - 1) as f64).cos();
    let gain: f64 = (0..n).map(w).sum();
    let m = n.next_power_of_two();
    let mut re = vec![0.0; m];
    let mut im = vec![0.0; m];
    for (i, v) in x.iter().enumerate() {
        re[i] = (v - mean) * w(i);
    }
    fft(&mut re, &mut im);
    (1..m / 2)
        .map(|k| {
            let f = k as f64 / (m as f64 * ds);
            (1.0 / f, 2.0 * re[k].hypot(im[k]) / gain)
        })
        .collect()
}

/// Amplitude spectra \[mm\] of estimate and truth (both sampled at `distance`, values in m) over
/// wavelength 1-250 m, log-log, on the metrics' 0.05 m grid without band-pass.
pub fn spectra(
    path: &Path,
    distance: &[f64],
    estimate: &[f64],
    truth: &[f64],
    title: &str,
) -> Result<(), Error> {
    let g = on_grid(distance, estimate, truth)?;
    let (lo, hi) = (1.0, 250.0);
    let keep = |x: &[f64]| -> Vec<(f64, f64)> {
        amplitude_spectrum(x, DS)
            .into_iter()
            .filter(|(l, _)| (lo..=hi).contains(l))
            .map(|(l, a)| (l, (a * 1e3).max(1e-9)))
            .collect()
    };
    let (e, t) = (keep(&g.e), keep(&g.t));
    if e.is_empty() {
        return Err(Error::input(
            "the record is too short for a spectrum between 1 and 250 m",
        ));
    }
    let top = e.iter().chain(&t).map(|p| p.1).fold(1e-9, f64::max) * 2.0;
    let bottom = (top * 1e-5).max(1e-9);
    let root = white_svg(path, (1000, 600))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 20))
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(65)
        .build_cartesian_2d((lo..hi).log_scale(), (bottom..top).log_scale())
        .map_err(err(path))?;
    chart
        .configure_mesh()
        .x_desc("wavelength [m]")
        .y_desc("amplitude [mm]")
        .draw()
        .map_err(err(path))?;
    // The band edges 3, 25, 70, 200 m.
    for edge in [3.0, 25.0, 70.0, 200.0] {
        chart
            .draw_series(LineSeries::new(
                vec![(edge, bottom), (edge, top)],
                RGBColor(180, 180, 180),
            ))
            .map_err(err(path))?;
    }
    chart
        .draw_series(LineSeries::new(t, TRUTH.stroke_width(1)))
        .map_err(err(path))?
        .label("truth")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], TRUTH));
    chart
        .draw_series(LineSeries::new(e, ESTIMATE.stroke_width(1)))
        .map_err(err(path))?
        .label("estimate")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], ESTIMATE));
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(err(path))?;
    root.present().map_err(err(path))
}

/// The vehicle's wheelset lateral displacement `y` \[mm\] and yaw `psi` \[mrad\] against the
/// identified simplified model's, over time, two panels.
pub fn model_adjustment(path: &Path, id: &Identification) -> Result<(), Error> {
    let n = id.time.len();
    if n < 2
        || [&id.y_vehicle, &id.psi_vehicle, &id.y_model, &id.psi_model]
            .iter()
            .any(|v| v.len() != n)
    {
        return Err(Error::input(
            "the identification's signals need equal lengths of at least 2",
        ));
    }
    let root = white_svg(path, (1000, 700))?;
    let root = root
        .titled(
            &format!(
                "vehicle vs identified model (kx {:.3e}, cx {:.3e}, ky {:.3e}, cy {:.3e})",
                id.params.kx, id.params.cx, id.params.ky, id.params.cy
            ),
            ("sans-serif", 18),
        )
        .map_err(err(path))?;
    let panels = root.split_evenly((2, 1));
    let t = &id.time;
    for ((vehicle, model, label), area) in [
        (&id.y_vehicle, &id.y_model, "y [mm]"),
        (&id.psi_vehicle, &id.psi_model, "psi [mrad]"),
    ]
    .into_iter()
    .zip(&panels)
    {
        let scale = |x: &[f64]| x.iter().map(|v| v * 1e3).collect::<Vec<_>>();
        let (v, m) = (scale(vehicle), scale(model));
        two_lines(
            area,
            path,
            None,
            t,
            (&v, "vehicle"),
            (&m, "simplified model"),
            ("time [s]", label),
            60,
        )?;
    }
    root.present().map_err(err(path))
}

/// The top of [`case_bars`]' axis at most: larger Jrel are cut there and written as numbers.
pub const CAP: f64 = 2.5;

/// Jrel per band (groups: whole, D1, D2, D3) for each case (one coloured bar each, the seeds'
/// standard deviation as a whisker), the paper's Jrel as a black diamond where it reports one.
/// The axis stops at [`CAP`]: a bar cut there carries its value.
pub fn case_bars(path: &Path, results: &[CaseResult], title: &str) -> Result<(), Error> {
    if results.is_empty() {
        return Err(Error::input("no case to draw"));
    }
    let cases = results.len();
    let width = 0.8 / cases as f64;
    let x = |band: usize, case: usize| band as f64 + 0.1 + case as f64 * width;
    let mut top: f64 = 0.0;
    for r in results {
        for b in &r.bands {
            top = top.max(b.1.jrel_mean + b.1.jrel_std);
        }
        for p in r.paper.iter().flatten() {
            top = top.max(p.2);
        }
    }
    // Jrel above CAP (far worse than a zero estimate) is cut at the top of the axis.
    let top = if top.is_finite() && top > 0.0 {
        (top * 1.25).min(CAP)
    } else {
        1.0
    };
    let root = white_svg(path, (1300, 600))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 20))
        .margin(10)
        .x_label_area_size(20)
        .y_label_area_size(50)
        // Two empty units on the right hold the legend, clear of the bars.
        .build_cartesian_2d(0.0..BANDS.len() as f64 + 2.0, 0.0..top)
        .map_err(err(path))?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .disable_x_axis()
        .y_desc("Jrel")
        .draw()
        .map_err(err(path))?;
    // The band names at the top of each group.
    chart
        .draw_series(BANDS.iter().enumerate().map(|(i, b)| {
            Text::new(
                format!("{} {}-{} m", b.name, b.short, b.long),
                (i as f64 + 0.3, top * 0.98),
                ("sans-serif", 15),
            )
        }))
        .map_err(err(path))?;
    for (c, r) in results.iter().enumerate() {
        let color = PALETTE[c % PALETTE.len()];
        chart
            .draw_series((0..BANDS.len()).filter_map(|b| {
                r.bands.get(b).map(|(_, s)| s).map(|s| {
                    Rectangle::new(
                        [
                            (x(b, c), 0.0),
                            (x(b, c) + width * 0.9, s.jrel_mean.min(top)),
                        ],
                        color.filled(),
                    )
                })
            }))
            .map_err(err(path))?
            .label(r.name.clone())
            .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 15, y + 5)], color.filled()));
        chart
            .draw_series((0..BANDS.len()).filter_map(|b| {
                r.bands.get(b).map(|(_, s)| s).map(|s| {
                    let m = x(b, c) + width * 0.45;
                    PathElement::new(
                        vec![
                            (m, (s.jrel_mean - s.jrel_std).clamp(0.0, top)),
                            (m, (s.jrel_mean + s.jrel_std).min(top)),
                        ],
                        BLACK,
                    )
                })
            }))
            .map_err(err(path))?;
        // The values of bars cut at the top of the axis, written on them.
        chart
            .draw_series((0..BANDS.len()).filter_map(|b| {
                r.bands
                    .get(b)
                    .filter(|(_, s)| s.jrel_mean > top)
                    .map(|(_, s)| {
                        Text::new(
                            format!("{:.3}", s.jrel_mean),
                            (x(b, c), top * 0.9),
                            ("sans-serif", 12),
                        )
                    })
            }))
            .map_err(err(path))?;
        if let Some(paper) = &r.paper {
            chart
                .draw_series(paper.iter().enumerate().map(|(b, p)| {
                    let m = x(b, c) + width * 0.45;
                    let d = width * 0.3;
                    let h = top * 0.012;
                    let y = p.2.min(top - h);
                    Polygon::new(
                        vec![(m - d, y), (m, y + h), (m + d, y), (m, y - h)],
                        BLACK.filled(),
                    )
                }))
                .map_err(err(path))?;
        }
    }
    chart
        .draw_series(std::iter::once(Polygon::new(
            vec![(0.0, 0.0), (0.0, 0.0), (0.0, 0.0)],
            BLACK.filled(),
        )))
        .map_err(err(path))?
        .label("paper")
        .legend(|(x, y)| {
            Polygon::new(
                vec![(x + 2, y), (x + 8, y - 5), (x + 14, y), (x + 8, y + 5)],
                BLACK.filled(),
            )
        });
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .margin(10)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(err(path))?;
    root.present().map_err(err(path))
}

/// The time series of one standard-system run: the vehicle's time, distance and true alignment,
/// and the estimate interpolated at the vehicle's distance from the estimator's own distance
/// signal (as the metrics compare them: at the same track position).
#[derive(Debug, Clone, PartialEq)]
pub struct TimeSeries {
    /// Time of each row \[s\].
    pub time: Vec<f64>,
    /// \[m\]
    pub distance: Vec<f64>,
    /// True alignment \[m\].
    pub truth: Vec<f64>,
    /// Estimated alignment \[m\].
    pub estimate: Vec<f64>,
}

impl TimeSeries {
    /// From a standard run's table (the first row, the initial values, dropped as the metrics do).
    pub fn from_table(table: &Table) -> Result<TimeSeries, Error> {
        let c = |n: &str| {
            table
                .column(n)
                .map(|x| x.get(1..).unwrap_or_default().to_vec())
                .ok_or_else(|| Error::Input(format!("no column {n}")))
        };
        let (time, distance, truth) = (c("time")?, c("vehicle.distance")?, c("vehicle.alignment")?);
        let (ed, e) = (c("estimator.distance")?, c("estimator.alignment")?);
        if ed.len() < 2 {
            return Err(Error::input("not enough samples"));
        }
        let estimate = resample(&ed, &e, &distance);
        Ok(TimeSeries {
            time,
            distance,
            truth,
            estimate,
        })
    }

    /// The CSV header [`TimeSeries::to_csv`] writes, units in the names.
    pub const HEADER: &'static str = "time_s,distance_m,alignment_true_m,alignment_estimate_m";

    /// The series as CSV: [`TimeSeries::HEADER`], then one row per sample in shortest
    /// round-trip form.
    pub fn to_csv(&self) -> String {
        let mut s = String::with_capacity(64 * self.time.len() + 64);
        s.push_str(Self::HEADER);
        s.push('\n');
        let mut b = ryu::Buffer::new();
        for i in 0..self.time.len() {
            for (j, v) in [
                self.time[i],
                self.distance[i],
                self.truth[i],
                self.estimate[i],
            ]
            .into_iter()
            .enumerate()
            {
                if j > 0 {
                    s.push(',');
                }
                s.push_str(b.format(v));
            }
            s.push('\n');
        }
        s
    }

    /// Writes [`TimeSeries::to_csv`] to `path`, replacing it (the caller has checked that it
    /// may); an error names the file.
    pub fn write_csv(&self, path: &Path) -> Result<(), Error> {
        std::fs::write(path, self.to_csv()).map_err(|e| Error::write(path, e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::study::cases::Spread;

    fn well_formed(path: &Path) {
        let text = std::fs::read_to_string(path).unwrap();
        let t = text.trim();
        assert!(t.starts_with("<svg"), "{}", &t[..t.len().min(80)]);
        assert!(t.ends_with("</svg>"));
        assert!(
            t.contains("<polyline") || t.contains("<path"),
            "no line in {}",
            path.display()
        );
    }

    /// 400 m at 0.1 m steps.
    fn synthetic() -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let s: Vec<f64> = (0..4000).map(|k| k as f64 * 0.1).collect();
        let truth: Vec<f64> = s
            .iter()
            .map(|v| 1e-3 * (v / 1.7).sin() + 2e-3 * (v / 9.0).cos() + 3e-3 * (v / 20.0).sin())
            .collect();
        let estimate: Vec<f64> = truth.iter().map(|v| 0.9 * v + 1e-4).collect();
        (s, estimate, truth)
    }

    #[test]
    fn fft_matches_a_plain_dft() {
        let x: Vec<f64> = (0..16).map(|i| ((i * 7 % 5) as f64).sin()).collect();
        let (mut re, mut im) = (x.clone(), vec![0.0; 16]);
        fft(&mut re, &mut im);
        for k in 0..16 {
            let (mut r, mut i) = (0.0, 0.0);
            for (n, v) in x.iter().enumerate() {
                let a = -2.0 * std::f64::consts::PI * (k * n) as f64 / 16.0;
                r += v * a.cos();
                i += v * a.sin();
            }
            assert!((r - re[k]).abs() < 1e-12 && (i - im[k]).abs() < 1e-12);
        }
    }

    #[test]
    fn a_sinusoid_peaks_at_its_wavelength_with_its_amplitude() {
        // 409.6 m at 0.05 m (8192 samples): 20.48 m falls on a bin.
        let x: Vec<f64> = (0..8192)
            .map(|k| 2.0 * (2.0 * std::f64::consts::PI * k as f64 * 0.05 / 20.48).sin())
            .collect();
        let s = amplitude_spectrum(&x, 0.05);
        let peak = s
            .iter()
            .cloned()
            .fold((0.0, 0.0), |a, b| if b.1 > a.1 { b } else { a });
        assert!((peak.0 - 20.48).abs() < 1e-9, "{peak:?}");
        assert!((peak.1 - 2.0).abs() < 0.01, "{peak:?}");
    }

    #[test]
    fn every_plot_is_a_well_formed_svg() {
        let dir = tempfile::tempdir().unwrap();
        let (s, e, t) = synthetic();
        let p = dir.path().join("alignment.svg");
        estimate_vs_truth(&p, &s, &e, &t, "synthetic").unwrap();
        well_formed(&p);
        let p = dir.path().join("spectra.svg");
        spectra(&p, &s, &e, &t, "synthetic").unwrap();
        well_formed(&p);

        let time: Vec<f64> = (0..500).map(|k| k as f64 * 0.01).collect();
        let id = Identification {
            params: fmu_estimator::params::Params::TABLE_2,
            cost: 0.0,
            cost_table_2: 0.0,
            evaluations: 0,
            y_vehicle: time.iter().map(|t| 1e-3 * t.sin()).collect(),
            psi_vehicle: time.iter().map(|t| 1e-3 * t.cos()).collect(),
            y_model: time.iter().map(|t| 1.1e-3 * t.sin()).collect(),
            psi_model: time.iter().map(|t| 0.9e-3 * t.cos()).collect(),
            time,
        };
        let p = dir.path().join("model.svg");
        model_adjustment(&p, &id).unwrap();
        well_formed(&p);

        let spread = |m: f64| Spread {
            j_mean: m,
            j_std: 0.01,
            jrel_mean: m,
            jrel_std: 0.02,
        };
        let case = |name: &str, paper: bool| CaseResult {
            name: name.into(),
            seeds: vec![2, 3],
            per_seed: vec![],
            bands: BANDS
                .iter()
                .enumerate()
                .map(|(i, b)| (b.name.to_string(), spread(0.2 + 0.1 * i as f64)))
                .collect(),
            paper: paper.then(|| {
                BANDS
                    .iter()
                    .map(|b| (b.name.to_string(), 0.3, 0.25))
                    .collect()
            }),
        };
        let p = dir.path().join("bars.svg");
        let mut big = case("b", false);
        big.bands[3].1.jrel_mean = 100.0;
        case_bars(&p, &[case("a", true), big], "cases").unwrap();
        well_formed(&p);
        let text = std::fs::read_to_string(&p).unwrap();
        assert!(text.contains("<rect") && text.contains("<polygon"));
        assert!(text.contains("100.000"), "a cut bar carries its value");
    }

    #[test]
    fn the_time_series_csv_has_a_header_and_one_row_per_sample() {
        let n = 101;
        let time: Vec<f64> = (0..n).map(|k| k as f64 * 1e-3).collect();
        let table = Table {
            columns: [
                "time",
                "vehicle.distance",
                "vehicle.alignment",
                "estimator.distance",
                "estimator.alignment",
            ]
            .iter()
            .map(|s| s.to_string())
            .collect(),
            data: vec![
                time.clone(),
                time.iter().map(|t| 20.0 * t).collect(),
                time.iter().map(|t| t.sin()).collect(),
                time.iter().map(|t| 20.0 * (t - 1e-3).max(0.0)).collect(),
                time.iter().map(|t| (t - 1e-3).max(0.0).sin()).collect(),
            ],
        };
        let ts = TimeSeries::from_table(&table).unwrap();
        assert_eq!(ts.time.len(), n - 1);
        // The estimate is read at the vehicle's distance: it is the truth there.
        for (e, t) in ts.estimate.iter().zip(&ts.truth).take(n - 2) {
            assert!((e - t).abs() < 1e-9, "{e} {t}");
        }
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("seed.csv");
        ts.write_csv(&p).unwrap();
        let text = std::fs::read_to_string(&p).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], TimeSeries::HEADER);
        assert_eq!(lines.len(), ts.time.len() + 1);
        assert!(lines[1..].iter().all(|l| l.split(',').count() == 4));
    }
}
