//! The design line estimated from the sensors, for a record whose design is not known
//! (issue 30's "design geometry unknown"): found from the whole record, offline, as a track
//! recording car's post-processing does; the estimator is then told it as if it were known.
//!
//! # Why a structural fit, not a filter
//! Transitions of 40-120 m lie in the D2 and D3 bands themselves, so no low-pass of the
//! sensors tells the design from the irregularities at those wavelengths (measured:
//! docs/accuracy.md, "Curves"). But the design is laid by rule (module [`crate`]): constant
//! levels of curvature and cant joined by transitions along which **both** change linearly,
//! rounded at each end. So the design is `sum_j A_j R_j(s)`, `R_j` a rounded ramp from 0 to 1
//! over the transition `[a_j, b_j]`, and only the ends and the amplitudes are unknown.
//!
//! # What each sensor says (integrated along the distance)
//! With `h` the sample step and the integrals taken sample by sample, at each whole metre of
//! the distance `s` (the estimator's own: `speed * h` per sample):
//! - the wheelset roll gyroscope's angle `Phi(s) = sum w_x h = -c(s) / (2 l)` (the track
//!   plane's roll, [`crate`] "Definition") plus the cross-level irregularity over the gauge,
//!   the wheelset's small roll on the rails, and a bias times the time. The cant ramps are
//!   long and large against the cross-level (a 30 mm cant is 0.02 rad, the cross-level's
//!   70-200 m content about 1e-3 rad), so `Phi` places the transitions' ends to metres;
//! - the yaw gyroscope's heading `Psi(s) = sum w_z h = T(s)` (the design heading, the integral
//!   of the curvature) plus the irregularity's slope, the wheelset's yaw on the track and a
//!   bias times the time. In the heading the irregularity is nearly white between 8 and
//!   300 m; in the curvature itself it would rise as the square of the wavenumber;
//! - the axle-box accelerometer `a = V^2 k - g c / (2 l)` plus the irregularities' response
//!   (the uncompensated acceleration, fmu-estimator's design module), so with the curvature
//!   found, `q = V^2 k - a` carries `g c / (2 l)`.
//!
//! # Steps
//! 1. Transitions where the roll angle's slope over [`BOX`] metres exceeds [`SLOPE`], kept if
//!    their roll exceeds half [`MIN_ROLL`], the gyroscope's constant bias taken out first (the
//!    median of the metres' roll rates: most metres are not in a transition).
//! 2. Their ends moved, metre by metre within [`REFINE`], to minimise the residual of the
//!    roll angle fitted by `1`, the time (a constant gyroscope bias) and the rounded ramps.
//! 3. A transition of roll below [`MIN_ROLL`] dropped; two overlapping ones of opposite sign
//!    lose the smaller; two of the same sign less than [`MERGE_GAP`] apart merged (one
//!    transition found in two pieces; reverse curves joined by a straight shorter than that
//!    become one transition through zero, as a direct reverse transition is laid); step 2
//!    again, until nothing changes.
//! 4. The ends moved once more within [`JOINT_REFINE`] to minimise the roll's residual plus
//!    [`HEADING_WEIGHT`] times the heading's (each relative to its value at the start), the
//!    heading fitted by `1`, the time and the ramps' integrals.
//! 5. The curvature changes: the heading's fitted amplitudes; the cant changes: `2 l / g`
//!    times the amplitudes of `q`'s integral fitted by `1`, the distance (an accelerometer
//!    bias) and the ramps' integrals.
//! 6. The ends moved back by [`LAG`], the vehicle's lag behind the design, and apart by
//!    [`WIDEN`], the fit's shortening.
//!
//! Measured on the validation lines against their own rows: the ends' errors about their mean
//! are 1.6 m rms, mostly a transition's length (the start and the end err in opposite
//! directions; the middle, fixed by the heading after it, is close), and mostly on the
//! transitions of small cant (below 40 mm, errors of 2-5 m; above 90 mm, 0.1 m). With the
//! true ends and the fitted levels the estimate would be whole 0.185, D2 0.073, D3 0.205,
//! against 0.142, 0.073 and 0.162 told the true design: the ends are what is missing, not the
//! levels.
//!
//! Every threshold was chosen on random validation lines (seeds 201-203, 211-220), the
//! standard curved line never (docs/accuracy.md, "Curves").
//!
//! # Limits
//! - A record starts on a straight: a curvature level from the start is taken as a gyroscope
//!   bias (at constant speed the two are the same column).
//! - A curve with less than [`MIN_ROLL`] of cant (about 6 mm) is not found: its response stays
//!   in the estimate.
//! - Each end's move refits every amplitude, its products updated only over the moved ramp
//!   (suffix sums of the least squares' columns), so the cost still grows faster than the length
//!   (the number of transitions times the candidates' solves): on the vehicle's records at
//!   18 m/s, 2.1 km 0.1 s and 10 km 7-8 s on 2 cores; `cargo bench -p design-line --bench fit`
//!   prints it for synthetic records. At most [`MAX_RECORD`].
//! - A transition whose roll slope is below [`SLOPE`] (60 mm of cant over more than 267 m,
//!   100 mm over more than 444 m) is not found.
//! - The roll gyroscope's bias is taken as the median of the metres' roll rates: a record
//!   of which transitions of one sign make up half or more (a short record of one long
//!   transition) is mis-fitted.
//! - A sensor sample that is not a finite number holds the last good one; a spike is not
//!   screened (the estimator's plausibility checks are not applied here).

