//! The design line: the track's intended horizontal curvature and cant as functions of the
//! distance, on which the vehicle FMU (`fmu-vehicle`) lays its irregularities and from which the
//! estimator FMU (`fmu-estimator`, its `line_file`) takes the design it removes.
//!
//! # Definition
//! Curvature `k(s)` \[1/m\], positive when the track turns left (the centre of the curve on the
//! left, `y` positive), and cant `c(s)` \[m\], the height of the right rail above the left one:
//! positive raises the outer rail of a left-hand curve, so a normally canted curve has `c` of
//! the sign of `k`. Both are linear between the rows of the line (a line file's rows, or the
//! points of [`DesignLine::one_curve`]) and held before the first row and after the last, with
//! each row's change of slope rounded (below). So:
//! - a straight is a stretch with `k = 0`, a circular curve one with constant `k`;
//! - a transition whose curvature goes linearly from one value to another is a clothoid (its
//!   curvature is linear in the arc length by definition), with the cant ramped linearly along
//!   it: the shapes of EN 13803 and of nearly every railway's design rules;
//! - a line starts straight and level where its first row says so; the vehicle starts at
//!   `s = 0` in its straight-track equilibrium.
//!
//! **Rounding.** A continuous rail cannot follow a kink in the cant or the curvature: laid and
//! tamped, the end of a ramp is rounded over metres. A kink would also make the track plane's
//! roll rate jump, an impulse no vehicle meets. So at each row the two straight pieces are
//! joined by a parabola over `rounding` metres centred on the row (`f + D (s - s_i + b)^2 /
//! (4 b)` with `D` the change of slope, `b` half the length), which makes curvature and cant
//! continuously differentiable with a bounded second derivative `D / (2 b)`. Where rows are
//! closer than the rounding, `b` is at most half the distance to the next row on either side.
//! Outside the roundings the line is exactly the linear one (a transition is a clothoid
//! there).
//!
//! The track plane is rolled by the cant about the track centre line at rail level: its roll
//! angle (left side up positive, the convention of every roll in the model) is
//! `phi_d = -c / (2 l)`, `2 l` the distance between the contact points (the model's gauge).
//!
//! # Integrals
//! The bodies of the vehicle sit at different distances on the line, so their track frames
//! differ in heading and lateral position. With the heading `T(s) = int_0^s k` and its
//! integral `P(s) = int_0^s T`, the design centre line at `s + x`, seen from the tangent at `s`
//! (small angles), is at the lateral offset `P(s + x) - P(s) - x T(s)` and turned by
//! `T(s + x) - T(s)`. With `k` linear on each segment `T` is quadratic and `P` cubic there, so
//! both are exact; each rounding adds its own exact polynomial terms (a parabola in `k`, so
//! quartic in `P`). Each segment carries `T` and `P` at its start, summed from the line's first
//! row (the offsets do not depend on where the sums start).

// `!(x > y)` is how a check also refuses NaN, which every value from a file may be.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod csv;
pub mod fit;

use std::path::Path;

/// The length over which each row's change of slope is rounded, unless a user says otherwise
/// \[m\]: the scale of a tamped ramp end (module docs, "Rounding").
pub const DEFAULT_ROUNDING: f64 = 10.0;
/// Shortest rounding \[m\]: below a metre the roll rate's rise is an impulse to the bodies.
pub const MIN_ROUNDING: f64 = 1.0;
/// Longest rounding \[m\]: beyond 100 m it would swallow the shortest transitions.
pub const MAX_ROUNDING: f64 = 100.0;

/// Tightest curve the model accepts \[1/m\]: a 25 m radius, below the tightest tram curves.
/// Linear creep and a coned tread on knife-edge rails are far out of their range beyond that.
pub const MAX_CURVATURE: f64 = 1.0 / 25.0;
/// Largest cant the model accepts \[m\]: EN 13803 allows at most 180-200 mm.
pub const MAX_CANT: f64 = 0.2;
/// Steepest cant ramp the model accepts \[m/m\]: 10 mm per metre, four times EN 13803's usual
/// limit (about 1:400). A steeper one (a cant without a transition) rolls the track plane too
/// fast for any vehicle, and in the rounding its roll acceleration made the model diverge.
pub const MAX_CANT_GRADIENT: f64 = 0.01;

