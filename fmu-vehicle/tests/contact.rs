//! Tests of the wheel-rail contact module against the independent oracles of
//! /work/docs/references.md sections 4-5 and analytic properties.

use fmu_vehicle::contact::*;

fn rel(x: f64, y: f64) -> f64 {
    (x - y).abs() / y.abs()
}

/// docs/references.md section 4 worked example: N 40 kN, r0 0.43 m, coned tread, rail crown 0.30 m.
fn worked_example() -> (ContactGeometry, Material, f64) {
    (ContactGeometry::coned(0.43, 0.30), Material::STEEL, 40e3)
}

// ---------------------------------------------------------------- elliptic integrals, Hertz

#[test]
fn elliptic_integrals_known_values() {
    // Parameter m = k^2 = 0.5 (Abramowitz & Stegun table 17.1, scipy ellipk/ellipe).
    assert!((elliptic_k(0.5) - 1.854_074_677_301_372).abs() < 1e-13);
    assert!((elliptic_e(0.5) - 1.350_643_881_047_675).abs() < 1e-13);
    // The brief's 9-decimal figures.
    assert!((elliptic_k(0.5) - 1.854074677).abs() < 1e-9);
    assert!((elliptic_e(0.5) - 1.350643881).abs() < 1e-9);
    // Further values: K(0.9) = 2.578092113348173, E(0.9) = 1.104774732704073,
    // K(0.1) = 1.612441348720219, E(0.1) = 1.530757636897763.
    assert!((elliptic_k(0.9) - 2.578_092_113_348_173).abs() < 1e-13);
    assert!((elliptic_e(0.9) - 1.104_774_732_704_073).abs() < 1e-13);
    assert!((elliptic_k(0.1) - 1.612_441_348_720_219).abs() < 1e-13);
    assert!((elliptic_e(0.1) - 1.530_757_636_897_763).abs() < 1e-13);
    // Limits.
    assert_eq!(elliptic_k(1.0), f64::INFINITY);
    assert_eq!(elliptic_e(1.0), 1.0);
    assert!(elliptic_k(1.5).is_nan() && elliptic_e(f64::NAN).is_nan());
    // Legendre's relation: E K' + E' K - K K' = pi/2.
    for m in [0.01, 0.2, 0.5, 0.77, 0.99] {
        let (k, e, kc, ec) = (
            elliptic_k(m),
            elliptic_e(m),
            elliptic_k(1.0 - m),
            elliptic_e(1.0 - m),
        );
        assert!((e * kc + ec * k - k * kc - std::f64::consts::FRAC_PI_2).abs() < 1e-13);
    }
}

#[test]
fn hertz_coefficients_table() {
    let (m30, n30) = hertz_coefficients(30f64.to_radians());
    let (m60, n60) = hertz_coefficients(60f64.to_radians());
    // Tabulated to 3 decimals (docs/references.md section 4).
    assert!((m30 - 2.731).abs() < 0.0015, "m(30) = {m30}");
    assert!((n30 - 0.493).abs() < 0.0015, "n(30) = {n30}");
    assert!((m60 - 1.486).abs() < 0.0015, "m(60) = {m60}");
    assert!((n60 - 0.717).abs() < 0.0015, "n(60) = {n60}");
    let (m90, n90) = hertz_coefficients(90f64.to_radians());
    assert!((m90 - 1.0).abs() < 1e-12 && (n90 - 1.0).abs() < 1e-12);
    // m grows and n shrinks as the contact gets more elongated (theta -> 0).
    let mut prev = (1.0, 1.0);
    for deg in (5..90).rev().step_by(5) {
        let (m, n) = hertz_coefficients((deg as f64).to_radians());
        assert!(m > prev.0 && n < prev.1, "not monotone at {deg} deg");
        prev = (m, n);
    }
}