use crate::DesignLine;

/// Shortest record \[m\]: shorter than a few transitions, levels and ends cannot be told apart.
pub const MIN_RECORD: f64 = 200.0;
/// Longest record \[m\]: the cost grows about as the cube of the length (module docs).
pub const MAX_RECORD: f64 = 100_000.0;
/// Width of the box over which the roll angle's slope is judged at the start \[m\].
pub const BOX: usize = 30;
/// Roll slope that marks a transition \[rad/m\] (a 30 mm cant over 100 m is 2e-4).
pub const SLOPE: f64 = 1.5e-4;
/// Smallest transition kept, in roll of the track plane \[rad\] (about 6 mm of cant).
pub const MIN_ROLL: f64 = 0.004;
/// Two transitions of the same sign closer than this are one \[m\].
pub const MERGE_GAP: f64 = 20.0;
/// Shortest transition \[m\].
pub const MIN_LENGTH: f64 = 20.0;
/// How far each end is moved in step 2 \[m\].
pub const REFINE: f64 = 15.0;
/// How far each end is moved in step 4 \[m\].
pub const JOINT_REFINE: f64 = 8.0;
/// The heading's weight against the roll's in step 4 (from 0.03, 0.1, 0.3, 1 and 3).
pub const HEADING_WEIGHT: f64 = 0.3;
/// How far the found transitions lie behind the design's \[m\]: the mean of their ends' errors
/// on the validation lines 211-220 (0.71 m over 132 ends; median 0.69). The wheelset's roll
/// and yaw on the rails follow the design a little late, by a distance, not a time: at 12 and
/// 25 m/s the middles' mean error stays within 0.1 m (lines 211-216). It is the ML95's:
/// another vehicle lags by its own.
pub const LAG: f64 = 0.7;
/// How much longer the design's transitions are than the found ones \[m\]: the found ones
/// come out shortened about their middles, by 0.95 m on average on the same validation
/// lines (from 0.5, 1.0 and 1.5 m, 1.0 gave the lowest D2 there).
pub const WIDEN: f64 = 1.0;
/// Passes of the end moves over all transitions.
const PASSES: usize = 3;

/// A recorded run at a constant sample step, every slice one value per sample.
#[derive(Debug, Clone, Copy)]
pub struct Record<'a> {
    /// Sample step \[s\].
    pub step: f64,
    /// Forward speed \[m/s\]; a sample whose speed is not finite does not advance.
    pub speed: &'a [f64],
    /// Wheelset yaw gyroscope \[rad/s\].
    pub yaw_rate: &'a [f64],
    /// Wheelset roll gyroscope \[rad/s\].
    pub roll_rate: &'a [f64],
    /// Axle-box lateral accelerometer \[m/s2\].
    pub acc_y: &'a [f64],
}

/// One transition found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Transition {
    /// Where it starts and ends on the record's distance \[m\].
    pub start: f64,
    /// Where it ends \[m\].
    pub end: f64,
    /// The change of curvature along it \[1/m\].
    pub curvature: f64,
    /// The change of cant along it \[m\].
    pub cant: f64,
}

/// The design found: its transitions, in order and not overlapping (where the corrections
/// would make two overlap, the later one starts where the earlier ends).
#[derive(Debug, Clone, PartialEq)]
pub struct Fitted {
    /// The transitions.
    pub transitions: Vec<Transition>,
}

impl Fitted {
    /// The line's rows (distance, curvature, cant), starting straight and level at 0, as a line
    /// file holds them.
    pub fn rows(&self) -> Vec<(f64, f64, f64)> {
        let mut rows = vec![(0.0, 0.0, 0.0)];
        let (mut k, mut c) = (0.0, 0.0);
        for t in &self.transitions {
            if t.start > rows.last().expect("one row at least").0 {
                rows.push((t.start, k, c));
            }
            k += t.curvature;
            c += t.cant;
            rows.push((t.end, k, c));
        }
        rows
    }

    /// The design at each sample of `record`, at the estimator's distance (`speed * step` per
    /// sample with a finite speed, after the sample's advance): the distances, and the
    /// curvature and cant (the estimator's `design_curvature`, `design_cant`).
    pub fn at_samples(
        &self,
        record: &Record,
        rounding: f64,
    ) -> Result<(Vec<f64>, Vec<[f64; 2]>), String> {
        let line = self.line(rounding)?;
        let mut d = 0.0;
        Ok(record
            .speed
            .iter()
            .map(|v| {
                if v.is_finite() {
                    d += v * record.step;
                }
                let p = line.at(d);
                (d, [p.curvature, p.cant])
            })
            .unzip())
    }

    /// The design line, rounded over `rounding` metres as the fit assumed.
    pub fn line(&self, rounding: f64) -> Result<DesignLine, String> {
        DesignLine::new(&self.rows(), rounding, |i| {
            format!("the design fitted from the sensors, row {i}")
        })
    }
}