/// The design geometry at one distance.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct DesignPoint {
    /// Curvature \[1/m\], left positive.
    pub curvature: f64,
    /// Its derivative along the line \[1/m2\].
    pub curvature_ds: f64,
    /// Cant, right rail above left \[m\].
    pub cant: f64,
    /// Its derivative along the line \[-\].
    pub cant_ds: f64,
    /// Its second derivative \[1/m\] (not 0 only in the roundings).
    pub cant_ds2: f64,
    /// Heading `T(s)`, the integral of the curvature from the first row \[rad\] (only
    /// differences of `T` and `P` have a meaning: module docs).
    pub heading: f64,
    /// `P(s)`, the integral of the heading from the first row \[m\].
    pub heading_integral: f64,
}

/// A design line (module docs): rows of (distance, curvature, cant), linear between them,
/// rounded at the rows.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DesignLine {
    s: Vec<f64>,
    curvature: Vec<f64>,
    cant: Vec<f64>,
    /// `T` and `P` at each row, of the linear line.
    heading: Vec<f64>,
    heading_integral: Vec<f64>,
    /// The roundings, in the order of the rows (they do not overlap).
    roundings: Vec<Rounding>,
    /// Per rounding, the sums over the roundings before it of what each adds to `T` once passed
    /// (`dk b^2 / 6`) and to `P` (`dk b^3 / 6 + dk b^2 / 6 (s - end)`, kept as a constant and a
    /// slope in `s`).
    passed_t: Vec<f64>,
    passed_p: Vec<(f64, f64)>,
}

/// The parabola joining the two straight pieces at one row.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
struct Rounding {
    /// The row's distance \[m\].
    at: f64,
    /// Half its length \[m\].
    half: f64,
    /// Changes of the curvature's and the cant's slopes at the row.
    dk: f64,
    dc: f64,
}

impl Rounding {
    fn start(&self) -> f64 {
        self.at - self.half
    }

    fn end(&self) -> f64 {
        self.at + self.half
    }

    /// What the rounding adds to a function whose slope changes by `d` at the row, and to its
    /// first and second derivatives and its first and second integrals, at `s` within it.
    fn terms(&self, d: f64, s: f64) -> [f64; 5] {
        let (x, b) = (s - self.start(), self.half);
        let past = (s - self.at).max(0.0);
        [
            d * (x * x / (4.0 * b) - past),
            d * (x / (2.0 * b) - if s > self.at { 1.0 } else { 0.0 }),
            d / (2.0 * b),
            d * (x.powi(3) / (12.0 * b) - past * past / 2.0),
            d * (x.powi(4) / (48.0 * b) - past.powi(3) / 6.0),
        ]
    }
}

/// One curve as the vehicle FMU's parameters give it (`curve_radius`, `curve_transition`, ...).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OneCurve {
    /// Where the entry transition starts \[m\].
    pub start: f64,
    /// Radius of the circular part \[m\], positive.
    pub radius: f64,
    /// Length of each transition \[m\], 0 for none.
    pub transition: f64,
    /// Length of the circular part \[m\].
    pub length: f64,
    /// Cant in the circular part, raising the outer rail \[m\], not negative.
    pub cant: f64,
    /// +1 a left-hand curve, -1 a right-hand one.
    pub direction: f64,
}