#[test]
fn hertz_ellipse_satisfies_its_defining_equations() {
    // Johnson eq. 3.46: A = p0 b (K - E) / (E* e^2 a^2), B = p0 b (a^2 E / b^2 - K) / (E* e^2 a^2),
    // N = 2 pi a b p0 / 3. Recover A and B from the computed ellipse and compare.
    let mat = Material::STEEL;
    for (r0, rc, n) in [
        (0.43, 0.30, 40e3),
        (0.425, 0.3, 23e3),
        (0.46, 0.3, 60e3),
        (0.5, 0.8, 1e4),
    ] {
        let geom = ContactGeometry::coned(r0, rc);
        let el = hertz(&geom, &mat, n);
        let (major, minor) = (el.a.max(el.b), el.a.min(el.b));
        let k = minor / major;
        let m = 1.0 - k * k;
        let (kk, ee) = (elliptic_k(m), elliptic_e(m));
        let p0 = 3.0 * n / (2.0 * std::f64::consts::PI * el.a * el.b);
        let es = mat.reduced_modulus();
        let a_curv = p0 * minor * (kk - ee) / (es * m * major * major);
        let b_curv = p0 * minor * (ee / (k * k) - kk) / (es * m * major * major);
        let (sx, sy) = geom.curvature_sums();
        assert!(rel(a_curv, 0.5 * sx.min(sy)) < 1e-9, "A {a_curv}");
        assert!(rel(b_curv, 0.5 * sx.max(sy)) < 1e-9, "B {b_curv}");
    }
}

#[test]
fn hertz_worked_example() {
    let (geom, mat, n) = worked_example();
    let el = hertz(&geom, &mat, n);
    assert!(rel(el.a, 5.11e-3) < 0.01, "a = {} mm", el.a * 1e3);
    assert!(rel(el.b, 4.02e-3) < 0.01, "b = {} mm", el.b * 1e3);
    // The long axis is in the rolling direction (rolling curvature 1/0.43 < lateral 1/0.30).
    assert!(el.a > el.b);
}

#[test]
fn hertz_orientation_and_symmetry() {
    let mat = Material::STEEL;
    // Swapping the curvatures of the two directions swaps the axes.
    let g1 = ContactGeometry::coned(0.43, 0.30);
    let g2 = ContactGeometry {
        wheel_radius: 0.30,
        wheel_transverse_radius: f64::INFINITY,
        rail_crown_radius: 0.43,
    };
    let (e1, e2) = (hertz(&g1, &mat, 5e4), hertz(&g2, &mat, 5e4));
    assert!(rel(e1.a, e2.b) < 1e-12 && rel(e1.b, e2.a) < 1e-12);
    // Equal curvature sums: a circle of the classical radius (3 N R / (4 E*))^(1/3), with
    // 1/R = 1/R1 + 1/R2 = 1/0.4 in both directions here (Johnson eq. 4.22).
    let g = ContactGeometry::coned(0.4, 0.4);
    let e = hertz(&g, &mat, 3e4);
    let r = (3.0 * 3e4 * 0.4 / (4.0 * mat.reduced_modulus())).cbrt();
    assert!(rel(e.a, r) < 1e-12 && rel(e.b, r) < 1e-12);
    // A convex wheel transverse radius adds lateral curvature; a concave one removes it.
    let convex = ContactGeometry {
        wheel_transverse_radius: 1.0,
        ..g1
    };
    let concave = ContactGeometry {
        wheel_transverse_radius: -1.0,
        ..g1
    };
    assert!(hertz(&convex, &mat, 5e4).b < e1.b && hertz(&concave, &mat, 5e4).b > e1.b);
}

#[test]
fn hertz_load_scaling_and_wheel_lift() {
    let (geom, mat, _) = worked_example();
    let e1 = hertz(&geom, &mat, 1e4);
    let e8 = hertz(&geom, &mat, 8e4);
    assert!(rel(e8.a, 2.0 * e1.a) < 1e-13 && rel(e8.b, 2.0 * e1.b) < 1e-13);
    for n in [0.0, -1.0, f64::NAN] {
        assert_eq!(hertz(&geom, &mat, n), Ellipse::ZERO);
    }
}

