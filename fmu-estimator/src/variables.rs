//! The estimator FMU's variable table: every value reference and variable, with its default
//! and description, in one place (the role of `config.h` in the Modelica Reference-FMUs). The
//! FMI layer (`fmu`), the configuration (`config`) and offline processing (`offline`) all read
//! it; it depends on none of them.

use crate::params::Params;
use crate::prior::Spectrum;
use fmi_abi::VarSpec;

/// The `calibration_file` parameter's default: the file shipped in the resources.
pub const DEFAULT_CALIBRATION_FILE: &str = "calibration.toml";

/// `min_speed`'s default \[m/s\]: below it the creep terms, which divide by the speed, are not
/// trusted and the estimate is held.
pub const MIN_SPEED_DEFAULT: f64 = 0.5;

/// Value references, dense from 0 within each base type (so a Real and an Integer may share a
/// number). Each names its FMI variable; what the variable means and its start value are in
/// [`VARIABLES`].
pub mod vr {
    /// `ws_acc_y` (Real input, m/s2).
    pub const WS_ACC_Y: u32 = 0;
    /// `ws_yaw_rate` (Real input, rad/s).
    pub const WS_YAW_RATE: u32 = 1;
    /// `frame_acc_y` (Real input, m/s2).
    pub const FRAME_ACC_Y: u32 = 2;
    /// `speed` (Real input, m/s).
    pub const SPEED: u32 = 3;
    /// `alignment` (Real output, m).
    pub const ALIGNMENT: u32 = 4;
    /// `alignment_std` (Real output, calculated at initialization, m).
    pub const ALIGNMENT_STD: u32 = 5;
    /// `distance` (Real output, m).
    pub const DISTANCE: u32 = 6;
    /// `est_y` (Real output, m).
    pub const EST_Y: u32 = 7;
    /// `est_psi` (Real output, rad).
    pub const EST_PSI: u32 = 8;
    /// `est_y_f` (Real output, m).
    pub const EST_Y_F: u32 = 9;
    /// `est_vy` (Real output, m/s).
    pub const EST_VY: u32 = 10;
    /// `est_psi_rate` (Real output, rad/s).
    pub const EST_PSI_RATE: u32 = 11;
    /// `est_vy_f` (Real output, m/s).
    pub const EST_VY_F: u32 = 12;
    /// `nis` (Real output, dimensionless).
    pub const NIS: u32 = 13;
    /// `m` (Real parameter, kg).
    pub const M: u32 = 14;
    /// `I` (Real parameter, kg.m2).
    pub const I: u32 = 15;
    /// `l` (Real parameter, m).
    pub const L: u32 = 16;
    /// `l_s` (Real parameter, m).
    pub const L_S: u32 = 17;
    /// `alpha` (Real parameter, dimensionless).
    pub const ALPHA: u32 = 18;
    /// `r_0` (Real parameter, m).
    pub const R_0: u32 = 19;
    /// `m_f` (Real parameter, kg).
    pub const M_F: u32 = 20;
    /// `f11` (Real parameter, N).
    pub const F11: u32 = 21;
    /// `f22` (Real parameter, N).
    pub const F22: u32 = 22;
    /// `f23` (Real parameter, N.m).
    pub const F23: u32 = 23;
    /// `f33` (Real parameter, N.m2).
    pub const F33: u32 = 24;
    /// `kx` (Real parameter, N/m).
    pub const KX: u32 = 25;
    /// `cx` (Real parameter, N.s/m).
    pub const CX: u32 = 26;
    /// `ky` (Real parameter, N/m).
    pub const KY: u32 = 27;
    /// `cy` (Real parameter, N.s/m).
    pub const CY: u32 = 28;
    /// `g` (Real parameter, m/s2).
    pub const G: u32 = 29;
    /// `sigma_acc_ws` (Real parameter, m/s2).
    pub const SIGMA_ACC_WS: u32 = 30;
    /// `sigma_yaw_rate` (Real parameter, rad/s).
    pub const SIGMA_YAW_RATE: u32 = 31;
    /// `sigma_acc_frame` (Real parameter, m/s2).
    pub const SIGMA_ACC_FRAME: u32 = 32;
    /// `sigma_xi` (Real parameter, m).
    pub const SIGMA_XI: u32 = 33;
    /// `q_acc_ws` (Real parameter, m2/s3).
    pub const Q_ACC_WS: u32 = 34;
    /// `q_yaw_acc` (Real parameter, rad2/s3).
    pub const Q_YAW_ACC: u32 = 35;
    /// `q_acc_frame` (Real parameter, m2/s3).
    pub const Q_ACC_FRAME: u32 = 36;
    /// `q_xi` (Real parameter, m2/s).
    pub const Q_XI: u32 = 37;
    /// `p0_xi` (Real parameter, m).
    pub const P0_XI: u32 = 38;
    /// `min_speed` (Real parameter, m/s).
    pub const MIN_SPEED: u32 = 39;
    /// `prior_a` (Real parameter, m.rad).
    pub const PRIOR_A: u32 = 40;
    /// `prior_omega_r` (Real parameter, rad/m).
    pub const PRIOR_OMEGA_R: u32 = 41;
    /// `prior_omega_c` (Real parameter, rad/m).
    pub const PRIOR_OMEGA_C: u32 = 42;
    /// `prior_sigma_xi` (Real parameter, m).
    pub const PRIOR_SIGMA_XI: u32 = 43;
    /// `est_xi_rate` (Real output, m/s).
    pub const EST_XI_RATE: u32 = 44;
    /// `design_speed` (Real parameter, m/s).
    pub const DESIGN_SPEED: u32 = 45;
    /// `ws_roll_rate` (Real input, rad/s).
    pub const WS_ROLL_RATE: u32 = 46;
    /// `lag` (Real parameter, m).
    pub const LAG: u32 = 47;
    /// `alignment_lagged` (Real output, m).
    pub const ALIGNMENT_LAGGED: u32 = 48;
    /// `alignment_lagged_std` (Real output, calculated at initialization, m).
    pub const ALIGNMENT_LAGGED_STD: u32 = 49;
    /// `distance_lagged` (Real output, calculated at initialization, m).
    pub const DISTANCE_LAGGED: u32 = 50;
    /// `alignment_kalman` (Real output, m).
    pub const ALIGNMENT_KALMAN: u32 = 51;
    /// `contact_scale` (Real output, dimensionless).
    pub const CONTACT_SCALE: u32 = 52;
    /// `conicity` (Real parameter, dimensionless).
    pub const CONICITY: u32 = 53;
    /// `conicity_estimate` (Real output, dimensionless).
    pub const CONICITY_ESTIMATE: u32 = 54;
    /// `novelty` (Real output, dimensionless).
    pub const NOVELTY: u32 = 55;
    /// `kalker_scale` (Real parameter, dimensionless).
    pub const KALKER_SCALE: u32 = 56;
    /// `bias_sigma_ws_acc_y` (Real parameter, m/s2).
    pub const BIAS_SIGMA_WS_ACC_Y: u32 = 57;
    /// `bias_sigma_ws_yaw_rate` (Real parameter, rad/s).
    pub const BIAS_SIGMA_WS_YAW_RATE: u32 = 58;
    /// `bias_sigma_frame_acc_y` (Real parameter, m/s2).
    pub const BIAS_SIGMA_FRAME_ACC_Y: u32 = 59;
    /// `bias_sigma_ws_roll_rate` (Real parameter, rad/s).
    pub const BIAS_SIGMA_WS_ROLL_RATE: u32 = 60;
    /// `ws_acc_y_bias` (Real output, m/s2).
    pub const WS_ACC_Y_BIAS: u32 = 61;
    /// `ws_yaw_rate_bias` (Real output, rad/s).
    pub const WS_YAW_RATE_BIAS: u32 = 62;
    /// `frame_acc_y_bias` (Real output, m/s2).
    pub const FRAME_ACC_Y_BIAS: u32 = 63;
    /// `ws_roll_rate_bias` (Real output, rad/s).
    pub const WS_ROLL_RATE_BIAS: u32 = 64;
    /// `design_curvature` (Real input, 1/m).
    pub const DESIGN_CURVATURE: u32 = 65;
    /// `design_cant` (Real input, m).
    pub const DESIGN_CANT: u32 = 66;
    /// `line_rounding` (Real parameter, m).
    pub const LINE_ROUNDING: u32 = 67;
    /// `line_start` (Real parameter, m).
    pub const LINE_START: u32 = 68;
    /// `heading_change` (Real output, rad).
    pub const HEADING_CHANGE: u32 = 69;
    /// `relative_velocity_change` (Real output, m/s).
    pub const RELATIVE_VELOCITY_CHANGE: u32 = 70;
    /// `heading_level` (Real output, rad).
    pub const HEADING_LEVEL: u32 = 71;
    // Integer
    /// `discretization` (Integer parameter).
    pub const DISCRETIZATION: u32 = 0;
    /// `skipped_updates` (Integer output).
    pub const SKIPPED_UPDATES: u32 = 1;
    /// `rebuilds` (Integer output).
    pub const REBUILDS: u32 = 2;
    /// `alignment_model` (Integer parameter).
    pub const ALIGNMENT_MODEL: u32 = 3;
    /// `gain` (Integer parameter).
    pub const GAIN: u32 = 4;
    /// `estimator` (Integer parameter).
    pub const ESTIMATOR: u32 = 5;
    /// `active_estimator` (Integer output).
    pub const ACTIVE_ESTIMATOR: u32 = 6;
    // Boolean
    /// `use_calibration_file` (Boolean parameter).
    pub const USE_CALIBRATION_FILE: u32 = 0;
    /// `updated` (Boolean output).
    pub const UPDATED: u32 = 1;
    /// `p0_stationary` (Boolean parameter).
    pub const P0_STATIONARY: u32 = 2;
    /// `use_roll_rate` (Boolean parameter).
    pub const USE_ROLL_RATE: u32 = 3;
    /// `allow_other_kalman` (Boolean parameter).
    pub const ALLOW_OTHER_KALMAN: u32 = 4;
    /// `outside_training` (Boolean output).
    pub const OUTSIDE_TRAINING: u32 = 5;
    // String
    /// `calibration_file` (String parameter).
    pub const CALIBRATION_FILE: u32 = 0;
    /// `tap_file` (String parameter).
    pub const TAP_FILE: u32 = 1;
    /// `design_response_file` (String parameter).
    pub const DESIGN_RESPONSE_FILE: u32 = 2;
    /// `line_file` (String parameter).
    pub const LINE_FILE: u32 = 3;
}

