//! The design geometry's response removed from the sensors, so that both filters see what they
//! were made for: the response to the irregularities alone.
//!
//! # Why
//! On a curve the sensors carry the design line (curvature `k`, cant `c`) on top of the
//! irregularities: the yaw rate `V k`, the uncompensated lateral acceleration
//! `a_nc = V^2 k - g c / (2 l)`, and the vehicle's quasi-static response (the wheelsets' shift,
//! the bodies' roll and its gravity), which is larger than the irregularities' own signals.
//! Measured on the standard curved line (docs/accuracy.md, "Curves"): left in, whole Jrel 53;
//! with only `V k` and `a_nc` removed, 1.8; with the exact response removed (the same line run
//! without irregularities), the straight-track figure.
//!
//! # The model
//! With the design known at the leading wheelset (the inputs `design_curvature` and
//! `design_cant`, EN 13848's reference), the response is, for a linear vehicle at speed `V`, a
//! causal linear function of the design's history along the line, because every body that
//! carries a sensor rides at or behind the leading wheelset. So per sensor:
//! - the rigid part, exact at any speed: `a_nc` on both accelerometers, `V k` on the yaw gyro;
//! - the rest, the vehicle's own response: a causal FIR on the design's history on a grid of
//!   `cell` metres (block means of `k` and `c`; `taps` cells), fitted per bank speed on the
//!   vehicle's runs along random curved lines without irregularities
//!   (`alignment-studies design-response`, docs/studies.md) and blended linearly between bank
//!   speeds (the nearest outside them). It is updated when a cell completes; between, it is held.
//!
//! The model belongs to a vehicle (`design_response_file`); the shipped one to the ML95. With
//! the inputs at 0 (straight track) nothing is removed.
//!
//! # Envelope
//! The model knows the curvatures and cant deficiencies of its training lines; beyond them the
//! vehicle is not linear any more. It also predicts, by a FIR of the same kind, the leading
//! wheelset's shift from the design line (fitted without flange contact): where that comes
//! within [`FLANGE_MARGIN`] of the vehicle's flange clearance, the wheelset runs against its
//! flange, whose response no
//! linear model of the free wheelset follows (nor do the taps, fitted on a free wheelset). In
//! both cases [`Design::outside`] says so (the FMU's `outside_training`), there and for
//! [`HOLD`] metres after.

use crate::learned::grid::Grid;
// A design input no line file may hold is a wrong input: the line's own limits.
use design_line::{MAX_CANT, MAX_CURVATURE};
use serde::{Deserialize, Serialize};
use std::collections::VecDeque;
use std::path::Path;
use std::sync::Arc;

/// The shipped model's name (`design_response_file`'s default), built into the library.
pub const SHIPPED_NAME: &str = "design-response.toml";

/// The shipped model's text (the ML95, `alignment-studies design-response`).
const SHIPPED: &str = include_str!("../resources/design-response.toml");

/// The models parsed so far, shared by the instances that read them.
pub(crate) static MODELS: crate::parsed::Cache<DesignModel> = crate::parsed::Cache::new();

/// The sensors in the estimator's order: `ws_acc_y`, `ws_yaw_rate`, `frame_acc_y`,
/// `ws_roll_rate`.
pub const SENSORS: [&str; 4] = ["ws_acc_y", "ws_yaw_rate", "frame_acc_y", "ws_roll_rate"];

/// The model's tables per bank speed: the four sensors, then the leading wheelset's lateral
/// shift from the design line (`ws_y`, for the flange check).
pub const TABLES: [&str; 5] = [
    "ws_acc_y",
    "ws_yaw_rate",
    "frame_acc_y",
    "ws_roll_rate",
    "ws_y",
];

/// One sensor's FIR at one speed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SensorResponse {
    /// Bank speed \[m/s\].
    pub speed: f64,
    /// One of [`TABLES`].
    pub sensor: String,
    /// Constant term (the fit's intercept; about 0).
    pub offset: f64,
    /// Response per unit curvature, one per cell of history, newest first.
    pub curvature: Vec<f64>,
    /// Response per metre of cant, likewise.
    pub cant: Vec<f64>,
}