#[test]
fn invalid_inputs_are_reported() {
    let mat = Material::STEEL;
    let conformal = ContactGeometry {
        wheel_radius: 0.43,
        wheel_transverse_radius: -0.25, // concave tread tighter than the rail crown
        rail_crown_radius: 0.30,
    };
    assert!(matches!(
        try_hertz(&conformal, &mat, 1e4),
        Err(ContactError::InvalidGeometry { .. })
    ));
    let bad = Material {
        young: 2.1e11,
        poisson: 0.5,
    };
    assert!(matches!(
        try_hertz(&ContactGeometry::coned(0.43, 0.3), &bad, 1e4),
        Err(ContactError::InvalidMaterial { .. })
    ));
    assert!(matches!(
        CreepLaw::try_new(&ContactGeometry::coned(0.43, 0.3), &mat, 0.0),
        Err(ContactError::InvalidReferenceLoad(_))
    ));
    let msg = CreepLaw::try_new(&conformal, &mat, 1e4)
        .unwrap_err()
        .to_string();
    assert!(msg.contains("non-Hertzian"), "{msg}");
}

#[test]
#[should_panic(expected = "non-Hertzian")]
fn hertz_panics_on_a_conformal_geometry() {
    let conformal = ContactGeometry {
        wheel_radius: 0.43,
        wheel_transverse_radius: -0.25,
        rail_crown_radius: 0.30,
    };
    hertz(&conformal, &Material::STEEL, 1e4);
}

#[test]
fn material_moduli() {
    let s = Material::default();
    assert_eq!(s, Material::STEEL);
    assert!(rel(s.shear_modulus(), 2.1e11 / 2.6) < 1e-15);
    assert!(rel(s.reduced_modulus(), 2.1e11 / (2.0 * 0.91)) < 1e-15);
}

// ---------------------------------------------------------------- Kalker

/// docs/references.md section 4, nu = 0.25: (a/b, [C11, C22, C23, C33]).
#[allow(clippy::approx_constant)] // 3.14 is a table entry, not pi
const RAILWAY_MD_NU_025: [(f64, [f64; 4]); 9] = [
    (0.2, [3.37, 2.63, 0.603, 4.27]),
    (0.4, [3.53, 2.88, 0.823, 2.32]),
    (0.6, [3.72, 3.14, 1.03, 1.68]),
    (0.8, [3.91, 3.41, 1.25, 1.37]),
    (1.0, [4.12, 3.67, 1.47, 1.19]),
    (1.0 / 0.8, [4.36, 3.99, 1.75, 1.04]),
    (1.0 / 0.6, [4.78, 4.50, 2.23, 0.892]),
    (1.0 / 0.4, [5.57, 5.48, 3.24, 0.747]),
    (1.0 / 0.2, [7.78, 8.14, 6.63, 0.601]),
];

#[test]
fn kalker_table_reproduces_references_at_nu_025() {
    for (a_over_b, expect) in RAILWAY_MD_NU_025 {
        let c = kalker_c(a_over_b, 0.25);
        for q in 0..4 {
            assert!(
                rel(c[q], expect[q]) < 1e-12,
                "a/b {a_over_b}: C{} = {} vs {}",
                ["11", "22", "23", "33"][q],
                c[q],
                expect[q]
            );
        }
    }
}

