//! Equations of motion of the vehicle: car body, two bogie frames, four wheelsets on a track
//! with irregularities. Written here for straight track; what a curved, canted design line
//! adds is derived in [`crate::curving`].
//!
//! # Coordinates
//! A track frame moves with the vehicle at speed `V` along the *ideal* (irregularity-free) track
//! centre line: `x` forward, `y` to the left, `z` up from the rail level, rotations `phi` (roll,
//! about `x`, left side up positive), `theta` (pitch, about `y`, nose down positive) and `psi`
//! (yaw, about `z`, nose left positive). Every body's coordinates are small displacements of its
//! centre of gravity from its nominal position in that frame (the paper's track-relative
//! coordinates, which on straight track are absolute lateral and vertical positions). The
//! rails themselves are displaced by the irregularities; they do not move in time, so the
//! creepages contain no rail velocity.
//!
//! Degrees of freedom (23): car body `y, z, phi, theta, psi`; each bogie frame `y, z, phi,
//! theta, psi`; each wheelset `y, psi`. A wheelset's vertical position and roll are prescribed
//! by the track at its own position `s_j` along the track (trailing wheelsets see the same track
//! later): `z_w = xi_vp(s_j)`, `phi_w = xi_cl(s_j) / (2 l) + alpha u_c / l`, the second term
//! being the roll of a coned wheelset displaced by `u_c` (below) on knife-edge rails (its left end
//! rides `alpha u_c` higher, its right end `alpha u_c` lower). Longitudinal motions
//! are not modelled (constant speed; traction and braking are outside the model).
//!
//! # Suspension (Lagrange equations, linear elements with real geometry)
//! Each suspension element joins a point `P` of body `A` to the same point of body `B` with
//! stiffness and damping along `x`, `y`, `z`. A small rigid motion `(u_t, theta)` moves the point
//! by `u_t + theta x r`, `r` the point's offset from the body's centre of gravity, so the element
//! deflects by `d = (u_A + theta_A x r_A) - (u_B + theta_B x r_B)` and acts on `A` with
//! `F = -(K d + C d')`, on `B` with `-F`; the generalized forces are the force and the moment
//! `r x F` about each centre of gravity. Heights and lateral spacings therefore couple lateral
//! motion, roll and yaw exactly as in the real vehicle: a lateral secondary force below the car
//! body's centre of gravity rolls it, longitudinal springs at `+/- b` give yaw stiffness
//! `2 kx b^2`, vertical springs at `+/- b` give roll stiffness `2 kz b^2`.
//!
//! Static loads: the secondary springs carry `m_c g / 4` each, the primary springs
//! `(m_b + m_c / 2) g / 4` each, the wheels their axle box loads plus half the wheelset's
//! weight. Gravity and these preloads cancel in the equations of motion, which are written for
//! the motion about static equilibrium, except for one second-order effect kept because it is
//! first order in the equations: a vertical preload `F0` acting at a point that rotates with its
//! body has a lever arm changed by `theta x r`, giving the moment `(theta x r) x F0`
//! (the "geometric stiffness" of loads carried above or below a centre of gravity; for the car
//! body it is the familiar destabilizing roll term `m_c g h`). The lateral stiffness of loaded
//! springs includes their column effect, so the quoted stiffnesses are used as they are.
//! Rotational elements: an anti-roll bar between car body and each bogie (roll) and a yaw
//! stiffness per side (yaw).
//!
//! # Contact-level displacement
//! The rolling radii depend on where the knife-edge rail touches the wheel, measured along the
//! axle. A rail at lateral position `xi +/- l`, about `r_0` below the axle of a wheelset at `y`
//! rolled by `phi_w`, touches it at `+/- l - (y - xi + r_0 phi_w)` from the wheelset's centre:
//! the roll moves the contact point along the wheel by `r_0 phi_w`. So the displacement that
//! sets the rolling radii is `u_c = y - xi + r_0 phi_w`. The roll is the track's,
//! `phi_t = xi_cl / (2 l)`, plus the cone's, `alpha u_c / l`, hence
//! `u_c (1 - r_0 alpha / l) = y - xi + r_0 phi_t` (the familiar `l - r_0 delta` denominators of
//! linear wheelset models). A wheelset that rolls with a canted track about its contact points
//! has its centre at `y = xi - r_0 phi_t` and `u_c = 0`: nothing in the contact changes, as it
//! must. The lateral creepage below is consistent with this: its `r_0 phi_w'` term vanishes on
//! the same motion, and with cone roll included the free wheelset's kinematic wavelength is
//! still exactly Klingel's.
//!
//! # Wheel-rail contact, at each wheel
//! Coned treads (conicity `alpha`) on knife-edge rails, rolling radii `r_0 +/- alpha u_c`, upper
//! sign left; `u` below stands for `u_c`. The material point of the wheel at the contact moves, relative to the fixed rail,
//! with creepages (as in the estimator's model, `fmu-estimator/src/model.rs`):
//! - longitudinal `nu_x = -/+ (alpha u / r_0 + l psi' / V)`,
//! - lateral `nu_y = (y' + r_0 phi_w') / V - psi` (the roll rate moves the contact point, which
//!   lies `r_0` below the axle, sideways: this is one way cross-level reaches the lateral motion),
//! - spin `psi' / V -/+ alpha / r_0`.
//!
//! Kalker's linear theory gives `Fx = -f11 nu_x`, `Fy = -f22 nu_y - f23 spin`,
//! `Mz = f23 nu_y - f33 spin` per wheel, with the coefficients of `contact::CreepLaw` computed
//! from Hertz contact under the wheel's *current* normal load. Optionally the tangential forces
//! saturate (Shen-Hedrick-Elkins) and a flange force acts outside a dead band.
//!
//! Normal loads: the wheelset's vertical and roll equilibrium with its prescribed motion,
//! `N_L + N_R = m_w (g + z_w'') + F_L + F_R` (`F` the total downward primary force at each axle
//! box, static plus dynamic) and `l (N_L - N_R) = b_p (F_L - F_R) + h_a F_y`, where the lateral
//! primary force `F_y` acting at the axle height `h_a` is reacted quasi-statically at the rails
//! (the lateral load transfer). The wheelset's roll inertia is neglected in the loads.
//!
//! The normal forces are perpendicular to the cone, inclined by `-/+ alpha` to the wheelset's
//! axis normal, and the wheelset is rolled by `phi_w` in space; their lateral components sum to
//! `(N_R - N_L) alpha - (N_L + N_R) phi_w`. With `phi_w = alpha u / l` this is the
//! gravitational stiffness `W alpha / l`; with the cross-level term it is the lateral component
//! of the load on a wheelset tilted by cross-level.
//!
//! The spinning wheelset (`Omega = V / r_0` about `y`, polar inertia `I_wy`) needs the yaw moment
//! `I_wy Omega phi_w'` to roll at `phi_w'`, so its yaw equation carries `-I_wy Omega phi_w'`.
//!
//! Wheelset equations: `m_w y'' = sum Fy + lateral normal components + flange + suspension`,
//! `I_wz psi'' = l (Fx_R - Fx_L) + sum Mz - I_wy Omega phi_w' + suspension`.

