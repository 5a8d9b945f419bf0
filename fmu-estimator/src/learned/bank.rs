//! The tap bank file (`resources/learned.taps`): the learned filter's taps for every speed,
//! sensor set and lag, with where they came from and what they require of the runtime.
//!
//! # Format (version 6; versions 3 to 5 are read too)
//! | part | content |
//! |---|---|
//! | first line | `learned-taps <version> <header bytes> <data bytes> <FNV-1a 64 of the data, hex>` |
//! | header | TOML, UTF-8: [`Header`] (grid, high-pass, provenance, the contract, the contact model, and every entry's windows without their taps) |
//! | data | the contact model's model spectra if it has them (below), then its conicity models' precision matrices (format 6, below), then the taps, entry after entry, window after window in header order, as the header's `encoding` says (below) |
//!
//! Version 4 adds the conicity conditions: each entry's `conicity`, the contact model's
//! `conicity_range`, `extra_bands` and per-speed conicity models ([`super::contact`]). A
//! version 3 bank has none, and is read as before. Version 5 adds `kalman_shelf`, the shelf
//! after the Kalman channel's high-pass ([`super::grid`]), and its design in the contract; a
//! bank of version 3 or 4 has none, and is read as before.
//! The conicity models of young memories (`young`, 2026-11-27) are optional within version 5:
//! a bank without them applies the full memory's model from a run's first cell, as before, and
//! a reader without them ignores them and does the same. So are the model spectra of the
//! conicity's likelihood (each speed's `spectra`, 2026-11-28, [`super::spectral::Spectra`]):
//! their layout in the header, their values as little-endian `f32` at the data block's start,
//! speed after speed, before the taps (a bank without them estimates the conicity from the
//! contact features alone).
//! Version 6 moves each conicity model's `precision` (the novelty's inverse covariance of the
//! features, [`super::contact::ConicityModel`]) out of the header: its upper triangle, row
//! after row, as little-endian `f64`, speed after speed, after the spectra (the header holds
//! `precision = []`). The matrix is symmetric, so the triangle is all of it, and binary `f64`
//! keeps every bit: in the header it took 20 characters a number and a third of the header
//! (268 kB of the bank over conicities' 824 kB), in the data block 5 kB a speed.
//!
//! A window of `past` points behind and `future` ahead over `C` channels holds
//! `C (past + future + 1)` taps, channel after channel (the entry's `channels` order); within a channel, tap `j`
//! multiplies the channel's value `j` grid points before the newest one. The estimate is for the
//! position `future` points behind the newest cell (the lag). Taps are in physical units (metres
//! of alignment per unit of the channel).
//!
//! | `encoding` | data per window | precision |
//! |---|---|---|
//! | `f32` (absent: format 3) | every tap as a little-endian `f32` | 7 significant digits: the estimate's rounding error is below 1e-6 of its rms |
//! | `i16` | per channel: a little-endian `f32` scale, then its taps as little-endian `i16`, each tap `q * scale` | the taps, rounded to `f32` first, divided by `scale = max |tap| / 32767` of the channel and rounded: every tap within 1.5e-5 of the channel's largest |
//! | `i12` | per channel: a little-endian `f32` scale, then its taps as 12-bit two's-complement codes, two in three bytes (the first code's low 8 bits, then its high 4 bits under the second's low 4, then the second's high 8; an odd last code in two bytes), each tap `q * scale` | the taps as `i16` rounds them, divided by `scale = max |tap| / 2047` and rounded: every tap within 2.6e-4 of the channel's largest |
//!
//! Why `i12` for the bank over conicities (21 conditions per speed, 4.4 MB in `i16`, 3.6 MB in
//! `i12`): its estimates need no more. On the 10 km validation runs (seeds 102-103, conicity
//! 0.075-0.3, Kalker 100 and 50 %, told nothing) the `i12` bank's estimate differs from the
//! `i16` one's by 0.07-0.8 % of the truth's rms in the whole band and 0.2-2.2 % in D1, against
//! errors of 11-16 % and 14-36 %; its whole Jrel moves by 3e-5 on the mean and 0.0008 at most.
//! With the `i16` codes rounded to 10 bits D1 differs by up to 10 %, to 8 bits by up to 75 %.
//! Rounding the taps as `i16` does first makes a bank re-encoded from `i16` (or `f32`) equal to
//! one written directly.
//!
//! The `[contract]` table ([`super::contract`]) holds the runtime constants and filter designs
//! the taps were fitted with and a hash of the Kalman channel's matrices; the FMU compares it
//! with its own at initialization. Formats 1 and 2 (before 2026-11-25) had no contract and are
//! refused: without one, a bank fitted by another build or with another Kalman channel would
//! run silently wrong, which is what the contract is for; `alignment-studies taps` makes a
//! format 6 bank.

use super::error::{BankError, BankProblem, EntryProblem};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The first word of a bank's first line: what tells a bank from any other file before its
/// sizes are trusted.
pub const MAGIC: &str = "learned-taps";
/// The format [`Header::to_bytes`] writes (and the header's `format`). Format 4 added the
/// conicity conditions (entries' `conicity`, the contact model's conicity models): a reader of
/// format 3 would take such a bank's entries of one speed for duplicates. Format 5 added the
/// Kalman channel's shelf: a reader of format 4 would leave it out and feed the taps another
/// channel than they were fitted on.
/// Format 6 moved the conicity models' precision matrices into the data block: a reader of
/// format 5 would find them empty.
pub const FORMAT: u32 = 6;
/// The formats this reader takes (3: no conicity conditions; 3 and 4: no shelf; 3 to 5: the
/// precision matrices in the header).
pub const READS: [u32; 4] = [3, 4, 5, 6];
/// The first format that keeps the precision matrices in the data block.
const PRECISION_IN_DATA: u32 = 6;

