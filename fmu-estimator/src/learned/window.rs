//! One window of taps and how it is applied at run time: which window a history gets, and how
//! its taps meet the history.
//!
//! | concern | rule |
//! |---|---|
//! | tap order | the bank file holds tap `j` as the one `j` cells before the newest ([`super::bank`]); a [`Window`] keeps them oldest first, so the dot product runs over a history in memory order |
//! | which window | the longest whose `past + future + 1` cells the history covers ([`longest_covered`]): at the start of a run the shorter start windows, then the full one |
//! | the sum | per channel a dot product with four partial sums (fixed summation order, vectorizable), channels added in the entry's order, each times its speed gain |
//!
//! The tap fit (`alignment-studies taps`) applies its candidate windows with this module too
//! (its validation objective, the windows' rms errors, the estimates from a run's start), over
//! a run's cells held as columns, so the figures it writes into a bank are those of the
//! estimates the FMU makes. `studies/src/study/learned/taps.rs` has the test that holds the two
//! together through `Learned` (speed quotients, delay line, blending) on the same samples, to
//! rounding.

use super::bank::Entry;
use super::grid::CHANNELS;
use serde::{Deserialize, Serialize};

/// A history of grid cells, per channel slot ([`super::grid::CHANNELS`]), newest last.
pub trait History {
    /// How many cells it holds (at most its capacity).
    fn filled(&self) -> usize;
    /// The newest `n` values of channel `slot`, oldest first (`n <= filled()`).
    fn latest(&self, slot: usize, n: usize) -> &[f64];
}

/// One window ready to apply: the channel slots it reads and its taps, channel after channel,
/// oldest first.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Window {
    past: usize,
    len: usize,
    slots: Vec<usize>,
    /// `slots.len() * len` taps, channel after channel, oldest first.
    taps: Vec<f64>,
    rms_error: f64,
}

impl Window {
    /// A window from taps in the bank file's order (per channel, newest first) for `past` cells
    /// of history and `future` of look-ahead; `rms_error` is its estimate's error on the fit.
    pub fn from_file_order(
        past: usize,
        future: usize,
        slots: Vec<usize>,
        file_taps: &[f64],
        rms_error: f64,
    ) -> Window {
        let len = past + future + 1;
        assert_eq!(
            file_taps.len(),
            slots.len() * len,
            "a window's taps are len per channel"
        );
        let mut taps = Vec::with_capacity(file_taps.len());
        for c in 0..slots.len() {
            taps.extend(file_taps[c * len..(c + 1) * len].iter().rev());
        }
        Window {
            past,
            len,
            slots,
            taps,
            rms_error,
        }
    }

    /// Cells of history it needs: past, the estimated cell and the look-ahead.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Never true: a window reads at least the estimated cell (for clippy's `len` rule).
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Grid points of history behind the estimated cell: which window a history of a given
    /// length gets.
    pub fn past(&self) -> usize {
        self.past
    }

    /// The window's validation rms error \[m\]: the standard deviation the FMU reports with
    /// its estimate.
    pub fn rms_error(&self) -> f64 {
        self.rms_error
    }

    /// The estimate from the newest [`Window::len`] cells of `history`; `gain` per channel slot
    /// brings a history kept in speed quotients back to the current speed (ones for a history
    /// of raw cells).
    pub fn apply(&self, history: &impl History, gain: &[f64; 5]) -> f64 {
        let mut e = 0.0;
        for (c, slot) in self.slots.iter().enumerate() {
            let x = history.latest(*slot, self.len);
            let t = &self.taps[c * self.len..(c + 1) * self.len];
            e += gain[*slot] * dot(t, x);
        }
        e
    }
}

/// The longest of `windows` (sorted by ascending length) whose cells a history of `filled`
/// cells covers; `None` before the shortest is covered.
pub fn longest_covered(windows: &[Window], filled: usize) -> Option<&Window> {
    windows.iter().rev().find(|w| w.len <= filled)
}

/// The windows of one bank entry, ready to apply, shortest history first.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Windows(Vec<Window>);

impl Windows {
    /// The entry's windows (its channel names checked against [`CHANNELS`] by the bank).
    pub fn of(e: &Entry) -> Windows {
        let slot = |name: &String| CHANNELS.iter().position(|c| c == name).expect("checked");
        let slots: Vec<usize> = e.channels.iter().map(slot).collect();
        let mut w: Vec<Window> = e
            .windows
            .iter()
            .map(|w| Window::from_file_order(w.past, w.future, slots.clone(), &w.taps, w.rms_error))
            .collect();
        w.sort_by_key(Window::len);
        Windows(w)
    }

    /// The estimate from the longest window the history covers, and its rms error; `gain` per
    /// channel slot brings the history's speed quotients back to the current speed.
    pub fn apply(&self, hist: &impl History, gain: &[f64; 5]) -> Option<(f64, f64)> {
        let w = longest_covered(&self.0, hist.filled())?;
        Some((w.apply(hist, gain), w.rms_error()))
    }

    /// The most cells a window reads.
    pub fn longest(&self) -> usize {
        self.0.iter().map(Window::len).max().unwrap_or(0)
    }
}

/// `sum a_i b_i` with four partial sums: lets the compiler vectorize, and fixes the summation
/// order (the fit's estimates and the FMU's are the same arithmetic). Where the processor has
/// AVX2 the four sums are one 256-bit register instead of two 128-bit ones: the same
/// operations in the same order (no fused multiply-add: the product is rounded before the sum,
/// as without AVX2), so the same result to the last bit (a NaN result may differ in its sign
/// bit: x86 keeps the first operand's NaN, and the compiler may order the portable sum's
/// operands either way), in a third of the instructions. The taps' products are the learned
/// filter's largest cost per sample at a changing speed.
fn dot(a: &[f64], b: &[f64]) -> f64 {
    debug_assert_eq!(a.len(), b.len(), "a window's taps and cells");
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the processor has AVX2 (checked just above), all the function requires.
        return unsafe { dot_avx2(a, b) };
    }
    dot_portable(a, b)
}