use crate::contact::{self, ContactGeometry, CreepLaw, Creepages, Material};
use crate::curving::Curving;
use crate::params::VehicleParams;
use crate::track::Irregularity;
use nalgebra::{SVector, Vector3};
use serde::{Deserialize, Serialize};

/// Degrees of freedom: 5 for the car body, 5 per bogie frame, 2 per wheelset (see the module
/// docs; the wheelsets' vertical motion and roll are prescribed by the track).
pub const NDOF: usize = 23;
/// One value per degree of freedom (displacements, velocities or accelerations), laid out as
/// [`dof`] says.
pub type Dof = SVector<f64, NDOF>;

/// Index of the first degree of freedom of each body.
pub mod dof {
    /// The car body's five (y, z, roll, pitch, yaw).
    pub const CAR: usize = 0;
    /// Bogie frame `k` (0 front, 1 rear): five, ordered as the car body's.
    pub const fn bogie(k: usize) -> usize {
        5 + 5 * k
    }
    /// Wheelset `j` (0 leading to 3 trailing): lateral displacement, then yaw (offset
    /// [`Y`] and 1).
    pub const fn wheelset(j: usize) -> usize {
        15 + 2 * j
    }
    /// Within a car body or bogie: y, z, roll, pitch, yaw.
    pub const Y: usize = 0;
    /// Vertical displacement, up positive \[m\].
    pub const Z: usize = 1;
    /// Roll about x, left side up positive \[rad\].
    pub const ROLL: usize = 2;
    /// Pitch about y, nose down positive \[rad\].
    pub const PITCH: usize = 3;
    /// Yaw about z, nose left positive \[rad\].
    pub const YAW: usize = 4;
}

