//! Calibration of the filter's noise covariances, as the paper does (section 4.2): from a
//! vehicle run with the true states known, the system error `e_x = x_k - F x_(k-1)` and the
//! measurement error `e_z = z_k - H x_k` (with the noisy sensor signals and the virtual
//! measurement 0) give `Q = mean(e_x e_x^T)` and `R = mean(e_z e_z^T)`.
//!
//! True states, from the vehicle FMU: the leading wheelset's `y`, `psi` and rates, the leading
//! bogie frame's lateral displacement and velocity at the point above that wheelset (the
//! simplified model's suspended frame) and the alignment the wheelset meets. `F` and `H` are
//! the estimator's own: the paper's second-order scheme (the FMU's default discretization) at
//! the run's speed and step. The first second (run-in ramp and start transient) is left out.
//!
//! The result is written to the estimator's calibration file with the identified parameters, so
//! the FMU ships a filter matched to the vehicle it is judged against.

use super::runs::{Fmus, Settings, vehicle_run};
use fmu_estimator::discretize::{Scheme, transition};
use fmu_estimator::filter::{Mat4, Vec4, Vec7};
use fmu_estimator::model::{Mat7, measurement_matrix, state_matrix};
use fmu_estimator::params::Params;

pub const TRUTH: [&str; 7] = [
    "ws_y",
    "ws_yaw",
    "frame_y",
    "ws_vy",
    "ws_yaw_rate_true",
    "frame_vy",
    "alignment",
];
pub const SENSORS: [&str; 3] = ["ws_acc_y", "ws_yaw_rate", "frame_acc_y"];

#[derive(Debug, Clone)]
pub struct Calibration {
    pub params: Params,
    pub q: Mat7,
    pub r: Mat4,
    pub seed: u32,
    pub speed: f64,
    pub step: f64,
}

/// Q and R from a standard-conditions vehicle run on track `seed`.
#[allow(clippy::needless_range_loop)] // k indexes the truth and sensor columns together
pub fn calibrate(
    fmus: &Fmus,
    params: &Params,
    seed: u32,
    stop: f64,
    step: f64,
) -> Result<Calibration, String> {
    let settings: Settings = super::runs::seeded(seed);
    let mut names: Vec<&str> = TRUTH.to_vec();
    names.extend(SENSORS);
    names.push("forward_speed");
    let table = vehicle_run(fmus, settings, &names, stop)?;
    let col = |n: &str| {
        table
            .column(&format!("vehicle.{n}"))
            .ok_or_else(|| format!("no column {n}"))
    };
    let truth: Vec<&[f64]> = TRUTH.iter().map(|n| col(n)).collect::<Result<_, _>>()?;
    let sensors: Vec<&[f64]> = SENSORS.iter().map(|n| col(n)).collect::<Result<_, _>>()?;
    let speed = *col("forward_speed")?.last().ok_or("empty run")?;
    let fc = state_matrix(params, speed);
    let f = transition(&fc, step, Scheme::Taylor2);
    let h = measurement_matrix(&fc);
    let x = |k: usize| Vec7::from_fn(|i, _| truth[i][k]);
    let first = (1.0 / step).round() as usize;
    let n = truth[0].len();
    if n <= first + 1 {
        return Err(format!("the calibration run is too short ({n} samples)"));
    }
    let (mut q, mut r) = (Mat7::zeros(), Mat4::zeros());
    for k in first..n {
        let ex = x(k) - f * x(k - 1);
        q += ex * ex.transpose();
        let z = Vec4::new(sensors[0][k], sensors[1][k], sensors[2][k], 0.0);
        let ez = z - h * x(k);
        r += ez * ez.transpose();
    }
    let m = (n - first) as f64;
    Ok(Calibration {
        params: *params,
        q: q / m,
        r: r / m,
        seed,
        speed,
        step,
    })
}

fn matrix_rows<const N: usize>(m: &nalgebra::SMatrix<f64, N, N>) -> String {
    let sym = (m + m.transpose()) * 0.5;
    let rows: Vec<String> = (0..N)
        .map(|i| {
            format!(
                "  [{}]",
                (0..N)
                    .map(|j| format!("{:e}", sym[(i, j)]))
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        })
        .collect();
    format!("[\n{},\n]", rows.join(",\n"))
}

/// The calibration file: provenance, the identified and fixed parameters, Q and R.
pub fn to_toml(c: &Calibration, identification_seed: u32, provenance: &str) -> String {
    let p = &c.params;
    format!(
        "# Calibration of the AlignmentEstimator FMU, written by `orchestrator study calibrate`.\n\
         # Regenerate it with that command; a test checks that doing so reproduces this file.\n\
         # {provenance}\n\
         status = \"calibrated against the RailVehicle FMU (identification seed {identification_seed}, calibration seed {seed})\"\n\
         step_size = {step:e}\n\
         speed = {speed:e}\n\n\
         # The simplified model: p_fix from the vehicle's parameter set (Kalker coefficients at the\n\
         # static wheel load), p_opt = (kx, cx, ky, cy) identified. These become the FMU's\n\
         # parameter defaults when it is built.\n\
         [parameters]\n\
         m = {m:e}\nI = {i:e}\nl = {l:e}\nl_s = {l_s:e}\nalpha = {alpha:e}\nr_0 = {r_0:e}\nm_f = {m_f:e}\n\
         f11 = {f11:e}\nf22 = {f22:e}\nf23 = {f23:e}\nf33 = {f33:e}\n\
         kx = {kx:e}\ncx = {cx:e}\nky = {ky:e}\ncy = {cy:e}\n\n\
         [noise]\n\
         # Discrete process noise covariance for step_size (7x7, state order y, psi, y_f, vy, psi_rate, vy_f, xi)\n\
         q = {q}\n\
         # Measurement noise covariance (4x4: ws_acc_y, ws_yaw_rate, frame_acc_y, virtual xi = 0)\n\
         r = {r}\n",
        seed = c.seed,
        step = c.step,
        speed = c.speed,
        m = p.m,
        i = p.i,
        l = p.l,
        l_s = p.l_s,
        alpha = p.alpha,
        r_0 = p.r_0,
        m_f = p.m_f,
        f11 = p.f11,
        f22 = p.f22,
        f23 = p.f23,
        f33 = p.f33,
        kx = p.kx,
        cx = p.cx,
        ky = p.ky,
        cy = p.cy,
        q = matrix_rows(&c.q),
        r = matrix_rows(&c.r),
    )
}