/// The design line of `record`, rounded over `rounding` metres, with `half_gauge` (half the
/// distance between the contact points \[m\]) and `gravity` \[m/s2\] of the vehicle's model.
pub fn fit(
    record: &Record,
    half_gauge: f64,
    gravity: f64,
    rounding: f64,
) -> Result<Fitted, String> {
    let n = record.speed.len();
    for (name, len) in [
        ("yaw_rate", record.yaw_rate.len()),
        ("roll_rate", record.roll_rate.len()),
        ("acc_y", record.acc_y.len()),
    ] {
        if len != n {
            return Err(format!(
                "{name} has {len} samples, speed {n}: one value per sample"
            ));
        }
    }
    for (name, x) in [
        ("step", record.step),
        ("half_gauge", half_gauge),
        ("gravity", gravity),
    ] {
        if !(x.is_finite() && x > 0.0) {
            return Err(format!("{name} {x} must be a positive number"));
        }
    }
    if !(rounding.is_finite() && (0.0..=crate::MAX_ROUNDING).contains(&rounding)) {
        return Err(format!(
            "rounding {rounding} m must be between 0 and {} m",
            crate::MAX_ROUNDING
        ));
    }
    let m = Metres::new(record)?;
    let Some((ramps, heading)) = find(&m, rounding) else {
        return Ok(Fitted {
            transitions: Vec::new(),
        });
    };
    let shape = Shape { rounding };
    let dk = heading.amplitudes();
    // q = V^2 k - a per metre (k at the metre's middle), integrated like the gyroscopes.
    let mut q_integral = Vec::with_capacity(m.len());
    let mut sum = 0.0;
    for i in 0..m.len() {
        let mid = i as f64 + 0.5;
        let k: f64 = ramps
            .iter()
            .zip(&dk)
            .map(|(r, a)| a * shape.ramp(*r, mid))
            .sum();
        sum += m.speed2[i] * k - m.acc[i];
        q_integral.push(sum);
    }
    // Fitted on the heading fit's own ramp columns (the ramps' integrals).
    let mut q = Ls::new(&q_integral, vec![vec![1.0; m.len()], m.positions()]);
    for col in &heading.cols[heading.fixed..] {
        q.push(col.clone());
    }
    let dq = q.amplitudes();
    let mut transitions: Vec<Transition> = ramps
        .iter()
        .zip(dk.iter().zip(&dq))
        .map(|(r, (k, q))| Transition {
            start: r[0] - LAG - WIDEN / 2.0,
            end: r[1] - LAG + WIDEN / 2.0,
            curvature: *k,
            cant: q * 2.0 * half_gauge / gravity,
        })
        .collect();
    for i in 1..transitions.len() {
        transitions[i].start = transitions[i].start.max(transitions[i - 1].end);
    }
    Ok(Fitted { transitions })
}

/// The record on the metres of its distance: the angles at `s = 1, 2, ...`, the accelerometer
/// and the squared speed as each metre's means.
struct Metres {
    roll: Vec<f64>,
    heading: Vec<f64>,
    time: Vec<f64>,
    acc: Vec<f64>,
    speed2: Vec<f64>,
}

impl Metres {
    fn new(r: &Record) -> Result<Metres, String> {
        let h = r.step;
        if let Some(i) = r.speed.iter().position(|v| *v < 0.0) {
            return Err(format!(
                "sample {i}: speed {} m/s is negative; the fit follows the distance forwards",
                r.speed[i]
            ));
        }
        let metres = r
            .speed
            .iter()
            .filter(|v| v.is_finite())
            .map(|v| v * h)
            .sum::<f64>()
            .floor();
        // Shorter than a few transitions, the levels cannot be told from the ends.
        if !(metres >= MIN_RECORD) {
            return Err(format!(
                "the record covers {metres} m; fitting the design needs at least {MIN_RECORD} m"
            ));
        }
        if metres > MAX_RECORD {
            return Err(format!(
                "the record covers {metres:e} m, more than the fit's {MAX_RECORD:e} m: split it (or check the speed's unit)"
            ));
        }
        let len = metres as usize;
        let mut out = Metres {
            roll: Vec::with_capacity(len),
            heading: Vec::with_capacity(len),
            time: Vec::with_capacity(len),
            acc: vec![0.0; len],
            speed2: vec![0.0; len],
        };
        let mut count = vec![0usize; len];
        let (mut d, mut roll, mut yaw) = (0.0, 0.0, 0.0);
        // A sensor sample that is not a finite number (a dropped sample) holds the last good one,
        // as a logger's sample-and-hold would, instead of failing the whole record.
        let mut last = [0.0; 3];
        for i in 0..r.speed.len() {
            let v = r.speed[i];
            for (held, x) in last
                .iter_mut()
                .zip([r.roll_rate[i], r.yaw_rate[i], r.acc_y[i]])
            {
                if x.is_finite() {
                    *held = x;
                }
            }
            let [wr, wy, a] = last;
            let dv = if v.is_finite() { v * h } else { 0.0 };
            let (d0, roll0, yaw0) = (d, roll, yaw);
            d += dv;
            roll += wr * h;
            yaw += wy * h;
            let bin = d0.floor() as usize;
            if bin < len && v.is_finite() {
                out.acc[bin] += a;
                out.speed2[bin] += v * v;
                count[bin] += 1;
            }
            // Every whole metre crossed by this sample: the angles there, linearly between.
            while out.roll.len() < len && (out.roll.len() + 1) as f64 <= d {
                let at = (out.roll.len() + 1) as f64;
                let f = if dv > 0.0 { (at - d0) / dv } else { 1.0 };
                out.roll.push(roll0 + f * (roll - roll0));
                out.heading.push(yaw0 + f * (yaw - yaw0));
                out.time.push(h * (i as f64 + f));
            }
        }
        // The sums above and the length were added in the same order, so every metre was
        // reached; kept consistent even if rounding ever said otherwise.
        let len = out.roll.len();
        out.acc.truncate(len);
        out.speed2.truncate(len);
        // A metre no sample started in (steps longer than a metre): its neighbour's means.
        for (i, &n) in count.iter().enumerate().take(len) {
            if n > 0 {
                out.acc[i] /= n as f64;
                out.speed2[i] /= n as f64;
            } else if i > 0 {
                out.acc[i] = out.acc[i - 1];
                out.speed2[i] = out.speed2[i - 1];
            }
        }
        Ok(out)
    }