/// Where the taps came from: enough to regenerate them and to judge where they hold.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Provenance {
    /// The vehicle model and parameter set the training runs used.
    pub vehicle: String,
    /// Track seed of the training runs (the calibration seed).
    pub training_seed: u32,
    /// Track seeds the ridge was chosen on, and the rms errors measured.
    pub validation_seeds: Vec<u32>,
    /// Those of the validation seeds the contact model was judged on (its errors, its young
    /// memories, its novelty level), where not all of them; empty: all.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub contact_validation_seeds: Vec<u32>,
    /// Kalker-coefficient scales of the training runs (one run each, normal equations summed).
    pub kalker_scales: Vec<f64>,
    /// Length of each training run \[m\].
    pub training_distance: f64,
    /// Sample step of the training runs \[s\] (the sensors' sampling interval).
    pub sample_step: f64,
    /// The least-squares objective the taps minimise.
    pub objective: String,
    /// The Kalman channel in words (the contract's `[contract.kalman]` is what is checked).
    pub partner: String,
    /// Ridge values tried (relative to the mean diagonal).
    pub ridges: Vec<f64>,
    /// The command that regenerates the file.
    pub command: String,
}

/// One set of windows: a speed, a sensor set, a lag.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Entry {
    /// The constant speed of the training runs \[m/s\].
    pub speed: f64,
    /// Channel names, from [`super::grid::CHANNELS`].
    pub channels: Vec<String>,
    /// Look-ahead in grid points (0: causal).
    pub lag: usize,
    /// The ridge chosen on the validation seeds (relative to the mean diagonal).
    pub ridge: f64,
    /// The weights of whole, D1, D2 and D3 in the fit's objective, chosen with the ridge
    /// (absent in banks fitted before 2026-11-25: all 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub band_weights: Option<[f64; 4]>,
    /// The mean objective on the validation seeds with that ridge.
    pub validation_objective: f64,
    /// The Kalker-coefficient scales this entry was trained and validated on, where they differ
    /// from the provenance's: a condition under which the vehicle is unstable at this speed
    /// (hunting into derailment) is left out.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub kalker_scales: Vec<f64>,
    /// The contact condition (Kalker-coefficient scale) this entry's taps are fitted for, in a
    /// bank that blends conditions by the estimated contact ([`super::contact`]); absent: the
    /// taps serve every condition (fitted on all of `kalker_scales` at once).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub condition: Option<f64>,
    /// The wheels' equivalent conicity this entry's taps are fitted for, in a bank fitted over
    /// conicities (its contact model then estimates the conicity too); absent: the vehicle's own.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub conicity: Option<f64>,
    /// The windows of this lag, one per history length (the full one and the start's shorter
    /// ones); the runtime takes the longest the history it holds allows ([`super::window`]).
    pub windows: Vec<Window>,
}

/// The taps for one history length. An entry's windows share its lag and differ in `past`:
/// the full one and shorter ones for the start of a run, when less history exists.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Window {
    /// Grid points of history behind the newest cell the window reads.
    pub past: usize,
    /// Grid points the estimate lies behind the newest cell: always the entry's lag.
    pub future: usize,
    /// Root-mean-square error of this window's estimate against the true alignment on the
    /// validation seeds \[m\]: the estimate's standard deviation.
    pub rms_error: f64,
    /// `channels × (past + future + 1)` taps in the order of the module docs, in physical units;
    /// kept in the data block (as `f32`), not in the header.
    #[serde(skip)]
    pub taps: Vec<f64>,
}

/// The header: everything but the taps.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Header {
    /// The format; a reader refuses any it does not take ([`READS`]).
    pub format: u32,
    /// Grid step along the track \[m\].
    pub grid: f64,
    /// Cut-off wavelength of the Kalman channel's causal high-pass \[m\].
    pub kalman_highpass: f64,
    /// The shelf after the high-pass: its pole at this many times the cut-off's wavenumber
    /// ([`super::grid`]); absent: no shelf (formats 3 and 4).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kalman_shelf: Option<f64>,
    /// Where the taps came from, for regenerating them and judging where they hold; only the
    /// sample step is relied on (the contract's Kalman matrices are discretized for it).
    pub provenance: Provenance,
    /// What the taps require of the runtime, checked at initialization.
    pub contract: super::contract::Contract,
    /// How the data block stores the taps (absent: `f32`, as format 3 did).
    #[serde(default, skip_serializing_if = "is_f32")]
    pub encoding: Encoding,
    /// The estimator of the contact condition, in a bank with per-condition entries.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub contact: Option<super::contact::ContactModel>,
    /// The long-wave stage after the causal taps ([`super::stage`]), when fitted. Optional
    /// within format 6 (2026-11-29): a reader without it ignores it and gives the taps'
    /// estimate alone, as before.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stage: Option<super::stage::StageBank>,
    /// The taps' entries: per speed, sensor set, lag and (with a contact model) condition.
    #[serde(rename = "entry")]
    pub entries: Vec<Entry>,
}

/// A whole tap bank.
pub type Bank = Header;

/// How the data block stores the taps (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Encoding {
    /// Every tap as an `f32`.
    #[default]
    F32,
    /// Per window and channel an `f32` scale, then the taps as `i16` multiples of it.
    I16,
    /// Per window and channel an `f32` scale, then the taps as 12-bit multiples of it.
    I12,
}

impl Encoding {
    /// Bytes of one window of `channels` channels and `len` taps each.
    fn bytes(self, channels: usize, len: usize) -> usize {
        match self {
            Encoding::F32 => 4 * channels * len,
            Encoding::I16 => channels * (4 + 2 * len),
            Encoding::I12 => channels * (4 + i12_bytes(len)),
        }
    }