/// A vehicle's design-response model, as its file holds it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DesignModel {
    /// File format (2).
    pub format: u32,
    /// The vehicle it was fitted on (text for people).
    pub vehicle: String,
    /// Grid cell \[m\].
    pub cell: f64,
    /// Half the distance between the contact points of the fitted vehicle \[m\] (for `a_nc`).
    pub half_gauge: f64,
    /// Gravity used \[m/s2\].
    pub gravity: f64,
    /// The largest curvature of the training lines \[1/m\].
    pub max_curvature: f64,
    /// The largest uncompensated lateral acceleration of the training runs \[m/s2\].
    pub max_uncompensated: f64,
    /// The fitted vehicle's lateral free play before flange contact \[m\]: where the predicted
    /// shift of the leading wheelset exceeds it, the vehicle (fitted without flange contact) is
    /// not what runs.
    pub flange_clearance: f64,
    /// One per bank speed and sensor, bank speeds ascending.
    pub response: Vec<SensorResponse>,
}

impl DesignModel {
    /// The checked model in the file at `path`, parsed once per process for every instance
    /// that reads the same bytes there ([`crate::parsed`]); errors name the file and what is
    /// wrong.
    pub fn read_shared(path: &Path) -> Result<std::sync::Arc<DesignModel>, String> {
        let named = |e: String| format!("design response file {}: {e}", path.display());
        let bytes = std::fs::read(path).map_err(|e| named(e.to_string()))?;
        MODELS.get_or_parse(&path.to_string_lossy(), &bytes, |b| {
            let text = std::str::from_utf8(b).map_err(|e| named(format!("not UTF-8 text: {e}")))?;
            DesignModel::parse(text).map_err(named)
        })
    }

    /// The shipped model (the ML95), parsed once per process ([`crate::parsed`]).
    pub fn shipped_shared() -> Result<std::sync::Arc<DesignModel>, String> {
        MODELS.get_or_parse(SHIPPED_NAME, SHIPPED.as_bytes(), |_| DesignModel::shipped())
    }

    /// The shipped model (the ML95).
    pub fn shipped() -> Result<DesignModel, String> {
        DesignModel::parse(SHIPPED).map_err(|e| format!("the built-in {SHIPPED_NAME}: {e}"))
    }

    /// A model from its TOML text, checked.
    fn parse(text: &str) -> Result<DesignModel, String> {
        let model: DesignModel = toml::from_str(text).map_err(|e| e.to_string())?;
        model.check()?;
        Ok(model)
    }

    /// The model's consistency: format, positive constants, every speed with the four
    /// sensors, equal tap counts, finite numbers.
    pub fn check(&self) -> Result<(), String> {
        if self.format != 2 {
            return Err(format!("format {} (this build reads 2)", self.format));
        }
        for (name, v) in [
            ("cell", self.cell),
            ("half_gauge", self.half_gauge),
            ("gravity", self.gravity),
            ("max_curvature", self.max_curvature),
            ("max_uncompensated", self.max_uncompensated),
            ("flange_clearance", self.flange_clearance),
        ] {
            if !(v > 0.0 && v.is_finite()) {
                return Err(format!("'{name}' = {v} must be positive and finite"));
            }
        }
        if self.flange_clearance <= FLANGE_MARGIN {
            return Err(format!(
                "'flange_clearance' = {} m must exceed the irregularities' margin {FLANGE_MARGIN} m",
                self.flange_clearance
            ));
        }
        if self.response.is_empty() || !self.response.len().is_multiple_of(TABLES.len()) {
            return Err(format!(
                "{} response tables: five (the four sensors and ws_y) per bank speed are needed",
                self.response.len()
            ));
        }
        let taps = self.response[0].curvature.len();
        if taps == 0 {
            return Err("the response tables have no taps".into());
        }
        let mut last_speed = f64::NEG_INFINITY;
        for (i, chunk) in self.response.chunks(TABLES.len()).enumerate() {
            let speed = chunk[0].speed;
            if !(speed > last_speed && speed > 0.0 && speed.is_finite()) {
                return Err(format!(
                    "bank speed {speed} m/s (table {}): speeds must be positive and ascending",
                    i * TABLES.len() + 1
                ));
            }
            last_speed = speed;
            for (r, name) in chunk.iter().zip(TABLES) {
                let finite = |x: &[f64]| x.iter().all(|v| v.is_finite());
                if r.speed != speed || r.sensor != name {
                    return Err(format!(
                        "at {speed} m/s the tables must be {TABLES:?} in order; found '{}' at {} m/s",
                        r.sensor, r.speed
                    ));
                }
                if r.curvature.len() != taps || r.cant.len() != taps {
                    return Err(format!(
                        "'{name}' at {speed} m/s has {} and {} taps; every table has {taps}",
                        r.curvature.len(),
                        r.cant.len()
                    ));
                }
                if !(finite(&r.curvature) && finite(&r.cant) && r.offset.is_finite()) {
                    return Err(format!("'{name}' at {speed} m/s has a non-finite number"));
                }
            }
        }
        Ok(())
    }