/// Standard gravity \[m/s2\], for the static loads and the geometric stiffness of preloads.
pub const GRAVITY: f64 = 9.81;

/// Bodies: 0 car, 1-2 bogies (front, rear), 3-6 wheelsets (front to rear).
const NBODY: usize = 7;

/// One translational suspension element between body `a` (upper) and body `b` (lower).
#[derive(Debug, Clone, Serialize, Deserialize)]
struct Element {
    a: usize,
    b: usize,
    ra: Vector3<f64>,
    rb: Vector3<f64>,
    k: Vector3<f64>,
    c: Vector3<f64>,
    /// Static vertical force on `a` (upwards), `-preload` on `b`.
    preload: f64,
    /// For primary elements: (wheelset, side: 0 left, 1 right).
    wheelset_side: Option<(usize, usize)>,
}

/// A rotational spring between bodies `a` and `b` about axis 3 (roll) or 5 (yaw) of the 6-vector.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct Rotational {
    a: usize,
    b: usize,
    axis: usize,
    k: f64,
}

/// Switches of the contact model.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ContactOptions {
    /// Multiplies all Kalker coefficients (the study's "Kalker -50 %" case).
    pub kalker_scale: f64,
    /// Saturate the tangential forces at `friction` times the normal load (Shen-Hedrick-Elkins);
    /// off, Kalker's linear forces grow without limit.
    pub saturation: bool,
    /// Wheel-rail friction coefficient \[-\], used only by the saturation.
    pub friction: f64,
    /// Add a flange force outside the dead band `flange_clearance`.
    pub flange: bool,
    /// Lateral free play before flange contact \[m\].
    pub flange_clearance: f64,
    /// Lateral stiffness of flange contact on the excess beyond the clearance \[N/m\].
    pub flange_stiffness: f64,
    /// The lateral components of the normal forces (gravitational stiffness and cross-level
    /// gravity). Off only in the Klingel test of a free wheelset.
    pub normal_force_lateral: bool,
    /// The roll `alpha u_c / l` of a displaced coned wheelset (in its kinematics, the contact
    /// position, the roll-rate term of the lateral creepage, the gyroscopic moment and the
    /// sensor). Off only in tests, to compare with models that ignore it.
    pub cone_roll: bool,
}

impl Default for ContactOptions {
    fn default() -> Self {
        ContactOptions {
            kalker_scale: 1.0,
            saturation: false,
            friction: 0.4,
            flange: false,
            flange_clearance: 0.009,
            flange_stiffness: 1.2e7,
            normal_force_lateral: true,
            cone_roll: true,
        }
    }
}

/// The vehicle's constant data, built once from a parameter set.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Vehicle {
    /// The parameter set the vehicle was built from.
    pub params: VehicleParams,
    /// The contact model's switches.
    pub options: ContactOptions,
    /// The equivalent conicity used: the FMU's `conicity` parameter when positive, else the
    /// vehicle file's.
    pub conicity: f64,
    mass: Dof,
    elements: Vec<Element>,
    rotational: Vec<Rotational>,
    /// Longitudinal position of each wheelset in the vehicle (from the car centre, forward).
    pub wheelset_x: [f64; 4],
    bogie_x: [f64; 2],
    /// Static normal load per wheel of each wheelset \[N\].
    pub static_wheel_load: [f64; 4],
    creep: CreepLaw,
}