    /// Appends the taps of one window (`channels` channels of `len` taps, channel after
    /// channel) to `data`.
    fn write(self, taps: &[f64], len: usize, data: &mut Vec<u8>) {
        match self {
            Encoding::F32 => {
                for t in taps {
                    data.extend_from_slice(&(*t as f32).to_le_bytes());
                }
            }
            Encoding::I16 => {
                for channel in taps.chunks(len.max(1)) {
                    let (scale, codes) = i16_codes(channel);
                    data.extend_from_slice(&scale.to_le_bytes());
                    for q in codes {
                        data.extend_from_slice(&q.to_le_bytes());
                    }
                }
            }
            Encoding::I12 => {
                for channel in taps.chunks(len.max(1)) {
                    let (scale, codes) = i12_codes(channel);
                    data.extend_from_slice(&scale.to_le_bytes());
                    pack_i12(&codes, data);
                }
            }
        }
    }

    /// Reads the taps of one window (`channels` channels of `len` taps) from `data`.
    fn read(self, data: &[u8], channels: usize, len: usize) -> Vec<f64> {
        match self {
            Encoding::F32 => data
                .chunks_exact(4)
                .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]) as f64)
                .collect(),
            Encoding::I16 | Encoding::I12 => {
                let mut taps = Vec::with_capacity(channels * len);
                for channel in data.chunks_exact(self.bytes(1, len)) {
                    let scale =
                        f32::from_le_bytes([channel[0], channel[1], channel[2], channel[3]]) as f64;
                    let codes = &channel[4..];
                    if self == Encoding::I16 {
                        taps.extend(
                            codes
                                .chunks_exact(2)
                                .map(|c| i16::from_le_bytes([c[0], c[1]]) as f64 * scale),
                        );
                    } else {
                        taps.extend(unpack_i12(codes, len).map(|q| q as f64 * scale));
                    }
                }
                taps
            }
        }
    }
}

/// A channel's taps as `i16` codes and their scale (the `i16` encoding; `i12` starts from it).
fn i16_codes(channel: &[f64]) -> (f32, Vec<i16>) {
    let rounded: Vec<f64> = channel.iter().map(|t| *t as f32 as f64).collect();
    quantize(&rounded, I16_STEPS)
}

/// A channel's taps as 12-bit codes and their scale: the taps as the `i16` encoding rounds them,
/// then divided by `max |tap| / 2047` (rounded to `f32`) and rounded. Through `i16`, an `i12`
/// bank re-encoded from an `i16` one equals one written directly; a bank read from `i12` is
/// written again to the same bytes ([`i12_already`]).
fn i12_codes(channel: &[f64]) -> (f32, Vec<i16>) {
    if let Some(read) = i12_already(channel) {
        return read;
    }
    let (s16, q16) = i16_codes(channel);
    let rounded: Vec<f64> = q16.iter().map(|q| *q as f64 * s16 as f64).collect();
    quantize(&rounded, I12_STEPS)
}

/// `taps` as multiples of `scale = max |tap| / steps` (rounded to `f32`), each code rounded and
/// within `steps`; all zero for a channel of zeros.
fn quantize(taps: &[f64], steps: f64) -> (f32, Vec<i16>) {
    let largest = taps.iter().fold(0.0f64, |m, t| m.max(t.abs()));
    let scale = (largest / steps) as f32;
    let codes = taps
        .iter()
        .map(|t| {
            if scale > 0.0 {
                (t / scale as f64).round().clamp(-steps, steps) as i16
            } else {
                0
            }
        })
        .collect();
    (scale, codes)
}

/// The codes of a channel whose taps are already 12-bit multiples of an `f32` scale, the largest
/// 2047 of them (a bank read from `i12`): written again as they are. Rounded as `i16` first,
/// their scale could move by one unit in the last place.
fn i12_already(channel: &[f64]) -> Option<(f32, Vec<i16>)> {
    let largest = channel.iter().fold(0.0f64, |m, t| m.max(t.abs()));
    let scale = (largest / I12_STEPS) as f32;
    // Products of an f32 and an integer under 2^11 are exact in f64, and so are their quotients.
    if !(scale > 0.0 && scale as f64 * I12_STEPS == largest) {
        return None;
    }
    let codes: Option<Vec<i16>> = channel
        .iter()
        .map(|t| {
            let q = t / scale as f64;
            (q == q.round() && q.abs() <= I12_STEPS).then_some(q as i16)
        })
        .collect();
    codes.map(|c| (scale, c))
}

/// Bytes of `len` 12-bit codes, two in three.
fn i12_bytes(len: usize) -> usize {
    (3 * len).div_ceil(2)
}

/// Appends 12-bit codes (each within +-2047), two in three bytes (module docs).
fn pack_i12(codes: &[i16], data: &mut Vec<u8>) {
    for pair in codes.chunks(2) {
        let a = (pair[0] as u16) & 0xfff;
        data.push(a as u8);
        match pair.get(1) {
            Some(b) => {
                let b = (*b as u16) & 0xfff;
                data.push((a >> 8) as u8 | ((b & 0xf) << 4) as u8);
                data.push((b >> 4) as u8);
            }
            None => data.push((a >> 8) as u8),
        }
    }
}

/// The `len` 12-bit codes of [`pack_i12`], sign-extended.
fn unpack_i12(bytes: &[u8], len: usize) -> impl Iterator<Item = i16> + '_ {
    let signed = |v: u16| ((v << 4) as i16) >> 4;
    (0..len).map(move |i| {
        let at = 3 * (i / 2);
        let v = if i % 2 == 0 {
            bytes[at] as u16 | ((bytes[at + 1] as u16 & 0xf) << 8)
        } else {
            (bytes[at + 1] as u16 >> 4) | ((bytes[at + 2] as u16) << 4)
        };
        signed(v)
    })
}

