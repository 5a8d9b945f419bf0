//! The learned filter's history: per channel, the newest cells in a ring buffer that hands any
//! window its cells as one contiguous slice.

use super::grid::CHANNELS;
use super::window;
use serde::{Deserialize, Serialize};

/// Per channel, the newest `capacity` values, each written twice (at `i` and `i + capacity`)
/// so the newest `n` are always one contiguous slice.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub(super) struct History {
    capacity: usize,
    data: Vec<Vec<f64>>,
    /// Position of the next write.
    pos: usize,
    filled: usize,
}

impl History {
    pub(super) fn new(capacity: usize) -> History {
        History {
            capacity,
            data: vec![vec![0.0; 2 * capacity]; CHANNELS.len()],
            pos: 0,
            filled: 0,
        }
    }

    pub(super) fn push(&mut self, x: &[f64; 5]) {
        for (d, v) in self.data.iter_mut().zip(x) {
            d[self.pos] = *v;
            d[self.pos + self.capacity] = *v;
        }
        self.pos = (self.pos + 1) % self.capacity;
        self.filled = (self.filled + 1).min(self.capacity);
    }
}

impl window::History for History {
    fn filled(&self) -> usize {
        self.filled
    }

    fn latest(&self, c: usize, n: usize) -> &[f64] {
        let end = self.pos + self.capacity;
        &self.data[c][end - n..end]
    }
}
