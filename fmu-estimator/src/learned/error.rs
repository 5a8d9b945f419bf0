//! The learned filter's errors: a tap bank that cannot be read or used ([`BankError`], with
//! what is wrong in it as a [`BankProblem`]), and a bank that holds no taps for what the FMU's
//! parameters choose ([`LearnedError`]). The crate's [`crate::error::Error`] carries them, the
//! second with the `tap_file` it concerns.

use std::path::PathBuf;

/// A tap bank that cannot be used; every variant but [`BankError::NotBuilt`] names the file.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BankError {
    /// The file could not be read (missing, too large), in `fmi_abi::resource`'s words.
    #[error("{0}")]
    Read(String),
    /// The file is not a tap bank, or one whose contents the runtime cannot rely on.
    #[error("{}: not a valid tap bank: {problem}", file.display())]
    Invalid {
        /// The file as it was named (a shipped bank: its name and ` (built in)`).
        file: PathBuf,
        /// What is wrong with it.
        problem: BankProblem,
    },
    /// A bank of a format this reader does not take; formats 1 and 2 had no contract, which
    /// the message explains (fitting again makes a readable bank).
    #[error(
        "{}: tap bank format {format} (this estimator reads formats {:?}){}",
        file.display(),
        super::bank::READS,
        if format == "1" || format == "2" {
            ": it has no contract (the runtime constants and Kalman channel it was fitted with), so whether this estimator applies it as it was fitted cannot be checked; fit it again with `alignment-studies taps`"
        } else {
            ""
        }
    )]
    Format {
        /// The file as it was named.
        file: PathBuf,
        /// The format field of the first line, as written (it need not be a number).
        format: String,
    },
    /// A shipped bank's name whose resource was empty when this library was built (the build
    /// script found no bank to embed).
    #[error("this build has no tap bank resources/{0}: run `alignment-studies taps`")]
    NotBuilt(String),
}

/// What makes a file not a valid tap bank ([`BankError::Invalid`]); the messages follow the
/// format's parts in `bank.rs`'s module docs.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BankProblem {
    /// No newline within the first line's length limit (so not a bank, and not read further).
    #[error("no first line")]
    NoFirstLine,
    /// The first line is not UTF-8.
    #[error("first line")]
    FirstLineText,
    /// The first line has not the magic and five fields.
    #[error("the first line is '{0}'")]
    FirstLine(String),
    /// A size in the first line is not a whole number.
    #[error("'{0}' in the first line")]
    Size(String),
    /// The bytes after the first line are not as many as it announces.
    #[error(
        "{body} bytes after the first line, which announces {header} + {data} (truncated or extended)"
    )]
    Length {
        /// Bytes after the first line.
        body: usize,
        /// The header's announced size.
        header: usize,
        /// The data's announced size.
        data: usize,
    },
    /// The data block's FNV-1a hash differs from the first line's.
    #[error("the taps' checksum does not match (damaged file)")]
    Checksum,
    /// The header is not UTF-8.
    #[error("the header is not UTF-8")]
    HeaderText,
    /// The header is not TOML of the format, in the TOML reader's words.
    #[error("header: {0}")]
    Toml(String),
    /// The header's `format` is not one this reader takes.
    #[error("header format {0}")]
    HeaderFormat(u32),
    /// The first line's format and the header's differ: one of them was edited, and which
    /// format's rules the file follows is not known.
    #[error("the first line says format {line}, the header format {header}")]
    FormatDisagrees {
        /// The first line's format.
        line: u32,
        /// The header's `format`.
        header: u32,
    },
    /// The contact model cannot be used.
    #[error(transparent)]
    Contact(#[from] ContactProblem),
    /// Some entries carry a contact condition and others do not, or there is no contact model
    /// to estimate the condition with.
    #[error("per-condition entries need a contact model and a condition on every entry")]
    Conditions,
    /// Some entries carry a conicity and others do not, or the contact model does not
    /// estimate the conicity.
    #[error(
        "entries per conicity need a contact model with a conicity range and a conicity on every entry"
    )]
    Conicities,
    /// The grid step is not a positive number \[m\].
    #[error("grid step {0} m")]
    Grid(f64),
    /// The training runs' sample step is not a positive number \[s\]: the contract's Kalman
    /// matrices are discretized for it.
    #[error("sample step {0} s")]
    SampleStep(f64),
    /// The Kalman channel's high-pass cut-off is not above two grid steps \[m\].
    #[error("Kalman high-pass at {0} m")]
    KalmanHighpass(f64),
    /// The shelf after the Kalman channel's high-pass is not a positive number.
    #[error("Kalman shelf {0}: a positive number")]
    KalmanShelf(f64),
    /// A shelf in a bank of a format before 5, which had none: a reader of that format would
    /// leave it out.
    #[error("Kalman shelf {0} in a bank of format {1} (a shelf needs format 5)")]
    ShelfFormat(f64, u32),
    /// The bank has no entries.
    #[error("no entries")]
    NoEntries,
    /// Entry `index` (0-based, in file order) cannot be used.
    #[error("entry {index}: {problem}")]
    Entry {
        /// The entry's position in the file.
        index: usize,
        /// What is wrong with it.
        problem: EntryProblem,
    },
    /// The data block holds another number of bytes than the header's windows need in its
    /// encoding.
    #[error(
        "the header's windows (and the contact model's spectra and precision matrices) need {needed} bytes, the data holds {held}"
    )]
    TapCount {
        /// Bytes the windows need.
        needed: usize,
        /// Bytes the data holds.
        held: usize,
    },
    /// The long-wave stage cannot be applied as it was fitted ([`super::stage`]).
    #[error("long-wave stage: {0}")]
    Stage(String),
    /// The entry at this position (0-based) has a tap that is NaN or infinite.
    #[error("entry {0} has a tap that is not a number")]
    Tap(usize),
}

