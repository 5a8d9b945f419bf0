//! The multichannel FIR estimator and its Wiener-Hopf fit (module docs of [`super`], steps 2-4):
//! biased correlation estimates, one Cholesky solve per window, windows cut to the data at the
//! ends of a record.

use crate::Error;
use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

/// The taps for one window of lags `-future..=past`, channel after channel.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct Window {
    past: usize,
    future: usize,
    taps: Vec<f64>,
}

/// A multichannel FIR estimator fitted by the Wiener-Hopf equations (module docs, steps 2-4),
/// on samples already on the grid: up to `past` points behind and `future` ahead.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Fir {
    past: usize,
    future: usize,
    scale: Vec<f64>,
    /// `start[p]`: `p < past` points behind (the first points); `end[f]`: `f < future` points
    /// ahead (the last points); `full`: the whole window.
    start: Vec<Window>,
    end: Vec<Window>,
    full: Window,
}

impl Fir {
    /// Fits the taps of the window `past`, `future` so that the channels estimate `target`.
    pub fn fit(
        channels: &[Vec<f64>],
        target: &[f64],
        past: usize,
        future: usize,
        ridge: f64,
    ) -> Result<Fir, Error> {
        check_training(channels, target, past + future + 1)?;
        let scale = unit_scales(channels)?;
        let x: Vec<Vec<f64>> = channels
            .iter()
            .zip(&scale)
            .map(|(c, s)| c.iter().map(|v| v / s).collect())
            .collect();
        let normal = Normal::new(&x, target, past, future);
        let solve = |p: usize, f: usize| normal.solve(p, f, ridge);
        Ok(Fir {
            past,
            future,
            scale,
            start: (0..past)
                .map(|p| solve(p, future))
                .collect::<Result<_, _>>()?,
            end: (0..future)
                .map(|f| solve(past, f))
                .collect::<Result<_, _>>()?,
            full: solve(past, future)?,
        })
    }

    /// That the windows and taps agree (a saved file may have been edited).
    pub(super) fn check(&self) -> Result<(), Error> {
        let nc = self.scale.len();
        if nc == 0 || self.scale.iter().any(|s| !(s.is_finite() && *s > 0.0)) {
            return Err(Error::input("the channel scales must be positive numbers"));
        }
        let expected = (0..self.past)
            .map(|p| (p, self.future))
            .chain((0..self.future).map(|f| (self.past, f)));
        let windows = self.start.iter().chain(&self.end);
        if self.start.len() != self.past || self.end.len() != self.future {
            return Err(Error::input(format!(
                "{} start and {} end windows for a window of {} behind and {} ahead",
                self.start.len(),
                self.end.len(),
                self.past,
                self.future
            )));
        }
        for (w, (p, f)) in windows
            .chain([&self.full])
            .zip(expected.chain([(self.past, self.future)]))
        {
            if w.past != p || w.future != f || w.taps.len() != nc * (p + f + 1) {
                return Err(Error::input(format!(
                    "the window of {} behind and {} ahead has {} taps (expected {} behind, {} ahead, {} taps)",
                    w.past,
                    w.future,
                    w.taps.len(),
                    p,
                    f,
                    nc * (p + f + 1)
                )));
            }
            if w.taps.iter().any(|t| !t.is_finite()) {
                return Err(Error::input(format!(
                    "the window of {} behind and {} ahead has a tap that is not a number",
                    p, f
                )));
            }
        }
        Ok(())
    }

    /// The estimate at every sample of `channels` (scaled as in training).
    pub fn apply(&self, channels: &[Vec<f64>]) -> Result<Vec<f64>, Error> {
        let n = channels.first().map_or(0, Vec::len);
        if channels.len() != self.scale.len() || channels.iter().any(|c| c.len() != n) {
            return Err(Error::input(format!(
                "the learned smoother takes {} channels of equal length",
                self.scale.len()
            )));
        }
        let width = self.past + self.future + 1;
        if n < width {
            return Err(Error::input(format!(
                "{n} samples are fewer than the learned smoother's window ({width})"
            )));
        }
        Ok((0..n)
            .map(|m| {
                let w = if m < self.past {
                    &self.start[m]
                } else if m + self.future >= n {
                    &self.end[n - 1 - m]
                } else {
                    &self.full
                };
                let len = w.past + w.future + 1;
                let mut e = 0.0;
                for (c, x) in channels.iter().enumerate() {
                    let taps = &w.taps[c * len..(c + 1) * len];
                    // tap i is lag l = i - future: the sample m - l.
                    for (i, tap) in taps.iter().enumerate() {
                        e += tap * x[m + w.future - i] / self.scale[c];
                    }
                }
                e
            })
            .collect())
    }
}