    /// The bank speeds.
    fn speeds(&self) -> impl Iterator<Item = f64> + '_ {
        self.response.chunks(TABLES.len()).map(|c| c[0].speed)
    }

    fn taps(&self) -> usize {
        self.response[0].curvature.len()
    }

    /// The FIR part for history `h` (newest first) at bank speed index `i`, per table.
    fn fir(&self, i: usize, h: &VecDeque<[f64; 2]>) -> [f64; 5] {
        let chunk = &self.response[i * TABLES.len()..(i + 1) * TABLES.len()];
        std::array::from_fn(|s| {
            let r = &chunk[s];
            r.offset
                + h.iter()
                    .zip(r.curvature.iter().zip(&r.cant))
                    .map(|(x, (a, b))| a * x[0] + b * x[1])
                    .sum::<f64>()
        })
    }

    /// The FIR part at `speed`, blended linearly between the bank speeds around it.
    fn fir_at(&self, speed: f64, h: &VecDeque<[f64; 2]>) -> [f64; 5] {
        // Per closed cell, on the estimator's path: the bank speeds read in place.
        let speed_of = |i: usize| self.response[i * TABLES.len()].speed;
        let n = self.response.len() / TABLES.len();
        let above = self.speeds().take_while(|&v| v <= speed).count();
        if above == 0 {
            return self.fir(0, h);
        }
        if above == n {
            return self.fir(n - 1, h);
        }
        let (i, j) = (above - 1, above);
        let w = (speed - speed_of(i)) / (speed_of(j) - speed_of(i));
        let (a, b) = (self.fir(i, h), self.fir(j, h));
        std::array::from_fn(|s| a[s] * (1.0 - w) + b[s] * w)
    }
}

/// How much of the flange clearance the irregularities take \[m\]: the leading wheelset's
/// motion relative to the rails they cause, 4.9 mm at its 99th percentile (the ML95 at 18 m/s,
/// German low track, seed 1). A predicted shift within this of the clearance puts the flange
/// against the rail now and then; on the standard curved line with flange contact that already
/// costs the wide curves (whole Jrel 0.70 against 0.11 without flange contact), so the flag
/// counts from there.
pub const FLANGE_MARGIN: f64 = 0.005;

/// The grid's Kalman-channel high-pass cut-off \[m\]: that channel carries 0 here, so any value.
const UNUSED_HIGHPASS: f64 = 1000.0;

/// How long the estimate stays outside after the design leaves the model \[m\]: the learned
/// filter's 60 m of history still holds what the sensors read there.
pub const HOLD: f64 = 60.0;

/// The design correction's state: the model, the history grid, the held FIR part.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Design {
    model: Option<Arc<DesignModel>>,
    /// The learned filter's distance grid (`crate::learned::grid`: block means, the cells a
    /// long step crosses repeating the mean, boundaries robust to a master's clock rounding),
    /// fed `[k, c, 0, 0, 0]`; `None` without a model.
    grid: Option<Grid>,
    /// Complete cells' means, newest first, at most the model's taps.
    history: VecDeque<[f64; 2]>,
    /// The FIR part from the last complete cell (the four sensors, the predicted shift).
    fir: [f64; 5],
    /// The distance up to which the estimate is outside the model (module docs, "Envelope"),
    /// and the last sample's distance \[m\].
    outside_until: f64,
    at: f64,
    /// Complete cells in a row whose mean was 0 (straight, level track): once the whole
    /// history is, the FIR part is 0 without a sum.
    level_cells: usize,
    /// The last valid design input.
    last: [f64; 2],
    /// The design line (`line_file`) and the line's distance at the run's start: where given,
    /// the design at `start + distance` replaces the inputs.
    line: Option<(Arc<design_line::DesignLine>, f64)>,
}