    fn len(&self) -> usize {
        self.roll.len()
    }

    /// Where the angles are: `s = 1, 2, ...`.
    fn positions(&self) -> Vec<f64> {
        (1..=self.len()).map(|i| i as f64).collect()
    }
}

/// The rounded ramp and its integral: the line's rounding ([`crate`], "Rounding") is a box mean
/// over `rounding` metres of the linear shape, which joins the pieces by the same parabola.
#[derive(Clone, Copy)]
struct Shape {
    rounding: f64,
}

impl Shape {
    /// The ramp from 0 at `r[0]` to 1 at `r[1]`, rounded.
    fn ramp(&self, r: [f64; 2], s: f64) -> f64 {
        let w = self.rounding;
        if w == 0.0 {
            return ramp_integral(r, s, 0);
        }
        (ramp_integral(r, s + w / 2.0, 1) - ramp_integral(r, s - w / 2.0, 1)) / w
    }

    /// Its integral from before the ramp to `s`.
    fn integral(&self, r: [f64; 2], s: f64) -> f64 {
        let w = self.rounding;
        if w == 0.0 {
            return ramp_integral(r, s, 1);
        }
        (ramp_integral(r, s + w / 2.0, 2) - ramp_integral(r, s - w / 2.0, 2)) / w
    }
}

/// The unrounded ramp (`order` 0), its integral (1) and its double integral (2) at `s`.
fn ramp_integral(r: [f64; 2], s: f64, order: u8) -> f64 {
    let (a, b) = (r[0], r[1]);
    let l = b - a;
    if s <= a {
        return 0.0;
    }
    if s <= b {
        let u = s - a;
        return match order {
            0 => u / l,
            1 => u * u / (2.0 * l),
            _ => u * u * u / (6.0 * l),
        };
    }
    let u = s - b;
    match order {
        0 => 1.0,
        1 => l / 2.0 + u,
        _ => l * l / 6.0 + l * u / 2.0 + u * u / 2.0,
    }
}

/// Least squares of one target on columns, of which one (a ramp's) is replaced at a time: the
/// Gram matrix is updated by that column's products alone, and those only over the stretch
/// where the column changed (a ramp's new column differs from its old one over the ramp, and by
/// a constant beyond it: the rest comes from each column's suffix sums), so a move's products
/// cost the ramp's length times the columns; building the column and its suffix sums still
/// costs the record's length once.
#[derive(Clone)]
struct Ls {
    y: Vec<f64>,
    yy: f64,
    cols: Vec<Vec<f64>>,
    /// `suffix[i][s]`: the sum of column `i` from `s` on (one more entry, 0, at the end).
    suffix: Vec<Vec<f64>>,
    y_suffix: Vec<f64>,
    gram: Vec<Vec<f64>>,
    rhs: Vec<f64>,
    /// Columns before the ramps' (constant, trend).
    fixed: usize,
}

/// Sums from each index to the end, with a 0 after the last.
fn suffix_sums(c: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; c.len() + 1];
    for s in (0..c.len()).rev() {
        out[s] = out[s + 1] + c[s];
    }
    out
}

impl Ls {
    fn new(y: &[f64], fixed: Vec<Vec<f64>>) -> Ls {
        let mut ls = Ls {
            y: y.to_vec(),
            yy: dot(y, y),
            cols: Vec::new(),
            suffix: Vec::new(),
            y_suffix: suffix_sums(y),
            gram: Vec::new(),
            rhs: Vec::new(),
            fixed: fixed.len(),
        };
        for c in fixed {
            ls.push(c);
        }
        ls
    }

    fn push(&mut self, col: Vec<f64>) {
        let row: Vec<f64> = self.cols.iter().map(|c| dot(c, &col)).collect();
        for (g, x) in self.gram.iter_mut().zip(&row) {
            g.push(*x);
        }
        let mut row = row;
        row.push(dot(&col, &col));
        self.gram.push(row);
        self.rhs.push(dot(&col, &self.y));
        self.suffix.push(suffix_sums(&col));
        self.cols.push(col);
    }

    /// Replaces column `j`, every product computed anew (after a series of [`Ls::try_col`]s,
    /// so that their rounding does not add up).
    fn set(&mut self, j: usize, col: Vec<f64>) {
        for i in 0..self.cols.len() {
            let x = if i == j {
                dot(&col, &col)
            } else {
                dot(&self.cols[i], &col)
            };
            self.gram[i][j] = x;
            self.gram[j][i] = x;
        }
        self.rhs[j] = dot(&col, &self.y);
        self.suffix[j] = suffix_sums(&col);
        self.cols[j] = col;
    }

