//! The vehicle on curves against steady-curving oracles (derivation: `fmu_vehicle::curving`).

use fmi_abi::{InstantiateContext, Logger, Model, Values};
use fmu_vehicle::curving::Curving;
use fmu_vehicle::dynamics::{Dof, GRAVITY, Vehicle, WheelsetTrack, dof};
use fmu_vehicle::fmu::{RailVehicle, VARIABLES, build_simulation, vr};
use fmu_vehicle::params::VehicleParams;
use fmu_vehicle::simulation::{Outputs, Simulation};

/// A vehicle on a clean track (no irregularities, no noise) with `edit` applied.
fn simulation(edit: impl FnOnce(&mut Values)) -> Simulation {
    let mut v = Values::from_table(VARIABLES);
    v.boolean[vr::LATERAL_IRREGULARITY as usize] = false;
    v.boolean[vr::VERTICAL_IRREGULARITY as usize] = false;
    v.boolean[vr::SENSOR_NOISE as usize] = false;
    edit(&mut v);
    let model =
        RailVehicle::instantiate(&InstantiateContext::default(), &Logger::silent()).unwrap();
    build_simulation(&model, &v, &Logger::silent()).unwrap()
}

/// One curve of radius `r` and cant `cant` (m) from 20 m on, 60 m transitions, 600 m long.
fn curve(r: f64, cant: f64, direction: i32) -> impl FnOnce(&mut Values) {
    move |v: &mut Values| {
        v.real[vr::CURVE_RADIUS as usize] = r;
        v.real[vr::CURVE_CANT as usize] = cant;
        v.real[vr::CURVE_START as usize] = 20.0;
        v.real[vr::CURVE_TRANSITION as usize] = 60.0;
        v.real[vr::CURVE_LENGTH as usize] = 600.0;
        v.integer[vr::CURVE_DIRECTION as usize] = direction;
    }
}

/// Removes the primary longitudinal stiffness: the wheelsets are free to yaw (steered by
/// their creep forces alone; the longitudinal dampers stay, and the speed is kept low, because
/// a wheelset without yaw stiffness hunts at any higher speed).
fn yaw_free(sim: &mut Simulation) {
    let mut params = sim.vehicle.params.clone();
    params.primary.kx = 0.0;
    sim.vehicle = Vehicle::new(params, sim.vehicle.conicity, sim.vehicle.options);
}

/// The state averaged over `seconds` at `speed` (the yaw-free wheelsets keep a small kinematic
/// oscillation; its period is about 2 s at 5 m/s).
fn mean_state(sim: &mut Simulation, seconds: f64, speed: f64) -> Dof {
    let n = (seconds / 1e-3).round() as usize;
    let mut sum = Dof::zeros();
    for _ in 0..n {
        sim.step(1e-3, speed);
        sum += sim.q;
    }
    sum / n as f64
}

fn run(sim: &mut Simulation, seconds: f64, speed: f64) -> Vec<Outputs> {
    let h = 1e-3;
    let n = (seconds / h).round() as usize;
    (0..n)
        .map(|_| {
            sim.step(h, speed);
            sim.outputs
        })
        .collect()
}

/// A wheelset free to yaw in a steady curve settles where both wheels roll without
/// longitudinal creep: the contact point shifted outwards by `r0 l / (alpha R)` (Boocock's
/// pure-rolling line; Wickens, *Fundamentals of rail vehicle dynamics*, ch. 6). The model's
/// wheelset also rolls with its cone, which moves the contact point by `r0 alpha / l` of the
/// shift, so its centre is at `(1 - r0 alpha / l)` of it. The primary longitudinal stiffness
/// and damping are removed (yaw-free wheelsets); the lateral stiffness stays.
#[test]
fn yaw_free_wheelsets_take_the_pure_rolling_shift() {
    let p = VehicleParams::ml95();
    let (r0, l) = (p.wheelset.rolling_radius, p.wheelset.half_gauge);
    for (alpha, r) in [(0.1, 1000.0), (0.2, 400.0)] {
        let mut sim = simulation(|v| {
            curve(r, 0.0, 1)(v);
            v.real[vr::CONICITY as usize] = alpha;
        });
        yaw_free(&mut sim);
        let speed = 5.0;
        run(&mut sim, 20.0, speed); // into the circular part (from 80 m on)
        let q = mean_state(&mut sim, 40.0, speed);
        let pure = r0 * l / (alpha * r) * (1.0 - r0 * alpha / l);
        for j in 0..4 {
            let y = q[dof::wheelset(j)];
            assert!(
                (-y / pure - 1.0).abs() < 0.03,
                "alpha {alpha}, R {r} m: wheelset {j} shifted {:.3} mm, pure rolling {:.3} mm outwards",
                y * 1e3,
                pure * 1e3
            );
        }
    }
}

