//! The numbers this module reports (run with `--nocapture` to print them): the docs/references.md
//! worked example and the ML95-like metro case, against the paper's Table 2.

use fmu_vehicle::contact::*;

fn coefficients(r0: f64, crown: f64, n: f64, mat: &Material) -> (Ellipse, CreepCoefficients) {
    let geom = ContactGeometry::coned(r0, crown);
    let el = hertz(&geom, mat, n);
    (el, creep_coefficients(el, mat))
}

fn line(label: &str, el: Ellipse, f: CreepCoefficients, mat: &Material) {
    let c = kalker_c(el.a / el.b, mat.poisson);
    println!(
        "{label}: a {:.3} mm, b {:.3} mm, a/b {:.4}; C = [{:.4}, {:.4}, {:.4}, {:.4}]; \
         f11 {:.4e} N, f22 {:.4e} N, f23 {:.4e} N m, f33 {:.3} N m^2",
        el.a * 1e3,
        el.b * 1e3,
        el.a / el.b,
        c[0],
        c[1],
        c[2],
        c[3],
        f.f11,
        f.f22,
        f.f23,
        f.f33
    );
}

#[test]
fn report_worked_example() {
    let mat = Material::STEEL;
    let (el, f) = coefficients(0.43, 0.30, 40e3, &mat);
    line("docs/references.md example (40 kN, r0 0.43)", el, f, &mat);
    println!(
        "  vs oracle: f11 {:+.2} %, f22 {:+.2} %, f23 {:+.2} %, f33 {:+.2} %",
        100.0 * (f.f11 / 7.56e6 - 1.0),
        100.0 * (f.f22 / 6.78e6 - 1.0),
        100.0 * (f.f23 / 13.6e3 - 1.0),
        100.0 * (f.f33 / 34.5 - 1.0)
    );
    let (m30, n30) = hertz_coefficients(30f64.to_radians());
    let (m60, n60) = hertz_coefficients(60f64.to_radians());
    println!("  Hertz m, n: 30 deg {m30:.5} / {n30:.5}; 60 deg {m60:.5} / {n60:.5}");
    assert!((f.f33 / 34.5 - 1.0).abs() < 0.02);
}

#[test]
fn report_ml95_case() {
    let mat = Material::STEEL;
    // Static load per wheel: (wheelset 1109 kg + suspended mass 3781 kg) g / 2.
    let n = (1109.0 + 3781.0) * 9.81 / 2.0;
    println!("ML95-like: N = {n:.2} N per wheel");
    let table2 = CreepCoefficients {
        f11: 5.5e6,
        f22: 5e6,
        f23: 9.3e3,
        f33: 15.0,
    };
    for (label, r0) in [
        ("r0 0.425 m", 0.425),
        ("r0 0.85 m (Table 2 as printed)", 0.85),
    ] {
        let (el, f) = coefficients(r0, 0.30, n, &mat);
        line(&format!("  {label}"), el, f, &mat);
        println!(
            "    vs Table 2: f11 {:+.1} %, f22 {:+.1} %, f23 {:+.1} %, f33 {:+.1} %",
            100.0 * (f.f11 / table2.f11 - 1.0),
            100.0 * (f.f22 / table2.f22 - 1.0),
            100.0 * (f.f23 / table2.f23 - 1.0),
            100.0 * (f.f33 / table2.f33 - 1.0)
        );
    }
    // What the CONTACT-style interpolation in nu (parabola in 1/C through the three
    // columns) would give instead of the linear one, at the r0 0.425 ellipse.
    let (el, _) = coefficients(0.425, 0.30, n, &mat);
    let ab = el.a / el.b;
    let (c0, c1, c2) = (kalker_c(ab, 0.0), kalker_c(ab, 0.25), kalker_c(ab, 0.5));
    let nu: f64 = 0.3;
    let mut diffs = [0.0; 4];
    for q in 0..4 {
        let inv = (nu - 0.25) * (nu - 0.5) * 8.0 / c0[q] - (nu - 0.5) * nu * 16.0 / c1[q]
            + nu * (nu - 0.25) * 8.0 / c2[q];
        diffs[q] = 100.0 * (1.0 / inv / kalker_c(ab, nu)[q] - 1.0);
    }
    println!(
        "  parabola-in-1/C (CONTACT) vs linear-in-nu interpolation at nu 0.3: \
         C11 {:+.2} %, C22 {:+.2} %, C23 {:+.2} %, C33 {:+.2} %",
        diffs[0], diffs[1], diffs[2], diffs[3]
    );
    // Sensitivity of the ML95 figures to the rail crown radius (UIC60 head: 300 mm crown,
    // 80 mm and 13 mm towards the gauge corner).
    for crown in [0.2, 0.3, 0.5] {
        let (el, f) = coefficients(0.425, crown, n, &mat);
        line(&format!("  r0 0.425, crown {crown} m"), el, f, &mat);
    }
    for d in diffs {
        assert!(d.abs() < 1.0);
    }
}
