//! One sample through the estimator: the single per-sample step that the FMU's `fmi2DoStep`
//! ([`crate::fmu`]) and offline processing ([`crate::offline`], the studies, the Python
//! bindings) both call, so the two give the same estimates for the same samples by
//! construction. What each caller adds is its own: the FMU logs and sets its outputs, offline
//! keeps the per-sample series.
//!
//! | stage | rule |
//! |---|---|
//! | roll-rate channel | read only when the learned taps use it; otherwise 0, so an unconnected or NaN roll-rate input changes nothing |
//! | implausible sensors | replaced by NaN ([`crate::plausible::sensors`]): the measurement update is skipped, the prediction kept |
//! | design geometry | its response is removed ([`crate::design`]) when a model is loaded, before the biases are observed (a canted standstill is not a bias) |
//! | biases | a standstill refines them from the samples the two rows above leave, each sensor on its own; every sample has them removed ([`crate::bias`]) |
//! | distance | advances by `speed * h` for every finite speed, also while the filter holds |
//! | hold | below `min_speed` or at a non-finite speed the filter does not step (the creep terms divide by the speed) |
//! | filter speed | `design_speed` when set, else the sample's speed |
//! | learned filter | steps with the sensors and the Kalman estimate, at the sample's own speed |
//! | `outside_training` | after the step, [`outside_training`]: the one rule both callers output |

use crate::bias::Bias;
use crate::core::Core;
use crate::design::Design;
use crate::engine::Skip;
use crate::error::{SampleError, StepError};
use crate::filter::Vec4;
use crate::learned::Learned;

/// One sample's inputs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Input {
    /// Forward speed \[m/s\]: negative is an error, NaN or below `min_speed` holds the filter.
    pub speed: f64,
    /// `ws_acc_y`, `ws_yaw_rate`, `frame_acc_y`, `ws_roll_rate`.
    pub sensors: [f64; 4],
    /// The design line at the leading wheelset: curvature \[1/m\], cant \[m\] (0 on
    /// straight track; read only with a design-response model).
    pub design: [f64; 2],
}

/// What the step did.
#[derive(Debug, Clone, PartialEq)]
pub enum Stepped {
    /// The filter held its estimate: the speed is below `min_speed`, or not finite.
    Held {
        /// Whether the speed was finite (then the distance advanced).
        finite_speed: bool,
    },
    /// The filter stepped: the update's normalized innovation squared, or why it was skipped,
    /// and the sensors replaced as implausible (their names and values).
    Filtered {
        /// The NIS of the measurement update, or why it was skipped (the prediction kept).
        update: Result<f64, Skip>,
        /// Each sensor replaced by NaN as implausible, as `name = value (|x| > limit)` for the
        /// log.
        implausible: Vec<String>,
    },
}

/// The estimator's settings a step reads.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Settings {
    /// Below this speed \[m/s\] the filter holds (`min_speed`).
    pub min_speed: f64,
    /// 0: the matrices follow the speed; above 0: built for this speed.
    pub design_speed: f64,
}

/// The `outside_training` output after a step, the same in the FMU and offline: the learned
/// filter's own flag (novelty, conicity), the design line beyond its response's envelope, or
/// the sensors' integrals beyond straight track's ([`crate::integrals`]).
pub fn outside_training(learned: Option<&Learned>, design: &Design, bias: &Bias) -> bool {
    learned.is_some_and(|l| l.outside_training()) || design.outside() || bias.integrals.outside()
}

/// Steps `core` (and `learned`) with one sample of step `h`, advancing `distance`. A negative
/// speed is an error ([`crate::plausible::speed`]), as is a filter that cannot step.
// Inlined into fmi2DoStep: as a call it cost 5-10 % of the FMU's step (bench do_step, same run).
#[inline(always)]
// The per-sample state each caller owns (filter, learned filter, biases, design, distance).
#[allow(clippy::too_many_arguments)]
pub fn step(
    settings: Settings,
    core: &mut Core,
    learned: Option<&mut Learned>,
    bias: &mut Bias,
    design: &mut Design,
    distance: &mut f64,
    h: f64,
    input: Input,
) -> Result<Stepped, SampleError> {
    let speed = input.speed;
    crate::plausible::sample_step(h)?;
    crate::plausible::speed(speed)?;
    let mut x = input.sensors;
    let roll_rate = learned.as_ref().is_some_and(|l| l.uses_roll_rate());
    if !roll_rate {
        x[3] = 0.0;
    }
    let implausible = crate::plausible::sensors(&mut x);
    if design.active() {
        let at = *distance + if speed.is_finite() { speed * h } else { 0.0 };
        let moving = if speed.is_finite() { speed } else { 0.0 };
        let r = design.response(at, moving, input.design);
        let used = if roll_rate { 4 } else { 3 };
        for i in 0..used {
            x[i] -= r[i];
        }
    }
    bias.observe(speed, h, &x);
    if speed.is_finite() {
        *distance += speed * h;
    }
    if !(speed >= settings.min_speed) || !speed.is_finite() {
        return Ok(Stepped::Held {
            finite_speed: speed.is_finite(),
        });
    }
    let x = bias.remove(&x);
    let filter_speed = if settings.design_speed > 0.0 {
        settings.design_speed
    } else {
        speed
    };
    let update = match core.step(filter_speed, h, &Vec4::new(x[0], x[1], x[2], 0.0)) {
        Ok(nis) => Ok(nis),
        Err(StepError::Skipped(skip)) => Err(skip),
        Err(StepError::Gain(e)) => return Err(SampleError::Gain(e)),
    };
    if let Some(l) = learned {
        let (kalman, kalman_std) = core.alignment();
        l.step(
            *distance,
            speed,
            &[x[0], x[1], x[2], x[3], kalman],
            kalman_std,
        );
    }
    Ok(Stepped::Filtered {
        update,
        implausible,
    })
}
