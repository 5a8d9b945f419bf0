//! `y = gain * u + offset` with direct feedthrough (the output follows the input without a step),
//! plus a way to fail on purpose: when the step starts at or after `fail_at` the FMU returns
//! fmi2Error with a message. Used to test masters: algebraic-loop detection (two of these
//! in a ring) and error handling mid-run. `ud` (discrete Real), `n_in` (Integer) and `flag_in`
//! (Boolean) are passed through to `yd`, `n_out` and `flag_out` at each step, for testing how
//! a master sets inputs of each kind.

use fmi_abi::{InstantiateContext, Logger, Model, ModelInfo, StepOutcome, Values, VarSpec};
use serde::{Deserialize, Serialize};

const U: u32 = 0;
const Y: u32 = 1;
const GAIN: u32 = 2;
const OFFSET: u32 = 3;
const FAIL_AT: u32 = 4;
const UD: u32 = 5;
const YD: u32 = 6;
const COUNT: u32 = 0;
const N_IN: u32 = 1;
const N_OUT: u32 = 2;
const FLAG_IN: u32 = 0;
const FLAG_OUT: u32 = 1;

static VARIABLES: &[VarSpec] = &[
    VarSpec::real_input(U, "u", "1", 0.0, "input"),
    VarSpec::real_output_calculated(Y, "y", "1", "gain * u + offset (direct feedthrough)"),
    VarSpec::real_parameter(GAIN, "gain", "1", 1.0, "gain"),
    VarSpec::real_parameter(OFFSET, "offset", "1", 0.0, "offset"),
    VarSpec::real_parameter(
        FAIL_AT,
        "fail_at",
        "s",
        1e300,
        "fmi2DoStep from this time on returns fmi2Error",
    ),
    VarSpec::integer_output(COUNT, "steps", 0, "steps taken"),
    VarSpec::real_input(
        UD,
        "ud",
        "1",
        0.0,
        "a discrete Real input (a sampled signal)",
    )
    .discrete(),
    VarSpec::real_output(YD, "yd", "1", 0.0, "ud, passed through at each step").discrete(),
    VarSpec::integer_input(N_IN, "n_in", 0, "an Integer input"),
    VarSpec::integer_output(N_OUT, "n_out", 0, "n_in, passed through at each step"),
    VarSpec::boolean_input(FLAG_IN, "flag_in", false, "a Boolean input"),
    VarSpec::boolean_output(
        FLAG_OUT,
        "flag_out",
        false,
        "flag_in, passed through at each step",
    ),
];

/// The model the export layer wraps (`fmu_feedthrough_export` makes it an FMU). Stateless apart from its FMI variables: every output is recomputed from the inputs at each step, so its FMU state is the variable values alone.
#[derive(Clone, Serialize, Deserialize)]
pub struct Feedthrough;

fn update(v: &mut Values) {
    v.real[Y as usize] = v.real[GAIN as usize] * v.real[U as usize] + v.real[OFFSET as usize];
}

impl Model for Feedthrough {
    const INFO: ModelInfo = ModelInfo {
        model_name: "Feedthrough",
        model_identifier: "Feedthrough",
        guid: "5a3d9f0e-7c21-4b8e-a6f4-2e91b0c7d815",
        description: "y = gain * u + offset, direct feedthrough; fails on purpose at fail_at",
        author: "railway track-geometry toolkit (test FMU)",
        version: env!("CARGO_PKG_VERSION"),
        default_start: 0.0,
        default_stop: 10.0,
        default_step: 0.1,
    };
    fn variables() -> &'static [VarSpec] {
        VARIABLES
    }
    fn output_dependencies(output: &str) -> Option<Vec<u32>> {
        // y depends directly on u (index 1 in ModelVariables); the others on nothing.
        if output == "y" {
            Some(vec![1])
        } else {
            Some(vec![])
        }
    }
    fn update_outputs(&mut self, v: &mut Values) {
        update(v);
    }
    fn instantiate(_: &InstantiateContext, _: &Logger) -> Result<Self, String> {
        Ok(Feedthrough)
    }
    fn calculate_initial(&mut self, v: &mut Values) {
        update(v);
    }
    fn exit_initialization(&mut self, v: &mut Values, _: &Logger) -> Result<(), String> {
        update(v);
        Ok(())
    }
    fn do_step(
        &mut self,
        v: &mut Values,
        t: f64,
        _h: f64,
        _: &Logger,
    ) -> Result<StepOutcome, String> {
        if t >= v.real[FAIL_AT as usize] {
            return Err(format!(
                "failing on purpose: the step starts at t = {t} >= fail_at = {}",
                v.real[FAIL_AT as usize]
            ));
        }
        update(v);
        v.integer[COUNT as usize] += 1;
        v.boolean[FLAG_OUT as usize] = v.boolean[FLAG_IN as usize];
        v.real[YD as usize] = v.real[UD as usize];
        v.integer[N_OUT as usize] = v.integer[N_IN as usize];
        Ok(StepOutcome::Ok)
    }
}

/// The method section of the FMU's documentation/index.html (`cargo xtask fmu` prepends it
/// to the generated variable table).
pub const METHOD_HTML: &str =
    "<h2>Method</h2><p>y = gain * u + offset at every step; fmi2Error from fail_at on.</p>";

/// The modelDescription.xml the FMU ships, generated from the variable table, so the XML and
/// the code cannot disagree.
pub fn model_description() -> model_description::ModelDescription {
    fmi_abi::description::model_description::<Feedthrough>()
}

#[cfg(test)]
mod tests {
    #[test]
    fn model_description_is_valid() {
        assert_eq!(super::model_description().validate(), vec![]);
    }
}