impl DesignLine {
    /// A line from its rows, rounded over `rounding` metres at each (0: kinks kept). `rows`
    /// are (distance, curvature, cant); `what(i)` names row `i` in messages (a file's line, a
    /// parameter set).
    pub fn new(
        rows: &[(f64, f64, f64)],
        rounding: f64,
        what: impl Fn(usize) -> String,
    ) -> Result<DesignLine, String> {
        if !(rounding >= 0.0 && rounding.is_finite()) {
            return Err(format!(
                "rounding {rounding} m must be a finite length, not negative"
            ));
        }
        if rows.is_empty() {
            return Err(format!("{}: a design line needs at least one row", what(0)));
        }
        for (i, &(s, k, c)) in rows.iter().enumerate() {
            if !(s.is_finite() && k.is_finite() && c.is_finite()) {
                return Err(format!(
                    "{}: distance, curvature and cant must be finite numbers",
                    what(i)
                ));
            }
            if i > 0 && !(s > rows[i - 1].0) {
                return Err(format!(
                    "{}: distance {s} m is not greater than the previous row's {} m; distances must be strictly increasing",
                    what(i),
                    rows[i - 1].0
                ));
            }
            if k.abs() > MAX_CURVATURE {
                return Err(format!(
                    "{}: curvature {k} 1/m (radius {:.1} m) is tighter than the model's limit of {MAX_CURVATURE} 1/m (radius 25 m)",
                    what(i),
                    1.0 / k.abs()
                ));
            }
            if i > 0 {
                let gradient = (c - rows[i - 1].2) / (s - rows[i - 1].0);
                if gradient.abs() > MAX_CANT_GRADIENT {
                    return Err(format!(
                        "{}: the cant changes by {:.1} mm per metre from the previous row, more than the model's limit of {} mm per metre (a cant needs a transition)",
                        what(i),
                        gradient.abs() * 1e3,
                        MAX_CANT_GRADIENT * 1e3
                    ));
                }
            }
            if c.abs() > MAX_CANT {
                return Err(format!(
                    "{}: cant {c} m is beyond the model's limit of {MAX_CANT} m (EN 13803 allows 180-200 mm)",
                    what(i)
                ));
            }
        }
        let n = rows.len();
        let mut line = DesignLine {
            s: rows.iter().map(|r| r.0).collect(),
            curvature: rows.iter().map(|r| r.1).collect(),
            cant: rows.iter().map(|r| r.2).collect(),
            heading: vec![0.0; n],
            heading_integral: vec![0.0; n],
            roundings: vec![],
            passed_t: vec![],
            passed_p: vec![],
        };
        // T and P from the first row, segment by segment (exact for linear curvature).
        for i in 0..n - 1 {
            let len = line.s[i + 1] - line.s[i];
            let (k0, k1) = line.segment_curvature(i);
            let t = line.heading[i];
            line.heading_integral[i + 1] =
                line.heading_integral[i] + t * len + k0 * len * len / 2.0 + k1 * len.powi(3) / 6.0;
            line.heading[i + 1] = t + k0 * len + k1 * len * len / 2.0;
        }
        // Slopes of the segments, with the held stretches' 0 before the first row and after
        // the last.
        let slopes: Vec<(f64, f64)> = (0..n)
            .map(|i| (line.segment_curvature(i).1, line.segment_cant_slope(i)))
            .collect();
        let slope = |i: Option<usize>| i.map_or((0.0, 0.0), |i| slopes[i]);
        let (mut t, mut p) = (0.0, (0.0, 0.0));
        for i in 0..n {
            let (k_before, c_before) = slope(i.checked_sub(1));
            let (k_after, c_after) = slope(Some(i));
            let (dk, dc) = (k_after - k_before, c_after - c_before);
            let mut half = rounding / 2.0;
            if i > 0 {
                half = half.min((line.s[i] - line.s[i - 1]) / 2.0);
            }
            if i + 1 < n {
                half = half.min((line.s[i + 1] - line.s[i]) / 2.0);
            }
            if (dk == 0.0 && dc == 0.0) || half <= 0.0 {
                continue;
            }
            let r = Rounding {
                at: line.s[i],
                half,
                dk,
                dc,
            };
            line.roundings.push(r);
            line.passed_t.push(t);
            line.passed_p.push(p);
            let b = half;
            t += dk * b * b / 6.0;
            p.0 += dk * b.powi(3) / 6.0 - dk * b * b / 6.0 * r.end();
            p.1 += dk * b * b / 6.0;
        }
        line.passed_t.push(t);
        line.passed_p.push(p);
        Ok(line)
    }