/// The largest magnitude of an `i16` tap: the channel's largest tap.
const I16_STEPS: f64 = 32767.0;
/// The largest magnitude of an `i12` tap: the channel's largest tap.
const I12_STEPS: f64 = 2047.0;

/// The longest first line a bank may have: its magic, format, size and hash take under 60
/// bytes, so anything longer is not a bank (and is not read further).
const MAX_FIRST_LINE: usize = 200;

/// The longest history a window may read, in grid points (20 km at 0.2 m, against the shipped
/// 60 m): a bound that stops a corrupt file from asking for gigabytes of history.
const MAX_PAST: usize = 100_000;

fn is_f32(e: &Encoding) -> bool {
    *e == Encoding::F32
}

impl Header {
    /// The file's bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut data = Vec::new();
        for s in self.spectra() {
            data.extend(s.values.iter().flat_map(|v| v.to_le_bytes()));
        }
        let mut head = std::borrow::Cow::Borrowed(self);
        if self.format >= PRECISION_IN_DATA {
            for m in head.to_mut().conicity_models_mut() {
                let p = std::mem::take(&mut m.precision);
                let n = p.len().isqrt();
                // The upper triangle, row after row; a reader mirrors it.
                for i in 0..n {
                    data.extend(
                        p[i * n + i..(i + 1) * n]
                            .iter()
                            .flat_map(|v| v.to_le_bytes()),
                    );
                }
            }
        }
        let header = toml::to_string(&*head).expect("plain numbers, strings and arrays");
        for e in &self.entries {
            for w in &e.windows {
                self.encoding
                    .write(&w.taps, w.past + w.future + 1, &mut data);
            }
        }
        // The header's own format: a bank re-encoded from an older one keeps its format on both.
        assemble(self.format, &header, &data)
    }

    /// Reads a tap bank, checking everything the runtime relies on; errors name `file`.
    pub fn parse(bytes: &[u8], file: &Path) -> Result<Bank, BankError> {
        let bad = |problem: BankProblem| BankError::Invalid {
            file: file.to_path_buf(),
            problem,
        };
        let nl = bytes
            .iter()
            .position(|b| *b == b'\n')
            .filter(|n| *n < MAX_FIRST_LINE)
            .ok_or_else(|| bad(BankProblem::NoFirstLine))?;
        let first =
            std::str::from_utf8(&bytes[..nl]).map_err(|_| bad(BankProblem::FirstLineText))?;
        let f: Vec<&str> = first.split(' ').collect();
        if f.len() != 5 || f[0] != MAGIC {
            return Err(bad(BankProblem::FirstLine(first.to_string())));
        }
        if !READS.iter().any(|r| f[1] == r.to_string()) {
            return Err(BankError::Format {
                file: file.to_path_buf(),
                format: f[1].to_string(),
            });
        }
        let num = |s: &str| {
            s.parse::<usize>()
                .map_err(|_| bad(BankProblem::Size(s.to_string())))
        };
        let (hlen, dlen) = (num(f[2])?, num(f[3])?);
        let body = &bytes[nl + 1..];
        if body.len() != hlen.saturating_add(dlen) {
            return Err(bad(BankProblem::Length {
                body: body.len(),
                header: hlen,
                data: dlen,
            }));
        }
        let (head, data) = body.split_at(hlen);
        if format!("{:016x}", fnv1a(data)) != f[4] {
            return Err(bad(BankProblem::Checksum));
        }
        let head = std::str::from_utf8(head).map_err(|_| bad(BankProblem::HeaderText))?;
        let mut bank: Bank =
            toml::from_str(head).map_err(|e| bad(BankProblem::Toml(e.to_string())))?;
        if f[1] != bank.format.to_string() {
            return Err(bad(BankProblem::FormatDisagrees {
                line: f[1].parse().unwrap_or_default(),
                header: bank.format,
            }));
        }
        let mut spectra = bank.read_spectra(data).map_err(bad)?;
        if bank.format >= PRECISION_IN_DATA {
            spectra += bank
                .read_precisions(&data[spectra..], spectra)
                .map_err(bad)?;
        }
        let data = &data[spectra..];
        bank.check().map_err(bad)?;
        let encoding = bank.encoding;
        let needed: usize = bank
            .entries
            .iter()
            .flat_map(|e| {
                e.windows
                    .iter()
                    .map(|w| encoding.bytes(e.channels.len(), w.past + w.future + 1))
            })
            .sum();
        if needed != data.len() {
            return Err(bad(BankProblem::TapCount {
                needed: needed + spectra,
                held: dlen,
            }));
        }
        let mut at = 0;
        for (i, e) in bank.entries.iter_mut().enumerate() {
            let nc = e.channels.len();
            for w in &mut e.windows {
                let len = w.past + w.future + 1;
                let n = encoding.bytes(nc, len);
                w.taps = encoding.read(&data[at..at + n], nc, len);
                at += n;
                if w.taps.iter().any(|t| !t.is_finite()) {
                    return Err(bad(BankProblem::Tap(i)));
                }
            }
        }
        Ok(bank)
    }

    /// The contact model's model spectra, speed after speed: the data block's order.
    fn spectra(&self) -> impl Iterator<Item = &super::spectral::Spectra> {
        self.contact
            .iter()
            .flat_map(|c| &c.speeds)
            .filter_map(|s| s.spectra.as_ref())
    }

    /// Fills the model spectra from the data block's start (where [`Self::to_bytes`] writes
    /// them); the bytes they took.
    fn read_spectra(&mut self, data: &[u8]) -> Result<usize, BankProblem> {
        let grid = self.grid;
        let mut at = 0usize;
        for s in self
            .contact
            .iter_mut()
            .flat_map(|c| &mut c.speeds)
            .filter_map(|s| s.spectra.as_mut())
        {
            let n = s.stored_values(grid).and_then(|n| n.checked_mul(4));
            let Some(bytes) = n.and_then(|n| data.get(at..at.checked_add(n)?)) else {
                return Err(BankProblem::TapCount {
                    needed: n.map_or(usize::MAX, |n| at.saturating_add(n)),
                    held: data.len(),
                });
            };
            s.values = bytes
                .chunks_exact(4)
                .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .collect();
            at += bytes.len();
        }
        Ok(at)
    }

    /// The contact model's conicity models, speed after speed: the data block's order.
    fn conicity_models_mut(&mut self) -> impl Iterator<Item = &mut super::contact::ConicityModel> {
        self.contact
            .iter_mut()
            .flat_map(|c| &mut c.speeds)
            .filter_map(|s| s.conicity.as_mut())
    }

    /// Fills the conicity models' precision matrices from `data` (the data block after its
    /// first `before` bytes, the spectra: [`Self::to_bytes`] writes them there); the bytes they
    /// took. A matrix in the header as well is refused: which one holds is not known.
    fn read_precisions(&mut self, data: &[u8], before: usize) -> Result<usize, BankProblem> {
        let mut at = 0usize;
        for m in self.conicity_models_mut() {
            if !m.precision.is_empty() {
                return Err(super::error::ContactProblem::PrecisionInHeader.into());
            }
            // The features: one coefficient each, then the constant.
            let n = m.coefficients.len().saturating_sub(1);
            let bytes = (n * (n + 1) / 2).checked_mul(8);
            let Some(bytes) = bytes.and_then(|b| data.get(at..at.checked_add(b)?)) else {
                return Err(BankProblem::TapCount {
                    needed: bytes
                        .map_or(usize::MAX, |b| before.saturating_add(at).saturating_add(b)),
                    held: before.saturating_add(data.len()),
                });
            };
            let mut triangle = bytes
                .chunks_exact(8)
                .map(|b| f64::from_le_bytes(b.try_into().expect("chunks of 8")));
            m.precision = vec![0.0; n * n];
            for i in 0..n {
                for j in i..n {
                    let v = triangle.next().expect("n (n + 1) / 2 values");
                    m.precision[i * n + j] = v;
                    m.precision[j * n + i] = v;
                }
            }
            at += bytes.len();
        }
        Ok(at)
    }

    /// Reads the tap bank at `path`.
    pub fn load(path: &Path) -> Result<Bank, BankError> {
        Bank::parse(&Bank::bytes(path)?, path)
    }

    /// The tap bank at `path`, parsed once per process for every instance that reads the same
    /// bytes there ([`crate::parsed`]).
    pub fn load_shared(path: &Path) -> Result<std::sync::Arc<Bank>, BankError> {
        Bank::parse_shared(&Bank::bytes(path)?, path)
    }

    /// [`Bank::parse`], shared with every other reader of the same bytes under `file`
    /// ([`crate::parsed`]).
    pub(crate) fn parse_shared(
        bytes: &[u8],
        file: &Path,
    ) -> Result<std::sync::Arc<Bank>, BankError> {
        BANKS.get_or_parse(&file.to_string_lossy(), bytes, |b| Bank::parse(b, file))
    }

    /// The bytes of the file at `path`, within the size a bank may have.
    fn bytes(path: &Path) -> Result<Vec<u8>, BankError> {
        fmi_abi::resource::read_bytes(path, "tap bank", 64 << 20).map_err(BankError::Read)
    }

    /// The consistency of the header (taps aside).
    fn check(&self) -> Result<(), BankProblem> {
        if !READS.contains(&self.format) {
            return Err(BankProblem::HeaderFormat(self.format));
        }
        if let Some(c) = &self.contact {
            c.check(self.grid)?;
        }
        if let Some(st) = &self.stage {
            st.check(self.grid).map_err(BankProblem::Stage)?;
        }
        let conditional = self
            .entries
            .iter()
            .filter(|e| e.condition.is_some())
            .count();
        if conditional > 0 && (conditional < self.entries.len() || self.contact.is_none()) {
            return Err(BankProblem::Conditions);
        }
        // Conicity conditions: on every entry, with a contact model that estimates them.
        let coned = self.entries.iter().filter(|e| e.conicity.is_some()).count();
        let estimates = self
            .contact
            .as_ref()
            .is_some_and(|c| c.conicity_range.is_some());
        if (coned > 0 || estimates) && (coned < self.entries.len() || !estimates) {
            return Err(BankProblem::Conicities);
        }
        if !(self.grid.is_finite() && self.grid > 0.0) {
            return Err(BankProblem::Grid(self.grid));
        }
        let step = self.provenance.sample_step;
        if !(step.is_finite() && step > 0.0) {
            // The contract's Kalman matrices are discretized for it.
            return Err(BankProblem::SampleStep(step));
        }
        if !(self.kalman_highpass.is_finite() && self.kalman_highpass > 2.0 * self.grid) {
            return Err(BankProblem::KalmanHighpass(self.kalman_highpass));
        }
        match self.kalman_shelf {
            Some(beta) if self.format < 5 => {
                return Err(BankProblem::ShelfFormat(beta, self.format));
            }
            Some(beta) if !(beta.is_finite() && beta > 0.0) => {
                return Err(BankProblem::KalmanShelf(beta));
            }
            _ => {}
        }
        if self.entries.is_empty() {
            return Err(BankProblem::NoEntries);
        }
        for (index, e) in self.entries.iter().enumerate() {
            e.check()
                .map_err(|problem| BankProblem::Entry { index, problem })?;
        }
        Ok(())
    }
}

