//! The distance grid the learned filter works on: a causal block mean of the 1 kHz samples over
//! cells of `ds` metres, and the causal high-pass of the Kalman channel.
//!
//! # Why a distance grid
//! The track is a function of distance; the sensors are sampled in time. Cells of fixed length
//! make the FIR's lags metres whatever the speed, so one history serves the taps of every speed
//! in the bank and a speed change costs nothing. A block mean (a box filter one cell long) is the
//! cheapest causal anti-alias filter: its delay is half a cell (0.1 m on the 0.2 m grid), and it
//! reads no sample after the cell's end.
//!
//! # Cells
//! Cell `m` holds the samples whose distance (after their step) lies in `[m ds, (m + 1) ds)`,
//! boundaries moved [`EDGE`] (1 nm) earlier. It closes at the first sample at or beyond
//! `(m + 1) ds - EDGE`; that sample belongs to the next cell. A step that crosses several boundaries (coarse steps, high speed) closes each crossed
//! cell with the same mean. Non-finite sensor samples are left out of the mean; a cell without
//! any finite sample repeats the previous cell's values.
//!
//! # The Kalman channel's high-pass
//! The paper's filter models the alignment as a random walk, so its estimate wanders at long
//! wavelengths (tens of mm over a few hundred metres on the standard run). Before it enters the
//! FIR it passes a causal second-order Butterworth high-pass in distance (cut-off
//! `kalman_highpass` metres, bilinear transform with pre-warping, i.e. the RBJ cookbook
//! high-pass with `Q = 1/sqrt(2)`): the FIR sees a bounded signal, so its output stays bounded
//! over any run length, and the taps learn the high-pass's phase inside the band.
//!
//! # The shelf after the high-pass (banks of format 5)
//! In wavenumber `s = i 2 pi / wavelength`, the high-pass `H = s^2 / (s^2 + sqrt(2) w s + w^2)`
//! (`w = 2 pi / kalman_highpass`) is, well inside its pass band, `1 - sqrt(2) w / s + O((w/s)^2)`:
//! at `s = i 2 pi / lambda` a phase lead of about `sqrt(2) lambda / kalman_highpass` radians at
//! wavelength `lambda` (exactly `atan(sqrt(2) r / (r^2 - 1))`, `r = kalman_highpass / lambda`:
//! 16 degrees at 200 m for a 1000 m cut-off). A 60 m window of taps cannot undo a phase that grows with the
//! wavelength (it would need the high-pass's inverse, integrators with a memory of the cut-off's
//! length), so the D3 band (70-200 m) paid for it. A bank may therefore state a first-order shelf
//! `S = (s + (beta + sqrt(2)) w) / (s + beta w)` (`kalman_shelf = beta`), applied after the
//! high-pass. `S = 1 + sqrt(2) w / s + O((w/s)^2)` at short waves, so `H S = 1 + O((w/s)^2)`:
//! the lead cancels to first order. At long waves `H S` still falls as `s^2`, so a random walk
//! (spectrum `1/s^2`) comes out bounded; the price is the shelf's gain `(beta + sqrt(2)) / beta`
//! below the cut-off, which lets more of the random walk through (the trade and its figures:
//! `KALMAN_SHELF` in `studies/src/study/learned/taps.rs`). Discretized by the bilinear
//! transform `s = (2 / ds) (1 - z^-1) / (1 + z^-1)` without pre-warping: at `w ds` of 1e-3 the
//! warping is below 1e-6.

use serde::{Deserialize, Serialize};

/// The most cells one sample may close: only a bound on the loop (1 << 20 cells is 210 km at
/// 0.2 m; the caller refuses a jump in distance long before that).
pub const MAX_CELLS_PER_SAMPLE: usize = 1 << 20;

/// The channels a tap bank may use, in the order the grid holds them.
pub const CHANNELS: [&str; 5] = [
    "ws_acc_y",
    "ws_yaw_rate",
    "frame_acc_y",
    "ws_roll_rate",
    "kalman",
];
/// Index of the Kalman channel in [`CHANNELS`].
pub const KALMAN: usize = 4;
/// Index of the roll-rate channel in [`CHANNELS`].
pub const ROLL_RATE: usize = 3;