    /// Replaces column `j` by updating the products over the stretch where it changed.
    fn try_col(&mut self, j: usize, col: Vec<f64>) {
        let old = &self.cols[j];
        let n = col.len();
        let Some(f) = (0..n).find(|&s| col[s] != old[s]) else {
            return;
        };
        // From `g` on the change is the constant `tail` (to rounding: 1e-12 of the values).
        let tail = col[n - 1] - old[n - 1];
        let tolerance = 1e-12 * (1.0 + col[n - 1].abs());
        let mut g = n;
        while g > f && (col[g - 1] - old[g - 1] - tail).abs() <= tolerance {
            g -= 1;
        }
        let diff = |s: usize| col[s] - old[s];
        for i in 0..self.cols.len() {
            if i == j {
                continue;
            }
            let c = &self.cols[i];
            let local: f64 = (f..g).map(|s| diff(s) * c[s]).sum();
            let x = self.gram[i][j] + local + tail * self.suffix[i][g];
            self.gram[i][j] = x;
            self.gram[j][i] = x;
        }
        let with_old: f64 =
            (f..g).map(|s| diff(s) * old[s]).sum::<f64>() + tail * self.suffix[j][g];
        let with_self: f64 =
            (f..g).map(|s| diff(s) * diff(s)).sum::<f64>() + tail * tail * (n - g) as f64;
        self.gram[j][j] += 2.0 * with_old + with_self;
        let with_y: f64 = (f..g).map(|s| diff(s) * self.y[s]).sum();
        self.rhs[j] += with_y + tail * self.y_suffix[g];
        self.suffix[j] = suffix_sums(&col);
        self.cols[j] = col;
    }

    /// The coefficients and the residual sum of squares.
    fn solve(&self) -> (Vec<f64>, f64) {
        let c = cholesky_solve(&self.gram, &self.rhs);
        let fitted: f64 = c.iter().zip(&self.rhs).map(|(a, b)| a * b).sum();
        (c, (self.yy - fitted).max(0.0))
    }

    fn rss(&self) -> f64 {
        self.solve().1
    }