/// The track seen by one wheelset at one instant, already scaled by the run-in ramp.
#[derive(Debug, Clone, Copy, Default)]
pub struct WheelsetTrack {
    /// The irregularities and their derivatives along the track at the wheelset's position.
    pub irr: Irregularity,
}

/// What the right-hand side also reports besides the accelerations.
#[derive(Debug, Clone, Copy, Default)]
pub struct Diagnostics {
    /// Normal load [left, right] per wheelset.
    pub wheel_loads: [[f64; 2]; 4],
    /// Wheelset roll angle and rate (prescribed by the track and the cone).
    pub wheelset_roll: [f64; 4],
    /// Wheelset roll rate \[rad/s\], for the roll-rate gyro.
    pub wheelset_roll_rate: [f64; 4],
}

impl Vehicle {
    // Bogie and wheelset indices address several arrays at once.
    #[allow(clippy::needless_range_loop)]
    /// Builds the mass matrix, the suspension elements with their static preloads and the
    /// creep coefficients at the static wheel load. `conicity` replaces the parameter set's.
    pub fn new(params: VehicleParams, conicity: f64, options: ContactOptions) -> Vehicle {
        let p = &params;
        let (mc, mb, mw) = (p.car_body.mass, p.bogie.mass, p.wheelset.mass);
        let mut mass = Dof::zeros();
        let car = [
            mc,
            mc,
            p.car_body.roll_inertia,
            p.car_body.pitch_inertia,
            p.car_body.yaw_inertia,
        ];
        let bog = [
            mb,
            mb,
            p.bogie.roll_inertia,
            p.bogie.pitch_inertia,
            p.bogie.yaw_inertia,
        ];
        for i in 0..5 {
            mass[dof::CAR + i] = car[i];
            mass[dof::bogie(0) + i] = bog[i];
            mass[dof::bogie(1) + i] = bog[i];
        }
        for j in 0..4 {
            mass[dof::wheelset(j)] = mw;
            mass[dof::wheelset(j) + 1] = p.wheelset.yaw_inertia;
        }
        let lb = p.car_body.semi_bogie_distance;
        let a = p.bogie.semi_wheelbase;
        let bogie_x = [lb, -lb];
        let wheelset_x = [lb + a, lb - a, -lb + a, -lb - a];
        let r0 = p.wheelset.rolling_radius;
        let cg = |body: usize| -> Vector3<f64> {
            match body {
                0 => Vector3::new(0.0, 0.0, p.car_body.cg_height),
                1 | 2 => Vector3::new(bogie_x[body - 1], 0.0, p.bogie.cg_height),
                _ => Vector3::new(wheelset_x[body - 3], 0.0, r0),
            }
        };
        let mut elements = vec![];
        let (s, pr) = (&p.secondary, &p.primary);
        for k in 0..2 {
            for sign in [1.0, -1.0] {
                let point = Vector3::new(bogie_x[k], sign * s.semi_spacing, s.height);
                elements.push(Element {
                    a: 0,
                    b: 1 + k,
                    ra: point - cg(0),
                    rb: point - cg(1 + k),
                    k: Vector3::new(s.kx, s.ky, s.kz),
                    c: Vector3::new(s.cx, s.cy, s.cz),
                    preload: mc * GRAVITY / 4.0,
                    wheelset_side: None,
                });
            }
        }
        for j in 0..4 {
            for (side, sign) in [(0, 1.0), (1, -1.0)] {
                let point = Vector3::new(wheelset_x[j], sign * pr.semi_spacing, pr.height);
                let bogie = 1 + j / 2;
                elements.push(Element {
                    a: bogie,
                    b: 3 + j,
                    ra: point - cg(bogie),
                    rb: point - cg(3 + j),
                    k: Vector3::new(pr.kx, pr.ky, pr.kz),
                    c: Vector3::new(pr.cx, pr.cy, pr.cz),
                    preload: (mb + mc / 2.0) * GRAVITY / 4.0,
                    wheelset_side: Some((j, side)),
                });
            }
        }
        let mut rotational = vec![];
        for k in 0..2 {
            rotational.push(Rotational {
                a: 0,
                b: 1 + k,
                axis: 3,
                k: s.anti_roll,
            });
            rotational.push(Rotational {
                a: 0,
                b: 1 + k,
                axis: 5,
                k: 2.0 * s.yaw_stiffness,
            });
        }
        // Per wheel: half the wheelset's weight plus one axle box's share of bogie and car body.
        let static_load = mw * GRAVITY / 2.0 + (mb + mc / 2.0) * GRAVITY / 4.0;
        let creep = CreepLaw::new(
            &ContactGeometry {
                wheel_radius: r0,
                wheel_transverse_radius: f64::INFINITY,
                rail_crown_radius: p.wheelset.rail_crown_radius,
            },
            &Material::default(),
            static_load,
        )
        .scaled(options.kalker_scale);
        Vehicle {
            params,
            options,
            conicity,
            mass,
            elements,
            rotational,
            wheelset_x,
            bogie_x,
            static_wheel_load: [static_load; 4],
            creep,
        }
    }

