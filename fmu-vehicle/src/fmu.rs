//! The vehicle as an FMI model: its variable table and what each FMI phase does.
//!
//! Initialization reads the vehicle parameter set, builds the track (synthesized from the
//! spectrum and seed, or read from `track_file`), and starts the vehicle in static equilibrium at
//! `distance = 0` (leading wheelset). Each `fmi2DoStep(t, h)` integrates exactly to `t + h` with
//! the speed input held over the step and reports sensors and truth at `t + h`.

use crate::dynamics::{ContactOptions, Vehicle};
use crate::line::{DesignLine, OneCurve};
use crate::params::VehicleParams;
use crate::simulation::{SensorNoise, SimConfig, Simulation};
use crate::track::{Spectrum, Track, TrackSpec};
use fmi_abi::{InstantiateContext, Logger, Model, ModelInfo, StepOutcome, Values, VarSpec};
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// Value references, dense from 0 within each base type (so a Real and an Integer may share a
/// number). Each names its FMI variable; what the variable means, its sign convention and its
/// start value are in [`VARIABLES`].
pub mod vr {
    // Real
    /// `speed` (Real input, m/s).
    pub const SPEED: u32 = 0;
    /// `ws_acc_y` (Real output, m/s2).
    pub const WS_ACC_Y: u32 = 1;
    /// `ws_yaw_rate` (Real output, rad/s).
    pub const WS_YAW_RATE: u32 = 2;
    /// `frame_acc_y` (Real output, m/s2).
    pub const FRAME_ACC_Y: u32 = 3;
    /// `distance` (Real output, m).
    pub const DISTANCE: u32 = 4;
    /// `alignment` (Real output, m).
    pub const ALIGNMENT: u32 = 5;
    /// `vertical_profile` (Real output, m).
    pub const VERTICAL_PROFILE: u32 = 6;
    /// `cross_level` (Real output, m).
    pub const CROSS_LEVEL: u32 = 7;
    /// `ws_y` (Real output, m).
    pub const WS_Y: u32 = 8;
    /// `ws_yaw` (Real output, rad).
    pub const WS_YAW: u32 = 9;
    /// `ws_vy` (Real output, m/s).
    pub const WS_VY: u32 = 10;
    /// `ws_yaw_rate_true` (Real output, rad/s).
    pub const WS_YAW_RATE_TRUE: u32 = 11;
    /// `frame_y` (Real output, m).
    pub const FRAME_Y: u32 = 12;
    /// `frame_vy` (Real output, m/s).
    pub const FRAME_VY: u32 = 13;
    /// `ws_acc_y_clean` (Real output, m/s2).
    pub const WS_ACC_Y_CLEAN: u32 = 14;
    /// `frame_acc_y_clean` (Real output, m/s2).
    pub const FRAME_ACC_Y_CLEAN: u32 = 15;
    /// `ws_roll` (Real output, rad).
    pub const WS_ROLL: u32 = 16;
    /// `bogie_y` (Real output, m).
    pub const BOGIE_Y: u32 = 17;
    /// `bogie_roll` (Real output, rad).
    pub const BOGIE_ROLL: u32 = 18;
    /// `bogie_yaw` (Real output, rad).
    pub const BOGIE_YAW: u32 = 19;
    /// `body_y` (Real output, m).
    pub const BODY_Y: u32 = 20;
    /// `body_roll` (Real output, rad).
    pub const BODY_ROLL: u32 = 21;
    /// `body_yaw` (Real output, rad).
    pub const BODY_YAW: u32 = 22;
    /// `body_z` (Real output, m).
    pub const BODY_Z: u32 = 23;
    /// `wheel_load_left` (Real output, calculated at initialization, N).
    pub const WHEEL_LOAD_LEFT: u32 = 24;
    /// `wheel_load_right` (Real output, calculated at initialization, N).
    pub const WHEEL_LOAD_RIGHT: u32 = 25;
    /// `conicity` (Real parameter, dimensionless).
    pub const CONICITY: u32 = 26;
    /// `kalker_scale` (Real parameter, dimensionless).
    pub const KALKER_SCALE: u32 = 27;
    /// `harmonic_amplitude` (Real parameter, m).
    pub const HARMONIC_AMPLITUDE: u32 = 28;
    /// `harmonic_wavelength` (Real parameter, m).
    pub const HARMONIC_WAVELENGTH: u32 = 29;
    /// `ramp_length` (Real parameter, m).
    pub const RAMP_LENGTH: u32 = 30;
    /// `min_wavelength` (Real parameter, m).
    pub const MIN_WAVELENGTH: u32 = 31;
    /// `max_wavelength` (Real parameter, m).
    pub const MAX_WAVELENGTH: u32 = 32;
    /// `sigma_acc` (Real parameter, m/s2).
    pub const SIGMA_ACC: u32 = 33;
    /// `sigma_gyro` (Real parameter, rad/s).
    pub const SIGMA_GYRO: u32 = 34;
    /// `friction` (Real parameter, dimensionless).
    pub const FRICTION: u32 = 35;
    /// `flange_clearance` (Real parameter, m).
    pub const FLANGE_CLEARANCE: u32 = 36;
    /// `flange_stiffness` (Real parameter, N/m).
    pub const FLANGE_STIFFNESS: u32 = 37;
    /// `max_internal_step` (Real parameter, s).
    pub const MAX_INTERNAL_STEP: u32 = 38;
    /// `min_speed` (Real parameter, m/s).
    pub const MIN_SPEED: u32 = 39;
    /// `forward_speed` (Real output, m/s).
    pub const FORWARD_SPEED: u32 = 40;
    /// `ws_roll_rate` (Real output, rad/s).
    pub const WS_ROLL_RATE: u32 = 41;
    /// `ws_roll_rate_true` (Real output, rad/s).
    pub const WS_ROLL_RATE_TRUE: u32 = 42;
    /// `sigma_roll_gyro` (Real parameter, rad/s).
    pub const SIGMA_ROLL_GYRO: u32 = 43;
    /// `ws_acc_y_bias` (Real parameter, m/s2).
    pub const WS_ACC_Y_BIAS: u32 = 44;
    /// `ws_acc_y_bias_instability` (Real parameter, m/s2).
    pub const WS_ACC_Y_BIAS_INSTABILITY: u32 = 45;
    /// `ws_acc_y_bias_tau` (Real parameter, s).
    pub const WS_ACC_Y_BIAS_TAU: u32 = 46;
    /// `ws_acc_y_scale_error` (Real parameter, 1).
    pub const WS_ACC_Y_SCALE_ERROR: u32 = 47;
    /// `ws_acc_y_misalignment` (Real parameter, rad).
    pub const WS_ACC_Y_MISALIGNMENT: u32 = 48;
    /// `ws_acc_y_noise_psd` (Real parameter, m2/s3).
    pub const WS_ACC_Y_NOISE_PSD: u32 = 49;
    /// `ws_acc_y_bandwidth` (Real parameter, Hz).
    pub const WS_ACC_Y_BANDWIDTH: u32 = 50;
    /// `ws_acc_y_range` (Real parameter, m/s2).
    pub const WS_ACC_Y_RANGE: u32 = 51;
    /// `ws_acc_y_resolution` (Real parameter, m/s2).
    pub const WS_ACC_Y_RESOLUTION: u32 = 52;
    /// `ws_yaw_rate_bias` (Real parameter, rad/s).
    pub const WS_YAW_RATE_BIAS: u32 = 53;
    /// `ws_yaw_rate_bias_instability` (Real parameter, rad/s).
    pub const WS_YAW_RATE_BIAS_INSTABILITY: u32 = 54;
    /// `ws_yaw_rate_bias_tau` (Real parameter, s).
    pub const WS_YAW_RATE_BIAS_TAU: u32 = 55;
    /// `ws_yaw_rate_scale_error` (Real parameter, 1).
    pub const WS_YAW_RATE_SCALE_ERROR: u32 = 56;
    /// `ws_yaw_rate_misalignment` (Real parameter, rad).
    pub const WS_YAW_RATE_MISALIGNMENT: u32 = 57;
    /// `ws_yaw_rate_noise_psd` (Real parameter, rad2/s).
    pub const WS_YAW_RATE_NOISE_PSD: u32 = 58;
    /// `ws_yaw_rate_bandwidth` (Real parameter, Hz).
    pub const WS_YAW_RATE_BANDWIDTH: u32 = 59;
    /// `ws_yaw_rate_range` (Real parameter, rad/s).
    pub const WS_YAW_RATE_RANGE: u32 = 60;
    /// `ws_yaw_rate_resolution` (Real parameter, rad/s).
    pub const WS_YAW_RATE_RESOLUTION: u32 = 61;
    /// `frame_acc_y_bias` (Real parameter, m/s2).
    pub const FRAME_ACC_Y_BIAS: u32 = 62;
    /// `frame_acc_y_bias_instability` (Real parameter, m/s2).
    pub const FRAME_ACC_Y_BIAS_INSTABILITY: u32 = 63;
    /// `frame_acc_y_bias_tau` (Real parameter, s).
    pub const FRAME_ACC_Y_BIAS_TAU: u32 = 64;
    /// `frame_acc_y_scale_error` (Real parameter, 1).
    pub const FRAME_ACC_Y_SCALE_ERROR: u32 = 65;
    /// `frame_acc_y_misalignment` (Real parameter, rad).
    pub const FRAME_ACC_Y_MISALIGNMENT: u32 = 66;
    /// `frame_acc_y_noise_psd` (Real parameter, m2/s3).
    pub const FRAME_ACC_Y_NOISE_PSD: u32 = 67;
    /// `frame_acc_y_bandwidth` (Real parameter, Hz).
    pub const FRAME_ACC_Y_BANDWIDTH: u32 = 68;
    /// `frame_acc_y_range` (Real parameter, m/s2).
    pub const FRAME_ACC_Y_RANGE: u32 = 69;
    /// `frame_acc_y_resolution` (Real parameter, m/s2).
    pub const FRAME_ACC_Y_RESOLUTION: u32 = 70;
    /// `ws_roll_rate_bias` (Real parameter, rad/s).
    pub const WS_ROLL_RATE_BIAS: u32 = 71;
    /// `ws_roll_rate_bias_instability` (Real parameter, rad/s).
    pub const WS_ROLL_RATE_BIAS_INSTABILITY: u32 = 72;
    /// `ws_roll_rate_bias_tau` (Real parameter, s).
    pub const WS_ROLL_RATE_BIAS_TAU: u32 = 73;
    /// `ws_roll_rate_scale_error` (Real parameter, 1).
    pub const WS_ROLL_RATE_SCALE_ERROR: u32 = 74;
    /// `ws_roll_rate_misalignment` (Real parameter, rad).
    pub const WS_ROLL_RATE_MISALIGNMENT: u32 = 75;
    /// `ws_roll_rate_noise_psd` (Real parameter, rad2/s).
    pub const WS_ROLL_RATE_NOISE_PSD: u32 = 76;
    /// `ws_roll_rate_bandwidth` (Real parameter, Hz).
    pub const WS_ROLL_RATE_BANDWIDTH: u32 = 77;
    /// `ws_roll_rate_range` (Real parameter, rad/s).
    pub const WS_ROLL_RATE_RANGE: u32 = 78;
    /// `ws_roll_rate_resolution` (Real parameter, rad/s).
    pub const WS_ROLL_RATE_RESOLUTION: u32 = 79;
    /// `design_curvature` (Real output, 1/m).
    pub const DESIGN_CURVATURE: u32 = 80;
    /// `design_cant` (Real output, m).
    pub const DESIGN_CANT: u32 = 81;
    /// `curve_radius` (Real parameter, m).
    pub const CURVE_RADIUS: u32 = 82;
    /// `curve_transition` (Real parameter, m).
    pub const CURVE_TRANSITION: u32 = 83;
    /// `curve_length` (Real parameter, m).
    pub const CURVE_LENGTH: u32 = 84;
    /// `curve_cant` (Real parameter, m).
    pub const CURVE_CANT: u32 = 85;
    /// `curve_start` (Real parameter, m).
    pub const CURVE_START: u32 = 86;
    /// `line_rounding` (Real parameter, m).
    pub const LINE_ROUNDING: u32 = 87;
    // Integer
    /// `track_seed` (Integer parameter).
    pub const TRACK_SEED: u32 = 0;
    /// `spectrum` (Integer parameter).
    pub const SPECTRUM: u32 = 1;
    /// `noise_seed` (Integer parameter).
    pub const NOISE_SEED: u32 = 2;
    /// `sensor_grade` (Integer parameter).
    pub const SENSOR_GRADE: u32 = 3;
    /// `curve_direction` (Integer parameter).
    pub const CURVE_DIRECTION: u32 = 4;
    // Boolean
    /// `lateral_irregularity` (Boolean parameter).
    pub const LATERAL_IRREGULARITY: u32 = 0;
    /// `vertical_irregularity` (Boolean parameter).
    pub const VERTICAL_IRREGULARITY: u32 = 1;
    /// `sensor_noise` (Boolean parameter).
    pub const SENSOR_NOISE: u32 = 2;
    /// `creep_saturation` (Boolean parameter).
    pub const CREEP_SATURATION: u32 = 3;
    /// `flange_contact` (Boolean parameter).
    pub const FLANGE_CONTACT: u32 = 4;
    // String
    /// `vehicle` (String parameter).
    pub const VEHICLE: u32 = 0;
    /// `track_file` (String parameter).
    pub const TRACK_FILE: u32 = 1;
    /// `line_file` (String parameter).
    pub const LINE_FILE: u32 = 2;
}

