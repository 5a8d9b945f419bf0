//! What the estimator refuses or skips in its inputs, in the FMU and offline alike.
//!
//! | input | rule | why |
//! |---|---|---|
//! | `speed` | negative: an error | the model is for forward running (creep terms divide by the speed; a reversing train is another vehicle orientation) |
//! | accelerometers | beyond [`MAX_ACC`]: the sample is skipped like a non-finite one | no axle-box or frame accelerometer reads 200 g; such a value is a fault, and one sample of 1e300 m/s2 would otherwise put 1e301 m into the estimate |
//! | gyroscopes | beyond [`MAX_RATE`]: skipped likewise | a wheelset does not turn at 100 rad/s about a vertical or longitudinal axis |
//! | the step | longer than [`MAX_SAMPLE_STEP`]: an error | the Kalman filter runs on its 1 ms clock (`Engine::step`): a step of `h` is `h / 1 ms` filter steps, and no sensor samples this rarely |

use crate::error::SampleError;

/// Largest plausible acceleration sample \[m/s2\] (200 g: axle-box shocks at wheel flats stay
/// below 100 g).
pub const MAX_ACC: f64 = 2000.0;
/// Largest plausible angular-rate sample \[rad/s\].
pub const MAX_RATE: f64 = 100.0;

/// Longest sample step \[s\]: 1000 of the Kalman filter's 1 ms steps per sample (sensors for
/// this sample at 100 Hz and faster).
pub const MAX_SAMPLE_STEP: f64 = 1.0;

/// An error if the sample step `h` is longer than [`MAX_SAMPLE_STEP`].
pub fn sample_step(h: f64) -> Result<(), SampleError> {
    if h > MAX_SAMPLE_STEP {
        return Err(SampleError::StepTooLong(h));
    }
    Ok(())
}

/// An error if `speed` is negative (NaN and infinite speeds are held over, not refused).
pub fn speed(speed: f64) -> Result<(), SampleError> {
    if speed < 0.0 {
        return Err(SampleError::NegativeSpeed(speed));
    }
    Ok(())
}

/// Replaces each implausible sensor value with NaN, so that the step skips it as a non-finite
/// sample; returns the names and values replaced (empty if none). Order: `ws_acc_y`,
/// `ws_yaw_rate`, `frame_acc_y`, `ws_roll_rate`.
pub fn sensors(x: &mut [f64; 4]) -> Vec<String> {
    const NAMES: [(&str, f64); 4] = [
        ("ws_acc_y", MAX_ACC),
        ("ws_yaw_rate", MAX_RATE),
        ("frame_acc_y", MAX_ACC),
        ("ws_roll_rate", MAX_RATE),
    ];
    let mut replaced = vec![];
    for (v, (name, max)) in x.iter_mut().zip(NAMES) {
        if v.is_finite() && v.abs() > max {
            replaced.push(format!("{name} = {v:e} (|x| > {max})"));
            *v = f64::NAN;
        }
    }
    replaced
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_step_over_a_second_is_refused() {
        assert!(sample_step(1e-3).is_ok() && sample_step(1.0).is_ok());
        let e = sample_step(1e300).unwrap_err().to_string();
        assert!(e.contains("1e300") && e.contains("step"), "{e}");
    }

    #[test]
    fn negative_speeds_are_refused_by_name() {
        assert!(speed(0.0).is_ok() && speed(20.0).is_ok() && speed(f64::NAN).is_ok());
        let e = speed(-3.0).unwrap_err().to_string();
        assert!(e.contains("'speed'") && e.contains("-3"), "{e}");
    }

    #[test]
    fn implausible_samples_become_nan_and_are_named() {
        let mut x = [1e300, 0.01, -2500.0, 0.5];
        let r = sensors(&mut x);
        assert!(x[0].is_nan() && x[2].is_nan());
        assert_eq!((x[1], x[3]), (0.01, 0.5));
        assert_eq!(r.len(), 2);
        assert!(
            r[0].starts_with("ws_acc_y") && r[1].starts_with("frame_acc_y"),
            "{r:?}"
        );
        let mut ok = [9.81 * 50.0, 3.0, -9.81 * 50.0, -3.0];
        assert!(sensors(&mut ok).is_empty());
    }
}