impl Entry {
    /// The consistency of one entry's header (taps aside).
    fn check(&self) -> Result<(), EntryProblem> {
        if !(self.speed.is_finite() && self.speed > 0.0) {
            return Err(EntryProblem::Speed(self.speed));
        }
        if self.channels.is_empty() {
            return Err(EntryProblem::NoChannels);
        }
        for c in &self.channels {
            if !super::grid::CHANNELS.contains(&c.as_str()) {
                return Err(EntryProblem::UnknownChannel(c.clone()));
            }
        }
        if let Some(c) = self.condition
            && !(c.is_finite() && c > 0.0)
        {
            return Err(EntryProblem::Condition(c));
        }
        if let Some(c) = self.conicity
            && !(c.is_finite() && c > 0.0)
        {
            return Err(EntryProblem::Conicity(c));
        }
        if self.windows.is_empty() {
            return Err(EntryProblem::NoWindows);
        }
        for w in &self.windows {
            if w.future != self.lag || w.past > MAX_PAST {
                return Err(EntryProblem::Window {
                    past: w.past,
                    future: w.future,
                    lag: self.lag,
                });
            }
            if !(w.rms_error.is_finite() && w.rms_error >= 0.0) {
                return Err(EntryProblem::RmsError(w.rms_error));
            }
        }
        Ok(())
    }
}