#[test]
fn kalker_table_other_columns_at_nodes() {
    // Spot checks of Kalker 1990 Table E.3 (via CONTACT's linrol) at nu = 0 and 0.5.
    let c = kalker_c(1.0, 0.0);
    assert_eq!([c[0], c[1], c[2]], [3.40, 3.40, 1.33]);
    let c = kalker_c(1.0, 0.5);
    assert_eq!([c[0], c[1], c[2]], [5.20, 3.98, 1.63]);
    let c = kalker_c(5.0, 0.5);
    assert!(rel(c[0], 8.82) < 1e-12 && rel(c[1], 9.79) < 1e-12 && rel(c[2], 7.89) < 1e-12);
    let c = kalker_c(0.3, 0.0);
    assert!(rel(c[0], 2.68) < 1e-12 && rel(c[2], 0.607) < 1e-12);
    // Poisson's ratio: linear between the columns.
    let (c0, c25, c30) = (kalker_c(1.0, 0.25), kalker_c(1.0, 0.5), kalker_c(1.0, 0.3));
    for q in 0..4 {
        assert!(rel(c30[q], 0.8 * c0[q] + 0.2 * c25[q]) < 1e-14);
    }
}

#[test]
fn kalker_interpolation_is_continuous_and_monotone() {
    for nu in [0.0, 0.1, 0.25, 0.28, 0.3, 0.4, 0.5] {
        // Continuity across a/b = 1 (both halves share the circular row).
        let (below, at, above) = (
            kalker_c(1.0 - 1e-12, nu),
            kalker_c(1.0, nu),
            kalker_c(1.0 + 1e-12, nu),
        );
        for q in 0..4 {
            assert!((below[q] - at[q]).abs() < 1e-9 && (above[q] - at[q]).abs() < 1e-9);
        }
        // Monotone in a/b over the whole table (0.1 .. 10, log-spaced): C11, C22, C23
        // non-decreasing and C33 non-increasing. Kalker's C11 column itself dips by 1 % for
        // a/b < 0.3 near nu = 0.5, so C11 is checked from a/b = 0.3 up when nu > 0.3.
        let mut prev = kalker_c(0.1, nu);
        for i in 1..=2000 {
            let ab = 10f64.powf(-1.0 + 2.0 * i as f64 / 2000.0);
            let c = kalker_c(ab, nu);
            let check_c11 = nu <= 0.3 || ab >= 0.3;
            assert!(
                !check_c11 || c[0] >= prev[0] - 1e-15,
                "C11 at a/b {ab}, nu {nu}"
            );
            assert!(c[1] >= prev[1] - 1e-15, "C22 at a/b {ab}, nu {nu}");
            assert!(c[2] >= prev[2] - 1e-15, "C23 at a/b {ab}, nu {nu}");
            assert!(c[3] <= prev[3] + 1e-15, "C33 at a/b {ab}, nu {nu}");
            prev = c;
        }
    }
    // Monotone in nu as well for C11, C22, C23 (Kalker's columns all increase with nu).
    for ab in [0.15, 0.5, 1.0, 1.3, 4.0] {
        let (a, b, c) = (kalker_c(ab, 0.1), kalker_c(ab, 0.3), kalker_c(ab, 0.45));
        for q in 0..3 {
            assert!(
                a[q] <= b[q] && b[q] <= c[q],
                "C{q} not increasing in nu at a/b {ab}"
            );
        }
    }
}

#[test]
fn kalker_clamping_outside_the_table() {
    assert_eq!(kalker_c(0.05, 0.25), kalker_c(0.1, 0.25));
    assert_eq!(kalker_c(20.0, 0.25), kalker_c(10.0, 0.25));
    assert_eq!(kalker_c(1.3, -0.1), kalker_c(1.3, 0.0));
    assert_eq!(kalker_c(1.3, 0.7), kalker_c(1.3, 0.5));
    assert!(kalker_c(f64::NAN, 0.3)[0].is_nan());
    assert_eq!(KALKER_TABLE_MIN_RATIO, 0.1);
}

