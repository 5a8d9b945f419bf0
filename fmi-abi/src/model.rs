//! What an FMU crate implements: its identity, its variable table and its equations. Everything
//! else (states, checks, logging, FMU state, the C entry points) is the export layer's.

use crate::logger::Logger;
use crate::variables::{Values, VarSpec};
use serde::Serialize;
use serde::de::DeserializeOwned;
use std::path::PathBuf;

/// Static facts written to modelDescription.xml.
#[derive(Debug, Clone, Copy)]
pub struct ModelInfo {
    /// `modelName`: the name tools show; free text.
    pub model_name: &'static str,
    /// The shared library name and the `modelIdentifier` attribute.
    pub model_identifier: &'static str,
    /// Unique per FMU and version (libcosim caches by GUID); no braces (libcosim #533). Our FMUs
    /// make it at build time from what shapes them (crate `state-layout`), so it changes
    /// whenever the modelDescription.xml may.
    pub guid: &'static str,
    /// `description`: one line for people.
    pub description: &'static str,
    /// `author`.
    pub author: &'static str,
    /// `version`: the model's own version (our FMUs use the crate's).
    pub version: &'static str,
    /// `DefaultExperiment` startTime in seconds.
    pub default_start: f64,
    /// `DefaultExperiment` stopTime in seconds.
    pub default_stop: f64,
    /// `DefaultExperiment` stepSize in seconds: the communication step the model is made for.
    pub default_step: f64,
}

/// How a step ended when it did not fail.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StepOutcome {
    /// The step completed (fmi2OK).
    Ok,
    /// The step completed but something was logged as a warning (fmi2Warning).
    Warning,
    /// The model ended the simulation at `at` (clamped into the step): fmi2DoStep returns
    /// fmi2Discard, fmi2GetRealStatus(fmi2LastSuccessfulTime) answers `at` and
    /// fmi2GetBooleanStatus(fmi2Terminated) true, so the master stops there (FMI 2.0 section
    /// 4.2.3). Further steps are refused; fmi2Terminate is allowed.
    Terminated {
        /// Where the model ended, in seconds; NaN means the step's start.
        at: f64,
    },
}

/// What fmi2Instantiate learned from the importer.
#[derive(Debug, Clone, Default)]
pub struct InstantiateContext {
    /// fmi2Instantiate's instanceName ("" when NULL), for the model's own messages.
    pub instance_name: String,
    /// Parsed fmuResourceLocation, when the importer gave a usable one.
    pub resources: Option<PathBuf>,
}

/// The equations of one FMU. Errors are plain messages: the layer logs them with the instance
/// name and returns fmi2Error. A model must be cheap to clone (FMU state is a clone) and
/// serializable (fmi2SerializeFMUstate).
pub trait Model: Clone + Send + Serialize + DeserializeOwned + 'static {
    /// The model's identity and default experiment, for modelDescription.xml and the GUID
    /// check at fmi2Instantiate.
    const INFO: ModelInfo;
    /// The layout of the model's serialized state, written into every serialized FMU state
    /// beside the GUID: a state whose layout differs is refused with a message instead of being
    /// decoded into wrong values (the GUID names the interface, which can stay the same while
    /// the internal state changes). A model whose state layout can change between builds sets
    /// it to a fingerprint of its sources; empty: the GUID alone decides.
    const STATE_LAYOUT: &'static str = "";

    /// The variable table: the modelDescription.xml's variables and the layer's checks of every
    /// get and set come from it, so the two cannot disagree. Value references index
    /// [`Values`] per base type (see `VarIndex`).
    fn variables() -> &'static [VarSpec];

    /// A fresh model; the layer keeps a copy of it for fmi2Reset.
    fn instantiate(ctx: &InstantiateContext, log: &Logger) -> Result<Self, String>;

    /// Computes outputs declared `initial="calculated"` from the current parameters, so that
    /// they can be read in initialization mode.
    fn calculate_initial(&mut self, _values: &mut Values) {}

    /// Direct feedthrough: the 1-based ModelVariables indices of the inputs that `output`
    /// depends on without a step (written as the `dependencies` attribute). The default, no
    /// dependency, is right for models that compute their outputs only inside fmi2DoStep.
    fn output_dependencies(_output: &str) -> Option<Vec<u32>> {
        Some(vec![])
    }

    /// Recomputes outputs that depend directly on inputs; the layer calls it before a get when
    /// inputs were set since the last step (only models with direct feedthrough need it).
    fn update_outputs(&mut self, _values: &mut Values) {}

    /// Checks parameters and builds whatever the steps need. Parameters already passed the
    /// table's min/max checks.
    fn exit_initialization(&mut self, values: &mut Values, log: &Logger) -> Result<(), String>;

    /// A tunable parameter was set between steps.
    fn parameters_changed(&mut self, _values: &mut Values, _log: &Logger) -> Result<(), String> {
        Ok(())
    }

    /// fmi2Terminate: the simulation is over (e.g. to log what was counted during it).
    fn terminate(&mut self, _values: &mut Values, _log: &Logger) {}

    /// Advances from `t` to `t + h` with the inputs in `values`, writing the outputs there.
    fn do_step(
        &mut self,
        values: &mut Values,
        t: f64,
        h: f64,
        log: &Logger,
    ) -> Result<StepOutcome, String>;
}