    /// Distance of wheelset `j` behind the leading wheelset.
    pub fn wheelset_offset(&self, j: usize) -> f64 {
        self.wheelset_x[0] - self.wheelset_x[j]
    }

    /// Longitudinal position of bogie pivot `k` from the car centre, forward positive \[m\].
    pub fn bogie_x(&self, k: usize) -> f64 {
        self.bogie_x[k]
    }

    /// Kalker's coefficients at the static wheel load, scaled by `kalker_scale`.
    pub fn creep_law(&self) -> &CreepLaw {
        &self.creep
    }

    /// The (diagonal) mass matrix: masses \[kg\] and moments of inertia \[kg m2\] per degree of
    /// freedom.
    pub fn mass_diagonal(&self) -> &Dof {
        &self.mass
    }

    /// The 6-vector (x, y, z, roll, pitch, yaw) of every body's displacement and velocity; on
    /// a curve, expressed in the car body's track frame ([`crate::curving`]).
    fn body_motion(
        &self,
        q: &Dof,
        qd: &Dof,
        presc: &[(f64, f64, f64, f64); 4],
        curving: Option<&Curving>,
    ) -> ([[f64; 6]; NBODY], [[f64; 6]; NBODY]) {
        let mut u = [[0.0; 6]; NBODY];
        let mut v = [[0.0; 6]; NBODY];
        for (body, base) in [(0, dof::CAR), (1, dof::bogie(0)), (2, dof::bogie(1))] {
            for i in 0..5 {
                // 6-vector slots: y=1, z=2, roll=3, pitch=4, yaw=5
                u[body][i + 1] = q[base + i];
                v[body][i + 1] = qd[base + i];
            }
        }
        for j in 0..4 {
            let (z, zd, roll, rolld) = presc[j];
            let b = 3 + j;
            u[b] = [
                0.0,
                q[dof::wheelset(j)],
                z,
                roll,
                0.0,
                q[dof::wheelset(j) + 1],
            ];
            v[b] = [
                0.0,
                qd[dof::wheelset(j)],
                zd,
                rolld,
                0.0,
                qd[dof::wheelset(j) + 1],
            ];
        }
        if let Some(c) = curving {
            for b in 0..NBODY {
                for (k, slot) in [1, 3, 5].into_iter().enumerate() {
                    u[b][slot] += c.offset[b][k];
                    v[b][slot] += c.offset_rate[b][k];
                }
            }
        }
        (u, v)
    }