/// Channels as long as the target, enough samples for a window of `width`, a finite target.
fn check_training(channels: &[Vec<f64>], target: &[f64], width: usize) -> Result<(), Error> {
    let n = target.len();
    if channels.is_empty() || channels.iter().any(|c| c.len() != n) {
        return Err(Error::input(
            "the learned smoother needs channels as long as the target",
        ));
    }
    if n < 2 * width {
        return Err(Error::input(format!(
            "{n} training samples are too few for a window of {width} (at least {})",
            2 * width
        )));
    }
    if let Some(k) = target.iter().position(|v| !v.is_finite()) {
        return Err(Error::input(format!(
            "training target sample {k} is not a number"
        )));
    }
    Ok(())
}

/// Each channel's standard deviation: the channels are divided by it so that one ridge suits
/// channels of any unit (conditioning only; the taps are scaled back by [`Fir::scale`]).
fn unit_scales(channels: &[Vec<f64>]) -> Result<Vec<f64>, Error> {
    channels
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let n = c.len() as f64;
            let mean = c.iter().sum::<f64>() / n;
            let sd = (c.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n).sqrt();
            if sd.is_finite() && sd > 0.0 {
                Ok(sd)
            } else {
                Err(Error::input(format!(
                    "training channel {i} is constant or not finite"
                )))
            }
        })
        .collect()
}

/// The Wiener-Hopf equations' ingredients (module docs, step 3): the channels' correlations
/// and their correlations with the target, biased (`1/N`) so that every window's matrix is a
/// Gram matrix.
struct Normal {
    /// `rho[c][d][tau + span] = (1/N) sum_n x_c[n] x_d[n + tau]`, `|tau| <= span`.
    rho: Vec<Vec<Vec<f64>>>,
    /// `r[c][l + future] = (1/N) sum_n x_c[n] t[n + l]`, `l` in `-future..=past`.
    r: Vec<Vec<f64>>,
    /// `past + future`: the largest lag difference a window needs.
    span: isize,
    /// The full window's look-ahead (the offset of `r`'s index).
    future: usize,
}

impl Normal {
    fn new(x: &[Vec<f64>], target: &[f64], past: usize, future: usize) -> Normal {
        let n = target.len();
        // rho(a, b, tau) = (1/N) sum_n a[n] b[n + tau].
        let corr = |a: &[f64], b: &[f64], tau: isize| -> f64 {
            let (lo, hi) = if tau >= 0 {
                (0, n - tau as usize)
            } else {
                ((-tau) as usize, n)
            };
            (lo..hi)
                .map(|i| a[i] * b[(i as isize + tau) as usize])
                .sum::<f64>()
                / n as f64
        };
        let span = (past + future) as isize;
        let rho = x
            .iter()
            .map(|a| {
                x.iter()
                    .map(|b| (-span..=span).map(|tau| corr(a, b, tau)).collect())
                    .collect()
            })
            .collect();
        let r = x
            .iter()
            .map(|a| {
                (-(future as isize)..=past as isize)
                    .map(|l| corr(a, target, l))
                    .collect()
            })
            .collect();
        Normal {
            rho,
            r,
            span,
            future,
        }
    }

