//! Statistical consistency of the filter on data simulated by its own model with known noise:
//! the textbook test that the implementation of predict/update is right.
//!
//! Truth: `x_k = F x_{k-1} + w_k`, `w ~ N(0, Q)`, starting from `x_0 ~ N(0, P_0)`; measurements
//! `z_k = H x_k + v_k`, `v ~ N(0, R)`, with `F`, `H`, `Q`, `R` exactly those the FMU builds. For
//! this test only, the fourth measurement is a real noisy measurement of the alignment (the FMU's
//! virtual measurement says 0 = xi + v, which a random-walk truth does not satisfy). Then the
//! normalized innovation squared is chi-square with 4 degrees of freedom at every step, and
//! the alignment error is Gaussian with the filter's own variance.

use fmi_abi::instance::Instance;
use fmi_abi::{InstantiateContext, Logger, Model};
use fmu_estimator::Estimator;
use fmu_estimator::discretize::{Scheme, transition};
use fmu_estimator::filter::{Kalman, Mat4, Vec4, Vec7};
use fmu_estimator::fmu::vr;
use fmu_estimator::model::{Mat7, measurement_matrix, state_matrix};
use fmu_estimator::params::Params;
use fmu_estimator::statespace::{BodyNoise, StateSpace};
use rand::SeedableRng;
use rand::rngs::StdRng;
use rand_distr::{Distribution, StandardNormal};

/// A sample of N(0, cov) through the Cholesky factor (cov may be singular: add a tiny jitter).
fn gaussian<const N: usize>(
    rng: &mut StdRng,
    cov: &nalgebra::SMatrix<f64, N, N>,
) -> nalgebra::SVector<f64, N> {
    let jitter = nalgebra::SMatrix::<f64, N, N>::identity() * (1e-30 + 1e-15 * cov.amax());
    let l = (cov + jitter)
        .cholesky()
        .expect("covariance is positive semi-definite")
        .l();
    let e = nalgebra::SVector::<f64, N>::from_fn(|_, _| StandardNormal.sample(rng));
    l * e
}

/// The FMU's diagonal process-noise intensities, read from its variable table (so this test
/// follows the shipped defaults).
fn default_q_rate() -> Mat7 {
    let start = |name: &str| match fmu_estimator::fmu::VARIABLES
        .iter()
        .find(|v| v.name == name)
        .map(|v| v.start)
    {
        Some(fmi_abi::variables::Start::Real(x)) => x,
        other => panic!("{name}: {other:?}"),
    };
    let q = [
        0.0,
        0.0,
        0.0,
        start("q_acc_ws"),
        start("q_yaw_acc"),
        start("q_acc_frame"),
        start("q_xi"),
    ];
    Mat7::from_diagonal(&Vec7::from_column_slice(&q))
}

struct Run {
    nis_mean: f64,
    nis_within_99: f64,
    xi_within_3_sigma: f64,
}

fn run(scheme: Scheme, steps: usize, seed: u64) -> Run {
    let p = Params::default();
    let (h, speed) = (1e-3, 20.0);
    let fc = state_matrix(&p, speed);
    let f = transition(&fc, h, scheme);
    let hm = measurement_matrix(&fc);
    // The FMU's diagonal model with its default intensities and sigmas.
    let q = default_q_rate() * h;
    let r = Mat4::from_diagonal(&Vec4::new(
        0.01f64.powi(2),
        0.0005f64.powi(2),
        0.01f64.powi(2),
        0.005f64.powi(2),
    ));
    let s0 = [5e-3, 1e-3, 5e-3, 5e-2, 1e-2, 5e-2, 5e-3];
    let p0 = Mat7::from_diagonal(&Vec7::from_fn(|i, _| s0[i] * s0[i]));

    let mut rng = StdRng::seed_from_u64(seed);
    let mut x = gaussian(&mut rng, &p0);
    let mut kf = Kalman::new(Vec7::zeros(), p0);
    let (mut nis_sum, mut nis_in, mut xi_in) = (0.0, 0usize, 0usize);
    for _ in 0..steps {
        x = f * x + gaussian(&mut rng, &q);
        let z = hm * x + gaussian(&mut rng, &r);
        kf.predict(&f, &q);
        let nis = kf.update(&hm, &r, &z).expect("S is positive definite");
        nis_sum += nis;
        nis_in += (nis < 13.2767) as usize; // chi-square(4) 99 % quantile
        xi_in += ((kf.x[6] - x[6]).abs() < 3.0 * kf.p[(6, 6)].sqrt()) as usize;
    }
    let n = steps as f64;
    Run {
        nis_mean: nis_sum / n,
        nis_within_99: nis_in as f64 / n,
        xi_within_3_sigma: xi_in as f64 / n,
    }
}

