//! Dahlquist's test equation `x' = -k x`, integrated exactly over each step
//! (`x(t + h) = x(t) exp(-k h)`), with an input `u` added to the derivative
//! (`x' = -k x + u`, held over the step). Output `x` has no direct feedthrough. Used to test and
//! benchmark masters, like the Modelica Reference-FMUs' Dahlquist.

use fmi_abi::{InstantiateContext, Logger, Model, ModelInfo, StepOutcome, Values, VarSpec};
use serde::{Deserialize, Serialize};

const X: u32 = 0;
const K: u32 = 1;
const U: u32 = 2;
const X0: u32 = 3;
const END_AT: u32 = 4;

static VARIABLES: &[VarSpec] = &[
    VarSpec::real_output_calculated(X, "x", "1", "the state (x0 at the start)"),
    VarSpec::real_parameter(K, "k", "1", 1.0, "decay rate").min(0.0),
    VarSpec::real_input(
        U,
        "u",
        "1",
        0.0,
        "added to the derivative, held over the step",
    ),
    VarSpec::real_parameter(X0, "x0", "1", 1.0, "initial state"),
    VarSpec::real_parameter(
        END_AT,
        "end_at",
        "s",
        0.0,
        "if positive: the model ends the simulation there (the step that passes it integrates up to it and returns fmi2Discard with fmi2Terminated), like a model reaching the end of its data",
    )
    .min(0.0),
];

/// The model the export layer wraps (`fmu_dahlquist_export` makes it an FMU). x = x0 at the start; `end_at` > 0 ends the run there with fmi2Terminated. Stateless apart from its FMI variables, so its FMU state is the variable values alone.
#[derive(Clone, Serialize, Deserialize)]
pub struct Dahlquist;

impl Model for Dahlquist {
    const INFO: ModelInfo = ModelInfo {
        model_name: "Dahlquist",
        model_identifier: "Dahlquist",
        guid: "0b7e1c52-3f2d-4a61-9e58-d1a4c2f7b903",
        description: "x' = -k x + u, exact per step",
        author: "railway track-geometry toolkit (test FMU)",
        version: env!("CARGO_PKG_VERSION"),
        default_start: 0.0,
        default_stop: 10.0,
        default_step: 0.1,
    };
    fn variables() -> &'static [VarSpec] {
        VARIABLES
    }
    fn instantiate(_: &InstantiateContext, _: &Logger) -> Result<Self, String> {
        Ok(Dahlquist)
    }
    fn calculate_initial(&mut self, v: &mut Values) {
        v.real[X as usize] = v.real[X0 as usize];
    }
    fn exit_initialization(&mut self, _: &mut Values, _: &Logger) -> Result<(), String> {
        Ok(())
    }
    fn do_step(
        &mut self,
        v: &mut Values,
        t: f64,
        h: f64,
        _: &Logger,
    ) -> Result<StepOutcome, String> {
        let end = v.real[END_AT as usize];
        // Within a nanosecond of the end counts as reaching it (a master's clock rounding).
        let (h, ends) = if end > 0.0 && t + h > end + 1e-9 {
            ((end - t).max(0.0), true)
        } else {
            (h, false)
        };
        let (x, k, u) = (v.real[X as usize], v.real[K as usize], v.real[U as usize]);
        v.real[X as usize] = if k > 0.0 {
            let e = (-k * h).exp();
            x * e + u / k * (1.0 - e)
        } else {
            x + u * h
        };
        if ends {
            // Integrated up to the end: the outputs are those of the last successful time.
            return Ok(StepOutcome::Terminated { at: t + h });
        }
        Ok(StepOutcome::Ok)
    }
}

/// The method section of the FMU's documentation/index.html (`cargo xtask fmu` prepends it
/// to the generated variable table).
pub const METHOD_HTML: &str = "<h2>Method</h2><p>x' = -k x + u, integrated exactly over each communication step with u held.</p>";

/// The modelDescription.xml the FMU ships, generated from the variable table, so the XML and
/// the code cannot disagree.
pub fn model_description() -> model_description::ModelDescription {
    fmi_abi::description::model_description::<Dahlquist>()
}

#[cfg(test)]
mod tests {
    #[test]
    fn model_description_is_valid() {
        assert_eq!(super::model_description().validate(), vec![]);
    }
}
