//! Identification of the simplified model's suspension equivalents (the paper's section 3.4).
//!
//! The parameters the real vehicle gives directly (`p_fix`: wheelset mass and yaw inertia,
//! half gauge, suspension semi-spacing, conicity, rolling radius, the suspended mass as a quarter
//! car body plus half a bogie, and Kalker's coefficients at the static wheel load) are taken from
//! the vehicle's parameter set; `p_opt = (kx, cx, ky, cy)` are identified. The vehicle FMU runs
//! with lateral irregularities only and no sensor noise (the paper's identification run); the
//! simplified model, driven by the same alignment (the one the leading wheelset meets), is
//! simulated with the exact discretization, and the time-domain misfit of `y` and `psi` is
//! minimized by Nelder-Mead.
//!
//! Misfit: `J_ls = mean((y_sm - y)^2) / var(y) + mean((psi_sm - psi)^2) / var(psi)`. The paper
//! sums the squared errors of the state vector; `y` \[m\] and `psi` \[rad\] have different units and
//! sizes, so each is normalized by its variance (otherwise the fit would ignore one of them).
//! The search runs on the logarithms of `p_opt`, bounded to 1/30 ... 30 times the paper's
//! Table 2 values (a quadratic penalty outside), which keeps the model's measurement equations
//! well conditioned (an unbounded search drives `ky` to a rigid link).

use super::optimize::nelder_mead;
use super::runs::{Fmus, Settings, vehicle_run};
use crate::Error;
use fmu_estimator::discretize::{Scheme, transition};
use fmu_estimator::filter::Vec7;
use fmu_estimator::model::state_matrix;
use fmu_estimator::params::Params;
use fmu_vehicle::dynamics::{ContactOptions, Vehicle};
use fmu_vehicle::params::VehicleParams;
use orchestrator::system::Value;

/// `p_fix` of the simplified model from the vehicle's parameter set (suspension equivalents
/// left at the paper's Table 2 values, to be identified).
pub fn fixed_parameters(v: &VehicleParams) -> Params {
    let vehicle = Vehicle::new(v.clone(), v.wheelset.conicity, ContactOptions::default());
    let c = vehicle.creep_law().at_load(vehicle.static_wheel_load[0]);
    Params {
        m: v.wheelset.mass,
        i: v.wheelset.yaw_inertia,
        l: v.wheelset.half_gauge,
        l_s: v.primary.semi_spacing,
        alpha: v.wheelset.conicity,
        r_0: v.wheelset.rolling_radius,
        m_f: v.suspended_mass_per_wheelset(),
        f11: c.f11,
        f22: c.f22,
        f23: c.f23,
        f33: c.f33,
        ..Params::TABLE_2
    }
}

/// The simplified model's `y` and `psi` driven by the alignment samples `xi` (held over each
/// step), at constant speed, from rest.
pub fn simulate(p: &Params, speed: f64, h: f64, xi: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let f = transition(&state_matrix(p, speed), h, Scheme::Exact);
    let mut x = Vec7::zeros();
    let (mut y, mut psi) = (Vec::with_capacity(xi.len()), Vec::with_capacity(xi.len()));
    for &a in xi {
        x[6] = a;
        x = f * x;
        y.push(x[0]);
        psi.push(x[1]);
    }
    (y, psi)
}

/// Fits `(kx, cx, ky, cy)` of `base` so that the simplified model driven by `drive` reproduces
/// `y` and `psi` (one sample per step, after each step). Returns the parameters, the misfit,
/// the misfit with Table 2's values, and the number of model evaluations.
pub fn fit(
    base: &Params,
    speed: f64,
    step: f64,
    drive: &[f64],
    y: &[f64],
    psi: &[f64],
) -> (Params, f64, f64, usize) {
    let var = |x: &[f64]| {
        let m = x.iter().sum::<f64>() / x.len() as f64;
        x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / x.len() as f64
    };
    let (vy, vpsi) = (var(y), var(psi));
    let t2 = Params::TABLE_2;
    let with = |z: &[f64]| Params {
        kx: t2.kx * z[0].exp(),
        cx: t2.cx * z[1].exp(),
        ky: t2.ky * z[2].exp(),
        cy: t2.cy * z[3].exp(),
        ..*base
    };
    let misfit = |p: &Params| {
        let (ys, ps) = simulate(p, speed, step, drive);
        let e = |a: &[f64], b: &[f64]| {
            a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>() / a.len() as f64
        };
        e(&ys, y) / vy + e(&ps, psi) / vpsi
    };
    let mut cost = |z: &[f64]| {
        let penalty: f64 = z.iter().map(|v| (v.abs() - BOUND).max(0.0).powi(2)).sum();
        let clamped: Vec<f64> = z.iter().map(|v| v.clamp(-BOUND, BOUND)).collect();
        let m = misfit(&with(&clamped));
        if m.is_finite() {
            m + 10.0 * penalty
        } else {
            1e9
        }
    };
    let cost_table_2 = cost(&[0.0; 4]);
    let (z, best, evaluations) = nelder_mead(&mut cost, &[0.0; 4], &[0.7; 4], 1e-12, 1500);
    let z: Vec<f64> = z.iter().map(|v| v.clamp(-BOUND, BOUND)).collect();
    (with(&z), best, cost_table_2, evaluations)
}