#[test]
fn innovations_are_chi_square_and_errors_stay_within_3_sigma() {
    for scheme in [Scheme::Exact, Scheme::Taylor2] {
        let steps = 20_000;
        let r = run(scheme, steps, 7);
        // Mean of chi-square(4): 4, standard deviation of the mean sqrt(8 / N) = 0.02.
        assert!(
            (r.nis_mean - 4.0).abs() < 0.1,
            "{scheme:?}: NIS mean {}",
            r.nis_mean
        );
        assert!(
            (r.nis_within_99 - 0.99).abs() < 0.004,
            "{scheme:?}: NIS below the 99 % quantile {}",
            r.nis_within_99
        );
        // 3 sigma of a Gaussian holds 99.73 %; the issue asks for at least 99 %.
        assert!(
            r.xi_within_3_sigma >= 0.99,
            "{scheme:?}: alignment inside 3 sigma {}",
            r.xi_within_3_sigma
        );
    }
}

#[test]
fn a_mis_specified_filter_is_detected_by_the_same_statistics() {
    // The oracle must be able to fail: the same data through a filter that under-states R by
    // a factor of 100 gives a NIS mean far above 4.
    let p = Params::default();
    let (h, speed) = (1e-3, 20.0);
    let fc = state_matrix(&p, speed);
    let f = transition(&fc, h, Scheme::Exact);
    let hm = measurement_matrix(&fc);
    let q = default_q_rate() * h;
    let r = Mat4::from_diagonal(&Vec4::new(1e-4, 2.5e-7, 1e-4, 2.5e-5));
    let mut rng = StdRng::seed_from_u64(3);
    let mut x = Vec7::zeros();
    let mut kf = Kalman::new(Vec7::zeros(), Mat7::identity() * 1e-6);
    let mut nis_sum = 0.0;
    for _ in 0..5000 {
        x = f * x + gaussian(&mut rng, &q);
        let z = hm * x + gaussian(&mut rng, &r);
        kf.predict(&f, &q);
        nis_sum += kf.update(&hm, &(r * 0.01), &z).unwrap();
    }
    assert!(nis_sum / 5000.0 > 40.0, "{}", nis_sum / 5000.0);
}

/// The FMU path (through the export layer's instance) runs the same filter: fed the same
/// measurements, it gives the same alignment estimate as the filter driven directly.
#[test]
fn the_fmu_runs_the_same_filter() {
    let ctx = InstantiateContext {
        instance_name: "t".into(),
        resources: None,
    };
    let mut inst = Instance::<Estimator>::new(&ctx, Logger::silent())
        .map_err(|(_, e)| e)
        .unwrap();
    inst.set_boolean(
        &[vr::USE_CALIBRATION_FILE, vr::P0_STATIONARY],
        &[false, false],
    )
    .unwrap();
    // The Kalman filter alone (estimator 1): its output is what this test compares.
    inst.set_integer(&[vr::DISCRETIZATION, vr::ESTIMATOR], &[2, 1])
        .unwrap();
    inst.setup_experiment(0.0, Some(1.0)).unwrap();
    inst.enter_initialization_mode().unwrap();
    inst.exit_initialization_mode().unwrap();

    let p = Params::DEFAULTS;
    let h = 1e-3;
    // The filter's matrices as the FMU builds them (statespace tests check them against
    // `model::state_matrix` and `discretize::transition`).
    let space = StateSpace::paper(&p, BodyNoise::Rate(default_q_rate()), true);
    let d = space.discrete(20.0, h, Scheme::Exact);
    let (f, hm) = (d.f, d.hm);
    let q = default_q_rate() * h;
    let r = Mat4::from_diagonal(&Vec4::new(1e-4, 2.5e-7, 1e-4, 2.5e-5));
    let s0 = [5e-3, 1e-3, 5e-3, 5e-2, 1e-2, 5e-2, 5e-3];
    let mut kf = Kalman::new(
        Vec7::zeros(),
        Mat7::from_diagonal(&Vec7::from_fn(|i, _| s0[i] * s0[i])),
    );
    let mut t = 0.0;
    for k in 0..500 {
        let z = [
            0.3 * (k as f64 * 0.05).sin(),
            0.01 * (k as f64 * 0.03).cos(),
            0.05 * (k as f64 * 0.02).sin(),
        ];
        inst.set_real(&[vr::WS_ACC_Y, vr::WS_YAW_RATE, vr::FRAME_ACC_Y], &z)
            .unwrap();
        inst.do_step(t, h).unwrap();
        t += h;
        kf.predict(&f, &q);
        kf.update(&hm, &r, &Vec4::new(z[0], z[1], z[2], 0.0))
            .unwrap();
        let mut out = [0.0; 2];
        inst.get_real(&[vr::ALIGNMENT, vr::ALIGNMENT_STD], &mut out)
            .unwrap();
        assert_eq!(out[0], kf.x[6], "step {k}");
        assert_eq!(out[1], kf.p[(6, 6)].sqrt(), "step {k}");
    }
    let mut d = [0.0];
    inst.get_real(&[vr::DISTANCE], &mut d).unwrap();
    assert!((d[0] - 10.0).abs() < 1e-9, "distance {}", d[0]);
    let _ = Estimator::INFO;
}