impl Design {
    /// A correction with `model` (`None`: off, every input ignored).
    pub fn new(model: Option<Arc<DesignModel>>) -> Design {
        Design {
            grid: model
                .as_ref()
                .map(|m| Grid::new(m.cell, UNUSED_HIGHPASS, None)),
            model,
            history: VecDeque::new(),
            fir: [0.0; 5],
            outside_until: f64::NEG_INFINITY,
            at: 0.0,
            level_cells: 0,
            last: [0.0; 2],
            line: None,
        }
    }

    /// The correction with the design read from `line` (the line, the line's distance at the
    /// run's start) instead of the inputs.
    pub fn with_line(mut self, line: Option<(Arc<design_line::DesignLine>, f64)>) -> Design {
        self.line = line;
        self
    }

    /// The design at the leading wheelset `distance` metres into the run (the sample's, after
    /// its advance: the estimator's `distance` output, where a master stepping the vehicle first
    /// has the vehicle): the line's at `start + distance` when `line_file` gave one, else
    /// `inputs`.
    fn given(&self, distance: f64, inputs: [f64; 2]) -> [f64; 2] {
        match &self.line {
            Some((line, start)) => {
                let p = line.at(start + distance);
                [p.curvature, p.cant]
            }
            None => inputs,
        }
    }

    /// Whether the design comes from `line_file` (the inputs are then not read).
    pub fn from_line(&self) -> bool {
        self.line.is_some()
    }

    /// The last valid design used \[1/m, m\].
    pub fn last(&self) -> [f64; 2] {
        self.last
    }

    /// Whether a model is loaded.
    pub fn active(&self) -> bool {
        self.model.is_some()
    }

    /// Whether the design or the cant deficiency is beyond the model's training envelope, or the
    /// predicted shift of the leading wheelset beyond the flange clearance, here or within the
    /// last [`HOLD`] metres (module docs).
    pub fn outside(&self) -> bool {
        self.at <= self.outside_until
    }