    /// Curvature at the start of segment `i` and its slope (0 for the held stretch after the
    /// last row).
    fn segment_curvature(&self, i: usize) -> (f64, f64) {
        let k0 = self.curvature[i];
        match self.s.get(i + 1) {
            Some(&b) => (k0, (self.curvature[i + 1] - k0) / (b - self.s[i])),
            None => (k0, 0.0),
        }
    }

    /// The cant's slope on segment `i` (0 on the held stretches).
    fn segment_cant_slope(&self, i: usize) -> f64 {
        match self.s.get(i + 1) {
            Some(&b) => (self.cant[i + 1] - self.cant[i]) / (b - self.s[i]),
            None => 0.0,
        }
    }

    /// The straight line: one row of zeros.
    pub fn straight() -> DesignLine {
        DesignLine::new(&[(0.0, 0.0, 0.0)], 0.0, |_| String::new()).expect("a valid line")
    }

    /// Whether the line is straight and level everywhere (the model then skips every design
    /// term, so straight-track results stay bit for bit those of the straight model).
    pub fn is_straight(&self) -> bool {
        self.curvature.iter().all(|&k| k == 0.0) && self.cant.iter().all(|&c| c == 0.0)
    }

    /// One curve: a straight to `start`, a clothoid transition with a linear cant ramp, the
    /// circular part, the exit transition, and a straight after it.
    pub fn one_curve(c: &OneCurve, rounding: f64) -> Result<DesignLine, String> {
        let name = |what: &str| format!("one-curve parameters ({what})");
        if !(c.radius > 0.0 && c.radius.is_finite()) {
            return Err(format!(
                "{}: radius {} m must be positive",
                name("curve_radius"),
                c.radius
            ));
        }
        for (v, n) in [
            (c.transition, "curve_transition"),
            (c.length, "curve_length"),
            (c.cant, "curve_cant"),
        ] {
            if !(v >= 0.0 && v.is_finite()) {
                return Err(format!(
                    "{}: {v} must be a finite number, not negative",
                    name(n)
                ));
            }
        }
        if !(c.start >= 0.0 && c.start.is_finite()) {
            return Err(format!(
                "{}: {} m must be a finite distance, not negative",
                name("curve_start"),
                c.start
            ));
        }
        if c.direction != 1.0 && c.direction != -1.0 {
            return Err(format!(
                "{}: {} must be 1 (left) or -1 (right)",
                name("curve_direction"),
                c.direction
            ));
        }
        let (k, h) = (c.direction / c.radius, c.direction * c.cant);
        let mut rows = vec![(c.start, 0.0, 0.0)];
        let mut s = c.start + c.transition;
        if c.transition > 0.0 {
            rows.push((s, k, h));
        } else {
            // An abrupt curve: curvature and cant step within a millimetre.
            s += 1e-3;
            rows.push((s, k, h));
        }
        s += c.length;
        if c.length > 0.0 {
            rows.push((s, k, h));
        }
        s += c.transition.max(1e-3);
        rows.push((s, 0.0, 0.0));
        DesignLine::new(&rows, rounding, |i| {
            format!("{} row {}", name("the points they make"), i + 1)
        })
    }