/// The variable table: modelDescription.xml, the documentation's table and the export layer's
/// checks all come from it, so the three cannot disagree. The descriptions say where each
/// sensor sits and give the sign conventions.
pub static VARIABLES: &[VarSpec] = &[
    VarSpec::real_input(
        vr::SPEED,
        "speed",
        "m/s",
        20.0,
        "Forward speed, held over each communication step; below min_speed the vehicle stands still",
    ),
    VarSpec::real_output(
        vr::WS_ACC_Y,
        "ws_acc_y",
        "m/s2",
        0.0,
        "Axle-box accelerometer on the leading wheelset: specific force along the axle (gravity enters through roll), with noise",
    ),
    VarSpec::real_output(
        vr::WS_YAW_RATE,
        "ws_yaw_rate",
        "rad/s",
        0.0,
        "Yaw gyroscope on the leading wheelset, with noise",
    ),
    VarSpec::real_output(
        vr::FRAME_ACC_Y,
        "frame_acc_y",
        "m/s2",
        0.0,
        "Lateral accelerometer on the leading bogie frame above the leading wheelset, with noise",
    ),
    VarSpec::real_output(
        vr::DISTANCE,
        "distance",
        "m",
        0.0,
        "Position of the leading wheelset along the track",
    ),
    VarSpec::real_output(
        vr::ALIGNMENT,
        "alignment",
        "m",
        0.0,
        "True lateral alignment at the leading wheelset (after the run-in ramp)",
    ),
    VarSpec::real_output(
        vr::VERTICAL_PROFILE,
        "vertical_profile",
        "m",
        0.0,
        "True vertical profile at the leading wheelset",
    ),
    VarSpec::real_output(
        vr::CROSS_LEVEL,
        "cross_level",
        "m",
        0.0,
        "True cross-level (left rail minus right rail height) at the leading wheelset",
    ),
    VarSpec::real_output(
        vr::WS_Y,
        "ws_y",
        "m",
        0.0,
        "Leading wheelset lateral displacement from the ideal track centre line",
    ),
    VarSpec::real_output(
        vr::WS_YAW,
        "ws_yaw",
        "rad",
        0.0,
        "Leading wheelset yaw angle",
    ),
    VarSpec::real_output(
        vr::WS_VY,
        "ws_vy",
        "m/s",
        0.0,
        "Leading wheelset lateral velocity",
    ),
    VarSpec::real_output(
        vr::WS_YAW_RATE_TRUE,
        "ws_yaw_rate_true",
        "rad/s",
        0.0,
        "Leading wheelset yaw rate (no noise)",
    ),
    VarSpec::real_output(
        vr::FRAME_Y,
        "frame_y",
        "m",
        0.0,
        "Leading bogie frame lateral displacement at the point above the leading wheelset",
    ),
    VarSpec::real_output(
        vr::FRAME_VY,
        "frame_vy",
        "m/s",
        0.0,
        "Lateral velocity of that point",
    ),
    VarSpec::real_output(
        vr::WS_ACC_Y_CLEAN,
        "ws_acc_y_clean",
        "m/s2",
        0.0,
        "ws_acc_y without noise",
    ),
    VarSpec::real_output(
        vr::FRAME_ACC_Y_CLEAN,
        "frame_acc_y_clean",
        "m/s2",
        0.0,
        "frame_acc_y without noise",
    ),
    VarSpec::real_output(
        vr::WS_ROLL,
        "ws_roll",
        "rad",
        0.0,
        "Leading wheelset roll (cross-level plus cone roll)",
    ),
    VarSpec::real_output(
        vr::BOGIE_Y,
        "bogie_y",
        "m",
        0.0,
        "Leading bogie frame lateral displacement (centre of gravity)",
    ),
    VarSpec::real_output(
        vr::BOGIE_ROLL,
        "bogie_roll",
        "rad",
        0.0,
        "Leading bogie frame roll",
    ),
    VarSpec::real_output(
        vr::BOGIE_YAW,
        "bogie_yaw",
        "rad",
        0.0,
        "Leading bogie frame yaw",
    ),
    VarSpec::real_output(
        vr::BODY_Y,
        "body_y",
        "m",
        0.0,
        "Car body lateral displacement",
    ),
    VarSpec::real_output(vr::BODY_ROLL, "body_roll", "rad", 0.0, "Car body roll"),
    VarSpec::real_output(vr::BODY_YAW, "body_yaw", "rad", 0.0, "Car body yaw"),
    VarSpec::real_output(
        vr::BODY_Z,
        "body_z",
        "m",
        0.0,
        "Car body bounce (from static equilibrium)",
    ),
    VarSpec::real_output_calculated(
        vr::WHEEL_LOAD_LEFT,
        "wheel_load_left",
        "N",
        "Normal load on the leading wheelset's left wheel (static load at the start)",
    ),
    VarSpec::real_output(
        vr::FORWARD_SPEED,
        "forward_speed",
        "m/s",
        0.0,
        "The speed the vehicle ran at over the last step (0 when standing): connect it to the estimator's speed",
    ),
    VarSpec::real_output_calculated(
        vr::WHEEL_LOAD_RIGHT,
        "wheel_load_right",
        "N",
        "Normal load on the leading wheelset's right wheel (static load at the start)",
    ),
    VarSpec::real_output(
        vr::WS_ROLL_RATE,
        "ws_roll_rate",
        "rad/s",
        0.0,
        "Roll gyroscope on the leading wheelset (rate of ws_roll, left side up positive), with noise",
    ),
    VarSpec::real_output(
        vr::WS_ROLL_RATE_TRUE,
        "ws_roll_rate_true",
        "rad/s",
        0.0,
        "Leading wheelset roll rate, the time derivative of ws_roll (no noise)",
    ),
    VarSpec::real_parameter(
        vr::CONICITY,
        "conicity",
        "1",
        0.0,
        "Tread conicity; 0 takes the vehicle file's value (0.1 for ML95)",
    )
    .min(0.0),
    VarSpec::real_parameter(
        vr::KALKER_SCALE,
        "kalker_scale",
        "1",
        1.0,
        "Multiplies every Kalker creep coefficient (0.5: the paper's -50 % case)",
    )
    .min(0.0),
    VarSpec::real_parameter(
        vr::HARMONIC_AMPLITUDE,
        "harmonic_amplitude",
        "m",
        0.0,
        "Amplitude of a harmonic alignment added to the track (the paper's resonance case: 0.001)",
    )
    .min(0.0),
    VarSpec::real_parameter(
        vr::HARMONIC_WAVELENGTH,
        "harmonic_wavelength",
        "m",
        15.66,
        "Wavelength of the harmonic alignment",
    )
    .min(0.0),
    VarSpec::real_parameter(
        vr::RAMP_LENGTH,
        "ramp_length",
        "m",
        10.0,
        "Irregularities fade in smoothly over this distance from the start",
    )
    .min(0.0),
    VarSpec::real_parameter(
        vr::MIN_WAVELENGTH,
        "min_wavelength",
        "m",
        1.0,
        "Shortest wavelength of the synthesized irregularities",
    )
    .min(0.0),
    VarSpec::real_parameter(
        vr::MAX_WAVELENGTH,
        "max_wavelength",
        "m",
        250.0,
        "Longest wavelength of the synthesized irregularities",
    )
    .min(0.0),
    VarSpec::real_parameter(
        vr::SIGMA_ACC,
        "sigma_acc",
        "m/s2",
        0.01,
        "Noise sigma of both accelerometers (per sample)",
    )
    .min(0.0),
    VarSpec::real_parameter(
        vr::SIGMA_GYRO,
        "sigma_gyro",
        "rad/s",
        0.0005,
        "Noise sigma of the yaw gyroscope (per sample)",
    )
    .min(0.0),
    VarSpec::real_parameter(
        vr::FRICTION,
        "friction",
        "1",
        0.4,
        "Wheel-rail friction coefficient (creep saturation only)",
    )
    .min(0.0),
    VarSpec::real_parameter(
        vr::FLANGE_CLEARANCE,
        "flange_clearance",
        "m",
        0.009,
        "Lateral free play before flange contact",
    )
    .min(0.0),
    VarSpec::real_parameter(
        vr::FLANGE_STIFFNESS,
        "flange_stiffness",
        "N/m",
        1.2e7,
        "Lateral stiffness of flange contact",
    )
    .min(0.0),
    VarSpec::real_parameter(
        vr::MAX_INTERNAL_STEP,
        "max_internal_step",
        "s",
        1e-3,
        "Largest internal Runge-Kutta step",
    )
    .min(1e-7),
    VarSpec::real_parameter(
        vr::MIN_SPEED,
        "min_speed",
        "m/s",
        0.5,
        "Below this speed the vehicle stands still",
    )
    .min(0.0),
    VarSpec::real_parameter(
        vr::SIGMA_ROLL_GYRO,
        "sigma_roll_gyro",
        "rad/s",
        0.0005,
        "Noise sigma of the wheelset roll gyroscope (per sample; its own random stream from noise_seed)",
    )
    .min(0.0),
    VarSpec::integer_parameter(
        vr::TRACK_SEED,
        "track_seed",
        1,
        "Seed of the synthesized track irregularities",
    )
    .min(0.0),
    VarSpec::integer_parameter(
        vr::CURVE_DIRECTION,
        "curve_direction",
        1,
        "One curve: 1 turns left, -1 turns right",
    )
    .min(-1.0)
    .max(1.0),
    VarSpec::integer_parameter(
        vr::SPECTRUM,
        "spectrum",
        1,
        "1: German low disturbance, 2: German high, 3: FRA class 5, 4: FRA class 6",
    )
    .min(1.0)
    .max(4.0),
    VarSpec::integer_parameter(vr::NOISE_SEED, "noise_seed", 2, "Seed of the sensor noise")
        .min(0.0),
    VarSpec::integer_parameter(
        vr::SENSOR_GRADE,
        "sensor_grade",
        0,
        "Sensor error preset: 0 the paper's ideal sensors; 1 tactical grade (Honeywell HG1700 class); 2 industrial MEMS (Xsens MTi-1 class): every sensor error parameter left at 0 takes the preset's value (docs/vehicle-fmu.md)",
    )
    .min(0.0)
    .max(2.0),
    VarSpec::real_parameter(vr::WS_ACC_Y_BIAS, "ws_acc_y_bias", "m/s2", 0.0, "Turn-on bias of the wheelset accelerometer, added to every sample (sensor errors: docs/vehicle-fmu.md)"),
    VarSpec::real_parameter(vr::WS_ACC_Y_BIAS_INSTABILITY, "ws_acc_y_bias_instability", "m/s2", 0.0, "Stationary standard deviation of the wheelset accelerometer's first-order Gauss-Markov bias (its own random stream; 0: none)").min(0.0),
    VarSpec::real_parameter(vr::WS_ACC_Y_BIAS_TAU, "ws_acc_y_bias_tau", "s", 0.0, "Correlation time of that Gauss-Markov bias").min(0.0),
    VarSpec::real_parameter(vr::WS_ACC_Y_SCALE_ERROR, "ws_acc_y_scale_error", "1", 0.0, "Scale factor error of the wheelset accelerometer (0.01: reads 1 % high)").min(-0.5).max(0.5),
    VarSpec::real_parameter(vr::WS_ACC_Y_MISALIGNMENT, "ws_acc_y_misalignment", "rad", 0.0, "Mounting misalignment of the wheelset accelerometer: its axis turned toward the coupled axis (vertical: gravity through a tilt)").min(-0.1).max(0.1),
    VarSpec::real_parameter(vr::WS_ACC_Y_NOISE_PSD, "ws_acc_y_noise_psd", "m2/s3", 0.0, "One-sided power spectral density of the wheelset accelerometer white noise (the square of the datasheet noise density); > 0 replaces the per-sample sigma by sqrt(psd x bandwidth), the bandwidth the Nyquist frequency of the step or the anti-alias filter's").min(0.0),
    VarSpec::real_parameter(vr::WS_ACC_Y_BANDWIDTH, "ws_acc_y_bandwidth", "Hz", 0.0, "Anti-alias cut-off of the wheelset accelerometer: 2nd-order Butterworth on every internal step (0: none)").min(0.0).max(2000.0),
    VarSpec::real_parameter(vr::WS_ACC_Y_RANGE, "ws_acc_y_range", "m/s2", 0.0, "Full scale of the wheelset accelerometer: saturation (0: none)").min(0.0),
    VarSpec::real_parameter(vr::WS_ACC_Y_RESOLUTION, "ws_acc_y_resolution", "m/s2", 0.0, "One LSB of the wheelset accelerometer: samples rounded to it (0: none)").min(0.0),
    VarSpec::real_parameter(vr::WS_YAW_RATE_BIAS, "ws_yaw_rate_bias", "rad/s", 0.0, "Turn-on bias of the yaw gyroscope, added to every sample (sensor errors: docs/vehicle-fmu.md)"),
    VarSpec::real_parameter(vr::WS_YAW_RATE_BIAS_INSTABILITY, "ws_yaw_rate_bias_instability", "rad/s", 0.0, "Stationary standard deviation of the yaw gyroscope's first-order Gauss-Markov bias (its own random stream; 0: none)").min(0.0),
    VarSpec::real_parameter(vr::WS_YAW_RATE_BIAS_TAU, "ws_yaw_rate_bias_tau", "s", 0.0, "Correlation time of that Gauss-Markov bias").min(0.0),
    VarSpec::real_parameter(vr::WS_YAW_RATE_SCALE_ERROR, "ws_yaw_rate_scale_error", "1", 0.0, "Scale factor error of the yaw gyroscope (0.01: reads 1 % high)").min(-0.5).max(0.5),
    VarSpec::real_parameter(vr::WS_YAW_RATE_MISALIGNMENT, "ws_yaw_rate_misalignment", "rad", 0.0, "Mounting misalignment of the yaw gyroscope: its axis turned toward the coupled axis (longitudinal: the roll rate)").min(-0.1).max(0.1),
    VarSpec::real_parameter(vr::WS_YAW_RATE_NOISE_PSD, "ws_yaw_rate_noise_psd", "rad2/s", 0.0, "One-sided power spectral density of the yaw gyroscope white noise (the square of the datasheet noise density); > 0 replaces the per-sample sigma by sqrt(psd x bandwidth), the bandwidth the Nyquist frequency of the step or the anti-alias filter's").min(0.0),
    VarSpec::real_parameter(vr::WS_YAW_RATE_BANDWIDTH, "ws_yaw_rate_bandwidth", "Hz", 0.0, "Anti-alias cut-off of the yaw gyroscope: 2nd-order Butterworth on every internal step (0: none)").min(0.0).max(2000.0),
    VarSpec::real_parameter(vr::WS_YAW_RATE_RANGE, "ws_yaw_rate_range", "rad/s", 0.0, "Full scale of the yaw gyroscope: saturation (0: none)").min(0.0),
    VarSpec::real_parameter(vr::WS_YAW_RATE_RESOLUTION, "ws_yaw_rate_resolution", "rad/s", 0.0, "One LSB of the yaw gyroscope: samples rounded to it (0: none)").min(0.0),
    VarSpec::real_parameter(vr::FRAME_ACC_Y_BIAS, "frame_acc_y_bias", "m/s2", 0.0, "Turn-on bias of the frame accelerometer, added to every sample (sensor errors: docs/vehicle-fmu.md)"),
    VarSpec::real_parameter(vr::FRAME_ACC_Y_BIAS_INSTABILITY, "frame_acc_y_bias_instability", "m/s2", 0.0, "Stationary standard deviation of the frame accelerometer's first-order Gauss-Markov bias (its own random stream; 0: none)").min(0.0),
    VarSpec::real_parameter(vr::FRAME_ACC_Y_BIAS_TAU, "frame_acc_y_bias_tau", "s", 0.0, "Correlation time of that Gauss-Markov bias").min(0.0),
    VarSpec::real_parameter(vr::FRAME_ACC_Y_SCALE_ERROR, "frame_acc_y_scale_error", "1", 0.0, "Scale factor error of the frame accelerometer (0.01: reads 1 % high)").min(-0.5).max(0.5),
    VarSpec::real_parameter(vr::FRAME_ACC_Y_MISALIGNMENT, "frame_acc_y_misalignment", "rad", 0.0, "Mounting misalignment of the frame accelerometer: its axis turned toward the coupled axis (vertical: gravity through a tilt)").min(-0.1).max(0.1),
    VarSpec::real_parameter(vr::FRAME_ACC_Y_NOISE_PSD, "frame_acc_y_noise_psd", "m2/s3", 0.0, "One-sided power spectral density of the frame accelerometer white noise (the square of the datasheet noise density); > 0 replaces the per-sample sigma by sqrt(psd x bandwidth), the bandwidth the Nyquist frequency of the step or the anti-alias filter's").min(0.0),
    VarSpec::real_parameter(vr::FRAME_ACC_Y_BANDWIDTH, "frame_acc_y_bandwidth", "Hz", 0.0, "Anti-alias cut-off of the frame accelerometer: 2nd-order Butterworth on every internal step (0: none)").min(0.0).max(2000.0),
    VarSpec::real_parameter(vr::FRAME_ACC_Y_RANGE, "frame_acc_y_range", "m/s2", 0.0, "Full scale of the frame accelerometer: saturation (0: none)").min(0.0),
    VarSpec::real_parameter(vr::FRAME_ACC_Y_RESOLUTION, "frame_acc_y_resolution", "m/s2", 0.0, "One LSB of the frame accelerometer: samples rounded to it (0: none)").min(0.0),
    VarSpec::real_parameter(vr::WS_ROLL_RATE_BIAS, "ws_roll_rate_bias", "rad/s", 0.0, "Turn-on bias of the roll gyroscope, added to every sample (sensor errors: docs/vehicle-fmu.md)"),
    VarSpec::real_parameter(vr::WS_ROLL_RATE_BIAS_INSTABILITY, "ws_roll_rate_bias_instability", "rad/s", 0.0, "Stationary standard deviation of the roll gyroscope's first-order Gauss-Markov bias (its own random stream; 0: none)").min(0.0),
    VarSpec::real_parameter(vr::WS_ROLL_RATE_BIAS_TAU, "ws_roll_rate_bias_tau", "s", 0.0, "Correlation time of that Gauss-Markov bias").min(0.0),
    VarSpec::real_parameter(vr::WS_ROLL_RATE_SCALE_ERROR, "ws_roll_rate_scale_error", "1", 0.0, "Scale factor error of the roll gyroscope (0.01: reads 1 % high)").min(-0.5).max(0.5),
    VarSpec::real_parameter(vr::WS_ROLL_RATE_MISALIGNMENT, "ws_roll_rate_misalignment", "rad", 0.0, "Mounting misalignment of the roll gyroscope: its axis turned toward the coupled axis (vertical: the yaw rate)").min(-0.1).max(0.1),
    VarSpec::real_parameter(vr::WS_ROLL_RATE_NOISE_PSD, "ws_roll_rate_noise_psd", "rad2/s", 0.0, "One-sided power spectral density of the roll gyroscope white noise (the square of the datasheet noise density); > 0 replaces the per-sample sigma by sqrt(psd x bandwidth), the bandwidth the Nyquist frequency of the step or the anti-alias filter's").min(0.0),
    VarSpec::real_parameter(vr::WS_ROLL_RATE_BANDWIDTH, "ws_roll_rate_bandwidth", "Hz", 0.0, "Anti-alias cut-off of the roll gyroscope: 2nd-order Butterworth on every internal step (0: none)").min(0.0).max(2000.0),
    VarSpec::real_parameter(vr::WS_ROLL_RATE_RANGE, "ws_roll_rate_range", "rad/s", 0.0, "Full scale of the roll gyroscope: saturation (0: none)").min(0.0),
    VarSpec::real_parameter(vr::WS_ROLL_RATE_RESOLUTION, "ws_roll_rate_resolution", "rad/s", 0.0, "One LSB of the roll gyroscope: samples rounded to it (0: none)").min(0.0),
    VarSpec::real_output(
        vr::DESIGN_CURVATURE,
        "design_curvature",
        "1/m",
        0.0,
        "Design curvature at the leading wheelset, positive when the track turns left (0 on straight track)",
    ),
    VarSpec::real_output(
        vr::DESIGN_CANT,
        "design_cant",
        "m",
        0.0,
        "Design cant at the leading wheelset: right rail above left (positive in a canted left-hand curve)",
    ),
    VarSpec::real_parameter(vr::CURVE_RADIUS, "curve_radius", "m", 0.0, "One curve on the line: radius of its circular part (0: straight track, or the line_file's line)").min(0.0),
    VarSpec::real_parameter(vr::CURVE_TRANSITION, "curve_transition", "m", 60.0, "One curve: length of each clothoid transition, along which the cant ramps linearly").min(0.0),
    VarSpec::real_parameter(vr::CURVE_LENGTH, "curve_length", "m", 200.0, "One curve: length of its circular part").min(0.0),
    VarSpec::real_parameter(vr::CURVE_CANT, "curve_cant", "m", 0.0, "One curve: cant of its circular part, raising the outer rail (at most 0.2)").min(0.0).max(crate::line::MAX_CANT),
    VarSpec::real_parameter(vr::LINE_ROUNDING, "line_rounding", "m", crate::line::DEFAULT_ROUNDING, "Length over which the design line's kinks (the ends of transitions and cant ramps) are rounded: a rail cannot kink").min(crate::line::MIN_ROUNDING).max(crate::line::MAX_ROUNDING),
    VarSpec::real_parameter(vr::CURVE_START, "curve_start", "m", 100.0, "One curve: distance at which its entry transition starts").min(0.0),
    VarSpec::boolean_parameter(
        vr::LATERAL_IRREGULARITY,
        "lateral_irregularity",
        true,
        "Stochastic alignment on",
    ),
    VarSpec::boolean_parameter(
        vr::VERTICAL_IRREGULARITY,
        "vertical_irregularity",
        true,
        "Stochastic vertical profile and cross-level on",
    ),
    VarSpec::boolean_parameter(
        vr::SENSOR_NOISE,
        "sensor_noise",
        true,
        "Gaussian noise on the sensor outputs",
    ),
    VarSpec::boolean_parameter(
        vr::CREEP_SATURATION,
        "creep_saturation",
        false,
        "Shen-Hedrick-Elkins saturation of the creep forces",
    ),
    VarSpec::boolean_parameter(
        vr::FLANGE_CONTACT,
        "flange_contact",
        false,
        "Flange contact (dead band plus stiffness)",
    ),
    VarSpec::string_parameter(
        vr::VEHICLE,
        "vehicle",
        "ml95.toml",
        "Vehicle parameter file: ml95.toml or manchester.toml in the resources, or an absolute path",
    ),
    VarSpec::string_parameter(
        vr::TRACK_FILE,
        "track_file",
        "",
        "Measured track CSV (distance, alignment, vertical, cross_level); empty: synthesize",
    ),
    VarSpec::string_parameter(
        vr::LINE_FILE,
        "line_file",
        "",
        "Design line CSV (distance, curvature, cant): curves with transitions and cant under the irregularities; empty: straight, or the curve_* parameters",
    ),
];