/// A causal biquad section, direct form II transposed.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct Biquad {
    b: [f64; 3],
    a: [f64; 2],
    s: [f64; 2],
}

impl Biquad {
    /// Second-order Butterworth high-pass with cut-off wavelength `cutoff` on a grid of `ds`
    /// (both metres).
    pub fn highpass(ds: f64, cutoff: f64) -> Biquad {
        let w0 = std::f64::consts::TAU * ds / cutoff;
        let (sin, cos) = w0.sin_cos();
        let alpha = sin / std::f64::consts::SQRT_2; // sin(w0) / (2 Q), Q = 1/sqrt(2)
        let a0 = 1.0 + alpha;
        let k = (1.0 + cos) / 2.0 / a0;
        Biquad {
            b: [k, -2.0 * k, k],
            a: [-2.0 * cos / a0, (1.0 - alpha) / a0],
            s: [0.0; 2],
        }
    }

    /// Second-order Butterworth low-pass with cut-off wavelength `cutoff` on a grid of `ds`
    /// (RBJ cookbook low-pass, `Q = 1/sqrt(2)`).
    pub fn lowpass(ds: f64, cutoff: f64) -> Biquad {
        Biquad::lowpass_q(ds, cutoff, std::f64::consts::FRAC_1_SQRT_2)
    }

    /// A second-order low-pass section of quality factor `q` (RBJ cookbook): the sections of
    /// a higher-order Butterworth low-pass share the cut-off and differ in `q`.
    pub fn lowpass_q(ds: f64, cutoff: f64, q: f64) -> Biquad {
        let w0 = std::f64::consts::TAU * ds / cutoff;
        let (sin, cos) = w0.sin_cos();
        let alpha = sin / (2.0 * q);
        let a0 = 1.0 + alpha;
        let k = (1.0 - cos) / 2.0 / a0;
        Biquad {
            b: [k, 2.0 * k, k],
            a: [-2.0 * cos / a0, (1.0 - alpha) / a0],
            s: [0.0; 2],
        }
    }

    /// The shelf `(s + (beta + sqrt(2)) w) / (s + beta w)` after the high-pass of cut-off
    /// wavelength `cutoff` (`w = 2 pi / cutoff`) on a grid of `ds` (both metres), `beta > 0`
    /// (module docs): a first-order section, its second-order coefficients zero.
    pub fn shelf(ds: f64, cutoff: f64, beta: f64) -> Biquad {
        let w = std::f64::consts::TAU / cutoff;
        let (zero, pole) = ((beta + std::f64::consts::SQRT_2) * w, beta * w);
        let k = 2.0 / ds;
        Biquad {
            b: [(k + zero) / (k + pole), (zero - k) / (k + pole), 0.0],
            a: [(pole - k) / (k + pole), 0.0],
            s: [0.0; 2],
        }
    }

    /// `[b0, b1, b2, a1, a2]`: the design, as a bank's contract states it.
    pub fn coefficients(&self) -> [f64; 5] {
        [self.b[0], self.b[1], self.b[2], self.a[0], self.a[1]]
    }

    /// Filters the next grid value `x` and returns the output; the state carries over, so
    /// values must come one per cell, in order.
    pub fn step(&mut self, x: f64) -> f64 {
        let y = self.b[0] * x + self.s[0];
        self.s[0] = self.b[1] * x - self.a[0] * y + self.s[1];
        self.s[1] = self.b[2] * x - self.a[1] * y;
        y
    }
}

/// How far before a cell's end a sample still closes it \[m\]. At 20 m/s and 1 kHz a 0.2 m cell
/// holds exactly 10 samples, so every cell ends on a sample, and whether that sample's distance
/// (a sum of `speed * h`) lands a rounding error before or after the boundary decided which cell
/// it fell in: a master whose steps are 1 ms +- 1 ulp (libcosim) got other cells than one with
/// exact steps. A nanometre is far above that rounding and far below anything on a track.
pub const EDGE: f64 = 1e-9;

