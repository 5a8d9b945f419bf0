//! The fuzzer's books: it cannot ask an FMU what state an instance is in or what a variable
//! holds, so it keeps what it can know, narrowed by every call, and checks the FMU against it.

use crate::api::Base;
use crate::log::LogSink;
use crate::oracle::States;
use fmi_abi::types::{fmi2CallbackFunctions, fmi2Component, fmi2FMUstate};
use std::collections::{BTreeMap, BTreeSet};

/// What the fuzzer knows a variable holds.
#[derive(Debug, Clone, PartialEq)]
pub(super) enum Known {
    Real(u64),
    Int(i32),
    Bool(bool),
    Str(String),
}

pub(super) type KnownMap = BTreeMap<(u8, u32), Known>;

pub(super) fn key(base: Base, vr: u32) -> (u8, u32) {
    (base as u8, vr)
}

/// Equal as written: bit-identical reals, except that any NaN reads back as a NaN.
pub(super) fn same(a: &Known, b: &Known) -> bool {
    match (a, b) {
        (Known::Real(x), Known::Real(y)) => {
            x == y || (f64::from_bits(*x).is_nan() && f64::from_bits(*y).is_nan())
        }
        _ => a == b,
    }
}

pub(super) struct SavedState {
    pub ptr: fmi2FMUstate,
    pub possible: States,
    pub time: Option<f64>,
    pub known: KnownMap,
    pub size: Option<usize>,
}

pub(super) struct Blob {
    pub bytes: Vec<u8>,
    pub possible: States,
    pub time: Option<f64>,
    pub known: KnownMap,
}

pub(super) struct Inst {
    pub id: usize,
    pub c: fmi2Component,
    pub sink: Box<LogSink>,
    pub _callbacks: Option<Box<fmi2CallbackFunctions>>,
    /// The name we passed (None: NULL).
    pub name: Option<String>,
    /// Logger and environment given: messages reach our sink.
    pub logs_to_us: bool,
    /// Whether the error category is on (fmi2SetDebugLogging may switch it off).
    pub errors_logged: bool,
    pub categories_off: BTreeSet<String>,
    pub possible: States,
    pub time: Option<f64>,
    pub known: KnownMap,
    pub states: Vec<SavedState>,
    pub fatal: bool,
    /// Non-input variables were changed (or a state restored): initialization may fail.
    pub params_touched: bool,
    /// Instantiated without a usable resource location.
    pub no_resources: bool,
}