/// What is wrong with one entry of a bank ([`BankProblem::Entry`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EntryProblem {
    /// The speed is not a positive number \[m/s\].
    #[error("speed {0}")]
    Speed(f64),
    /// The entry reads no channel.
    #[error("no channels")]
    NoChannels,
    /// A channel name not in [`super::grid::CHANNELS`].
    #[error("unknown channel '{0}'")]
    UnknownChannel(String),
    /// The contact condition (Kalker-coefficient scale) is not a positive number.
    #[error("condition {0}")]
    Condition(f64),
    /// The conicity is not a positive number.
    #[error("conicity {0}")]
    Conicity(f64),
    /// The entry has no windows.
    #[error("no windows")]
    NoWindows,
    /// A window whose look-ahead is not the entry's lag, or whose history exceeds the bound
    /// that keeps a corrupt file from asking for gigabytes of history.
    #[error("a window of {past} behind and {future} ahead under a lag of {lag}")]
    Window {
        /// Grid points behind.
        past: usize,
        /// Grid points ahead.
        future: usize,
        /// The entry's lag in grid points.
        lag: usize,
    },
    /// A window's validation rms error is negative or not a number \[m\].
    #[error("rms error {0}")]
    RmsError(f64),
}

/// What makes a bank's contact model unusable ([`BankProblem::Contact`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ContactProblem {
    /// The features' band is not `0 < short < long` \[m\].
    #[error("contact band {short}-{long} m")]
    Band {
        /// Shortest wavelength \[m\].
        short: f64,
        /// Longest wavelength \[m\].
        long: f64,
    },
    /// The moments' memory is not a positive length \[m\].
    #[error("contact memory {0} m")]
    Memory(f64),
    /// The trained range of Kalker scales is not `0 < lo <= hi`.
    #[error("contact range {lo}-{hi}")]
    Range {
        /// Lowest scale.
        lo: f64,
        /// Highest scale.
        hi: f64,
    },
    /// The model has no speeds.
    #[error("a contact model without speeds")]
    NoSpeeds,
    /// A speed's model has another number of coefficients than features + 1, or one that is
    /// not finite.
    #[error("contact model at {speed} m/s: {count} coefficients (want {want} finite ones)")]
    Coefficients {
        /// The model's speed \[m/s\].
        speed: f64,
        /// Coefficients it has.
        count: usize,
        /// Coefficients it must have (one per feature, [`super::contact::FEATURES`] per band,
        /// and the constant).
        want: usize,
    },
    /// The speeds are not strictly increasing (the blend interpolates between them).
    #[error("contact model speeds not increasing")]
    SpeedsNotIncreasing,
    /// The trained range of conicities is not `0 < lo <= hi`.
    #[error("conicity range {lo}-{hi}")]
    ConicityRange {
        /// Lowest conicity.
        lo: f64,
        /// Highest conicity.
        hi: f64,
    },
    /// A speed's conicity model is missing (the bank has a conicity range), present without a
    /// conicity range, or not of the features' sizes and finite.
    #[error("contact model at {speed} m/s: conicity model missing, unexpected or malformed")]
    Conicity {
        /// The model's speed \[m/s\].
        speed: f64,
    },
    /// A conicity model's precision matrix is in the header of a bank whose format keeps it in
    /// the data block (format 6 on).
    #[error(
        "a conicity model's precision in the header: from format 6 it belongs in the data block"
    )]
    PrecisionInHeader,
    /// A speed's model spectra ([`super::spectral::Spectra`]) are malformed, or present at some
    /// speeds only, or in a bank without conicities.
    #[error("contact model at {speed} m/s: spectra: {problem}")]
    Spectra {
        /// The model's speed \[m/s\].
        speed: f64,
        /// What is wrong.
        problem: String,
    },
}