/// The cell accumulator.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct Grid {
    ds: f64,
    /// The distance at which the open cell closes.
    next: f64,
    sum: [f64; 5],
    count: u32,
    last: [f64; 5],
    highpass: Biquad,
    shelf: Option<Biquad>,
}

/// Cells closed by one sample: how many, their channel values (the high-pass, and the shelf if
/// any, applied to the Kalman channel of each), and the distance of the sample that closed them.
#[derive(Debug, Clone, PartialEq)]
pub struct Closed {
    /// The closed cells, oldest first: more than one when a sample jumps over a whole cell
    /// (each empty cell repeats the last mean).
    pub cells: Vec<[f64; 5]>,
    /// The distance of the sample that closed them \[m\]: the position their causal estimate
    /// is for.
    pub distance: f64,
}

impl Grid {
    /// An empty grid of cells `ds` long starting at distance 0, its Kalman channel high-passed
    /// at the wavelength `kalman_highpass` (both metres) and, with `kalman_shelf`, shelved
    /// after it (module docs), as the bank states them.
    pub fn new(ds: f64, kalman_highpass: f64, kalman_shelf: Option<f64>) -> Grid {
        Grid {
            ds,
            next: ds,
            sum: [0.0; 5],
            count: 0,
            last: [0.0; 5],
            highpass: Biquad::highpass(ds, kalman_highpass),
            shelf: kalman_shelf.map(|beta| Biquad::shelf(ds, kalman_highpass, beta)),
        }
    }

    /// The cell length \[m\]: converts the windows' grid points to metres.
    pub fn step_length(&self) -> f64 {
        self.ds
    }

    /// Adds the sample `x` (channels in [`CHANNELS`] order) taken at `distance`; returns the
    /// cells it closes. `x` belongs to the cell it is in, never to one it closes.
    pub fn add(&mut self, distance: f64, x: &[f64; 5]) -> Option<Closed> {
        if !distance.is_finite() {
            // Nothing can be placed on the grid (an absurd step); the cell stays open.
            return None;
        }
        let mut closed = None;
        if distance >= self.next - EDGE {
            let mean = if self.count == 0 {
                self.last
            } else {
                std::array::from_fn(|c| self.sum[c] / self.count as f64)
            };
            self.last = mean;
            // Whole cells crossed: at most what the distance allows (a huge jump is refused by
            // the caller; here it only bounds the loop).
            let n = (((distance - self.next + EDGE) / self.ds).floor() as usize + 1)
                .min(MAX_CELLS_PER_SAMPLE);
            let mut cells = Vec::with_capacity(n);
            for _ in 0..n {
                let mut cell = mean;
                cell[KALMAN] = self.highpass.step(mean[KALMAN]);
                if let Some(shelf) = &mut self.shelf {
                    cell[KALMAN] = shelf.step(cell[KALMAN]);
                }
                cells.push(cell);
            }
            self.next += n as f64 * self.ds;
            self.sum = [0.0; 5];
            self.count = 0;
            closed = Some(Closed { cells, distance });
        }
        if x.iter().all(|v| v.is_finite()) {
            for (s, v) in self.sum.iter_mut().zip(x) {
                *s += v;
            }
            self.count += 1;
        }
        closed
    }
}

/// A record on the grid: the channel values of every closed cell and the index of the sample
/// that closed it (the position the causal estimate of that cell is for).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct GridRecord {
    /// Every closed cell's channel values, as [`Closed::cells`].
    pub cells: Vec<[f64; 5]>,
    /// Per cell, the index of the sample that closed it.
    pub closed_by: Vec<usize>,
}