/// The most one fmi2DoStep may ask for: the track grid grows to cover the distance (72 bytes
/// per 5 cm) and the integration takes `h / internal step` Runge-Kutta steps, so a step of 1e9 s
/// (or a speed of 1e300 m/s) aborted the process on a failed allocation or never returned
/// (found by fmi-fuzz). 20 km and a million internal steps are far beyond any sensible
/// communication step and still finish in seconds.
const MAX_STEP_DISTANCE: f64 = 2e4;
const MAX_SUBSTEPS: f64 = 1e6;

/// How far past the flange clearance the leading wheelset may move laterally relative to the
/// track before the run is stopped as a derailment \[m\]. A wheel flange is about 30 mm high
/// and wide: a wheelset whose lateral displacement relative to the rails exceeds the clearance by
/// that much has climbed the rail. The model has no such contact (its flange is a linear
/// spring), so it would go on computing a physically impossible state: the ML95 with its Kalker
/// coefficients halved reaches 0.37 m at 30 m/s (hunting).
pub const DERAILMENT_MARGIN: f64 = 0.03;

/// The word every derailment error starts with (`derailed: the leading wheelset is ...`), for
/// callers that treat it as a result (an unstable running condition) rather than a failure.
pub const DERAILED: &str = "derailed";

/// Whether `message`, as an importer receives it from this FMU's log, reports a derailment.
/// FMI carries an FMU's failure to its importer as text only (fmi2DoStep returns fmi2Error and
/// the reason is the message logged with it; the export layer puts `fmi2DoStep at t=T: ` in
/// front of the model's text), so this is the one place that reads that text: the message has
/// a `: `-separated part that is exactly [`DERAILED`].
pub fn is_derailment(message: &str) -> bool {
    message.starts_with(&format!("{DERAILED}: ")) || message.contains(&format!(": {DERAILED}: "))
}