    /// The ramps' coefficients.
    fn amplitudes(&self) -> Vec<f64> {
        self.solve().0.split_off(self.fixed)
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Solves the symmetric positive semi-definite `g x = b`, with a ridge of 1e-12 of the
/// diagonal so that a column that became a copy of another (a ramp moved onto a neighbour's)
/// gives a finite answer instead of a failure.
fn cholesky_solve(g: &[Vec<f64>], b: &[f64]) -> Vec<f64> {
    let n = b.len();
    let mut l = vec![vec![0.0; n]; n];
    for i in 0..n {
        for j in 0..=i {
            let mut s = g[i][j];
            if i == j {
                s += 1e-12 * g[i][i] + f64::MIN_POSITIVE;
            }
            s -= (0..j).map(|k| l[i][k] * l[j][k]).sum::<f64>();
            l[i][j] = if i == j {
                s.max(f64::MIN_POSITIVE).sqrt()
            } else {
                s / l[j][j]
            };
        }
    }
    let mut y = vec![0.0; n];
    for i in 0..n {
        let s: f64 = (0..i).map(|k| l[i][k] * y[k]).sum();
        y[i] = (b[i] - s) / l[i][i];
    }
    let mut x = vec![0.0; n];
    for i in (0..n).rev() {
        let s: f64 = (i + 1..n).map(|k| l[k][i] * x[k]).sum();
        x[i] = (y[i] - s) / l[i][i];
    }
    x
}

/// Steps 1-4: the transitions' ends, and the heading's fit on them (its ramp columns final), or
/// `None` when there is no transition.
fn find(m: &Metres, rounding: f64) -> Option<(Vec<[f64; 2]>, Ls)> {
    let shape = Shape { rounding };
    let s = m.positions();
    let n = m.len();
    let mut ramps = initial(&without_bias(&m.roll, &m.time));
    let ramp_col = |r: [f64; 2]| -> Vec<f64> { s.iter().map(|&x| shape.ramp(r, x)).collect() };
    let int_col = |r: [f64; 2]| -> Vec<f64> { s.iter().map(|&x| shape.integral(r, x)).collect() };
    let roll_ls = |ramps: &[[f64; 2]]| {
        let mut ls = Ls::new(&m.roll, vec![vec![1.0; n], m.time.clone()]);
        for r in ramps {
            ls.push(ramp_col(*r));
        }
        ls
    };
    let last = n as f64 - 2.0;
    // Moves each end within `reach`, one metre at a time, to minimise `cost`; the ends stay
    // in order: neither past its neighbours' nor making a transition shorter than MIN_LENGTH.
    let cost =
        |lss: &Vec<(Ls, bool, f64)>| -> f64 { lss.iter().map(|(ls, _, w)| w * ls.rss()).sum() };
    let refine = |ramps: &mut Vec<[f64; 2]>, reach: f64, lss: &mut Vec<(Ls, bool, f64)>| {
        for _ in 0..PASSES {
            for i in 0..ramps.len() {
                for e in 0..2 {
                    let cur = ramps[i][e];
                    let (lo, hi) = if e == 0 {
                        let prev = if i > 0 { ramps[i - 1][1] } else { 1.0 };
                        (prev.max(1.0), ramps[i][1] - MIN_LENGTH)
                    } else {
                        let next = if i + 1 < ramps.len() {
                            ramps[i + 1][0]
                        } else {
                            last
                        };
                        (ramps[i][0] + MIN_LENGTH, next.min(last))
                    };
                    let mut best = (cost(lss), cur);
                    let mut c = cur - reach;
                    while c <= cur + reach + 1e-9 {
                        if c >= lo && c <= hi && c != cur {
                            let mut r = ramps[i];
                            r[e] = c;
                            for (ls, integral, _) in lss.iter_mut() {
                                let col = if *integral { int_col(r) } else { ramp_col(r) };
                                ls.try_col(ls.fixed + i, col);
                            }
                            let v = cost(lss);
                            if v < best.0 {
                                best = (v, c);
                            }
                        }
                        c += 1.0;
                    }
                    ramps[i][e] = best.1;
                    for (ls, integral, _) in lss.iter_mut() {
                        let col = if *integral {
                            int_col(ramps[i])
                        } else {
                            ramp_col(ramps[i])
                        };
                        ls.set(ls.fixed + i, col);
                    }
                }
            }
        }
    };
    let refine_roll = |ramps: &mut Vec<[f64; 2]>| {
        let mut lss = vec![(roll_ls(ramps), false, 1.0)];
        refine(ramps, REFINE, &mut lss);
    };
    refine_roll(&mut ramps);
    for _ in 0..50 {
        if ramps.is_empty() {
            break;
        }
        let amp = roll_ls(&ramps).amplitudes();
        let mut changed = true;
        let small = (0..ramps.len())
            .filter(|&i| amp[i].abs() < MIN_ROLL)
            .min_by(|&i, &j| amp[i].abs().total_cmp(&amp[j].abs()));
        if let Some(i) = small {
            ramps.remove(i);
        } else if let Some(i) = (0..ramps.len().saturating_sub(1)).find(|&i| {
            let same = amp[i].signum() == amp[i + 1].signum();
            let gap = ramps[i + 1][0] - ramps[i][1];
            (!same && gap < 1.0) || (same && gap < MERGE_GAP)
        }) {
            if amp[i].signum() == amp[i + 1].signum() {
                ramps[i][1] = ramps[i + 1][1];
                ramps.remove(i + 1);
            } else {
                ramps.remove(if amp[i].abs() < amp[i + 1].abs() {
                    i
                } else {
                    i + 1
                });
            }
        } else {
            changed = false;
        }
        if !changed {
            break;
        }
        refine_roll(&mut ramps);
    }
    if ramps.is_empty() {
        return None;
    }
    let roll = roll_ls(&ramps);
    let mut heading = Ls::new(&m.heading, vec![vec![1.0; n], m.time.clone()]);
    for r in &ramps {
        heading.push(int_col(*r));
    }
    let (r0, h0) = (roll.rss(), heading.rss());
    let weight = |x: f64| if x > 0.0 { 1.0 / x } else { 1.0 };
    let mut lss = vec![
        (roll, false, weight(r0)),
        (heading, true, HEADING_WEIGHT * weight(h0)),
    ];
    refine(&mut ramps, JOINT_REFINE, &mut lss);
    // `refine` leaves every column computed anew for the ramps' final ends.
    let (heading, _, _) = lss.pop().expect("the heading's fit is the last");
    Some((ramps, heading))
}

/// The roll angle less a constant gyroscope bias times the time, the bias the median of the
/// metres' roll rates: most metres of a line are not in a transition, so the median is the
/// bias's, whatever the cant (at 10 m/s a MEMS turn-on bias of 1.75e-3 rad/s is a slope of
/// 1.75e-4 rad/m, above [`SLOPE`]).
fn without_bias(roll: &[f64], time: &[f64]) -> Vec<f64> {
    let mut rates: Vec<f64> = (1..roll.len())
        .filter(|&i| time[i] > time[i - 1])
        .map(|i| (roll[i] - roll[i - 1]) / (time[i] - time[i - 1]))
        .collect();
    if rates.is_empty() {
        return roll.to_vec();
    }
    let mid = rates.len() / 2;
    let bias = *rates.select_nth_unstable_by(mid, f64::total_cmp).1;
    roll.iter().zip(time).map(|(r, t)| r - bias * t).collect()
}

/// Step 1: runs where the roll angle's slope over [`BOX`] metres exceeds [`SLOPE`] with one
/// sign, as `[start, end]`, kept if their roll exceeds half [`MIN_ROLL`].
fn initial(roll: &[f64]) -> Vec<[f64; 2]> {
    let n = roll.len();
    // Slope per metre: roll at the metre's end minus at its start (0 at s = 0).
    let slope: Vec<f64> = (0..n)
        .map(|i| roll[i] - if i > 0 { roll[i - 1] } else { 0.0 })
        .collect();
    // Centred box mean, the ends held (edge values repeated).
    let half = BOX / 2;
    let at = |i: isize| slope[i.clamp(0, n as isize - 1) as usize];
    let smooth: Vec<f64> = (0..n as isize)
        .map(|i| {
            (i - half as isize..i - half as isize + BOX as isize)
                .map(at)
                .sum::<f64>()
                / BOX as f64
        })
        .collect();
    let angle = |i: usize| if i == 0 { 0.0 } else { roll[i - 1] };
    let mut out = Vec::new();
    let mut i = 0;
    while i < n {
        if smooth[i].abs() > SLOPE {
            let mut j = i;
            while j + 1 < n
                && smooth[j + 1].abs() > SLOPE
                && smooth[j + 1].signum() == smooth[i].signum()
            {
                j += 1;
            }
            if (angle(j + 1) - angle(i)).abs() > MIN_ROLL / 2.0 {
                let a = (i as f64).max(1.0);
                let b = ((j + 1) as f64).min(n as f64 - 2.0);
                if b - a >= MIN_LENGTH {
                    out.push([a, b]);
                } else {
                    let mid = ((a + b) / 2.0)
                        .clamp(1.0 + MIN_LENGTH / 2.0, n as f64 - 2.0 - MIN_LENGTH / 2.0);
                    out.push([mid - MIN_LENGTH / 2.0, mid + MIN_LENGTH / 2.0]);
                }
            }
            i = j + 1;
        } else {
            i += 1;
        }
    }
    // Runs next to each other stay apart by at least nothing: the refinement keeps the order.
    for k in 1..out.len() {
        if out[k][0] < out[k - 1][1] {
            out[k][0] = out[k - 1][1];
        }
    }
    out.retain(|r| r[1] - r[0] >= MIN_LENGTH);
    out
}

/// Records of a rigid body following a line exactly: the unit tests' and the bench's oracle.
pub mod synthetic {
    use crate::DesignLine;

    /// The sensors (speed, yaw rate, roll rate, lateral acceleration) of a body following
    /// `line` exactly at speed `v`, every `step` seconds for `length` metres, with `half_gauge`
    /// and standard gravity, plus `noise(i)` times 1e-3 rad/s on the gyroscopes and 0.05 m/s2
    /// on the accelerometer.
    pub fn record(
        line: &DesignLine,
        v: f64,
        step: f64,
        length: f64,
        half_gauge: f64,
        noise: impl Fn(usize) -> f64,
    ) -> [Vec<f64>; 4] {
        let g = 9.81;
        let mut out: [Vec<f64>; 4] = Default::default();
        for i in 0..(length / (v * step)) as usize {
            let d = line.at((i + 1) as f64 * v * step);
            out[0].push(v);
            out[1].push(v * d.curvature + 1e-3 * noise(i));
            out[2].push(-v * d.cant_ds / (2.0 * half_gauge) + 1e-3 * noise(i + 7));
            out[3]
                .push(v * v * d.curvature - g * d.cant / (2.0 * half_gauge) + 0.05 * noise(i + 13));
        }
        out
    }

    /// The fit's view of such a record's columns.
    pub fn view(columns: &[Vec<f64>; 4], step: f64) -> super::Record<'_> {
        super::Record {
            step,
            speed: &columns[0],
            yaw_rate: &columns[1],
            roll_rate: &columns[2],
            acc_y: &columns[3],
        }
    }

    /// A deterministic pseudo-random sequence in \[-1, 1\] (no dependency for a test).
    pub fn noise(i: usize) -> f64 {
        let x = (i as u64)
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((x >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const V: f64 = 18.0;
    const H: f64 = 1e-3;
    const L: f64 = 0.75;
    const G: f64 = 9.81;

    fn record(
        v: f64,
        line: &DesignLine,
        length: f64,
        noise: impl Fn(usize) -> f64,
    ) -> [Vec<f64>; 4] {
        synthetic::record(line, v, H, length, L, noise)
    }

    /// Where the fit puts row `i` of a line whose vehicle follows it without lag (the rigid
    /// body of these tests): the corrections for the real vehicle's lag and shortening move it.
    fn expected(rows: &[(f64, f64, f64)], i: usize) -> f64 {
        match i {
            0 => rows[0].0,
            _ if i % 2 == 1 => rows[i].0 - LAG - WIDEN / 2.0,
            _ => rows[i].0 - LAG + WIDEN / 2.0,
        }
    }

    /// `f`'s rows against the line's `rows`, within `tol` (m, 1/m, m).
    fn assert_rows(f: &Fitted, rows: &[(f64, f64, f64)], tol: [f64; 3]) {
        let got = f.rows();
        assert_eq!(got.len(), rows.len(), "{got:?}");
        for (i, (g, r)) in got.iter().zip(rows).enumerate() {
            let off = [g.0 - expected(rows, i), g.1 - r.1, g.2 - r.2];
            assert!(
                off.iter().zip(tol).all(|(o, t)| o.abs() <= t),
                "{g:?} against {r:?}"
            );
        }
    }

    fn fitted(r: &[Vec<f64>; 4]) -> Fitted {
        fit(&synthetic::view(r, H), L, G, 10.0).expect("fits")
    }

    /// Two curves, left and right, of the shapes the line module defines.
    fn line() -> (Vec<(f64, f64, f64)>, DesignLine) {
        let rows = vec![
            (0.0, 0.0, 0.0),
            (150.0, 0.0, 0.0),
            (210.0, 1.0 / 600.0, 0.08),
            (410.0, 1.0 / 600.0, 0.08),
            (470.0, 0.0, 0.0),
            (600.0, 0.0, 0.0),
            (700.0, -1.0 / 400.0, -0.12),
            (850.0, -1.0 / 400.0, -0.12),
            (950.0, 0.0, 0.0),
        ];
        let line = DesignLine::new(&rows, 10.0, |i| format!("row {i}")).expect("a valid line");
        (rows, line)
    }

    #[test]
    fn an_exact_record_gives_back_its_line() {
        let (rows, line) = line();
        let f = fitted(&record(V, &line, 1100.0, |_| 0.0));
        assert_rows(&f, &rows, [0.5, 0.01 / 400.0, 0.002]);
        f.line(10.0).expect("the fit is a valid line");
    }

    #[test]
    fn noise_moves_the_ends_by_metres_at_most() {
        let (rows, line) = line();
        let f = fitted(&record(V, &line, 1100.0, synthetic::noise));
        assert_rows(&f, &rows, [2.0, 0.03 / 400.0, 0.005]);
    }

    #[test]
    fn biases_and_dropped_samples_leave_the_line() {
        let (rows, line) = line();
        // At 10 m/s a MEMS roll gyroscope's turn-on bias (1.75e-3 rad/s) is a roll slope of
        // 1.75e-4 rad/m, above SLOPE everywhere; with a yaw bias and an accelerometer bias.
        let mut r = record(10.0, &line, 1100.0, |_| 0.0);
        r[1].iter_mut().for_each(|x| *x += 2e-3);
        r[2].iter_mut().for_each(|x| *x += 1.75e-3);
        r[3].iter_mut().for_each(|x| *x += 0.05);
        // Dropped samples: a speed and each sensor once.
        r[0][20_000] = f64::NAN;
        r[1][30_000] = f64::NAN;
        r[2][40_000] = f64::INFINITY;
        r[3][50_000] = f64::NAN;
        assert_rows(&fitted(&r), &rows, [1.0, 0.02 / 400.0, 0.003]);
    }

    #[test]
    fn a_straight_record_has_no_transitions() {
        let line = DesignLine::straight();
        let f = fitted(&record(V, &line, 500.0, |i| (i % 97) as f64 / 48.0 - 1.0));
        assert!(f.transitions.is_empty(), "{:?}", f.transitions);
        assert_eq!(f.rows(), vec![(0.0, 0.0, 0.0)]);
    }

    #[test]
    fn bad_records_are_named() {
        let v = vec![V; 100];
        let short = Record {
            step: H,
            speed: &v,
            yaw_rate: &v,
            roll_rate: &v,
            acc_y: &v,
        };
        let e = fit(&short, L, G, 10.0).unwrap_err();
        assert!(e.contains("at least 200 m"), "{e}");
        let e = fit(
            &Record {
                acc_y: &v[..10],
                ..short
            },
            L,
            G,
            10.0,
        )
        .unwrap_err();
        assert!(e.contains("acc_y has 10 samples"), "{e}");
        let e = fit(&short, -1.0, G, 10.0).unwrap_err();
        assert!(e.contains("half_gauge"), "{e}");
        let e = fit(&short, L, G, 500.0).unwrap_err();
        assert!(e.contains("rounding 500"), "{e}");
        let mut v = vec![V; 100_000];
        v[7] = -1.0;
        let e = fit(
            &Record {
                speed: &v,
                yaw_rate: &v,
                roll_rate: &v,
                acc_y: &v,
                ..short
            },
            L,
            G,
            10.0,
        )
        .unwrap_err();
        assert!(e.contains("sample 7: speed -1"), "{e}");
        let fast = vec![1e30; 1000];
        let e = fit(
            &Record {
                speed: &fast,
                yaw_rate: &fast,
                roll_rate: &fast,
                acc_y: &fast,
                ..short
            },
            L,
            G,
            10.0,
        )
        .unwrap_err();
        assert!(e.contains("more than the fit's"), "{e}");
    }

    #[test]
    fn a_moved_ramp_updates_the_products_as_computing_them_anew_does() {
        let shape = Shape { rounding: 10.0 };
        let n = 3000;
        let s: Vec<f64> = (1..=n).map(|i| i as f64).collect();
        let y: Vec<f64> = s.iter().map(|x| (x / 37.0).sin() + 1e-3 * x).collect();
        let cols = |rs: &[[f64; 2]]| -> Vec<Vec<f64>> {
            rs.iter()
                .map(|r| s.iter().map(|&x| shape.integral(*r, x)).collect())
                .collect()
        };
        let start = [[400.0, 460.0], [900.0, 1000.0], [2000.0, 2050.0]];
        let mut moved = Ls::new(&y, vec![vec![1.0; n], s.clone()]);
        for c in cols(&start) {
            moved.push(c);
        }
        // Each end of the middle ramp, back and forth, as the refinement moves them.
        for r in [
            [890.0, 1000.0],
            [890.0, 1012.0],
            [903.0, 1012.0],
            [903.0, 995.0],
        ] {
            moved.try_col(3, cols(&[r]).remove(0));
            let mut anew = Ls::new(&y, vec![vec![1.0; n], s.clone()]);
            for c in cols(&[start[0], r, start[2]]) {
                anew.push(c);
            }
            for (a, b) in moved.gram.iter().flatten().zip(anew.gram.iter().flatten()) {
                assert!((a - b).abs() <= 1e-9 * b.abs().max(1.0), "{a} against {b}");
            }
            for (a, b) in moved.rhs.iter().zip(&anew.rhs) {
                assert!((a - b).abs() <= 1e-9 * b.abs().max(1.0), "{a} against {b}");
            }
            assert!((moved.rss() - anew.rss()).abs() <= 1e-6 * anew.rss());
        }
    }

    #[test]
    fn the_rounded_shapes_are_box_means_of_the_linear_ones() {
        // Against a numerical box mean and a numerical integral of the unrounded ramp.
        let shape = Shape { rounding: 10.0 };
        let r = [100.0, 160.0];
        for s in [90.0, 96.0, 103.0, 130.0, 157.0, 163.0, 200.0] {
            let k = 20_000;
            let mean: f64 = (0..k)
                .map(|j| ramp_integral(r, s - 5.0 + 10.0 * (j as f64 + 0.5) / k as f64, 0))
                .sum::<f64>()
                / k as f64;
            assert!((shape.ramp(r, s) - mean).abs() < 1e-8, "{s}");
            let integral: f64 = (0..k)
                .map(|j| shape.ramp(r, s * (j as f64 + 0.5) / k as f64))
                .sum::<f64>()
                * s
                / k as f64;
            assert!((shape.integral(r, s) - integral).abs() < 1e-5, "{s}");
        }
    }
}