    /// Reads a line file: CSV with the header `distance,curvature,cant` (m, 1/m, m; other
    /// columns ignored, blank lines and lines starting with `#` skipped). Errors name the file,
    /// the line and the column.
    pub fn from_csv(path: &Path, rounding: f64) -> Result<DesignLine, String> {
        // 64 MiB: a line of a million rows.
        let text = fmi_abi::resource::read_text(path, "line file", 1 << 26)?;
        let file = path.display().to_string();
        let expected = "distance,curvature,cant";
        let rows = csv::rows(&file, &text, &["distance", "curvature", "cant"], expected)?;
        if rows.is_empty() {
            return Err(format!(
                "{file}: no rows (a header '{expected}' and at least one row are needed)"
            ));
        }
        let values: Vec<(f64, f64, f64)> = rows.iter().map(|(_, r)| (r[0], r[1], r[2])).collect();
        DesignLine::new(&values, rounding, |i| format!("{file}: line {}", rows[i].0))
    }

    /// The segment holding `s`: the last row at or before it, or `None` before the first.
    fn segment(&self, s: f64) -> Option<usize> {
        let i = self.s.partition_point(|&x| x <= s);
        i.checked_sub(1)
    }

    /// The geometry at distance `s`.
    pub fn at(&self, s: f64) -> DesignPoint {
        let mut d = self.linear_at(s);
        // Roundings wholly behind `s` (they end in order), then the one `s` may be in.
        let done = self.roundings.partition_point(|r| r.end() <= s);
        d.heading += self.passed_t[done];
        let (p0, p1) = self.passed_p[done];
        d.heading_integral += p0 + p1 * s;
        if let Some(r) = self.roundings.get(done).filter(|r| r.start() < s) {
            let k = r.terms(r.dk, s);
            let c = r.terms(r.dc, s);
            d.curvature += k[0];
            d.curvature_ds += k[1];
            d.heading += k[3];
            d.heading_integral += k[4];
            d.cant += c[0];
            d.cant_ds += c[1];
            d.cant_ds2 += c[2];
        }
        d
    }

    /// The line without its roundings.
    fn linear_at(&self, s: f64) -> DesignPoint {
        let Some(i) = self.segment(s) else {
            let d = s - self.s[0];
            let k = self.curvature[0];
            return DesignPoint {
                curvature: k,
                curvature_ds: 0.0,
                cant: self.cant[0],
                cant_ds: 0.0,
                cant_ds2: 0.0,
                heading: self.heading[0] + k * d,
                heading_integral: self.heading_integral[0] + self.heading[0] * d + k * d * d / 2.0,
            };
        };
        let t = s - self.s[i];
        let (k0, k1) = self.segment_curvature(i);
        let c1 = self.segment_cant_slope(i);
        let (t0, p0) = (self.heading[i], self.heading_integral[i]);
        DesignPoint {
            curvature: k0 + k1 * t,
            curvature_ds: k1,
            cant: self.cant[i] + c1 * t,
            cant_ds: c1,
            cant_ds2: 0.0,
            heading: t0 + k0 * t + k1 * t * t / 2.0,
            heading_integral: p0 + t0 * t + k0 * t * t / 2.0 + k1 * t.powi(3) / 6.0,
        }
    }