/// The FMI model state.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RailVehicle {
    resources: Option<PathBuf>,
    sim: Option<Simulation>,
}

impl RailVehicle {
    fn load_params(&self, name: &str) -> Result<VehicleParams, String> {
        VehicleParams::named(name, self.resources.as_deref())
    }

    fn write_outputs(&self, v: &mut Values) {
        let Some(sim) = &self.sim else { return };
        let o = &sim.outputs;
        let r = &mut v.real;
        for (i, x) in [
            (vr::WS_ACC_Y, o.ws_acc_y),
            (vr::WS_YAW_RATE, o.ws_yaw_rate),
            (vr::FRAME_ACC_Y, o.frame_acc_y),
            (vr::DISTANCE, o.distance),
            (vr::ALIGNMENT, o.alignment),
            (vr::VERTICAL_PROFILE, o.vertical_profile),
            (vr::CROSS_LEVEL, o.cross_level),
            (vr::WS_Y, o.ws_y),
            (vr::WS_YAW, o.ws_yaw),
            (vr::WS_VY, o.ws_vy),
            (vr::WS_YAW_RATE_TRUE, o.ws_yaw_rate_clean),
            (vr::FRAME_Y, o.frame_y),
            (vr::FRAME_VY, o.frame_vy),
            (vr::WS_ACC_Y_CLEAN, o.ws_acc_y_clean),
            (vr::FRAME_ACC_Y_CLEAN, o.frame_acc_y_clean),
            (vr::WS_ROLL, o.ws_roll),
            (vr::BOGIE_Y, o.bogie_y),
            (vr::BOGIE_ROLL, o.bogie_roll),
            (vr::BOGIE_YAW, o.bogie_yaw),
            (vr::BODY_Y, o.body_y),
            (vr::BODY_ROLL, o.body_roll),
            (vr::BODY_YAW, o.body_yaw),
            (vr::BODY_Z, o.body_z),
            (vr::WHEEL_LOAD_LEFT, o.wheel_load_left),
            (vr::WHEEL_LOAD_RIGHT, o.wheel_load_right),
            (vr::FORWARD_SPEED, o.forward_speed),
            (vr::WS_ROLL_RATE, o.ws_roll_rate),
            (vr::WS_ROLL_RATE_TRUE, o.ws_roll_rate_clean),
            (vr::DESIGN_CURVATURE, o.design_curvature),
            (vr::DESIGN_CANT, o.design_cant),
        ] {
            r[i as usize] = x;
        }
    }
}