/// A valid bank that holds no taps for the sensor set or lag the FMU's parameters choose
/// (`use_roll_rate`, `lag`), or whose entries for them do not form one table by speed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LearnedError {
    /// No causal entry for the sensor set.
    #[error("the tap bank has no causal taps for {}", sensors(*roll_rate))]
    NoCausal {
        /// Whether the roll-rate gyroscope's set was asked for.
        roll_rate: bool,
    },
    /// No fixed lag within half a grid step of the one asked for.
    #[error(
        "lag = {lag} m: the tap bank holds fixed-lag taps for {} m ({}); 0 switches the lagged output off",
        lags(held),
        sensors(*roll_rate)
    )]
    Lag {
        /// The lag asked for \[m\].
        lag: f64,
        /// The fixed lags the bank holds for the sensor set \[m\], ascending.
        held: Vec<f64>,
        /// Whether the roll-rate gyroscope's set was asked for.
        roll_rate: bool,
    },
    /// The fixed-lag entries are at other speeds than the causal ones (the blend in speed
    /// needs one set of speeds).
    #[error("the tap bank's {taps} taps are not at the speeds of its causal taps")]
    LagSpeeds {
        /// The fixed-lag taps.
        taps: Taps,
    },
    /// A bank without contact conditions has two entries of one kind at one speed.
    #[error("the tap bank has two {taps} entries for one speed ({speed} m/s)")]
    TwoEntries {
        /// Which entries.
        taps: Taps,
        /// The speed \[m/s\].
        speed: f64,
    },
}

/// Which of an entry set's taps an error is about: the causal ones, or those of a fixed lag.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Taps {
    /// Lag 0.
    Causal,
    /// A fixed lag \[m\].
    Lagged(f64),
}

impl std::fmt::Display for Taps {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Taps::Causal => write!(f, "causal"),
            Taps::Lagged(m) => write!(f, "{m} m lag"),
        }
    }
}

/// The sensor set, for messages.
fn sensors(roll_rate: bool) -> &'static str {
    if roll_rate {
        "four sensors (with the roll-rate gyroscope)"
    } else {
        "three sensors"
    }
}

/// The lags a bank holds, for messages: `no lag` when there is none.
fn lags(held: &[f64]) -> String {
    if held.is_empty() {
        return "no lag".into();
    }
    let shown: Vec<String> = held.iter().map(|l| format!("{l}")).collect();
    shown.join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Oracle: the messages these errors had as text before they were typed (2026-11-25),
    /// which users, the harness and the studies' tests match on, literally.
    #[test]
    fn the_messages_are_the_texts_they_replace() {
        let file = PathBuf::from("x.taps");
        let format = |f: &str| {
            BankError::Format {
                file: file.clone(),
                format: f.into(),
            }
            .to_string()
        };
        assert_eq!(
            format("7"),
            "x.taps: tap bank format 7 (this estimator reads formats [3, 4, 5, 6])"
        );
        assert_eq!(
            format("2"),
            "x.taps: tap bank format 2 (this estimator reads formats [3, 4, 5, 6]): it has no contract (the runtime constants and Kalman channel it was fitted with), so whether this estimator applies it as it was fitted cannot be checked; fit it again with `alignment-studies taps`"
        );
        let invalid = |problem: BankProblem| {
            BankError::Invalid {
                file: file.clone(),
                problem,
            }
            .to_string()
        };
        assert_eq!(
            invalid(BankProblem::Entry {
                index: 3,
                problem: EntryProblem::Window {
                    past: 5,
                    future: 2,
                    lag: 3
                }
            }),
            "x.taps: not a valid tap bank: entry 3: a window of 5 behind and 2 ahead under a lag of 3"
        );
        assert_eq!(
            invalid(
                ContactProblem::Band {
                    short: 3.0,
                    long: 2.5
                }
                .into()
            ),
            "x.taps: not a valid tap bank: contact band 3-2.5 m"
        );
        assert_eq!(
            LearnedError::Lag {
                lag: 10.0,
                held: vec![0.6, 3.0],
                roll_rate: false
            }
            .to_string(),
            "lag = 10 m: the tap bank holds fixed-lag taps for 0.6, 3 m (three sensors); 0 switches the lagged output off"
        );
        assert_eq!(
            LearnedError::Lag {
                lag: 1.0,
                held: vec![],
                roll_rate: true
            }
            .to_string(),
            "lag = 1 m: the tap bank holds fixed-lag taps for no lag m (four sensors (with the roll-rate gyroscope)); 0 switches the lagged output off"
        );
        assert_eq!(
            LearnedError::TwoEntries {
                taps: Taps::Lagged(0.6000000000000001),
                speed: 20.0
            }
            .to_string(),
            "the tap bank has two 0.6000000000000001 m lag entries for one speed (20 m/s)"
        );
    }
}