#[test]
fn creep_coefficients_worked_example() {
    let (geom, mat, n) = worked_example();
    let f = creep_coefficients(hertz(&geom, &mat, n), &mat);
    assert!(rel(f.f11, 7.56e6) < 0.02, "f11 = {}", f.f11);
    assert!(rel(f.f22, 6.78e6) < 0.02, "f22 = {}", f.f22);
    assert!(rel(f.f23, 13.6e3) < 0.02, "f23 = {}", f.f23);
    assert!(rel(f.f33, 34.5) < 0.02, "f33 = {}", f.f33);
    // Using E instead of G would overstate by 2 (1 + nu) = 2.6 (docs/references.md's warning).
    assert!(f.f11 < 8e6);
}

#[test]
fn creep_coefficients_definition() {
    let mat = Material::STEEL;
    let el = Ellipse { a: 6e-3, b: 3e-3 };
    let c = kalker_c(2.0, 0.3);
    let g = mat.shear_modulus();
    let ab: f64 = 18e-6;
    let f = creep_coefficients(el, &mat);
    assert!(rel(f.f11, g * ab * c[0]) < 1e-14);
    assert!(rel(f.f22, g * ab * c[1]) < 1e-14);
    assert!(rel(f.f23, g * ab.powf(1.5) * c[2]) < 1e-14);
    assert!(rel(f.f33, g * ab * ab * c[3]) < 1e-14);
    assert_eq!(
        creep_coefficients(Ellipse::ZERO, &mat),
        CreepCoefficients::default()
    );
}

#[test]
fn creep_law_matches_direct_computation() {
    let mat = Material::STEEL;
    for geom in [
        ContactGeometry::coned(0.43, 0.30),
        ContactGeometry::coned(0.425, 0.30),
        ContactGeometry::coned(0.25, 0.60), // ellipse long in the lateral direction
        ContactGeometry {
            wheel_radius: 0.46,
            wheel_transverse_radius: 0.5,
            rail_crown_radius: 0.3,
        },
    ] {
        let law = CreepLaw::new(&geom, &mat, 40e3);
        for n in [1.0, 500.0, 12e3, 23_985.45, 40e3, 77e3, 2.5e5] {
            let direct = creep_coefficients(hertz(&geom, &mat, n), &mat);
            let fast = law.at_load(n);
            for (x, y) in [
                (fast.f11, direct.f11),
                (fast.f22, direct.f22),
                (fast.f23, direct.f23),
                (fast.f33, direct.f33),
            ] {
                assert!(rel(x, y) < 1e-12, "N {n}: {x} vs {y}");
            }
        }
        // Scaling exponents: doubling the load multiplies by 2^(2/3), 2^(2/3), 2, 2^(4/3).
        let (f1, f2) = (law.at_load(20e3), law.at_load(40e3));
        assert!(rel(f2.f11 / f1.f11, 2f64.powf(2.0 / 3.0)) < 1e-14);
        assert!(rel(f2.f22 / f1.f22, 2f64.powf(2.0 / 3.0)) < 1e-14);
        assert!(rel(f2.f23 / f1.f23, 2.0) < 1e-14);
        assert!(rel(f2.f33 / f1.f33, 2f64.powf(4.0 / 3.0)) < 1e-14);
        // The reference load is reproduced exactly.
        assert_eq!(law.at_load(40e3), law.reference_coefficients());
        assert_eq!(law.reference_load(), 40e3);
        // Wheel lift.
        for n in [0.0, -100.0, f64::NAN] {
            assert_eq!(law.at_load(n), CreepCoefficients::default());
            let forces = linear_creep(
                &law.at_load(n),
                &Creepages {
                    longitudinal: 1e-3,
                    lateral: 2e-3,
                    spin: 0.1,
                },
            );
            assert_eq!(forces, CreepForces::default());
            assert_eq!(saturate(forces, 0.3, n), CreepForces::default());
        }
    }
}

