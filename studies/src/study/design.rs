//! The vehicle's response to the design line, fitted for the estimator's design correction
//! (`fmu_estimator::design`, whose docs give the model): per bank speed, causal FIRs from the
//! history of the design's curvature and cant (block means on the estimator's grid) to what
//! each sensor reads beyond the rigid part (`a_nc` on the accelerometers, `V k` on the yaw
//! gyroscope).
//!
//! # Training data
//! The vehicle FMU without irregularities and without noise on random curved lines
//! ([`random_line`]: radius 300-1500 m either way, clothoid transitions 40-120 m, circular
//! parts 150-400 m, cant for a design speed of 10-25 m/s and 30-110 % of its balance, at most
//! 120 mm, straights of 50-250 m between): what the sensors read is then the design's response
//! alone. Every line ends on a straight longer than the FIR's memory, so the least squares on
//! the grid is exactly the Toeplitz system of the cells' correlations.
//!
//! # Fit
//! Ridge least squares per speed and sensor over the training lines, the ridge ([`RIDGES`])
//! chosen on two validation lines of other seeds, no intercept (so straight, level track gives
//! exactly 0).

use super::runs::{Fmus, Settings, vehicle_run_driven};
use crate::Error;
use fmu_estimator::design::{DesignModel, SENSORS, SensorResponse, TABLES};
use fmu_vehicle::simulation::NoiseRng;
use nalgebra::{DMatrix, DVector};
use orchestrator::system::Value;
use rayon::prelude::*;
use std::path::Path;

/// How far off (uniformly, each sample on its own) the validation places the design samples
/// it feeds the taps \[m\]: half a cell, as odometry places a line database's design. The
/// training lines' inputs are exact, and the smooth designs leave the taps' short-wave gain
/// free: with the smallest ridge they reached 2300 per metre of cant summing to -0.04, and a
/// sample now and then in the next cell (measured with a master's 1e-16 m clock rounding,
/// before the design history used the learned filter's grid) moved the estimate by 0.2 mm.
/// Judged on jittered inputs, the ridge keeps that gain in check.
pub const JITTER: f64 = 0.1;

/// Validation lines per speed (for the ridge), and the offset of their seeds from the
/// training lines'.
const VALIDATION_LINES: u64 = 2;
const VALIDATION_SEED_OFFSET: u64 = 1000;

/// Gravity the vehicle model uses \[m/s2\].
const GRAVITY: f64 = fmu_vehicle::dynamics::GRAVITY;

/// How the design response is fitted.
#[derive(Debug, Clone, PartialEq)]
pub struct DesignFitOptions {
    /// Bank speeds \[m/s\], ascending.
    pub speeds: Vec<f64>,
    /// Training lines per speed (the same lines at every speed).
    pub lines: usize,
    /// Length of each line's curved part \[m\].
    pub length: f64,
    /// Seed of the first line (line `i` has seed `seed + i`).
    pub seed: u64,
    /// Grid cell \[m\].
    pub cell: f64,
    /// Cells of history.
    pub taps: usize,
}

impl Default for DesignFitOptions {
    fn default() -> Self {
        DesignFitOptions {
            speeds: (0..11).map(|i| 5.0 + 2.5 * f64::from(i)).collect(),
            lines: 6,
            length: 2500.0,
            seed: 7100,
            cell: 0.2,
            taps: 250,
        }
    }
}