    /// The taps of the window `p` behind and `f` ahead, with a ridge of `ridge` times the
    /// matrix's mean diagonal.
    fn solve(&self, p: usize, f: usize, ridge: f64) -> Result<Window, Error> {
        let nc = self.rho.len();
        let lags: Vec<isize> = (-(f as isize)..=p as isize).collect();
        let k = nc * lags.len();
        let at = |i: usize| (i / lags.len(), lags[i % lags.len()]);
        let mut m = DMatrix::<f64>::from_fn(k, k, |i, j| {
            let ((c, l), (d, q)) = (at(i), at(j));
            self.rho[c][d][(l - q + self.span) as usize]
        });
        let mean_diag = m.diagonal().mean();
        for i in 0..k {
            m[(i, i)] += ridge * mean_diag;
        }
        let rhs = DVector::<f64>::from_fn(k, |i, _| {
            let (c, l) = at(i);
            self.r[c][(l + self.future as isize) as usize]
        });
        let taps = m
            .cholesky()
            .ok_or_else(|| {
                Error::input("the learned smoother's normal equations are not positive definite")
            })?
            .solve(&rhs);
        Ok(Window {
            past: p,
            future: f,
            taps: taps.iter().copied().collect(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::study::learned::synthetic::{noise, rms};

    /// A target of `n` points and two channels cut from one longer noise: the target 3 points
    /// late (`x0[m] = t[m - 3]`) and 2 points early (`x1[m] = t[m + 2]`), true shifts at every
    /// point, ends included.
    fn shifted_pair(n: usize, seed: u64) -> (Vec<f64>, Vec<Vec<f64>>) {
        let long = noise(n + 10, seed);
        let t = long[5..5 + n].to_vec();
        let x0 = long[2..2 + n].to_vec();
        let x1 = long[7..7 + n].to_vec();
        (t, vec![x0, x1])
    }

    #[test]
    fn a_delayed_copy_is_undone_at_every_point_when_an_advanced_copy_exists() {
        // Oracle: t[m] = x0[m + 3] = x1[m - 2], so an exact inverse exists inside the window;
        // at the first points only the delayed copy's future and at the last only the advanced
        // copy's past are available, and each still holds t[m] exactly. The taps come from
        // biased correlation estimates, whose edge terms are O(window / N) = 0.5 %, so the
        // inverse is exact to that order; a filter padding the record with zeros instead of
        // cutting its window would miss by about half of |t| at the ends.
        let (t, x) = shifted_pair(4000, 7);
        let fir = Fir::fit(&x, &t, 10, 10, 1e-9).unwrap();
        let (test, inputs) = shifted_pair(500, 11);
        let e = fir.apply(&inputs).unwrap();
        let worst = e
            .iter()
            .zip(&test)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(worst < 0.02 * rms(&test), "{}", worst / rms(&test));
    }

    #[test]
    fn a_fixed_lag_filter_never_reads_beyond_its_lag() {
        // Oracle: causality by construction. Changing the inputs from sample k on must leave
        // every estimate before k - future untouched.
        let (t, x) = shifted_pair(3000, 3);
        let fir = Fir::fit(&x, &t, 15, 2, 1e-6).unwrap();
        let (_, mut inputs) = shifted_pair(600, 4);
        let before = fir.apply(&inputs).unwrap();
        let k = 400;
        for c in &mut inputs {
            for v in &mut c[k..] {
                *v += 1.0;
            }
        }
        let after = fir.apply(&inputs).unwrap();
        assert_eq!(before[..k - 2], after[..k - 2]);
        assert_ne!(before[k - 2], after[k - 2]);
    }

    #[test]
    fn an_unrelated_channel_gives_almost_nothing() {
        // Independent white noises: the fitted taps are the sampling noise of 41 correlations
        // over 8000 points, so the output on fresh data is about sqrt(41 / 8000) = 0.07 of the
        // target.
        let fir = Fir::fit(&[noise(8000, 99)], &noise(8000, 1), 20, 20, 1e-6).unwrap();
        let e = fir.apply(&[noise(2000, 5)]).unwrap();
        assert!(rms(&e) < 0.2 * rms(&noise(2000, 6)), "{}", rms(&e));
    }

    #[test]
    fn too_short_inputs_are_refused_by_name() {
        let t = noise(30, 1);
        assert!(
            Fir::fit(std::slice::from_ref(&t), &t, 10, 10, 1e-6)
                .unwrap_err()
                .to_string()
                .contains("too few")
        );
        let mut bad = noise(400, 3);
        bad[17] = f64::NAN;
        let e = Fir::fit(&[noise(400, 2)], &bad, 10, 10, 1e-6)
            .unwrap_err()
            .to_string();
        assert!(e.contains("sample 17"), "{e}");
        let fir = Fir::fit(&[noise(400, 2)], &noise(400, 3), 10, 10, 1e-6).unwrap();
        assert!(
            fir.apply(&[noise(15, 2)])
                .unwrap_err()
                .to_string()
                .contains("fewer than")
        );
    }
}