const P: Params = Params::DEFAULTS;
const P_SIGMA_XI: f64 = crate::params::PRIOR_SIGMA_XI;

/// The variable table: the single source of the FMU's interface (see `fmi_abi::variables`).
pub static VARIABLES: &[VarSpec] = &[
    VarSpec::real_input(vr::WS_ACC_Y, "ws_acc_y", "m/s2", 0.0, "Wheelset lateral acceleration (accelerometer on the axle box)"),
    VarSpec::real_input(vr::WS_YAW_RATE, "ws_yaw_rate", "rad/s", 0.0, "Wheelset yaw angular velocity (gyroscope)"),
    VarSpec::real_input(vr::FRAME_ACC_Y, "frame_acc_y", "m/s2", 0.0, "Bogie frame lateral acceleration above the wheelset (accelerometer)"),
    VarSpec::real_input(vr::SPEED, "speed", "m/s", 20.0, "Forward speed of the vehicle; below min_speed the estimate is held"),
    VarSpec::real_output(vr::ALIGNMENT, "alignment", "m", 0.0, "Estimated lateral alignment of the track at the wheelset"),
    VarSpec::real_output_calculated(vr::ALIGNMENT_STD, "alignment_std", "m", "Standard deviation of the alignment estimate (square root of P[7,7])"),
    VarSpec::real_output(vr::DISTANCE, "distance", "m", 0.0, "Distance travelled, integrated from speed (rectangle rule, speed sampled at the end of each step)"),
    VarSpec::real_output(vr::EST_Y, "est_y", "m", 0.0, "Estimated wheelset lateral displacement from the ideal track centre line"),
    VarSpec::real_output(vr::EST_PSI, "est_psi", "rad", 0.0, "Estimated wheelset yaw angle"),
    VarSpec::real_output(vr::EST_Y_F, "est_y_f", "m", 0.0, "Estimated suspended frame lateral displacement"),
    VarSpec::real_output(vr::EST_VY, "est_vy", "m/s", 0.0, "Estimated wheelset lateral velocity"),
    VarSpec::real_output(vr::EST_PSI_RATE, "est_psi_rate", "rad/s", 0.0, "Estimated wheelset yaw rate"),
    VarSpec::real_output(vr::EST_VY_F, "est_vy_f", "m/s", 0.0, "Estimated suspended frame lateral velocity"),
    VarSpec::real_output(vr::NIS, "nis", "1", 0.0, "Normalized innovation squared of the last update (chi-square with 4 degrees of freedom when the filter is consistent)"),
    VarSpec::real_parameter(vr::M, "m", "kg", P.m, "Wheelset mass (Table 2, or the calibration file)").min(0.0),
    VarSpec::real_parameter(vr::I, "I", "kg.m2", P.i, "Wheelset yaw moment of inertia (Table 2, or the calibration file)").min(0.0),
    VarSpec::real_parameter(vr::L, "l", "m", P.l, "Half the distance between the wheel-rail contact points (Table 2, or the calibration file)").min(0.0),
    VarSpec::real_parameter(vr::L_S, "l_s", "m", P.l_s, "Half the distance between the longitudinal primary suspension elements (Table 2, or the calibration file)").min(0.0),
    VarSpec::real_parameter(vr::ALPHA, "alpha", "1", P.alpha, "Nominal conicity of the wheel treads (Table 2, or the calibration file)").min(0.0),
    VarSpec::real_parameter(vr::R_0, "r_0", "m", P.r_0, "Rolling radius of the centred wheelset; Table 2 prints 0.85 m, the wheel diameter (see docs)").min(0.0),
    VarSpec::real_parameter(vr::M_F, "m_f", "kg", P.m_f, "Suspended mass carried by the wheelset: quarter car body plus half bogie frame (Table 2, or the calibration file)").min(0.0),
    VarSpec::real_parameter(vr::F11, "f11", "N", P.f11, "Kalker longitudinal creep coefficient per wheel (Table 2, or the calibration file)").min(0.0),
    VarSpec::real_parameter(vr::F22, "f22", "N", P.f22, "Kalker lateral creep coefficient per wheel (Table 2, or the calibration file)").min(0.0),
    VarSpec::real_parameter(vr::F23, "f23", "N.m", P.f23, "Kalker lateral/spin creep coefficient per wheel (Table 2, or the calibration file)").min(0.0),
    VarSpec::real_parameter(vr::F33, "f33", "N.m2", P.f33, "Kalker spin creep coefficient per wheel (Table 2, or the calibration file)").min(0.0),
    VarSpec::real_parameter(vr::KX, "kx", "N/m", P.kx, "Longitudinal primary stiffness per side at +/- l_s (identified; Table 2 until calibrated)").min(0.0),
    VarSpec::real_parameter(vr::CX, "cx", "N.s/m", P.cx, "Longitudinal primary damping per side at +/- l_s (identified; Table 2 until calibrated)").min(0.0),
    VarSpec::real_parameter(vr::KY, "ky", "N/m", P.ky, "Lateral primary stiffness, wheelset to frame (identified; Table 2 until calibrated)").min(0.0),
    VarSpec::real_parameter(vr::CY, "cy", "N.s/m", P.cy, "Lateral primary damping, wheelset to frame (identified; Table 2 until calibrated)").min(0.0),
    VarSpec::real_parameter(vr::G, "g", "m/s2", P.g, "Gravitational acceleration (gravitational stiffness W alpha / l)").min(0.0),
    VarSpec::real_parameter(vr::SIGMA_ACC_WS, "sigma_acc_ws", "m/s2", 0.01, "Noise sigma of the wheelset accelerometer (R, diagonal model)").min(0.0),
    VarSpec::real_parameter(vr::SIGMA_YAW_RATE, "sigma_yaw_rate", "rad/s", 0.0005, "Noise sigma of the gyroscope (R, diagonal model)").min(0.0),
    VarSpec::real_parameter(vr::SIGMA_ACC_FRAME, "sigma_acc_frame", "m/s2", 0.01, "Noise sigma of the frame accelerometer (R, diagonal model)").min(0.0),
    VarSpec::real_parameter(vr::SIGMA_XI, "sigma_xi", "m", 0.005, "Sigma of the virtual measurement alignment = 0 (R, diagonal model)").min(0.0),
    VarSpec::real_parameter(vr::Q_ACC_WS, "q_acc_ws", "m2/s3", 1e-4, "Intensity of the white acceleration noise on the wheelset (Q, diagonal model)").min(0.0),
    VarSpec::real_parameter(vr::Q_YAW_ACC, "q_yaw_acc", "rad2/s3", 1e-4, "Intensity of the white yaw acceleration noise on the wheelset (Q, diagonal model)").min(0.0),
    VarSpec::real_parameter(vr::Q_ACC_FRAME, "q_acc_frame", "m2/s3", 1e-4, "Intensity of the white acceleration noise on the frame (Q, diagonal model)").min(0.0),
    VarSpec::real_parameter(vr::Q_XI, "q_xi", "m2/s", 1e-5, "Intensity of the alignment random walk (Q, diagonal model)").min(0.0),
    VarSpec::real_parameter(vr::P0_XI, "p0_xi", "m", 0.005, "Initial standard deviation of the alignment estimate").min(0.0),
    VarSpec::real_parameter(vr::MIN_SPEED, "min_speed", "m/s", MIN_SPEED_DEFAULT, "Below this speed the filter holds its estimate (creep terms divide by the speed)").min(0.0),
    VarSpec::real_parameter(vr::PRIOR_A, "prior_a", "m.rad", Spectrum::GERMAN_LOW.a, "Amplitude A of the alignment spectrum the 8-state priors assume (docs/references.md section 3; German low disturbance)").min(0.0),
    VarSpec::real_parameter(vr::PRIOR_OMEGA_R, "prior_omega_r", "rad/m", Spectrum::GERMAN_LOW.omega_r, "Lower corner wavenumber of the alignment spectrum (alignment_model 3)").min(0.0),
    VarSpec::real_parameter(vr::PRIOR_OMEGA_C, "prior_omega_c", "rad/m", Spectrum::GERMAN_LOW.omega_c, "Upper corner wavenumber of the alignment spectrum (alignment_models 2 and 3)").min(0.0),
    VarSpec::real_parameter(vr::PRIOR_SIGMA_XI, "prior_sigma_xi", "m", P_SIGMA_XI, "Sigma of the virtual measurement alignment = 0 for alignment_models 2 and 3; 0 switches it off (tuned on the calibration seed)").min(0.0),
    VarSpec::real_output(vr::EST_XI_RATE, "est_xi_rate", "m/s", 0.0, "Estimated rate of change of the alignment seen by the wheelset (alignment_models 2 and 3; 0 otherwise)"),
    VarSpec::real_parameter(vr::DESIGN_SPEED, "design_speed", "m/s", 0.0, "0: the filter's matrices follow the speed input at every step; > 0: they are built once for this speed, as in the paper (the input still drives the distance)").min(0.0),
    VarSpec::integer_parameter(vr::ALIGNMENT_MODEL, "alignment_model", 1, "Alignment prior: 1 the paper's random walk; 2 integrated random walk; 3 shaping filter of the track spectrum").min(1.0).max(3.0),
    VarSpec::integer_parameter(vr::GAIN, "gain", 0, "0: the estimator's own (the paper's filter time-varying; the learned filter's Kalman channel steady-state); 1: time-varying Kalman gain; 2: steady-state gain from the discrete algebraic Riccati equation, scheduled on speed (solved once per 0.01 m/s bin)").min(0.0).max(2.0),
    VarSpec::integer_parameter(vr::DISCRETIZATION, "discretization", 1, "1: the paper's second-order Taylor scheme; 2: exact (matrix exponential)").min(1.0).max(2.0),
    VarSpec::integer_output(vr::SKIPPED_UPDATES, "skipped_updates", 0, "Steps whose measurement update was skipped (non-finite sample or singular innovation covariance)"),
    VarSpec::integer_output(vr::REBUILDS, "rebuilds", 0, "How many times F, H and Q were rebuilt (on a change of speed or step size)"),
    VarSpec::boolean_parameter(vr::USE_CALIBRATION_FILE, "use_calibration_file", true, "Take Q and R from the calibration file when it holds them"),
    VarSpec::boolean_parameter(vr::P0_STATIONARY, "p0_stationary", true, "Start the time-varying filter from the stationary covariance at the first step's speed (no start-up transient); false: from p0_xi and typical body amplitudes, as the paper"),
    VarSpec::boolean_output(vr::UPDATED, "updated", false, "Whether the last step applied a measurement update"),
    VarSpec::real_input(vr::DESIGN_CURVATURE, "design_curvature", "1/m", 0.0, "Design curvature of the line at the wheelset, positive turning left (0 on straight track): its response is removed from the sensors (design_response_file)"),
    VarSpec::real_input(vr::DESIGN_CANT, "design_cant", "m", 0.0, "Design cant at the wheelset, right rail above left (positive in a canted left-hand curve; 0 on level track)"),
    VarSpec::string_parameter(vr::DESIGN_RESPONSE_FILE, "design_response_file", crate::design::SHIPPED_NAME, "The vehicle's response to the design line (alignment-studies design-response), removed from the sensors where design_curvature or design_cant (or line_file) is not 0; absolute, or relative to the resources, then to the working directory; shipped: design-response.toml (the ML95); empty: none (the design inputs are ignored; line_file is then an error)"),
    VarSpec::string_parameter(vr::LINE_FILE, "line_file", "", "The design line as a line file (CSV distance,curvature,cant, as the vehicle FMU reads it), absolute, or relative to the FMU's resources directory, then to the working directory: the design at line_start + distance replaces design_curvature and design_cant; empty (default): the inputs"),
    VarSpec::real_parameter(vr::LINE_ROUNDING, "line_rounding", "m", design_line::DEFAULT_ROUNDING, "line_file: length over which each row's change of slope is rounded, as the vehicle FMU's line_rounding (1-100 m)").min(design_line::MIN_ROUNDING).max(design_line::MAX_ROUNDING),
    VarSpec::real_parameter(vr::LINE_START, "line_start", "m", 0.0, "line_file: the line's distance where the estimator's distance output is 0 (the design is read at line_start + distance)"),
    VarSpec::real_input(vr::WS_ROLL_RATE, "ws_roll_rate", "rad/s", 0.0, "Wheelset roll angular velocity (gyroscope), optional: read only when use_roll_rate is true"),
    VarSpec::integer_parameter(vr::ESTIMATOR, "estimator", 2, "What 'alignment' carries: 1 the paper's Kalman filter alone; 2 the learned filter (taps from tap_file, the Kalman filter as one of its channels), falling back to the Kalman filter outside the taps' speed range").min(1.0).max(2.0),
    VarSpec::real_parameter(vr::LAG, "lag", "m", 10.0, "Lag of the fixed-lag output alignment_lagged (estimator 2): one the tap bank holds (10 m shipped); 0 switches it off").min(0.0),
    VarSpec::boolean_parameter(vr::USE_ROLL_RATE, "use_roll_rate", false, "Use the taps fitted with the wheelset roll-rate gyroscope (connect ws_roll_rate); false: the three-sensor taps"),
    VarSpec::boolean_parameter(vr::ALLOW_OTHER_KALMAN, "allow_other_kalman", false, "estimator 2: run the learned filter, with a warning, when its Kalman channel differs from the one the tap bank was fitted with (other model parameters, calibration, alignment_model, design_speed or min_speed): approximate; false: that is an error at initialization"),
    VarSpec::string_parameter(vr::TAP_FILE, "tap_file", "learned.taps", "The learned filter's tap bank (alignment-studies taps), absolute, or relative to the FMU's resources directory, then to the working directory; shipped: learned.taps (taps per contact condition at conicity 0.1, Kalker 100, 75 and 50 %, blended by the estimated contact_scale; the contact model of learned-conicity.taps, so it estimates the conicity and sets novelty and outside_training where the wheels are not the ones its taps know), learned-nominal.taps (Kalker 100 % only; no contact model), learned-conicity.taps (conicity 0.05-0.4 x Kalker 100, 75, 50 %, blended by conicity_estimate and contact_scale; sets novelty and outside_training)"),
    VarSpec::real_output(vr::ALIGNMENT_LAGGED, "alignment_lagged", "m", 0.0, "Fixed-lag estimate of the alignment at distance_lagged (estimator 2, lag > 0; over the first lag + 1 m and outside the taps' speed range the causal output made at distance_lagged, from its first 0.2 m grid point on: the learned estimate, or the Kalman one where none was made)"),
    VarSpec::real_output_calculated(vr::ALIGNMENT_LAGGED_STD, "alignment_lagged_std", "m", "Standard deviation of alignment_lagged (rms error of its taps on the validation seeds)"),
    VarSpec::real_output_calculated(vr::DISTANCE_LAGGED, "distance_lagged", "m", "The position alignment_lagged is for: distance - lag"),
    VarSpec::real_output(vr::ALIGNMENT_KALMAN, "alignment_kalman", "m", 0.0, "The Kalman filter's own alignment estimate (the paper's estimator)"),
    VarSpec::real_output(vr::CONTACT_SCALE, "contact_scale", "1", 0.0, "The wheel-rail contact's Kalker-coefficient scale as the learned filter estimates it from the sensors (1: nominal creep coefficients, 0.5: halved, as worn wheels and rails); it blends the taps fitted per condition. 0 when the tap bank has no contact model (learned-nominal.taps, estimator 1)"),
    VarSpec::real_parameter(vr::CONICITY, "conicity", "1", 0.0, "The wheels' equivalent conicity, when known (estimator 2, a tap bank with a conicity model: learned.taps, learned-conicity.taps): the taps are blended at it (within their own conicities: 0.1 alone for learned.taps), and outside_training sets when it lies beyond them by over 15 %; 0: estimated from the sensors (conicity_estimate). The paper's filter's conicity is alpha").min(0.0),
    VarSpec::real_parameter(vr::KALKER_SCALE, "kalker_scale", "1", 0.0, "The wheel-rail contact's Kalker-coefficient scale, when known (estimator 2, a tap bank with contact conditions): the taps are blended at it from the first metre, instead of at contact_scale as the sensors tell it over 200 m (clamped to the bank's trained range, 0.5-1 for the shipped banks); 0: estimated").min(0.0),
    VarSpec::real_output(vr::CONICITY_ESTIMATE, "conicity_estimate", "1", 0.0, "The wheels' equivalent conicity as the learned filter reads it: the conicity parameter when set, else estimated from the sensors (within the contact model's range, 0.05-0.4 for the shipped banks): from 30 m into a run, Whittle's likelihood of the three sensors' cross-spectra over the last 30-200 m against the bank's model spectra, averaged with the contact features' linear model (200 m memory), every 10 m (every 25 m once 200 m are in). The taps are blended at it within their own conicities (0.1 alone for learned.taps); outside_training sets when its running mean over 500 m (from 200 m into the run) lies beyond them by over 15 %. 0 when the tap bank has no conicity model (learned-nominal.taps, estimator 1)"),
    VarSpec::real_output(vr::NOVELTY, "novelty", "1", 0.0, "How far the sensors' contact features lie from what the tap bank's training runs showed at the estimated condition (squared Mahalanobis distance over the level exceeded on 0.2 % of the validation distance; 200 m memory; judged from 50 m into a run, then every metre): above 1 the vehicle or its wheels are unlike what the taps were fitted on. 0 without a conicity model (learned-nominal.taps, estimator 1)"),
    VarSpec::boolean_output(vr::OUTSIDE_TRAINING, "outside_training", false, "novelty above 1, or the conicity (the one told; or conicity_estimate's running mean from 200 m into the run, 500 m memory) beyond the taps' conicities by over 15 %, or the design line beyond the design response's envelope or near the flanges, or heading_change beyond heading_level or relative_velocity_change beyond 0.5 m/s (a curve whose design is not connected, or a sensor bias not removed; either estimator): the estimate is less trustworthy here (alignment_std grows with the novelty, the conicity's distance, and those changes over their levels); a warning is logged when it first sets"),
    VarSpec::real_output(vr::HEADING_CHANGE, "heading_change", "rad", 0.0, "The yaw gyroscope's heading change over the last 500 m run (since the start before that): its rate integrated in motion, less the bias removed and the design line's response. Straight track's irregularities keep it within about 0.004 rad (German low; FRA class 5 at 30 m/s 0.0124); beyond heading_level outside_training sets (a curve whose design is not connected, or a yaw-gyroscope bias not removed)"),
    VarSpec::real_output(vr::HEADING_LEVEL, "heading_level", "rad", 0.015, "The level heading_change is judged against: 0.015 (above the roughest track's wander) until 2000 m have been run, then 8 times the heading's wander over the last 2000 m (the rms of its residual from a straight line, which leaves a bias's steady turn out), within 0.004-0.015"),
    VarSpec::real_output(vr::RELATIVE_VELOCITY_CHANGE, "relative_velocity_change", "m/s", 0.0, "The wheelset's lateral velocity relative to the bogie frame as the two accelerometers integrate it (ws_acc_y - frame_acc_y in motion, less the biases removed and the design line's response) over the last 500 m run (since the start before that). The primary suspension bounds it on any line: within 0.034 m/s on straight track (German low; FRA class 5 at 30 m/s 0.106); beyond 0.5 one accelerometer carries a bias the other does not (at 20 m/s one of 0.02 m/s2 or more), and outside_training sets"),
    VarSpec::integer_output(vr::ACTIVE_ESTIMATOR, "active_estimator", 1, "Which estimate 'alignment' carries at this step: 1 the Kalman filter (estimator 1, start of the run, speed outside the taps' range), 2 the learned filter"),
    VarSpec::real_parameter(vr::BIAS_SIGMA_WS_ACC_Y, "bias_sigma_ws_acc_y", "m/s2", 0.0, "Prior standard deviation of the wheelset accelerometer's bias (its turn-on bias, a datasheet figure): > 0 estimates the bias while the train stands still (speed below 0.01 m/s) and removes it from every sample; 0: not estimated").min(0.0),
    VarSpec::real_parameter(vr::BIAS_SIGMA_WS_YAW_RATE, "bias_sigma_ws_yaw_rate", "rad/s", 0.0, "As bias_sigma_ws_acc_y, for the yaw gyroscope").min(0.0),
    VarSpec::real_parameter(vr::BIAS_SIGMA_FRAME_ACC_Y, "bias_sigma_frame_acc_y", "m/s2", 0.0, "As bias_sigma_ws_acc_y, for the frame accelerometer").min(0.0),
    VarSpec::real_parameter(vr::BIAS_SIGMA_WS_ROLL_RATE, "bias_sigma_ws_roll_rate", "rad/s", 0.0, "As bias_sigma_ws_acc_y, for the roll gyroscope").min(0.0),
    VarSpec::real_output(vr::WS_ACC_Y_BIAS, "ws_acc_y_bias", "m/s2", 0.0, "The wheelset accelerometer's estimated bias, removed from its samples (0 unless bias_sigma_ws_acc_y > 0 and the train has stood still)"),
    VarSpec::real_output(vr::WS_YAW_RATE_BIAS, "ws_yaw_rate_bias", "rad/s", 0.0, "The yaw gyroscope's estimated bias, removed from its samples"),
    VarSpec::real_output(vr::FRAME_ACC_Y_BIAS, "frame_acc_y_bias", "m/s2", 0.0, "The frame accelerometer's estimated bias, removed from its samples"),
    VarSpec::real_output(vr::WS_ROLL_RATE_BIAS, "ws_roll_rate_bias", "rad/s", 0.0, "The roll gyroscope's estimated bias, removed from its samples"),
    VarSpec::string_parameter(vr::CALIBRATION_FILE, "calibration_file", DEFAULT_CALIBRATION_FILE, "Calibration file (Q and R, and in [parameters] the model they were made with, taken for the parameters left at their defaults), absolute, or relative to the FMU's resources directory, then to the working directory; a file other than the default that does not exist is an error"),
];