/// [`dot_portable`] with its four partial sums in the lanes of one AVX register (the compiler
/// left to itself shuffles them between two).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn dot_avx2(a: &[f64], b: &[f64]) -> f64 {
    use std::arch::x86_64::{
        _mm256_add_pd, _mm256_loadu_pd, _mm256_mul_pd, _mm256_setzero_pd, _mm256_storeu_pd,
    };
    let n = a.len().min(b.len());
    let chunks = n / 4;
    let mut sum = _mm256_setzero_pd();
    for k in 0..chunks {
        // SAFETY: `4 k + 3 < n`, within both slices; unaligned loads.
        let (x, y) = unsafe {
            (
                _mm256_loadu_pd(a.as_ptr().add(4 * k)),
                _mm256_loadu_pd(b.as_ptr().add(4 * k)),
            )
        };
        sum = _mm256_add_pd(sum, _mm256_mul_pd(x, y));
    }
    let mut s = [0.0; 4];
    // SAFETY: `s` holds four f64.
    unsafe { _mm256_storeu_pd(s.as_mut_ptr(), sum) };
    let mut r = (s[0] + s[1]) + (s[2] + s[3]);
    for (x, y) in a[4 * chunks..n].iter().zip(&b[4 * chunks..n]) {
        r += x * y;
    }
    r
}

/// The four-partial-sum dot product itself.
fn dot_portable(a: &[f64], b: &[f64]) -> f64 {
    let mut s = [0.0; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for i in 0..4 {
            s[i] += x[i] * y[i];
        }
    }
    let mut r = (s[0] + s[1]) + (s[2] + s[3]);
    for (x, y) in ra.iter().zip(rb) {
        r += x * y;
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A record's cells as columns, read up to (not including) `end`.
    struct Prefix<'a> {
        columns: &'a [Vec<f64>],
        end: usize,
    }

    impl History for Prefix<'_> {
        fn filled(&self) -> usize {
            self.end
        }

        fn latest(&self, slot: usize, n: usize) -> &[f64] {
            &self.columns[slot][self.end - n..self.end]
        }
    }

    /// The estimate is the written-out sum over channels and lags (file order: tap `j` meets
    /// the cell `j` before the newest), with each channel's gain.
    #[test]
    fn a_window_is_the_sum_of_taps_times_cells_newest_first_in_the_file() {
        let cells: Vec<[f64; 5]> = (0..9)
            .map(|k| {
                let k = k as f64;
                [k, 10.0 + k * k, -k, 0.5 * k, 100.0 - k]
            })
            .collect();
        let (past, future) = (3, 2);
        let len = past + future + 1;
        let slots = vec![1, 4];
        let file: Vec<f64> = (0..slots.len() * len)
            .map(|i| 0.1 * i as f64 - 0.3)
            .collect();
        let w = Window::from_file_order(past, future, slots.clone(), &file, 0.0);
        let gain = [1.0, 2.0, 1.0, 1.0, 0.5];
        let columns: Vec<Vec<f64>> = (0..5)
            .map(|s| cells.iter().map(|c| c[s]).collect())
            .collect();
        for newest in len - 1..cells.len() {
            let mut by_hand = 0.0;
            for (c, s) in slots.iter().enumerate() {
                let mut sum = 0.0;
                for j in 0..len {
                    sum += file[c * len + j] * cells[newest - j][*s];
                }
                by_hand += gain[*s] * sum;
            }
            let e = w.apply(
                &Prefix {
                    columns: &columns,
                    end: newest + 1,
                },
                &gain,
            );
            assert!((e - by_hand).abs() < 1e-12, "{newest}: {e} {by_hand}");
        }
    }

    #[test]
    fn the_longest_covered_window_is_chosen() {
        let w = |past| Window::from_file_order(past, 1, vec![0], &vec![0.0; past + 2], 0.0);
        let windows = [w(0), w(2), w(5)];
        assert!(longest_covered(&windows, 1).is_none());
        assert_eq!(longest_covered(&windows, 2).unwrap().past(), 0);
        assert_eq!(longest_covered(&windows, 4).unwrap().past(), 2);
        assert_eq!(longest_covered(&windows, 6).unwrap().past(), 2);
        assert_eq!(longest_covered(&windows, 7).unwrap().past(), 5);
    }

    /// The AVX2 dot product is the portable one to the last bit (the fit's estimates and the
    /// FMU's must not depend on the processor), at every length's remainder, on finite values
    /// spread over twelve decades where the summation order shows.
    #[test]
    #[cfg(target_arch = "x86_64")]
    fn the_avx2_dot_product_is_the_portable_one_bit_for_bit() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            eprintln!("no AVX2 here: nothing to compare");
            return;
        }
        let mut seed = 0x9e37_79b9_7f4a_7c15_u64;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            let u = (seed >> 11) as f64 / (1u64 << 53) as f64;
            (u - 0.5) * 10f64.powi((seed % 13) as i32 - 6)
        };
        for n in (0..40).chain([1001, 1503]) {
            let a: Vec<f64> = (0..n).map(|_| next()).collect();
            let b: Vec<f64> = (0..n).map(|_| next()).collect();
            // SAFETY: AVX2 checked above.
            let fast = unsafe { dot_avx2(&a, &b) };
            assert_eq!(fast.to_bits(), dot_portable(&a, &b).to_bits(), "length {n}");
        }
    }
}