    /// What the design adds to the four sensors at this sample: the leading wheelset at
    /// `distance` (after the sample's advance), moving at `speed` (0 standing: only the cant's
    /// gravity), the design `[curvature, cant]` there (the inputs; with `line_file`, the
    /// line's instead).
    pub fn response(&mut self, distance: f64, speed: f64, design: [f64; 2]) -> [f64; 4] {
        let Some(model) = self.model.clone() else {
            return [0.0; 4];
        };
        self.at = distance;
        let design = self.given(distance, design);
        // A design no line has (not finite, tighter than 25 m, cant beyond 0.2 m) is a wrong
        // input: the last valid one is held, and the estimate is flagged.
        let [k, c] = if design.iter().all(|x| x.is_finite())
            && design[0].abs() <= MAX_CURVATURE
            && design[1].abs() <= MAX_CANT
        {
            self.last = design;
            design
        } else {
            self.outside_until = distance + HOLD;
            self.last
        };
        let a_nc = speed * speed * k - model.gravity * c / (2.0 * model.half_gauge);
        if k.abs() > model.max_curvature * 1.05 || a_nc.abs() > model.max_uncompensated * 1.05 {
            self.outside_until = distance + HOLD;
        }
        let closed = match self.grid.as_mut() {
            Some(grid) if speed > 0.0 => grid.add(distance, &[k, c, 0.0, 0.0, 0.0]),
            _ => None,
        };
        if let Some(closed) = closed {
            {
                // The cells a long step crossed repeat the mean, as the fit's grid fills them.
                let n = closed.cells.len();
                for cell in &closed.cells[n.saturating_sub(model.taps())..] {
                    let mean = [cell[0], cell[1]];
                    self.level_cells = if mean == [0.0; 2] {
                        self.level_cells + 1
                    } else {
                        0
                    };
                    self.history.push_front(mean);
                }
                self.history.truncate(model.taps());
                self.fir = if self.level_cells >= model.taps() {
                    model.fir_at(speed, &VecDeque::new())
                } else {
                    model.fir_at(speed, &self.history)
                };
                if self.fir[4].abs() > model.flange_clearance - FLANGE_MARGIN {
                    self.outside_until = distance + HOLD;
                }
            }
        }
        // Standing, the vehicle keeps its quasi-static state (shift, roll): the accelerometers'
        // part is held, the gyroscopes' is 0.
        let fir = if speed > 0.0 {
            self.fir
        } else {
            [self.fir[0], 0.0, self.fir[2], 0.0, self.fir[4]]
        };
        [a_nc + fir[0], speed * k + fir[1], a_nc + fir[2], fir[3]]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model(taps: usize) -> DesignModel {
        let response = [10.0, 20.0]
            .iter()
            .flat_map(|&speed| {
                TABLES.iter().enumerate().map(move |(i, s)| SensorResponse {
                    speed,
                    sensor: s.to_string(),
                    offset: 0.0,
                    curvature: (0..taps)
                        .map(|j| speed * (i + 1) as f64 * (j + 1) as f64)
                        .collect(),
                    cant: vec![0.5 * speed; taps],
                })
            })
            .collect();
        DesignModel {
            format: 2,
            vehicle: "test".into(),
            cell: 0.2,
            half_gauge: 0.75,
            gravity: 9.81,
            max_curvature: 0.01,
            max_uncompensated: 2.0,
            flange_clearance: 1e9,
            response,
        }
    }

    /// The correction is the rigid part plus the direct convolution of the cells' means with
    /// the taps, blended between the bank speeds.
    #[test]
    fn the_correction_is_the_documented_sum() {
        let m = Arc::new(model(3));
        let mut d = Design::new(Some(m.clone()));
        let (v, h) = (15.0, 1e-3);
        let design = |s: f64| [1e-3 * (s / 10.0).sin(), 0.01 * (s / 7.0).cos()];
        let mut s = 0.0;
        let mut cells: Vec<Vec<[f64; 2]>> = vec![];
        let mut last = vec![];
        for _ in 0..2000 {
            s += v * h;
            let x = design(s);
            let got = d.response(s, v, x);
            // The grid's cells, boundaries EDGE early (`crate::learned::grid`).
            let cell = ((s + crate::learned::grid::EDGE) / 0.2).floor() as usize;
            if cells.len() <= cell {
                cells.resize(cell + 1, vec![]);
            }
            // The model's FIR part from the cells completed before this sample's cell.
            let done: Vec<[f64; 2]> = cells[..cell]
                .iter()
                .rev()
                .filter(|c| !c.is_empty())
                .take(3)
                .map(|c| {
                    let n = c.len() as f64;
                    [
                        c.iter().map(|x| x[0]).sum::<f64>() / n,
                        c.iter().map(|x| x[1]).sum::<f64>() / n,
                    ]
                })
                .collect();
            cells[cell].push(x);
            let fir = |speed: f64, i: usize| {
                done.iter()
                    .enumerate()
                    .map(|(j, c)| {
                        speed * (i + 1) as f64 * (j + 1) as f64 * c[0] + 0.5 * speed * c[1]
                    })
                    .sum::<f64>()
            };
            let a_nc = v * v * x[0] - 9.81 * x[1] / 1.5;
            let want: Vec<f64> = (0..4)
                .map(|i| {
                    let f = 0.5 * fir(10.0, i) + 0.5 * fir(20.0, i);
                    f + [a_nc, v * x[0], a_nc, 0.0][i]
                })
                .collect();
            for i in 0..4 {
                assert!(
                    (got[i] - want[i]).abs() < 1e-12,
                    "{s}: {i} {} {}",
                    got[i],
                    want[i]
                );
            }
            last = got.to_vec();
        }
        assert!(last.iter().all(|x| x.abs() > 0.0));
        // Standing: the cant's gravity, and the accelerometers' quasi-static part held.
        let held = d.fir;
        assert_eq!(
            d.response(s, 0.0, [0.002, 0.1]),
            [
                -9.81 * 0.1 / 1.5 + held[0],
                0.0,
                -9.81 * 0.1 / 1.5 + held[2],
                0.0
            ]
        );
        assert!(!d.outside());
        d.response(s, 15.0, [0.02, 0.0]);
        assert!(d.outside());
        d.response(s + HOLD - 1.0, 15.0, [0.0, 0.0]);
        assert!(d.outside());
        d.response(s + HOLD + 1.0, 15.0, [0.0, 0.0]);
        assert!(!d.outside());
        // Off: nothing.
        assert_eq!(
            Design::new(None).response(1.0, 15.0, [0.002, 0.1]),
            [0.0; 4]
        );
    }

    /// With a line, the design is the line's at `start + distance` (the vehicle FMU's outputs,
    /// `design-line`'s own definition), whatever the inputs; without, the inputs.
    #[test]
    fn a_line_replaces_the_inputs() {
        let line = design_line::DesignLine::new(
            &[(0.0, 0.0, 0.0), (100.0, 0.002, 0.1), (200.0, 0.002, 0.1)],
            10.0,
            |i| format!("row {i}"),
        )
        .expect("line");
        let d = Design::new(Some(Arc::new(model(8))));
        assert!(!d.from_line());
        assert_eq!(d.given(50.0, [1e-3, 0.05]), [1e-3, 0.05]);
        let d = d.with_line(Some((Arc::new(line), 30.0)));
        assert!(d.from_line());
        // 30 + 20 = 50 m: half-way up the ramp, 45 m from its rounded start.
        let got = d.given(20.0, [0.0, 0.0]);
        assert!(
            (got[0] - 0.001).abs() < 1e-15 && (got[1] - 0.05).abs() < 1e-15,
            "{got:?}"
        );
        // Beyond the last row the line holds its last values.
        assert_eq!(d.given(1000.0, [0.0, 0.0]), [0.002, 0.1]);
    }

    /// A long step fills the cells it jumps over with the completed cell's mean, as the fit's
    /// grid does; a design no line has is replaced by the last valid one, and flagged.
    #[test]
    fn long_steps_and_wrong_inputs() {
        let mut d = Design::new(Some(Arc::new(model(8))));
        d.response(0.05, 20.0, [1e-3, 0.01]);
        d.response(0.15, 20.0, [1e-3, 0.01]);
        d.response(1.05, 20.0, [2e-3, 0.02]); // from cell 0 to cell 5
        assert_eq!(d.history.len(), 5);
        assert!(d.history.iter().all(|c| *c == [1e-3, 0.01]));
        assert!(!d.outside());
        for wrong in [[f64::NAN, 0.0], [1.0, 0.0], [0.0, 1e300]] {
            let mut e = d.clone();
            let got = e.response(1.1, 20.0, wrong);
            let want = d.clone().response(1.1, 20.0, [2e-3, 0.02]);
            assert_eq!(got, want, "{wrong:?}");
            assert!(e.outside(), "{wrong:?}");
        }
    }

    /// A predicted shift within FLANGE_MARGIN of the flange clearance flags the estimate, for
    /// HOLD metres after.
    #[test]
    fn a_shift_beyond_the_flange_clearance_is_outside() {
        let mut m = model(3);
        m.flange_clearance = 0.01 + FLANGE_MARGIN;
        let mut d = Design::new(Some(Arc::new(m)));
        // The shift table's taps at the bank speed 10 m/s are 50, 100, 150 per 1/m: a steady
        // curvature of 2e-5 predicts 0.006 m, 5e-5 predicts 0.015 m.
        for (k, flagged) in [(2e-5, false), (5e-5, true)] {
            let mut s = 0.0;
            let mut d2 = d.clone();
            for _ in 0..200 {
                s += 0.01;
                d2.response(s, 10.0, [k, 0.0]);
            }
            assert_eq!(d2.outside(), flagged, "{k}");
            // Back on straight track, the flag clears HOLD metres after the shift's memory.
            for _ in 0..(HOLD as usize + 5) * 100 {
                s += 0.01;
                d2.response(s, 10.0, [0.0, 0.0]);
            }
            assert!(!d2.outside(), "{k}");
        }
        d.response(0.01, 10.0, [0.0, 0.0]);
        assert!(!d.outside());
    }

    #[test]
    fn broken_models_are_refused_by_name() {
        let mut m = model(3);
        m.response[6].cant.pop();
        assert!(
            m.check()
                .unwrap_err()
                .contains("'ws_yaw_rate' at 20 m/s has 3 and 2 taps")
        );
        let mut m = model(3);
        m.response.swap(0, 1);
        assert!(m.check().unwrap_err().contains("in order"));
        let mut m = model(3);
        m.cell = 0.0;
        assert!(m.check().unwrap_err().contains("'cell'"));
        let mut m = model(3);
        m.response[0].curvature[1] = f64::NAN;
        assert!(m.check().unwrap_err().contains("non-finite"));
        assert!(model(3).check().is_ok());
    }
}