/// Builds the simulation from the FMI parameter values (shared with tests and tools).
pub fn build_simulation(
    model: &RailVehicle,
    v: &Values,
    log: &Logger,
) -> Result<Simulation, String> {
    let real = |i: u32| v.real[i as usize];
    let int = |i: u32| v.integer[i as usize];
    let boolean = |i: u32| v.boolean[i as usize];
    let params = model.load_params(&v.string[vr::VEHICLE as usize])?;
    let conicity = if real(vr::CONICITY) > 0.0 {
        real(vr::CONICITY)
    } else {
        params.wheelset.conicity
    };
    let options = ContactOptions {
        kalker_scale: real(vr::KALKER_SCALE),
        saturation: boolean(vr::CREEP_SATURATION),
        friction: real(vr::FRICTION),
        flange: boolean(vr::FLANGE_CONTACT),
        flange_clearance: real(vr::FLANGE_CLEARANCE),
        flange_stiffness: real(vr::FLANGE_STIFFNESS),
        normal_force_lateral: true,
        cone_roll: true,
    };
    if options.kalker_scale <= 0.0 {
        return Err(format!(
            "parameter 'kalker_scale' = {} must be positive",
            options.kalker_scale
        ));
    }
    let vehicle = Vehicle::new(params, conicity, options);
    let track_file = v.string[vr::TRACK_FILE as usize].trim().to_string();
    // The first 25 s of track at the start speed (the grid grows as the vehicle runs, with
    // the same nodes a longer first synthesis would have made). Capped: a speed input of
    // 1e300 made this terabytes (an aborted allocation, found by fmi-fuzz). A NaN speed takes
    // the lower bound (`clamp` would pass the NaN through).
    let start = real(vr::SPEED).abs();
    let speed = if start.is_nan() {
        20.0
    } else {
        start.clamp(20.0, 100.0)
    };
    let (s_min, s_max) = (-vehicle.wheelset_offset(3) - 5.0, 25.0 * speed + 50.0);
    let track = if track_file.is_empty() {
        let (min_wl, max_wl) = (real(vr::MIN_WAVELENGTH), real(vr::MAX_WAVELENGTH));
        if !(min_wl > 0.0 && max_wl > min_wl) {
            return Err(format!(
                "parameters 'min_wavelength' = {min_wl} and 'max_wavelength' = {max_wl} must satisfy 0 < min < max"
            ));
        }
        let harmonic = real(vr::HARMONIC_AMPLITUDE);
        if harmonic > 0.0 && !(real(vr::HARMONIC_WAVELENGTH) > 0.0) {
            return Err(
                "parameter 'harmonic_wavelength' must be positive when harmonic_amplitude is set"
                    .into(),
            );
        }
        let spec = TrackSpec {
            spectrum: Spectrum::from_fmi(int(vr::SPECTRUM))?,
            seed: int(vr::TRACK_SEED) as u64,
            lateral: boolean(vr::LATERAL_IRREGULARITY),
            vertical: boolean(vr::VERTICAL_IRREGULARITY),
            harmonic_amplitude: harmonic,
            harmonic_wavelength: real(vr::HARMONIC_WAVELENGTH),
            min_wavelength: min_wl,
            max_wavelength: max_wl,
        };
        spec.validate()?;
        Track::generate(&spec, s_min, s_max)
    } else {
        let path = resource_path(model, &track_file);
        log.info(&format!("track from {}", path.display()));
        Track::from_csv(&path)?
    };
    let line = design_line(model, v, log)?;
    let config = SimConfig {
        max_internal_step: real(vr::MAX_INTERNAL_STEP),
        ramp_length: real(vr::RAMP_LENGTH),
        min_speed: real(vr::MIN_SPEED).max(1e-3),
    };
    let noise = SensorNoise {
        enabled: boolean(vr::SENSOR_NOISE),
        sigma_acc: real(vr::SIGMA_ACC),
        sigma_gyro: real(vr::SIGMA_GYRO),
        sigma_roll_gyro: real(vr::SIGMA_ROLL_GYRO),
    };
    let grade = int(vr::SENSOR_GRADE);
    let preset = crate::sensors::preset(grade)
        .ok_or_else(|| format!("parameter 'sensor_grade' = {grade}: 0, 1 or 2"))?;
    let first = [
        vr::WS_ACC_Y_BIAS,
        vr::WS_YAW_RATE_BIAS,
        vr::FRAME_ACC_Y_BIAS,
        vr::WS_ROLL_RATE_BIAS,
    ];
    let mut spec = preset;
    for (i, base) in first.into_iter().enumerate() {
        // Nine parameters per sensor, in SensorSpec's field order; one set to anything but 0
        // wins over the preset.
        let p = &mut spec[i];
        let fields = [
            &mut p.bias,
            &mut p.bias_instability,
            &mut p.bias_tau,
            &mut p.scale_error,
            &mut p.misalignment,
            &mut p.noise_density,
            &mut p.bandwidth,
            &mut p.range,
            &mut p.resolution,
        ];
        for (k, field) in fields.into_iter().enumerate() {
            let value = real(base + k as u32);
            if value != 0.0 {
                // The noise is given as a PSD (integer SI exponents), kept as its density.
                *field = if k == 5 { value.sqrt() } else { value };
            }
        }
        if p.bias_instability > 0.0 && !(p.bias_tau > 0.0) {
            return Err(format!(
                "parameter '{}_bias_tau' must be positive when {}_bias_instability is set",
                crate::sensors::NAMES[i],
                crate::sensors::NAMES[i]
            ));
        }
    }
    Ok(
        Simulation::new(vehicle, track, config, noise, int(vr::NOISE_SEED) as u64)
            .with_sensors(spec)
            .with_line(line),
    )
}

