//! The grid estimates between closings: the last two points, extrapolated linearly in distance.

use serde::{Deserialize, Serialize};

/// An estimate on the grid: its value, rms error, and the distance it was made at.
#[derive(Debug, Clone, Copy, Default, Serialize, Deserialize, PartialEq)]
pub(super) struct Point {
    pub(super) value: f64,
    pub(super) std: f64,
    pub(super) distance: f64,
}

/// The last two grid estimates, for the linear extrapolation between closings.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub(super) struct Track {
    pub(super) points: Vec<Point>,
}

impl Track {
    pub(super) fn push(&mut self, p: Point) {
        if self.points.len() == 2 {
            self.points.remove(0);
        }
        self.points.push(p);
    }

    pub(super) fn clear(&mut self) {
        self.points.clear();
    }

    /// The estimate at `distance` (linear extrapolation from the last two points; the last
    /// point alone when only one exists or they coincide).
    pub(super) fn at(&self, distance: f64) -> Option<(f64, f64)> {
        match self.points.as_slice() {
            [] => None,
            [p] => Some((p.value, p.std)),
            [a, b] => {
                let span = b.distance - a.distance;
                let slope = if span > 0.0 {
                    (b.value - a.value) / span
                } else {
                    0.0
                };
                // Never further than one cell ahead: a held speed of zero must not extrapolate.
                let ahead = (distance - b.distance).clamp(0.0, span.max(0.0));
                Some((b.value + slope * ahead, b.std))
            }
            _ => unreachable!("two points at most"),
        }
    }
}
