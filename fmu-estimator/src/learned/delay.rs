//! The delay line of the causal output: what the fixed-lag output carries until its own window
//! has its look-ahead.

use super::track::Point;
use serde::{Deserialize, Serialize};

/// The causal output on the grid over the last `lag` metres (and two more points), oldest
/// first: learned estimates, or the Kalman filter's where none was made. The fixed-lag output
/// while its own window is not available.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub(super) struct Delay {
    points: std::collections::VecDeque<Point>,
    capacity: usize,
}

impl Delay {
    /// A delay line for a lag of `lag` grid points (none for 0): the lag and two more points.
    pub(super) fn new(lag: usize) -> Delay {
        Delay {
            points: Default::default(),
            capacity: if lag > 0 { lag + 2 } else { 0 },
        }
    }

    /// Keeps `p` (nothing without a lagged output).
    pub(super) fn push(&mut self, p: Point) {
        if self.capacity == 0 {
            return;
        }
        if self.points.len() == self.capacity {
            self.points.pop_front();
        }
        self.points.push_back(p);
    }

    /// The causal estimate made at `distance` (linear between grid points; the oldest point
    /// before it, the newest after it).
    pub(super) fn at(&self, distance: f64) -> Option<(f64, f64)> {
        let first = self.points.front()?;
        if distance <= first.distance {
            return Some((first.value, first.std));
        }
        let i = self.points.partition_point(|p| p.distance < distance);
        let Some(b) = self.points.get(i) else {
            let last = self.points.back().expect("non-empty");
            return Some((last.value, last.std));
        };
        let a = &self.points[i - 1];
        let w = (distance - a.distance) / (b.distance - a.distance);
        Some((a.value + w * (b.value - a.value), b.std))
    }
}