#[test]
fn creep_law_reference_load_does_not_matter() {
    let (geom, mat, _) = worked_example();
    let (l1, l2) = (
        CreepLaw::new(&geom, &mat, 1e3),
        CreepLaw::new(&geom, &mat, 9e4),
    );
    let (a, b) = (l1.at_load(31e3), l2.at_load(31e3));
    assert!(rel(a.f11, b.f11) < 1e-12 && rel(a.f33, b.f33) < 1e-12);
}

#[test]
fn creep_law_scaled_and_from_coefficients() {
    let (geom, mat, n) = worked_example();
    let law = CreepLaw::new(&geom, &mat, n);
    let half = law.scaled(0.5);
    let (f, h) = (law.at_load(3e4), half.at_load(3e4));
    assert_eq!(
        (h.f11, h.f22, h.f23, h.f33),
        (0.5 * f.f11, 0.5 * f.f22, 0.5 * f.f23, 0.5 * f.f33)
    );
    // The paper's Table 2 coefficients as a law through the static wheel load.
    let table2 = CreepCoefficients {
        f11: 5.5e6,
        f22: 5e6,
        f23: 9.3e3,
        f33: 15.0,
    };
    let paper = CreepLaw::from_coefficients(table2, 23_985.45).unwrap();
    assert_eq!(paper.at_load(23_985.45), table2);
    assert!(rel(paper.at_load(2.0 * 23_985.45).f23, 2.0 * 9.3e3) < 1e-14);
    assert!(CreepLaw::from_coefficients(table2, -1.0).is_err());
}

#[test]
fn creep_law_serde_round_trip() {
    let (geom, mat, n) = worked_example();
    let law = CreepLaw::new(&geom, &mat, n);
    let text = toml::to_string(&law).unwrap();
    let back: CreepLaw = toml::from_str(&text).unwrap();
    assert_eq!(law, back);
    let g: ContactGeometry = toml::from_str(&toml::to_string(&geom).unwrap()).unwrap();
    assert_eq!(g.wheel_radius, geom.wheel_radius);
}

// ---------------------------------------------------------------- creep forces

#[test]
fn linear_creep_signs() {
    let c = CreepCoefficients {
        f11: 7e6,
        f22: 6e6,
        f23: 1.3e4,
        f33: 30.0,
    };
    let f = |lon, lat, spin| {
        linear_creep(
            &c,
            &Creepages {
                longitudinal: lon,
                lateral: lat,
                spin,
            },
        )
    };
    let p = f(1e-3, 0.0, 0.0);
    assert_eq!((p.fx, p.fy, p.mz), (-7e3, 0.0, 0.0));
    let p = f(0.0, 1e-3, 0.0);
    assert_eq!((p.fx, p.fy, p.mz), (0.0, -6e3, 13.0));
    let p = f(0.0, 0.0, 0.1);
    assert_eq!((p.fx, p.fy, p.mz), (0.0, -1.3e3, -3.0));
    // Linear superposition.
    let p = f(1e-3, 1e-3, 0.1);
    assert_eq!((p.fx, p.fy, p.mz), (-7e3, -6e3 - 1.3e3, 13.0 - 3.0));
}

#[test]
fn saturation_small_creep_is_linear() {
    let (mu, n) = (0.3, 4e4);
    // u = 1e-3: relative change u/3 ~ 3.3e-4 < 1e-3.
    let lin = CreepForces {
        fx: 0.6 * 1e-3 * mu * n,
        fy: -0.8 * 1e-3 * mu * n,
        mz: 0.5,
    };
    let s = saturate(lin, mu, n);
    assert!(rel(s.tangential(), lin.tangential()) < 1e-3);
    assert!(rel(s.fx, lin.fx) < 1e-3 && rel(s.fy, lin.fy) < 1e-3 && rel(s.mz, lin.mz) < 1e-3);
    // Exactly linear at zero force.
    let zero = CreepForces {
        fx: 0.0,
        fy: 0.0,
        mz: 2.0,
    };
    assert_eq!(saturate(zero, mu, n), zero);
    // F' = mu N (u - u^2/3 + u^3/27) for u <= 3, direction kept.
    let lin = CreepForces {
        fx: 3.0 * 0.36 * mu * n,
        fy: 4.0 * 0.36 * mu * n,
        mz: 1.0,
    }; // u = 1.8
    let s = saturate(lin, mu, n);
    let u: f64 = 1.8;
    assert!(
        rel(
            s.tangential(),
            mu * n * (u - u * u / 3.0 + u.powi(3) / 27.0)
        ) < 1e-14
    );
    assert!(rel(s.fx / s.fy, 0.75) < 1e-14);
    assert!(rel(s.mz, she_factor(u)) < 1e-14);
}