    /// Generalized accelerations for the state (q, qd) at speed `v` with the track seen by each
    /// wheelset, on a curved line the design line's terms (`None` on straight track). Also
    /// returns loads and wheelset roll for the sensors.
    pub fn accelerations(
        &self,
        q: &Dof,
        qd: &Dof,
        v: f64,
        track: &[WheelsetTrack; 4],
        curving: Option<&Curving>,
    ) -> (Dof, Diagnostics) {
        let p = &self.params;
        let (l, r0, alpha) = (
            p.wheelset.half_gauge,
            p.wheelset.rolling_radius,
            self.conicity,
        );
        let mut diag = Diagnostics::default();

        // Prescribed wheelset vertical motion and roll.
        let mut presc = [(0.0, 0.0, 0.0, 0.0); 4];
        let mut zdd = [0.0; 4];
        let mut contact_u = [0.0; 4];
        let cone = if self.options.cone_roll {
            alpha / l
        } else {
            0.0
        };
        // u_c (1 - r0 alpha / l) = y - xi + r0 phi_t: see "Contact-level displacement" above.
        let scale = 1.0 / (1.0 - r0 * cone);
        for j in 0..4 {
            let irr = &track[j].irr;
            let (track_roll, track_roll_rate) = (
                irr.cross_level / (2.0 * l),
                v * irr.cross_level_ds / (2.0 * l),
            );
            let u = (q[dof::wheelset(j)] - irr.alignment + r0 * track_roll) * scale;
            let ud = (qd[dof::wheelset(j)] - v * irr.alignment_ds + r0 * track_roll_rate) * scale;
            let roll = track_roll + cone * u;
            let roll_rate = track_roll_rate + cone * ud;
            contact_u[j] = u;
            presc[j] = (irr.vertical, v * irr.vertical_ds, roll, roll_rate);
            zdd[j] = v * v * irr.vertical_ds2;
            diag.wheelset_roll[j] = roll;
            diag.wheelset_roll_rate[j] = roll_rate;
        }
        let (u, w) = self.body_motion(q, qd, &presc, curving);

        // Generalized forces on the 6-vectors of every body.
        let mut f6 = [[0.0; 6]; NBODY];
        let mut down = [[0.0; 2]; 4]; // total downward primary force at each axle box
        let mut lateral_primary = [0.0; 4]; // lateral primary force on each wheelset
        for e in &self.elements {
            let point = |r: &Vector3<f64>, x: &[f64; 6]| {
                let t = Vector3::new(x[0], x[1], x[2]);
                let th = Vector3::new(x[3], x[4], x[5]);
                t + th.cross(r)
            };
            let d = point(&e.ra, &u[e.a]) - point(&e.rb, &u[e.b]);
            let dd = point(&e.ra, &w[e.a]) - point(&e.rb, &w[e.b]);
            let f = -(e.k.component_mul(&d) + e.c.component_mul(&dd)); // on a
            let f0a = Vector3::new(0.0, 0.0, e.preload);
            let tha = Vector3::new(u[e.a][3], u[e.a][4], u[e.a][5]);
            let thb = Vector3::new(u[e.b][3], u[e.b][4], u[e.b][5]);
            let ma = e.ra.cross(&f) + tha.cross(&e.ra).cross(&f0a);
            let mb = -e.rb.cross(&f) + thb.cross(&e.rb).cross(&(-f0a));
            for i in 0..3 {
                f6[e.a][i] += f[i];
                f6[e.a][i + 3] += ma[i];
                f6[e.b][i] -= f[i];
                f6[e.b][i + 3] += mb[i];
            }
            if let Some((j, side)) = e.wheelset_side {
                down[j][side] = e.preload + f[2];
                lateral_primary[j] -= f[1];
            }
        }
        for r in &self.rotational {
            let m = -r.k * (u[r.a][r.axis] - u[r.b][r.axis]);
            f6[r.a][r.axis] += m;
            f6[r.b][r.axis] -= m;
        }

        // The design line's D'Alembert forces and frame yaw accelerations ([`crate::curving`]).
        if let Some(c) = curving {
            let slots = [dof::CAR, dof::bogie(0), dof::bogie(1)]
                .into_iter()
                .chain((0..4).map(dof::wheelset));
            let height = crate::curving::body_heights(self);
            for (body, base) in slots.enumerate() {
                let yaw = if body < 3 { base + dof::YAW } else { base + 1 };
                f6[body][1] -=
                    self.mass[base] * (c.lateral[body] - height[body] * c.roll_acceleration[body]);
                f6[body][5] -= self.mass[yaw] * c.yaw_acceleration[body];
                if body < 3 {
                    f6[body][3] -= self.mass[base + dof::ROLL] * c.roll_acceleration[body];
                }
            }
        }

        // Contact.
        let mw = p.wheelset.mass;
        let bp = p.primary.semi_spacing;
        let h_axle = p.primary.height;
        let omega_spin = v / r0;
        for j in 0..4 {
            let b = 3 + j;
            let psi = q[dof::wheelset(j) + 1];
            let (yd, psid) = (qd[dof::wheelset(j)], qd[dof::wheelset(j) + 1]);
            let rel = contact_u[j];
            let (roll, roll_rate) = (presc[j].2, presc[j].3);
            let total = mw * (GRAVITY + zdd[j]) + down[j][0] + down[j][1];
            let mut transfer = (bp * (down[j][0] - down[j][1]) + h_axle * lateral_primary[j]) / l;
            // On a curve: the curvature, the frame's roll rate and the wheelset's own lateral
            // D'Alembert force at its axle ([`crate::curving`], "Wheel-rail contact").
            let (k, frame_roll_rate) = match curving {
                Some(c) => {
                    transfer -= r0 * mw * (c.lateral[b] - r0 * c.roll_acceleration[b]) / l;
                    (c.curvature[b], c.roll_rate[b])
                }
                None => (0.0, 0.0),
            };
            let n = [
                ((total + transfer) / 2.0).max(0.0),
                ((total - transfer) / 2.0).max(0.0),
            ];
            diag.wheel_loads[j] = n;
            let mut long = alpha * rel / r0 + l * psid / v;
            let mut turn = psid / v;
            if curving.is_some() {
                long += l * k;
                turn += k;
            }
            let lat = (yd + r0 * roll_rate) / v - psi;
            let mut fy = 0.0;
            let mut mz = 0.0;
            for (side, sign) in [(0usize, 1.0f64), (1, -1.0)] {
                let coef = self.creep.at_load(n[side]);
                let nu = Creepages {
                    longitudinal: -sign * long,
                    lateral: lat,
                    spin: turn - sign * alpha / r0,
                };
                let mut cf = contact::linear_creep(&coef, &nu);
                if self.options.saturation {
                    cf = contact::saturate(cf, self.options.friction, n[side]);
                }
                fy += cf.fy;
                // Yaw moment of the longitudinal force at lateral +/- l: -y Fx.
                mz += -sign * l * cf.fx + cf.mz;
            }
            if self.options.normal_force_lateral {
                fy += (n[1] - n[0]) * alpha - (n[0] + n[1]) * roll;
            }
            if self.options.flange {
                fy += contact::flange_force(
                    rel,
                    self.options.flange_clearance,
                    self.options.flange_stiffness,
                );
            }
            let absolute_roll_rate = if curving.is_some() {
                roll_rate + frame_roll_rate
            } else {
                roll_rate
            };
            mz -= p.wheelset.spin_inertia * omega_spin * absolute_roll_rate;
            f6[b][1] += fy;
            f6[b][5] += mz;
        }

        // Project onto the degrees of freedom and divide by the (diagonal) mass matrix.
        let mut acc = Dof::zeros();
        for (body, base) in [(0, dof::CAR), (1, dof::bogie(0)), (2, dof::bogie(1))] {
            for i in 0..5 {
                acc[base + i] = f6[body][i + 1] / self.mass[base + i];
            }
        }
        for j in 0..4 {
            acc[dof::wheelset(j)] = f6[3 + j][1] / self.mass[dof::wheelset(j)];
            acc[dof::wheelset(j) + 1] = f6[3 + j][5] / self.mass[dof::wheelset(j) + 1];
        }
        (acc, diag)
    }
}