/// The result, with the time series of the fit for the report's plot.
#[derive(Debug, Clone)]
pub struct Identification {
    /// `p_fix` with the identified `(kx, cx, ky, cy)`.
    pub params: Params,
    /// The misfit `J_ls` at the optimum (with the bound's penalty, 0 inside the bounds).
    pub cost: f64,
    /// The misfit with the paper's Table 2 suspension values, for comparison.
    pub cost_table_2: f64,
    /// Cost evaluations Nelder-Mead used.
    pub evaluations: usize,
    /// Times of the compared samples \[s\] (the run's rows after the first).
    pub time: Vec<f64>,
    /// The vehicle's leading wheelset lateral displacement \[m\].
    pub y_vehicle: Vec<f64>,
    /// The vehicle's leading wheelset yaw \[rad\].
    pub psi_vehicle: Vec<f64>,
    /// The identified simplified model's `y` \[m\], driven by the same alignment.
    pub y_model: Vec<f64>,
    /// The identified simplified model's `psi` \[rad\].
    pub psi_model: Vec<f64>,
}

const BOUND: f64 = 3.401_197_381_662_155; // ln 30

/// Identifies `(kx, cx, ky, cy)` on track `seed` (lateral irregularities, no noise).
pub fn identify(
    fmus: &Fmus,
    vehicle_params: &VehicleParams,
    seed: u32,
    stop: f64,
    step: f64,
) -> Result<Identification, crate::Error> {
    let mut settings: Settings = super::runs::seeded(seed);
    settings.push(("vertical_irregularity".into(), Value::Boolean(false)));
    settings.push(("sensor_noise".into(), Value::Boolean(false)));
    let table = vehicle_run(
        fmus,
        settings,
        &["ws_y", "ws_yaw", "alignment", "forward_speed"],
        stop,
    )?;
    let col = |n: &str| {
        table
            .column(&format!("vehicle.{n}"))
            .map(|c| c.to_vec())
            .ok_or_else(|| Error::Input(format!("no column {n}")))
    };
    let (y, psi, xi, v) = (
        col("ws_y")?,
        col("ws_yaw")?,
        col("alignment")?,
        col("forward_speed")?,
    );
    let t = table
        .column("time")
        .ok_or_else(|| Error::input("no time column"))?
        .to_vec();
    let speed = v.last().copied().unwrap_or(20.0);
    // Row k is time t_k; the step from t_k to t_(k+1) uses the alignment at t_k.
    let drive = &xi[..xi.len() - 1];
    let (y_ref, psi_ref) = (&y[1..], &psi[1..]);
    let base = fixed_parameters(vehicle_params);
    let (params, best, cost_table_2, evaluations) = fit(&base, speed, step, drive, y_ref, psi_ref);
    let (y_model, psi_model) = simulate(&params, speed, step, drive);
    Ok(Identification {
        params,
        cost: best,
        cost_table_2,
        evaluations,
        time: t[1..].to_vec(),
        y_vehicle: y_ref.to_vec(),
        psi_vehicle: psi_ref.to_vec(),
        y_model,
        psi_model,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Data from the simplified model itself with known suspension values: the fit recovers
    /// them (the identification's own oracle).
    #[test]
    fn the_fit_recovers_known_parameters_from_the_models_own_response() {
        let truth = Params {
            kx: 1.1e6,
            cx: 2.0e4,
            ky: 6.0e6,
            cy: 9.0e4,
            ..Params::TABLE_2
        };
        let (h, speed) = (1e-3, 20.0);
        // A rich alignment: a few sinusoids between 5 and 150 m.
        let xi: Vec<f64> = (0..10_000)
            .map(|k| {
                let s = k as f64 * h * speed;
                [
                    (5.3, 3e-4),
                    (13.0, 6e-4),
                    (31.0, 1e-3),
                    (77.0, 1.5e-3),
                    (150.0, 2e-3),
                ]
                .iter()
                .map(|(l, a)| a * (2.0 * std::f64::consts::PI * s / l + l).sin())
                .sum()
            })
            .collect();
        let (y, psi) = simulate(&truth, speed, h, &xi);
        let (p, misfit, start, _) = fit(&Params::TABLE_2, speed, h, &xi, &y, &psi);
        assert!(misfit < 1e-6 * start, "misfit {misfit} from {start}");
        for (name, got, want) in [
            ("kx", p.kx, truth.kx),
            ("cx", p.cx, truth.cx),
            ("ky", p.ky, truth.ky),
            ("cy", p.cy, truth.cy),
        ] {
            assert!((got / want - 1.0).abs() < 0.02, "{name}: {got} vs {want}");
        }
    }
}