/// Runs [`Grid`] over a whole record: `distance[k]` and `x[k]` of sample `k`.
pub fn decimate(
    distance: &[f64],
    x: &[[f64; 5]],
    ds: f64,
    kalman_highpass: f64,
    kalman_shelf: Option<f64>,
) -> GridRecord {
    let mut g = Grid::new(ds, kalman_highpass, kalman_shelf);
    let mut out = GridRecord::default();
    for (k, (d, s)) in distance.iter().zip(x).enumerate() {
        if let Some(c) = g.add(*d, s) {
            for cell in c.cells {
                out.cells.push(cell);
                out.closed_by.push(k);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_are_block_means_of_their_own_samples() {
        // 0.02 m per sample, 0.2 m cells: samples 1..=9 (distances 0.02..0.18) and sample 0 at
        // distance 0 form cell 0, which sample 10 (0.2 m) closes.
        let d: Vec<f64> = (0..100).map(|k| 0.02 * k as f64 + 1e-12).collect();
        let x: Vec<[f64; 5]> = (0..100).map(|k| [k as f64, 0.0, 0.0, 0.0, 0.0]).collect();
        let r = decimate(&d, &x, 0.2, 500.0, None);
        assert_eq!(r.closed_by[0], 10);
        assert!((r.cells[0][0] - 4.5).abs() < 1e-12, "{}", r.cells[0][0]);
        assert!((r.cells[1][0] - 14.5).abs() < 1e-12);
        assert_eq!(r.cells.len(), 9);
    }

    #[test]
    fn a_coarse_step_closes_every_crossed_cell() {
        let mut g = Grid::new(0.2, 500.0, None);
        assert!(g.add(0.1, &[1.0; 5]).is_none());
        let c = g.add(0.75, &[3.0; 5]).unwrap();
        assert_eq!(c.cells.len(), 3);
        assert_eq!(c.cells[0][0], 1.0);
        let c = g.add(0.85, &[5.0; 5]).unwrap();
        assert_eq!(c.cells.len(), 1);
        assert_eq!(c.cells[0][0], 3.0);
    }

    #[test]
    fn the_highpass_is_a_butterworth_of_order_two() {
        // Oracle: |H| of the analog prototype, s^2 / (s^2 + sqrt(2) s + 1), at the pre-warped
        // frequency: 1/sqrt(2) at the cut-off, (f/fc)^2 well below it, 1 well above.
        let gain = |wavelength: f64| {
            let mut b = Biquad::highpass(0.2, 500.0);
            let n = 200_000;
            let w = std::f64::consts::TAU * 0.2 / wavelength;
            let y: Vec<f64> = (0..n).map(|k| b.step((w * k as f64).sin())).collect();
            let tail = &y[n / 2..];
            (2.0 * tail.iter().map(|v| v * v).sum::<f64>() / tail.len() as f64).sqrt()
        };
        assert!((gain(500.0) - std::f64::consts::FRAC_1_SQRT_2).abs() < 2e-3);
        assert!((gain(5000.0) / 0.01 - 1.0).abs() < 0.02, "{}", gain(5000.0));
        assert!((gain(20.0) - 1.0).abs() < 2e-3);
    }

    #[test]
    fn the_lowpass_is_a_butterworth_of_order_two() {
        // Oracle: |1 / (s^2 + sqrt(2) s + 1)| at the pre-warped frequency: 1/sqrt(2) at the
        // cut-off, 1 well below it, and the bilinear map's value a decade above.
        let gain = |wavelength: f64| {
            let mut b = Biquad::lowpass(0.2, 25.0);
            let n = 100_000;
            let w = std::f64::consts::TAU * 0.2 / wavelength;
            let y: Vec<f64> = (0..n).map(|k| b.step((w * k as f64).sin())).collect();
            let tail = &y[n / 2..];
            (2.0 * tail.iter().map(|v| v * v).sum::<f64>() / tail.len() as f64).sqrt()
        };
        assert!((gain(25.0) - std::f64::consts::FRAC_1_SQRT_2).abs() < 2e-3);
        assert!((gain(1000.0) - 1.0).abs() < 2e-3);
        let r =
            (std::f64::consts::PI * 0.2 / 2.5).tan() / (std::f64::consts::PI * 0.2 / 25.0).tan();
        let want = 1.0 / ((1.0 - r * r).powi(2) + 2.0 * r * r).sqrt();
        assert!(
            (gain(2.5) / want - 1.0).abs() < 1e-3,
            "{} {want}",
            gain(2.5)
        );
    }

    #[test]
    fn the_shelf_cancels_the_highpass_phase_lead() {
        // Oracle: the analog H(s) S(s) of the module docs at s = i 2 pi / wavelength; the
        // discrete chain's gain and phase measured by projecting its steady response to a sine
        // onto sine and cosine.
        let (ds, cutoff, beta) = (0.2, 1000.0, 1.0);
        let measured = |wavelength: f64, shelf: bool| {
            let mut g = Grid::new(ds, cutoff, shelf.then_some(beta));
            let w = std::f64::consts::TAU * ds / wavelength;
            let n = (40.0 * cutoff.max(wavelength) / ds) as usize;
            // Sample k lies in the middle of cell k; the next sample closes that cell.
            let mut y = Vec::with_capacity(n);
            for k in 0..=n {
                let x = (w * k as f64).sin();
                if let Some(closed) = g.add((k as f64 + 0.5) * ds, &[0.0, 0.0, 0.0, 0.0, x]) {
                    y.extend(closed.cells.iter().map(|cell| cell[KALMAN]));
                }
            }
            let (mut c, mut q, mut m) = (0.0, 0.0, 0usize);
            for (k, y) in y.iter().enumerate().skip(n / 2) {
                c += y * (w * k as f64).sin();
                q += y * (w * k as f64).cos();
                m += 1;
            }
            let (c, q) = (2.0 * c / m as f64, 2.0 * q / m as f64);
            ((c * c + q * q).sqrt(), q.atan2(c))
        };
        let analog = |wavelength: f64| {
            let (s, w) = (
                nalgebra::Complex::new(0.0, std::f64::consts::TAU / wavelength),
                std::f64::consts::TAU / cutoff,
            );
            let r2 = std::f64::consts::SQRT_2;
            let h = s * s / (s * s + r2 * w * s + w * w) * (s + (beta + r2) * w) / (s + beta * w);
            (h.norm(), h.arg())
        };
        for wavelength in [70.0, 200.0, 1000.0, 20_000.0] {
            let (g, p) = measured(wavelength, true);
            let (ga, pa) = analog(wavelength);
            assert!(
                (g / ga - 1.0).abs() < 2e-3,
                "{wavelength} m: gain {g} against {ga}"
            );
            assert!(
                (p - pa).abs() < 2e-3,
                "{wavelength} m: phase {p} against {pa}"
            );
        }
        // At 200 m (r = 5) the high-pass alone leads by atan(sqrt(2) 5 / 24) (16 degrees); with
        // the shelf what is left is of higher order in 200 / 1000 (2 degrees).
        let (_, alone) = measured(200.0, false);
        let lead = (std::f64::consts::SQRT_2 * 5.0 / 24.0).atan();
        assert!((alone - lead).abs() < 2e-3, "{alone} against {lead}");
        let (_, shelved) = measured(200.0, true);
        assert!(shelved.abs() < 0.04, "{shelved}");
    }

    #[test]
    fn non_finite_samples_are_left_out_of_the_mean() {
        let mut g = Grid::new(1.0, 500.0, None);
        g.add(0.2, &[2.0; 5]);
        g.add(0.4, &[f64::NAN, 0.0, 0.0, 0.0, 0.0]);
        let c = g.add(1.0, &[0.0; 5]).unwrap();
        assert_eq!(c.cells[0][0], 2.0);
        // A cell of non-finite samples only repeats the last mean.
        g.add(1.5, &[f64::INFINITY; 5]);
        let c = g.add(2.0, &[0.0; 5]).unwrap();
        assert_eq!(c.cells[0][0], 0.0);
    }
}