/// With the cant balancing the curve (`V^2 / R = g c / (2 l)`) nothing pushes the vehicle
/// sideways, so its bodies sit where the geometry puts them: each bogie centre at the mean of
/// its wheelsets plus the curve's offset `a^2 / (2 R)` from the chord between them, the car body
/// at the mean of its bogies plus `l_b^2 / (2 R)` (yaw-free wheelsets, as above, so no
/// wheelset is forced against the curve), all measured where the springs join them (the
/// wheelsets roll with their cone and the bodies with them, which moves the spring points by
/// their heights times the roll). The accelerometers read only the cone's roll.
#[test]
fn a_balanced_curve_puts_the_bodies_on_their_chords() {
    let p = VehicleParams::ml95();
    let (l, a, lb) = (
        p.wheelset.half_gauge,
        p.bogie.semi_wheelbase,
        p.car_body.semi_bogie_distance,
    );
    let (r, speed) = (800.0, 5.0);
    let cant = speed * speed / r * 2.0 * l / GRAVITY;
    let mut sim = simulation(curve(r, cant, -1));
    yaw_free(&mut sim);
    run(&mut sim, 20.0, speed);
    let q = mean_state(&mut sim, 40.0, speed);
    let out = run(&mut sim, 0.001, speed);
    let k = -1.0 / r;
    // Lateral positions of the spring points: a body rolled by phi moves a point at height z
    // above rail level by -(z - h) phi, h its centre of gravity's height.
    let (hp, hs) = (p.primary.height, p.secondary.height);
    let (hb, hc, r0) = (
        p.bogie.cg_height,
        p.car_body.cg_height,
        p.wheelset.rolling_radius,
    );
    let at = |base: usize, z: f64, h: f64| q[base + dof::Y] - (z - h) * q[base + dof::ROLL];
    // The ML95's primary springs sit at the axle's height, so a wheelset's roll does not move
    // them.
    assert_eq!(hp, r0);
    let wheelset = |j: usize| q[dof::wheelset(j)];
    for b in 0..2 {
        let mean = (wheelset(2 * b) + wheelset(2 * b + 1)) / 2.0;
        let bogie = at(dof::bogie(b), hp, hb);
        let expect = mean + a * a * k / 2.0;
        assert!(
            (bogie - expect).abs() < 2e-5,
            "bogie {b}'s primary spring points at {:.4} mm, geometry says {:.4} mm",
            bogie * 1e3,
            expect * 1e3
        );
    }
    let mean = (at(dof::bogie(0), hs, hb) + at(dof::bogie(1), hs, hb)) / 2.0;
    let body = at(dof::CAR, hs, hc);
    let expect = mean + lb * lb * k / 2.0;
    assert!(
        (body - expect).abs() < 2e-5,
        "car body's secondary spring points at {:.4} mm, geometry says {:.4} mm",
        body * 1e3,
        expect * 1e3
    );
    let o = out.last().unwrap();
    assert!(o.design_curvature == k && o.design_cant == -cant);
    let cone = GRAVITY * (o.ws_roll + o.design_cant / (2.0 * l));
    assert!(
        (o.ws_acc_y_clean - cone).abs() < 5e-3,
        "{} vs {cone}",
        o.ws_acc_y_clean
    );
    // (The yaw-free wheelsets oscillate a little about their steady yaw.)
    assert!((o.ws_yaw_rate_clean - speed * k).abs() < 0.1 * (speed * k).abs());
}

/// Under a cant deficiency the accelerometer on the wheelset reads the uncompensated lateral
/// acceleration `V^2 / R - g c / (2 l)` (plus gravity through its cone roll), the yaw gyroscope
/// `V / R`, and the outer wheel carries more load; a right-hand curve mirrors a left-hand one.
#[test]
fn a_cant_deficiency_reads_as_the_uncompensated_acceleration() {
    let p = VehicleParams::ml95();
    let l = p.wheelset.half_gauge;
    let (r, cant, speed) = (600.0, 0.06, 20.0);
    let a_nc = speed * speed / r - GRAVITY * cant / (2.0 * l);
    let left = run(&mut simulation(curve(r, cant, 1)), 25.0, speed);
    let right = run(&mut simulation(curve(r, cant, -1)), 25.0, speed);
    let (o, m) = (left.last().unwrap(), right.last().unwrap());
    let cone = GRAVITY * (o.ws_roll + o.design_cant / (2.0 * l));
    assert!(
        (o.ws_acc_y_clean - cone - a_nc).abs() < 0.01 * a_nc,
        "reads {} + cone {cone}, a_nc {a_nc}",
        o.ws_acc_y_clean - cone
    );
    assert!((o.ws_yaw_rate_clean - speed / r).abs() < 1e-3 * speed / r);
    // The outer wheels carry the overturning moment of the D'Alembert forces at the centres of
    // gravity (a rigid vehicle's; the suspension's roll adds a little). Per wheelset, the
    // curving forces add couples of their own (the leading wheelset of a stiff bogie is held
    // inwards at its axle against outward creep at the rail), which cancel over the bogie.
    let mut sim = simulation(curve(r, cant, 1));
    run(&mut sim, 25.0, speed);
    let line = sim.line.clone().unwrap();
    let c = Curving::at(&line, &sim.vehicle, sim.s, speed);
    let (_, diag) = sim.vehicle.accelerations(
        &sim.q,
        &sim.qd,
        speed,
        &[WheelsetTrack::default(); 4],
        Some(&c),
    );
    let moment: f64 = diag.wheel_loads.iter().map(|n| l * (n[1] - n[0])).sum();
    let rigid = a_nc
        * (p.car_body.mass * p.car_body.cg_height
            + 2.0 * p.bogie.mass * p.bogie.cg_height
            + 4.0 * p.wheelset.mass * p.wheelset.rolling_radius);
    println!("overturning moment {moment:.0} N m, rigid vehicle {rigid:.0} N m");
    assert!((moment / rigid - 1.0).abs() < 0.05, "{moment} vs {rigid}");
    for (x, y) in [
        (o.ws_acc_y, m.ws_acc_y),
        (o.ws_yaw_rate, m.ws_yaw_rate),
        (o.frame_acc_y, m.frame_acc_y),
        (o.ws_y, m.ws_y),
        (o.body_roll, m.body_roll),
        (o.ws_roll_rate, m.ws_roll_rate),
    ] {
        assert!((x + y).abs() <= 1e-9 * x.abs().max(1e-6), "{x} vs {y}");
    }
    assert!((o.wheel_load_left - m.wheel_load_right).abs() < 1e-6);
}