/// A file name as the FMU's String parameters take it: absolute, or relative to the resources.
fn resource_path(model: &RailVehicle, name: &str) -> PathBuf {
    let path = PathBuf::from(name);
    if path.is_absolute() {
        path
    } else {
        model
            .resources
            .as_ref()
            .map(|d| d.join(&path))
            .unwrap_or(path)
    }
}

/// The design line: `line_file`, or one curve from the `curve_*` parameters, or straight.
fn design_line(model: &RailVehicle, v: &Values, log: &Logger) -> Result<DesignLine, String> {
    let file = v.string[vr::LINE_FILE as usize].trim();
    let radius = v.real[vr::CURVE_RADIUS as usize];
    let rounding = v.real[vr::LINE_ROUNDING as usize];
    if !(crate::line::MIN_ROUNDING..=crate::line::MAX_ROUNDING).contains(&rounding) {
        return Err(format!(
            "parameter 'line_rounding' = {rounding} m must lie in 1-100 m"
        ));
    }
    if !file.is_empty() {
        if radius != 0.0 {
            return Err(format!(
                "parameters 'line_file' = '{file}' and 'curve_radius' = {radius} m both give a design line: set one"
            ));
        }
        let path = resource_path(model, file);
        log.info(&format!("design line from {}", path.display()));
        return DesignLine::from_csv(&path, rounding);
    }
    if radius == 0.0 {
        return Ok(DesignLine::straight());
    }
    DesignLine::one_curve(
        &OneCurve {
            start: v.real[vr::CURVE_START as usize],
            radius,
            transition: v.real[vr::CURVE_TRANSITION as usize],
            length: v.real[vr::CURVE_LENGTH as usize],
            cant: v.real[vr::CURVE_CANT as usize],
            direction: f64::from(v.integer[vr::CURVE_DIRECTION as usize]),
        },
        rounding,
    )
}