/// A bank's bytes from its parts: the first line (`format`, the parts' sizes, the data's hash),
/// the header, the data.
fn assemble(format: u32, header: &str, data: &[u8]) -> Vec<u8> {
    let mut out = format!(
        "{MAGIC} {format} {} {} {:016x}\n",
        header.len(),
        data.len(),
        fnv1a(data)
    )
    .into_bytes();
    out.extend_from_slice(header.as_bytes());
    out.extend_from_slice(data);
    out
}

/// The banks parsed so far, shared by the instances that read them ([`Bank::load_shared`],
/// [`super::shared_named`]).
pub(crate) static BANKS: crate::parsed::Cache<Bank> = crate::parsed::Cache::new();

/// FNV-1a, 64 bits: detects a damaged or edited data block.
pub(crate) fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf29ce484222325, |h, b| {
        (h ^ *b as u64).wrapping_mul(0x100000001b3)
    })
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// The contract of this library's defaults at the sample bank's grid and high-pass.
    pub fn sample_contract() -> crate::learned::contract::Contract {
        let values = crate::offline::settings(&[]).unwrap();
        let (config, _) = crate::offline::config(&values, None).unwrap();
        crate::learned::contract::Contract::expected(&config, 0.2, 500.0, None, None, 1e-3)
    }

    /// A small bank with recognisable taps.
    pub fn sample_bank() -> Bank {
        let entry = |speed: f64, lag: usize| Entry {
            speed,
            channels: vec!["ws_acc_y".into(), "kalman".into()],
            lag,
            ridge: 1e-6,
            band_weights: Some([1.0, 10.0, 10.0, 1.0]),
            validation_objective: 0.1,
            kalker_scales: vec![],
            condition: None,
            conicity: None,
            windows: [2usize, 5]
                .iter()
                .map(|&past| Window {
                    past,
                    future: lag,
                    rms_error: 1e-3 * past as f64,
                    taps: (0..2 * (past + lag + 1))
                        .map(|k| (k as f64 * 0.37 + speed).sin())
                        .collect(),
                })
                .collect(),
        };
        Header {
            format: FORMAT,
            grid: 0.2,
            kalman_highpass: 500.0,
            kalman_shelf: None,
            provenance: Provenance {
                vehicle: "test".into(),
                training_seed: 101,
                validation_seeds: vec![102, 103],
                contact_validation_seeds: vec![],
                kalker_scales: vec![1.0, 0.5],
                training_distance: 1000.0,
                sample_step: 1e-3,
                objective: "test".into(),
                partner: "test".into(),
                ridges: vec![1e-6],
                command: "none".into(),
            },
            contract: sample_contract(),
            encoding: Encoding::F32,
            contact: None,
            stage: None,
            entries: vec![
                entry(10.0, 0),
                entry(20.0, 0),
                entry(10.0, 3),
                entry(20.0, 3),
            ],
        }
    }

    #[test]
    fn a_bank_survives_its_file_to_f32_precision() {
        let b = sample_bank();
        let bytes = b.to_bytes();
        let back = Bank::parse(&bytes, Path::new("t.taps")).unwrap();
        assert_eq!(back.entries.len(), 4);
        for (e, f) in b.entries.iter().zip(&back.entries) {
            for (w, v) in e.windows.iter().zip(&f.windows) {
                assert_eq!(w.taps.len(), v.taps.len());
                for (a, b) in w.taps.iter().zip(&v.taps) {
                    assert_eq!(*b, *a as f32 as f64);
                }
            }
        }
        // Written again, byte for byte.
        assert_eq!(back.to_bytes(), bytes);
    }

    /// The sample bank in `encoding`, with a channel of zeros and one with a tap far larger
    /// than the rest; its bytes; and the bank read back from them.
    fn quantized_sample(encoding: Encoding) -> (Bank, Vec<u8>, Bank) {
        let mut b = sample_bank();
        b.encoding = encoding;
        b.entries[0].windows[0]
            .taps
            .iter_mut()
            .take(3)
            .for_each(|t| *t = 0.0);
        b.entries[1].windows[1].taps[0] = 40.0;
        let bytes = b.to_bytes();
        let back = Bank::parse(&bytes, Path::new("t.taps")).unwrap();
        assert_eq!(back.encoding, encoding);
        (b, bytes, back)
    }

    /// Every tap of `read` within `share` of its channel's largest tap in `written`, plus the
    /// `f32` rounding before the codes.
    fn assert_taps_within(written: &Bank, read: &Bank, share: f64) {
        for (e, f) in written.entries.iter().zip(&read.entries) {
            for (w, v) in e.windows.iter().zip(&f.windows) {
                let len = w.past + w.future + 1;
                for (ch, (a, b)) in w.taps.chunks(len).zip(v.taps.chunks(len)).enumerate() {
                    let largest = a.iter().fold(0.0f64, |m, t| m.max(t.abs()));
                    for (x, y) in a.iter().zip(b) {
                        assert!(
                            (x - y).abs() <= share * largest * (1.0 + 1e-6) + 1e-7 * x.abs(),
                            "channel {ch}: {x} read back as {y}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn an_i16_bank_keeps_every_tap_within_its_channel_s_step() {
        let (b, bytes, back) = quantized_sample(Encoding::I16);
        let mut f32_bank = b.clone();
        f32_bank.encoding = Encoding::F32;
        // The data block's size, from the first line: smaller than the f32 one's (about half
        // for the shipped windows of 300 taps; these are short, so the scales weigh more).
        let data = |b: &[u8]| -> usize {
            let first = std::str::from_utf8(&b[..b.iter().position(|c| *c == b'\n').unwrap()])
                .unwrap()
                .to_string();
            first.split(' ').nth(3).unwrap().parse().unwrap()
        };
        assert!(data(&bytes) < data(&f32_bank.to_bytes()) * 9 / 10);
        // Half a step of the channel's scale.
        assert_taps_within(&b, &back, 0.5 / 32767.0);
        // Written again, byte for byte; and re-encoding an f32 bank gives the same bytes.
        assert_eq!(back.to_bytes(), bytes);
        let mut via_f32 = Bank::parse(&f32_bank.to_bytes(), Path::new("t.taps")).unwrap();
        via_f32.encoding = Encoding::I16;
        assert_eq!(via_f32.to_bytes(), bytes);
    }

    /// The shipped banks (`f32` and `i12`), read and written again, give their own bytes: what
    /// `studies/tests/taps.rs` relies on when it compares a fresh fit with the shipped file.
    #[test]
    fn the_shipped_banks_are_written_again_to_their_own_bytes() {
        for name in [
            "learned.taps",
            "learned-nominal.taps",
            "learned-conicity.taps",
        ] {
            let path = Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("resources")
                .join(name);
            let bytes = std::fs::read(&path).unwrap();
            let bank = Bank::parse(&bytes, &path).unwrap();
            assert!(
                bank.to_bytes() == bytes,
                "{name} is not written again as it is"
            );
        }
    }

    #[test]
    fn twelve_bit_codes_pack_two_in_three_bytes() {
        for codes in [
            vec![0i16, -1, 2047, -2047, 1, -2048 + 1, 1234],
            vec![-5],
            vec![7, -8],
        ] {
            let mut data = Vec::new();
            pack_i12(&codes, &mut data);
            assert_eq!(data.len(), i12_bytes(codes.len()));
            assert_eq!(unpack_i12(&data, codes.len()).collect::<Vec<_>>(), codes);
        }
        // The layout of the module docs: 0x123 and -1 (0xfff).
        let mut data = Vec::new();
        pack_i12(&[0x123, -1], &mut data);
        assert_eq!(data, [0x23, 0xf1, 0xff]);
    }

    #[test]
    fn an_i12_bank_keeps_every_tap_within_its_channel_s_step_and_equals_one_via_i16() {
        let (b, bytes, back) = quantized_sample(Encoding::I12);
        // Half an i12 step, after the i16 rounding's half step (`i12_codes`).
        assert_taps_within(&b, &back, 0.5 / 2047.0 + 0.5 / 32767.0);
        // Written again, byte for byte; re-encoded from an i16 or an f32 bank, the same bytes.
        assert_eq!(back.to_bytes(), bytes);
        for from in [Encoding::I16, Encoding::F32] {
            let mut other = b.clone();
            other.encoding = from;
            let mut via = Bank::parse(&other.to_bytes(), Path::new("t.taps")).unwrap();
            via.encoding = Encoding::I12;
            assert_eq!(via.to_bytes(), bytes, "via {from:?}");
        }
    }

    /// A shelf must be a positive number, and only a format that has shelves may state one: a
    /// reader of format 4 would leave it out.
    #[test]
    fn a_shelf_is_checked() {
        let p = Path::new("x.taps");
        let mut b = sample_bank();
        b.kalman_shelf = Some(0.0);
        let e = Bank::parse(&b.to_bytes(), p).unwrap_err().to_string();
        assert!(e.contains("Kalman shelf 0"), "{e}");
        b.kalman_shelf = Some(1.0);
        b.format = 4;
        let e = Bank::parse(&b.to_bytes(), p).unwrap_err().to_string();
        assert!(e.contains("needs format 5"), "{e}");
        b.format = FORMAT;
        let read = Bank::parse(&b.to_bytes(), p).unwrap();
        assert_eq!(read.kalman_shelf, Some(1.0));
    }

    /// A bank's header and data block, as [`assemble`] joined them.
    fn split(bytes: &[u8]) -> (&str, &[u8]) {
        let nl = bytes.iter().position(|b| *b == b'\n').unwrap();
        let first = std::str::from_utf8(&bytes[..nl]).unwrap();
        let hlen: usize = first.split(' ').nth(2).unwrap().parse().unwrap();
        let (header, data) = bytes[nl + 1..].split_at(hlen);
        (std::str::from_utf8(header).unwrap(), data)
    }

    #[test]
    fn model_spectra_are_read_from_the_data_block_and_nowhere_else() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("resources/learned.taps");
        let mut bank = Bank::load(&path).unwrap();
        bank.format = FORMAT;
        let spectra: Vec<&Vec<f32>> = bank.spectra().map(|s| &s.values).collect();
        assert_eq!(spectra.len(), 11);
        let bytes = bank.to_bytes();
        let (header, data) = split(&bytes);
        let held: usize = spectra.iter().map(|v| 4 * v.len()).sum();
        // Spectra cut short: refused, naming the bytes.
        let cut = assemble(FORMAT, header, &data[..held / 2]);
        let e = Bank::parse(&cut, &path).unwrap_err().to_string();
        assert!(e.contains("need") && e.contains("bytes"), "{e}");
        // Values in the header instead are refused.
        let inline = header.replacen("values = \"\"", "values = \"AACAPw==\"", 1);
        let e = Bank::parse(&assemble(FORMAT, &inline, data), &path)
            .unwrap_err()
            .to_string();
        assert!(e.contains("data block"), "{e}");
    }

    /// Format 6 keeps each conicity model's precision matrix as its upper triangle in the data
    /// block, every bit of it; format 5 kept the whole matrix in the header, and is still read.
    #[test]
    fn precision_matrices_are_kept_whole_in_the_data_block_and_once() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("resources/learned.taps");
        let mut bank = Bank::load(&path).unwrap();
        bank.format = FORMAT;
        let models: Vec<_> = bank.conicity_models_mut().map(|m| m.clone()).collect();
        assert_eq!(models.len(), 11);
        let bytes = bank.to_bytes();
        let (header, data) = split(&bytes);
        assert_eq!(header.matches("precision = []").count(), 11);
        let mut read = Bank::parse(&bytes, &path).unwrap();
        for (m, r) in models.iter().zip(read.conicity_models_mut()) {
            let n = m.coefficients.len() - 1;
            assert_eq!(r.precision.len(), n * n);
            for i in 0..n {
                for j in 0..n {
                    // The upper triangle as written, mirrored below the diagonal.
                    assert_eq!(r.precision[i * n + j], m.precision[i.min(j) * n + i.max(j)]);
                }
            }
        }
        // Written again, the same bytes.
        assert_eq!(read.to_bytes(), bytes);
        // Format 5 keeps the matrix in the header, and reads back the same.
        let mut five = read.clone();
        five.format = 5;
        let old = five.to_bytes();
        assert!(old.len() > bytes.len() + 11 * 8 * 35 * 36 / 2);
        assert_eq!(Bank::parse(&old, &path).unwrap(), five);
        // A format 6 header with a matrix in it is refused.
        let (header5, data5) = split(&old);
        let edited = assemble(6, &header5.replacen("format = 5", "format = 6", 1), data5);
        let e = Bank::parse(&edited, &path).unwrap_err().to_string();
        assert!(e.contains("precision in the header"), "{e}");
        // Cut short: refused, naming the bytes.
        let spectra: usize = read.spectra().map(|s| 4 * s.values.len()).sum();
        let short = assemble(FORMAT, header, &data[..spectra + 100]);
        let e = Bank::parse(&short, &path).unwrap_err().to_string();
        assert!(e.contains("need") && e.contains("bytes"), "{e}");
    }

    #[test]
    fn damaged_files_are_refused_by_name() {
        let bytes = sample_bank().to_bytes();
        let p = Path::new("x.taps");
        let mut flipped = bytes.clone();
        *flipped.last_mut().unwrap() ^= 1;
        let e = Bank::parse(&flipped, p).unwrap_err().to_string();
        assert!(e.starts_with("x.taps:") && e.contains("checksum"), "{e}");
        let e = Bank::parse(&bytes[..bytes.len() - 3], p)
            .unwrap_err()
            .to_string();
        assert!(e.contains("truncated"), "{e}");
        let mut no_step = sample_bank();
        no_step.provenance.sample_step = 0.0;
        let e = Bank::parse(&no_step.to_bytes(), p).unwrap_err().to_string();
        assert!(e.contains("sample step 0 s"), "{e}");
        let e = Bank::parse(b"hello\n", p).unwrap_err().to_string();
        assert!(e.contains("first line"), "{e}");
        let text = String::from_utf8_lossy(&bytes)
            .replace(&format!("learned-taps {FORMAT}"), "learned-taps 7");
        let e = Bank::parse(text.as_bytes(), p).unwrap_err().to_string();
        assert!(e.contains("format 7"), "{e}");
        // A first line edited to another format this reader takes disagrees with the header.
        let nl = bytes.iter().position(|b| *b == b'\n').unwrap();
        let first = String::from_utf8(bytes[..nl].to_vec()).unwrap().replacen(
            &format!("learned-taps {FORMAT}"),
            "learned-taps 4",
            1,
        );
        let edited = [first.as_bytes(), &bytes[nl..]].concat();
        let e = Bank::parse(&edited, p).unwrap_err().to_string();
        assert!(
            e.contains(&format!(
                "first line says format 4, the header format {FORMAT}"
            )),
            "{e}"
        );
        // A bank of the formats before the contract says why it is refused.
        let text = String::from_utf8_lossy(&bytes)
            .replace(&format!("learned-taps {FORMAT}"), "learned-taps 2");
        let e = Bank::parse(text.as_bytes(), p).unwrap_err().to_string();
        assert!(e.contains("format 2") && e.contains("no contract"), "{e}");
    }
}