/// A random curved line (module docs): rows (distance, curvature, cant), starting with 100 m
/// of straight and ending with `tail` metres of it.
pub fn random_line(seed: u64, length: f64, half_gauge: f64, tail: f64) -> Vec<(f64, f64, f64)> {
    let mut rng = NoiseRng::new(seed);
    let mut uniform =
        |a: f64, b: f64| a + (b - a) * (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
    let mut rows = vec![(0.0, 0.0, 0.0)];
    let mut s = 100.0;
    rows.push((s, 0.0, 0.0));
    while s < length {
        let sign = if uniform(0.0, 1.0) < 0.5 { -1.0 } else { 1.0 };
        let radius = uniform(300.0, 1500.0);
        let (transition, circular) = (uniform(40.0, 120.0), uniform(150.0, 400.0));
        let design_speed: f64 = uniform(10.0, 25.0);
        let balance = design_speed.powi(2) / radius * 2.0 * half_gauge / GRAVITY;
        let cant = (balance * uniform(0.3, 1.1)).min(0.12);
        let (k, c) = (sign / radius, sign * cant);
        rows.push((s + transition, k, c));
        rows.push((s + transition + circular, k, c));
        s += 2.0 * transition + circular;
        rows.push((s, 0.0, 0.0));
        s += uniform(50.0, 250.0);
        rows.push((s, 0.0, 0.0));
    }
    rows.push((s + tail, 0.0, 0.0));
    rows
}

/// A line as the vehicle FMU's line file reads it.
pub fn line_csv(rows: &[(f64, f64, f64)]) -> String {
    let mut s = String::from("distance,curvature,cant\n");
    for (d, k, c) in rows {
        s.push_str(&format!("{d},{k},{c}\n"));
    }
    s
}

/// One clean run's grid: per cell the design's means (curvature, cant) and each sensor's
/// residual beyond the rigid part; and the largest `|a_nc|` met.
struct Grid {
    design: [Vec<f64>; 2],
    /// The design with its samples placed off ([`JITTER`]), for the validation.
    rounded: [Vec<f64>; 2],
    /// Per table ([`TABLES`]): the sensors beyond the rigid part, then the wheelset's shift.
    residual: [Vec<f64>; 5],
    max_uncompensated: f64,
}

/// Block means of `x` over cells of `cell` m by `distance`; cells without a sample take the
/// previous cell's value.
fn cells(distance: &[f64], x: &[f64], cell: f64, n: usize) -> Vec<f64> {
    let (mut sum, mut count) = (vec![0.0; n], vec![0u32; n]);
    for (d, v) in distance.iter().zip(x) {
        let i = (d / cell).floor();
        if i >= 0.0 && (i as usize) < n {
            sum[i as usize] += v;
            count[i as usize] += 1;
        }
    }
    let mut last = 0.0;
    sum.iter()
        .zip(&count)
        .map(|(s, &c)| {
            if c > 0 {
                last = s / f64::from(c);
            }
            last
        })
        .collect()
}

/// Runs the vehicle along `line` (a file) at `speed` without irregularities or noise and grids
/// what it reads.
fn clean_run(
    fmus: &Fmus,
    line: &Path,
    length: f64,
    speed: f64,
    cell: f64,
    half_gauge: f64,
) -> Result<Grid, Error> {
    let settings: Settings = vec![
        (
            "line_file".into(),
            Value::String(line.display().to_string()),
        ),
        ("lateral_irregularity".into(), Value::Boolean(false)),
        ("vertical_irregularity".into(), Value::Boolean(false)),
        ("sensor_noise".into(), Value::Boolean(false)),
        ("speed".into(), Value::Real(speed)),
    ];
    let stop = (length / speed * 1000.0).floor() / 1000.0;
    let variables = [
        "distance",
        "forward_speed",
        "design_curvature",
        "design_cant",
        "ws_acc_y",
        "ws_yaw_rate",
        "frame_acc_y",
        "ws_roll_rate",
        "ws_y",
    ];
    let table = vehicle_run_driven(fmus, settings, &variables, stop, Some(&|_| speed))?;
    let col = |n: &str| -> Result<Vec<f64>, Error> {
        table
            .column(&format!("vehicle.{n}"))
            .map(|x| x[1..].to_vec())
            .ok_or_else(|| Error::Input(format!("the vehicle FMU has no output '{n}'")))
    };
    let (d, v, k, c) = (
        col("distance")?,
        col("forward_speed")?,
        col("design_curvature")?,
        col("design_cant")?,
    );
    let n = (length / cell).floor() as usize;
    let mut max_uncompensated: f64 = 0.0;
    let rigid: Vec<[f64; 4]> = (0..d.len())
        .map(|i| {
            let a_nc = v[i] * v[i] * k[i] - GRAVITY * c[i] / (2.0 * half_gauge);
            max_uncompensated = max_uncompensated.max(a_nc.abs());
            [a_nc, v[i] * k[i], a_nc, 0.0]
        })
        .collect();
    let mut residual: [Vec<f64>; 5] = Default::default();
    for (s, name) in SENSORS.iter().enumerate() {
        let x = col(name)?;
        let r: Vec<f64> = x.iter().zip(&rigid).map(|(x, r)| x - r[s]).collect();
        residual[s] = cells(&d, &r, cell, n);
    }
    residual[4] = cells(&d, &col("ws_y")?, cell, n);
    // Each sample placed JITTER off (uniform), as odometry places a line database's design.
    let mut rng = NoiseRng::new(d.len() as u64);
    let jittered: Vec<f64> = d
        .iter()
        .map(|x| x + JITTER * (2.0 * (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64 - 1.0))
        .collect();
    // The estimator applies tap 0 to the last complete cell, while a sample's own cell is still
    // filling: so the design history is regressed one cell late.
    let late = |x: Vec<f64>| -> Vec<f64> { std::iter::once(0.0).chain(x).take(n).collect() };
    Ok(Grid {
        design: [late(cells(&d, &k, cell, n)), late(cells(&d, &c, cell, n))],
        rounded: [
            late(cells(&jittered, &k, cell, n)),
            late(cells(&jittered, &c, cell, n)),
        ],
        residual,
        max_uncompensated,
    })
}

/// `sum_m a[m] b[m + lag]` for lags `-(taps - 1)..taps`, index `lag + taps - 1`.
fn correlation(a: &[f64], b: &[f64], taps: usize) -> Vec<f64> {
    let n = a.len();
    (0..2 * taps - 1)
        .map(|i| {
            let lag = i as isize - (taps as isize - 1);
            (0..n)
                .filter_map(|m| {
                    let j = m as isize + lag;
                    (j >= 0 && (j as usize) < n).then(|| a[m] * b[j as usize])
                })
                .sum()
        })
        .collect()
}

/// Ridges tried, relative to the mean diagonal of each input's block of the normal matrix (one
/// scale for both had damped the curvature taps far harder: whole Jrel on the standard curved
/// line 0.151 against 0.148 per block, seeds 1-5): the design inputs are smooth
/// and the normal matrix ill-conditioned, so a ridge that is small for rough inputs (1e-6)
/// already biases the fit (whole Jrel on the standard curved line 0.21 against 0.15 with 1e-12,
/// seeds 1-3, in the study's prototype), and the smallest leaves the taps' short-wave gain
/// free ([`JITTER`]); each speed and sensor takes the one with the smallest residual on the
/// validation lines, fed jittered inputs.
pub const RIDGES: [f64; 7] = [1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12];

/// The FIR `h` (curvature taps, then cant taps) applied to grid `g` (its exact design, or the
/// `rounded` one), against its residual `s`: the sums of squares of the error and of the
/// residual, and the cell count.
fn misfit(h: &DVector<f64>, g: &Grid, s: usize, taps: usize, rounded: bool) -> (f64, f64, usize) {
    let n = g.residual[s].len();
    let x = if rounded { &g.rounded } else { &g.design };
    let (mut err, mut sig) = (0.0, 0.0);
    for t in 0..n {
        let mut y = 0.0;
        for i in 0..taps.min(t + 1) {
            y += h[i] * x[0][t - i] + h[taps + i] * x[1][t - i];
        }
        err += (g.residual[s][t] - y).powi(2);
        sig += g.residual[s][t].powi(2);
    }
    (err, sig, n)
}

/// The fit for one speed: per sensor, (curvature taps, cant taps, the chosen ridge, the
/// training residual's and signal's rms, the validation residual's and signal's rms).
type Fitted = (Vec<f64>, Vec<f64>, f64, [f64; 4]);

/// The flange clearance the vehicle FMU runs with unless set (its `flange_clearance` default)
/// \[m\].
const DEFAULT_FLANGE_CLEARANCE: f64 = 0.009;

/// Ridge least squares over the training grids, the ridge chosen on the validation grids.
fn solve(train: &[Grid], valid: &[Grid], taps: usize) -> Result<Vec<Fitted>, Error> {
    let m = 2 * taps;
    let mut a = DMatrix::<f64>::zeros(m, m);
    for g in train {
        for p in 0..2 {
            for q in 0..2 {
                let r = correlation(&g.design[p], &g.design[q], taps);
                for i in 0..taps {
                    for j in 0..taps {
                        // sum_n x_p[n - i] x_q[n - j] = r_pq(i - j)
                        a[(p * taps + i, q * taps + j)] +=
                            r[(i as isize - j as isize + taps as isize - 1) as usize];
                    }
                }
            }
        }
    }
    // Relative to each input's own block (curvature about 1e-3, cant about 1e-1: one scale for
    // both would damp the curvature taps 1e4 times harder).
    let block = |b: usize| (b * taps..(b + 1) * taps).map(|i| a[(i, i)]).sum::<f64>() / taps as f64;
    let scale = [block(0), block(1)];
    let factors: Vec<_> = RIDGES
        .iter()
        .filter_map(|&ridge| {
            let mut ar = a.clone();
            for i in 0..m {
                ar[(i, i)] += ridge * scale[i / taps];
            }
            ar.cholesky().map(|c| (ridge, c))
        })
        .collect();
    if factors.is_empty() {
        return Err(Error::Input(
            "the design-response normal equations are singular at every ridge".into(),
        ));
    }
    let rms = |grids: &[Grid], h: &DVector<f64>, s: usize, rounded: bool| {
        let (mut e, mut q, mut n) = (0.0, 0.0, 0usize);
        for g in grids {
            let (de, dq, dn) = misfit(h, g, s, taps, rounded);
            e += de;
            q += dq;
            n += dn;
        }
        let n = n.max(1) as f64;
        ((e / n).sqrt(), (q / n).sqrt())
    };
    (0..TABLES.len())
        .map(|s| {
            let mut b = DVector::<f64>::zeros(m);
            for g in train {
                for p in 0..2 {
                    // sum_n x_p[n - i] y[n] = r_{x_p, y}(i)
                    let r = correlation(&g.design[p], &g.residual[s], taps);
                    for i in 0..taps {
                        b[p * taps + i] += r[i + taps - 1];
                    }
                }
            }
            let (ridge, h, (ve, vs)) = factors
                .iter()
                .map(|(ridge, c)| {
                    let h = c.solve(&b);
                    let v = rms(valid, &h, s, true);
                    (*ridge, h, v)
                })
                .min_by(|x, y| x.2.0.total_cmp(&y.2.0))
                .expect("at least one ridge");
            let (te, ts) = rms(train, &h, s, false);
            Ok((
                h.rows(0, taps).iter().copied().collect(),
                h.rows(taps, taps).iter().copied().collect(),
                ridge,
                [te, ts, ve, vs],
            ))
        })
        .collect()
}

/// What a fit reports per speed and sensor.
#[derive(Debug, Clone, PartialEq)]
pub struct FitQuality {
    /// Bank speed \[m/s\].
    pub speed: f64,
    /// Per table ([`TABLES`]): the chosen ridge, and the rms of the training residual, of
    /// what was to fit there, of the validation residual and of what was to fit there, in the
    /// table's unit.
    pub rms: [(f64, [f64; 4]); 5],
}

/// Fits the model on the vehicle FMU of `fmus` (its line files written into `work`).
pub fn fit(
    fmus: &Fmus,
    options: &DesignFitOptions,
    work: &Path,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<(DesignModel, Vec<FitQuality>), Error> {
    let params = fmus.vehicle_params()?;
    let half_gauge = params.wheelset.half_gauge;
    let tail = options.taps as f64 * options.cell + 100.0;
    let mut lines = vec![];
    let mut max_curvature: f64 = 0.0;
    // Training lines, then the validation lines (seeds VALIDATION_SEED_OFFSET on).
    let seeds: Vec<u64> = (0..options.lines as u64)
        .map(|i| options.seed + i)
        .chain((0..VALIDATION_LINES).map(|i| options.seed + VALIDATION_SEED_OFFSET + i))
        .collect();
    for (i, &seed) in seeds.iter().enumerate() {
        let rows = random_line(seed, options.length, half_gauge, tail);
        max_curvature = rows.iter().fold(max_curvature, |m, r| m.max(r.1.abs()));
        let path = work.join(format!("design-line-{i}.csv"));
        std::fs::write(&path, line_csv(&rows))
            .map_err(|e| Error::Io(format!("{}: {e}", path.display())))?;
        lines.push((path, rows.last().map_or(0.0, |r| r.0)));
    }
    let jobs: Vec<(f64, usize)> = options
        .speeds
        .iter()
        .flat_map(|&v| (0..lines.len()).map(move |i| (v, i)))
        .collect();
    let grids: Vec<(f64, Grid)> = jobs
        .par_iter()
        .map(|&(v, i)| {
            let (path, length) = &lines[i];
            let g = clean_run(fmus, path, *length, v, options.cell, half_gauge)?;
            progress(&format!("design response: line {} at {v} m/s run", i + 1));
            Ok((v, g))
        })
        .collect::<Result<_, Error>>()?;
    let max_uncompensated = grids
        .iter()
        .fold(0.0f64, |m, g| m.max(g.1.max_uncompensated));
    let grids: Vec<(f64, Grid)> = grids;
    let mut by_speed: Vec<(f64, Vec<Grid>, Vec<Grid>)> = options
        .speeds
        .iter()
        .map(|&v| (v, vec![], vec![]))
        .collect();
    for ((v, i), (_, g)) in jobs.iter().zip(grids) {
        let slot = by_speed
            .iter_mut()
            .find(|b| b.0 == *v)
            .expect("a bank speed");
        if *i < options.lines {
            slot.1.push(g);
        } else {
            slot.2.push(g);
        }
    }
    let fitted: Vec<(f64, Vec<Fitted>)> = by_speed
        .par_iter()
        .map(|(v, train, valid)| Ok((*v, solve(train, valid, options.taps)?)))
        .collect::<Result<_, Error>>()?;
    let mut response = vec![];
    let mut quality = vec![];
    for (v, per_sensor) in fitted {
        let mut rms = [(0.0, [0.0; 4]); 5];
        for (s, (k, c, ridge, figures)) in per_sensor.into_iter().enumerate() {
            rms[s] = (ridge, figures);
            response.push(SensorResponse {
                speed: v,
                sensor: TABLES[s].to_string(),
                offset: 0.0,
                curvature: k,
                cant: c,
            });
        }
        quality.push(FitQuality { speed: v, rms });
    }
    let flange_clearance = fmus
        .vehicle_settings
        .iter()
        .rev()
        .find(|(n, _)| n == "flange_clearance")
        .and_then(|(_, v)| match v {
            Value::Real(x) => Some(*x),
            Value::String(t) => t.trim().parse().ok(),
            _ => None,
        })
        .unwrap_or(DEFAULT_FLANGE_CLEARANCE);
    let model = DesignModel {
        format: 2,
        vehicle: params.name.clone(),
        cell: options.cell,
        half_gauge,
        gravity: GRAVITY,
        max_curvature,
        max_uncompensated,
        flange_clearance,
        response,
    };
    model.check().map_err(Error::Input)?;
    Ok((model, quality))
}

/// The model as its file holds it, the taps to five significant digits (the correction's
/// relative error from the rounding is about 1e-5).
pub fn to_toml(model: &DesignModel, header: &str) -> String {
    let mut s = String::new();
    for line in header.lines() {
        s.push_str(&format!("# {line}\n"));
    }
    s.push_str(&format!(
        "format = {}\nvehicle = \"{}\"\ncell = {}\nhalf_gauge = {}\ngravity = {}\nmax_curvature = {:.6e}\nmax_uncompensated = {:.6e}\nflange_clearance = {}\n",
        model.format, model.vehicle, model.cell, model.half_gauge, model.gravity, model.max_curvature, model.max_uncompensated, model.flange_clearance
    ));
    let list = |x: &[f64]| {
        x.iter()
            .map(|v| format!("{v:.4e}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    for r in &model.response {
        s.push_str(&format!(
            "\n[[response]]\nspeed = {}\nsensor = \"{}\"\noffset = {}\ncurvature = [{}]\ncant = [{}]\n",
            r.speed,
            r.sensor,
            r.offset,
            list(&r.curvature),
            list(&r.cant)
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Toeplitz normal equations are the least squares on the grid: a response made by
    /// known taps is recovered.
    #[test]
    fn known_taps_are_recovered() {
        let taps = 6;
        let n = 4000;
        let mut rng = NoiseRng::new(3);
        let mut smooth = |scale: f64| {
            let mut x = 0.0;
            let mut v: Vec<f64> = (0..n)
                .map(|_| {
                    x = 0.95 * x + scale * rng.normal();
                    x
                })
                .collect();
            // Level at the end, longer than the memory (the training lines' straight tail).
            for e in v.iter_mut().skip(n - 2 * taps) {
                *e = 0.0;
            }
            v
        };
        let (k, c) = (smooth(1e-3), smooth(0.01));
        let hk: Vec<f64> = (0..taps).map(|i| 3.0 - i as f64).collect();
        let hc: Vec<f64> = (0..taps).map(|i| 0.5 * i as f64).collect();
        let y: Vec<f64> = (0..n)
            .map(|t| {
                (0..taps.min(t + 1))
                    .map(|i| hk[i] * k[t - i] + hc[i] * c[t - i])
                    .sum()
            })
            .collect();
        let g = Grid {
            design: [k.clone(), c.clone()],
            rounded: [k, c],
            residual: [y.clone(), y.clone(), y.clone(), y.clone(), y],
            max_uncompensated: 0.0,
        };
        let valid = Grid {
            design: g.design.clone(),
            rounded: g.design.clone(),
            residual: g.residual.clone(),
            max_uncompensated: 0.0,
        };
        let fitted = solve(&[g], &[valid], taps).unwrap();
        let (fk, fc, _, [err, sig, _, _]) = &fitted[0];
        for i in 0..taps {
            assert!(
                (fk[i] - hk[i]).abs() < 1e-3 * 3.0,
                "{i}: {} {}",
                fk[i],
                hk[i]
            );
            assert!(
                (fc[i] - hc[i]).abs() < 1e-3 * 3.0,
                "{i}: {} {}",
                fc[i],
                hc[i]
            );
        }
        assert!(err / sig < 1e-3, "{err} {sig}");
    }

    #[test]
    fn random_lines_stay_within_their_ranges() {
        let rows = random_line(5, 3000.0, 0.75, 150.0);
        assert!(rows.windows(2).all(|w| w[1].0 > w[0].0));
        assert!(
            rows.iter()
                .all(|r| r.1.abs() <= 1.0 / 300.0 + 1e-12 && r.2.abs() <= 0.12)
        );
        let last = rows.len() - 1;
        assert_eq!((rows[last].1, rows[last - 1].1), (0.0, 0.0));
        assert!(rows[last].0 - rows[last - 1].0 >= 150.0);
    }
}