    /// The rows (distance, curvature, cant), as given.
    pub fn rows(&self) -> impl Iterator<Item = (f64, f64, f64)> + '_ {
        (0..self.s.len()).map(|i| (self.s[i], self.curvature[i], self.cant[i]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(rows: &[(f64, f64, f64)], rounding: f64) -> DesignLine {
        DesignLine::new(rows, rounding, |i| format!("row {i}")).unwrap()
    }

    /// Heading and offset integrals against a midpoint-rule quadrature of the curvature.
    #[test]
    fn the_integrals_match_quadrature() {
        let l = line(
            &[
                (-5.0, 0.001, 0.0),
                (30.0, 0.0, 0.0),
                (70.0, 1.0 / 300.0, 0.1),
                (120.0, -0.002, 0.0),
            ],
            10.0,
        );
        let (mut t, mut p, ds) = (0.0, 0.0, 1e-3);
        let mut s = 0.0;
        while s < 160.0 {
            let k = l.at(s + ds / 2.0).curvature;
            p += (t + k * ds / 2.0) * ds;
            t += k * ds;
            s += ds;
            if (s - s.round()).abs() < ds / 2.0 && s.round() as i64 % 10 == 0 {
                let (d, o) = (l.at(s), l.at(0.0));
                let heading = d.heading - o.heading;
                let offset = d.heading_integral - o.heading_integral - s * o.heading;
                assert!((heading - t).abs() < 1e-9, "T({s}) {heading} vs {t}");
                assert!((offset - p).abs() < 1e-7, "P({s}) {offset} vs {p}");
            }
        }
        // Before the first row: the first row's curvature held.
        let d = l.at(-10.0);
        assert!(
            (d.heading - (-0.005)).abs() < 1e-15 && (d.heading_integral - 0.0125).abs() < 1e-15
        );
    }

    /// A clothoid of length L into a curve of radius R: heading s^2 / (2 R L), offset
    /// s^3 / (6 R L), the textbook cubic parabola.
    #[test]
    fn a_transition_is_a_clothoid() {
        let (r, len) = (300.0, 60.0);
        let left = OneCurve {
            start: 100.0,
            radius: r,
            transition: len,
            length: 200.0,
            cant: 0.1,
            direction: 1.0,
        };
        let l = DesignLine::one_curve(&left, 0.0).unwrap();
        let base = l.at(100.0);
        for x in [10.0, 30.0, 60.0] {
            let d = l.at(100.0 + x);
            assert!((d.heading - base.heading - x * x / (2.0 * r * len)).abs() < 1e-12);
            let offset = d.heading_integral - base.heading_integral - x * base.heading;
            assert!((offset - x.powi(3) / (6.0 * r * len)).abs() < 1e-12);
            assert!((d.cant - 0.1 * x / len).abs() < 1e-12);
        }
        let mid = l.at(250.0);
        assert_eq!(
            (mid.curvature, mid.cant, mid.curvature_ds),
            (1.0 / r, 0.1, 0.0)
        );
        // A right-hand curve mirrors it.
        let right = DesignLine::one_curve(
            &OneCurve {
                direction: -1.0,
                ..left
            },
            0.0,
        )
        .unwrap();
        assert_eq!(right.at(250.0).curvature, -1.0 / r);
        assert_eq!(right.at(250.0).cant, -0.1);
    }

    /// The rounding joins the straight pieces with matching value and slope at both of its
    /// ends, has the second derivative D / (2 b) inside, leaves the line alone outside, and
    /// shrinks where rows are closer than it.
    #[test]
    fn the_roundings_are_smooth_and_local() {
        let rows = [
            (0.0, 0.0, 0.0),
            (50.0, 0.002, 0.06),
            (56.0, 0.002, 0.06),
            (200.0, 0.0, 0.0),
        ];
        let (l, sharp) = (line(&rows, 10.0), line(&rows, 0.0));
        let e = 1e-7;
        for s in [45.0, 47.0, 53.0, 59.0, 195.0, 205.0] {
            // The ends of each rounding (b = 5 at 0 m and 200 m, 3 at 50 m and 56 m).
            for x in [s - e, s + e] {
                let (a, b) = (l.at(x), sharp.at(x));
                assert!((a.cant - b.cant).abs() < 1e-9 && (a.curvature - b.curvature).abs() < 1e-9);
            }
            let (a, b) = (l.at(s - e), l.at(s + e));
            assert!(
                (a.cant_ds - b.cant_ds).abs() < 1e-8,
                "{s}: {} {}",
                a.cant_ds,
                b.cant_ds
            );
            assert!((a.curvature_ds - b.curvature_ds).abs() < 1e-9);
        }
        // Inside: the parabola's curvature, and continuity through the row itself.
        let mid = l.at(48.0);
        assert!(
            (mid.cant_ds2 + 0.06 / 50.0 / 6.0).abs() < 1e-15,
            "{}",
            mid.cant_ds2
        );
        let (a, b) = (l.at(50.0 - e), l.at(50.0 + e));
        assert!((a.cant_ds - b.cant_ds).abs() < 1e-8 && (a.cant - b.cant).abs() < 1e-9);
        // Away from the rows it is the linear line, and so is the heading's change there.
        for s in [20.0, 100.0, 150.0] {
            let (a, b) = (l.at(s), sharp.at(s));
            assert_eq!(
                (a.curvature, a.cant, a.cant_ds2),
                (b.curvature, b.cant, 0.0)
            );
        }
        let turn = |x: &DesignLine| x.at(150.0).heading - x.at(100.0).heading;
        assert!((turn(&l) - turn(&sharp)).abs() < 1e-15);
    }

    #[test]
    fn impossible_lines_are_refused_with_the_row() {
        let e = DesignLine::new(&[(0.0, 0.0, 0.0), (0.0, 0.001, 0.0)], 10.0, |i| {
            format!("f.csv: line {}", i + 2)
        })
        .unwrap_err();
        assert!(
            e.contains("f.csv: line 3") && e.contains("strictly increasing"),
            "{e}"
        );
        let e = DesignLine::new(&[(0.0, 0.1, 0.0)], 10.0, |_| "x".into()).unwrap_err();
        assert!(e.contains("radius 10.0 m"), "{e}");
        let e = DesignLine::new(&[(0.0, 0.0, 0.3)], 10.0, |_| "x".into()).unwrap_err();
        assert!(e.contains("cant 0.3 m"), "{e}");
        // A canted curve without a transition: its cant would step within a millimetre.
        let abrupt = OneCurve {
            start: 10.0,
            radius: 600.0,
            transition: 0.0,
            length: 100.0,
            cant: 0.08,
            direction: 1.0,
        };
        let e = DesignLine::one_curve(&abrupt, 10.0).unwrap_err();
        assert!(e.contains("a cant needs a transition"), "{e}");
        assert!(
            DesignLine::one_curve(
                &OneCurve {
                    cant: 0.0,
                    ..abrupt
                },
                10.0
            )
            .is_ok()
        );
        let e = DesignLine::one_curve(
            &OneCurve {
                start: 0.0,
                radius: 300.0,
                transition: 50.0,
                length: 10.0,
                cant: 0.0,
                direction: 0.5,
            },
            10.0,
        )
        .unwrap_err();
        assert!(e.contains("curve_direction"), "{e}");
    }

    #[test]
    fn a_line_file_is_read_and_its_errors_name_the_line() {
        let dir = std::env::temp_dir().join(format!("line-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let good = dir.join("good.csv");
        std::fs::write(
            &good,
            "# a curve\ndistance,cant,curvature,note\n0,0,0,straight\n50,0.1,0.002,\n",
        )
        .unwrap();
        let l = DesignLine::from_csv(&good, 10.0).unwrap();
        assert_eq!(
            l.rows().collect::<Vec<_>>(),
            vec![(0.0, 0.0, 0.0), (50.0, 0.002, 0.1)]
        );
        let bad = dir.join("bad.csv");
        std::fs::write(&bad, "distance,curvature,cant\n0,0,0\n50,abc,0\n").unwrap();
        let e = DesignLine::from_csv(&bad, 10.0).unwrap_err();
        assert!(e.contains("bad.csv: line 3, column 2 ('curvature')"), "{e}");
        std::fs::write(&bad, "distance,curvature\n0,0\n").unwrap();
        assert!(
            DesignLine::from_csv(&bad, 10.0)
                .unwrap_err()
                .contains("no column 'cant'")
        );
        std::fs::write(&bad, "distance,curvature,cant\n0,0,0\n10,0.5,0\n").unwrap();
        assert!(
            DesignLine::from_csv(&bad, 10.0)
                .unwrap_err()
                .contains("bad.csv: line 3")
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