impl Model for RailVehicle {
    const INFO: ModelInfo = ModelInfo {
        model_name: "RailVehicle",
        model_identifier: "RailVehicle",
        // By build.rs from the sources and what shapes the modelDescription: new when they change.
        guid: env!("VEHICLE_GUID"),
        description: "A metro car (car body, two bogies, four wheelsets) on an irregular straight or curved track with lateral and vertical dynamics, Kalker creep and virtual inertial sensors.",
        author: "railway track-geometry toolkit",
        version: env!("CARGO_PKG_VERSION"),
        default_start: 0.0,
        default_stop: 20.0,
        default_step: 0.001,
    };
    /// A fingerprint of the sources, by build.rs: a state saved by another build is refused.
    const STATE_LAYOUT: &'static str = env!("VEHICLE_STATE_LAYOUT");

    fn variables() -> &'static [VarSpec] {
        VARIABLES
    }

    fn instantiate(ctx: &InstantiateContext, _log: &Logger) -> Result<Self, String> {
        Ok(RailVehicle {
            resources: ctx.resources.clone(),
            sim: None,
        })
    }

    /// The wheel loads start at the static load of the chosen vehicle.
    fn calculate_initial(&mut self, v: &mut Values) {
        if let Ok(p) = self.load_params(&v.string[vr::VEHICLE as usize]) {
            let load = Vehicle::new(p, 0.1, ContactOptions::default()).static_wheel_load[0];
            v.real[vr::WHEEL_LOAD_LEFT as usize] = load;
            v.real[vr::WHEEL_LOAD_RIGHT as usize] = load;
        }
    }

    fn exit_initialization(&mut self, v: &mut Values, log: &Logger) -> Result<(), String> {
        let sim = build_simulation(self, v, log)?;
        self.sim = Some(sim);
        self.write_outputs(v);
        Ok(())
    }

    fn do_step(
        &mut self,
        v: &mut Values,
        _t: f64,
        h: f64,
        log: &Logger,
    ) -> Result<StepOutcome, String> {
        let speed = v.real[vr::SPEED as usize];
        let sim = self.sim.as_mut().ok_or("not initialized")?;
        let mut outcome = StepOutcome::Ok;
        if !speed.is_finite() || speed < 0.0 {
            log.warning(&format!(
                "speed input {speed} is not a finite non-negative number: the vehicle is held"
            ));
            outcome = StepOutcome::Warning;
        }
        if speed.is_finite() && speed >= sim.config.min_speed {
            let distance = speed * h;
            let substeps = h / sim.internal_step(speed);
            if !(distance <= MAX_STEP_DISTANCE && substeps <= MAX_SUBSTEPS) {
                return Err(format!(
                    "a step of {h} s at {speed} m/s would cover {distance:.3e} m in {substeps:.3e} internal steps; \
                     one fmi2DoStep may cover at most {MAX_STEP_DISTANCE:e} m and {MAX_SUBSTEPS:e} internal steps"
                ));
            }
        }
        sim.step(h, if speed.is_finite() { speed } else { 0.0 });
        let o = &sim.outputs;
        if ![o.ws_acc_y, o.ws_yaw_rate, o.frame_acc_y, o.ws_y]
            .iter()
            .all(|x| x.is_finite())
        {
            return Err(format!(
                "the vehicle state became non-finite at distance {} m",
                sim.s
            ));
        }
        let relative = o.ws_y - o.alignment;
        let limit = v.real[vr::FLANGE_CLEARANCE as usize] + DERAILMENT_MARGIN;
        if relative.abs() > limit {
            return Err(format!(
                "{DERAILED}: the leading wheelset is {:.1} mm off the track centre line at distance {:.1} m \
                 (flange clearance {:.1} mm + {:.0} mm of flange): the vehicle is unstable at {speed} m/s \
                 with these parameters (hunting), and the model cannot go on",
                relative * 1e3,
                sim.s,
                v.real[vr::FLANGE_CLEARANCE as usize] * 1e3,
                DERAILMENT_MARGIN * 1e3
            ));
        }
        self.write_outputs(v);
        Ok(outcome)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_derailment_is_read_from_its_message_only() {
        // As an importer logs it: fmi-abi's prefix, then do_step's text.
        assert!(is_derailment(
            "fmi2DoStep at t=12.5: derailed: the leading wheelset is 39.4 mm off the track centre line"
        ));
        assert!(is_derailment(
            "derailed: the leading wheelset is 39.4 mm off"
        ));
        for other in [
            "fmi2DoStep at t=1: the vehicle state became non-finite at distance 3 m",
            "fmi2DoStep at t=1: the vehicle derailed",
            "underailed: x",
            "fmi2DoStep at t=1: not derailed: x",
        ] {
            assert!(!is_derailment(other), "{other}");
        }
    }

    #[test]
    fn absurd_steps_and_speeds_are_refused_instead_of_attempted() {
        let ctx = InstantiateContext {
            instance_name: "t".into(),
            resources: None,
        };
        let log = Logger::silent();
        let mut m = RailVehicle::instantiate(&ctx, &log).unwrap();
        let mut v = Values::from_table(VARIABLES);
        v.boolean[vr::LATERAL_IRREGULARITY as usize] = false;
        v.boolean[vr::VERTICAL_IRREGULARITY as usize] = false;
        // A start speed of 1e300 used to ask for a track of 2.5e301 m.
        v.real[vr::SPEED as usize] = 1e300;
        m.exit_initialization(&mut v, &log).unwrap();
        let e = m.do_step(&mut v, 0.0, 1e-3, &log).unwrap_err();
        assert!(e.contains("at most"), "{e}");
        // A step of 1e9 s at 20 m/s: an allocation of terabytes before.
        v.real[vr::SPEED as usize] = 20.0;
        let e = m.do_step(&mut v, 0.0, 1e9, &log).unwrap_err();
        assert!(e.contains("at most"), "{e}");
        // Standing still, any step is harmless and allowed; a normal step still works.
        v.real[vr::SPEED as usize] = 0.0;
        assert!(m.do_step(&mut v, 0.0, 1e9, &log).is_ok());
        v.real[vr::SPEED as usize] = 20.0;
        assert!(m.do_step(&mut v, 1e9, 1e-3, &log).is_ok());
    }

    #[test]
    fn the_variable_table_is_dense_and_the_model_description_valid() {
        fmi_abi::variables::VarIndex::new(super::VARIABLES).unwrap();
        let md = crate::model_description();
        assert_eq!(md.validate(), vec![]);
        assert_eq!(
            model_description::ModelDescription::from_xml(&md.to_xml()).unwrap(),
            md
        );
    }
}