#[test]
fn saturation_large_creep_tends_to_mu_n() {
    let (mu, n) = (0.35, 3e4);
    for u in [3.0, 3.5, 10.0, 1e3, 1e9] {
        let lin = CreepForces {
            fx: -u * mu * n / 2f64.sqrt(),
            fy: u * mu * n / 2f64.sqrt(),
            mz: -7.0,
        };
        let s = saturate(lin, mu, n);
        assert!(rel(s.tangential(), mu * n) < 1e-12, "u {u}");
        assert!(s.fx < 0.0 && s.fy > 0.0 && s.mz < 0.0);
    }
    // The saturated magnitude is monotone and never exceeds mu N.
    let mut prev = 0.0;
    for i in 0..=600 {
        let u = i as f64 * 0.01;
        let f = u * she_factor(u);
        assert!(f >= prev - 1e-15 && f <= 1.0 + 1e-15, "u {u}");
        prev = f;
    }
    // No friction or no load: no force.
    let lin = CreepForces {
        fx: 1.0,
        fy: 1.0,
        mz: 1.0,
    };
    assert_eq!(saturate(lin, 0.0, n), CreepForces::default());
    assert_eq!(saturate(lin, mu, 0.0), CreepForces::default());
}

#[test]
fn saturation_is_continuous_and_smooth_at_u_3() {
    let h = 1e-9;
    let (below, at, above) = (
        (3.0 - h) * she_factor(3.0 - h),
        3.0 * she_factor(3.0),
        (3.0 + h) * she_factor(3.0 + h),
    );
    assert!((at - 1.0).abs() < 1e-15);
    assert!((below - at).abs() < 1e-12 && (above - at).abs() < 1e-12);
    // The factor itself: 1/3 from both sides, slope -1/9 from both sides.
    assert!((she_factor(3.0) - 1.0 / 3.0).abs() < 1e-15);
    let h = 1e-6;
    let left = (she_factor(3.0) - she_factor(3.0 - h)) / h;
    let right = (she_factor(3.0 + h) - she_factor(3.0)) / h;
    assert!((left + 1.0 / 9.0).abs() < 1e-6 && (right + 1.0 / 9.0).abs() < 1e-6);
}

#[test]
fn flange_dead_band_then_restoring_spring() {
    let (c, k) = (9e-3, 12e6);
    for u in [0.0, 1e-3, -5e-3, 9e-3, -9e-3] {
        assert_eq!(flange_force(u, c, k), 0.0, "u {u}");
    }
    assert!(rel(flange_force(10e-3, c, k), -12e3) < 1e-12);
    assert!(rel(flange_force(-11e-3, c, k), 24e3) < 1e-12);
    // Continuous at the band edge, odd in u.
    assert!(flange_force(9e-3 + 1e-12, c, k).abs() < 1e-4);
    for u in [0.0095, 0.02, 0.05] {
        assert_eq!(flange_force(-u, c, k), -flange_force(u, c, k));
    }
    // No clearance: a plain spring.
    assert_eq!(flange_force(1e-3, 0.0, k), -k * 1e-3);
    assert_eq!(flange_force(1e-3, -1.0, k), -k * 1e-3);
}
