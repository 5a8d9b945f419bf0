//! The vehicle on a curved, canted design line ([`crate::line`](mod@crate::line)): what the track-following
//! frames add to the equations of motion of [`crate::dynamics`].
//!
//! # Frames and coordinates
//! Each body has a track frame of its own, at its own distance `s_i` on the design line (car
//! body `s_c`, bogie `k` at `s_c + x_k`, wheelset `j` at `s_c + x_j`, `x` the nominal positions
//! of [`Vehicle`]), moving with the vehicle at speed `V`: origin on the design centre line at
//! rail level, `x` along its tangent, `y` to the left in the track plane, `z` normal to it,
//! rolled with the cant by `phi_d = -c / (2 l)`. A body's coordinates are its displacements in
//! its own frame, as on straight track (where all the frames are one), so:
//! - `ws_y` is the wheelset's shift from the design centre line, the irregularities are laid on
//!   the design line as before (EN 13848 measures them from it), and nothing else in the
//!   straight model changes its meaning;
//! - on straight track every term below is 0, and the model skips them (bit for bit the
//!   straight model).
//!
//! The frame of a body at `s` turns at the rate `V k(s)` and rolls at `V phi_d'(s)`.
//!
//! # Inertial and gravity terms (each body, in its own frame)
//! The frame's origin accelerates towards the centre by `V^2 k`; gravity has the component
//! `g sin(c / 2l) ~ g c / (2 l)` along its `y` (towards the low rail). For a body of mass `m`
//! both act at the centre of gravity, as the D'Alembert force `-m a_nc` with the
//! **uncompensated lateral acceleration** `a_nc = V^2 k - g c / (2 l)`. The frame's yaw
//! acceleration `V^2 k'` (in transitions) gives `-I_z V^2 k'` in the yaw equation. Terms of
//! second order (products of the frame's rates with the bodies' small velocities, which act
//! longitudinally or vertically; `V^2 k c` in the vertical) are left out.
//!
//! The frame rolls with the cant: in the roundings of the cant ramps ([`crate::line`](mod@crate::line)) with the
//! roll acceleration `alpha = V^2 phi_d''`, which moves a point at height `h` above the roll
//! axis (the rail-level centre line) by `-h alpha` laterally. So each body's lateral equation
//! gains `+m h alpha` (its centre of gravity at `h`) and the car body's and bogie frames' roll
//! equations `-I_x alpha` (a wheelset's roll is held by the rails).
//!
//! # Suspension between bodies in different frames
//! A suspension element joins two bodies whose frames differ. The deflections are computed
//! with every body's displacement expressed in the car body's frame: the frame of a body at
//! `s_c + x`, seen from the car body's, is turned by `dpsi = T(s_c + x) - T(s_c)`, shifted
//! laterally by `dy = P(s_c + x) - P(s_c) - x T(s_c)` ([`crate::line`](mod@crate::line)) and rolled by
//! `dphi = phi_d(s_c + x) - phi_d(s_c)`. A body's displacement 6-vector gains
//! `(0, dy - h dphi, 0, dphi, 0, dpsi)`, `h` its centre of gravity's height (the frame rolls
//! about the rail-level centre line), and its velocity the time derivatives,
//! `V (k(s_c + x) - k(s_c))` for `dpsi` and `V (T(s_c + x) - T(s_c) - x k(s_c))` for `dy`.
//! The deflections are exact to first order in the offsets; the forces they give are applied
//! in each body's own frame (rotating them by the offsets would change them by products of the
//! offsets with the dynamic forces, second order). One first-order term is left out: the
//! static spring preloads `F0` between two bodies whose frames are rolled against each other
//! by `dphi` (in a cant ramp only) have a lateral component `F0 dphi` in either frame (about
//! 800 N per bogie on the standard curved line's steepest ramp, opposite at the two bogies);
//! their moments' change with the offsets (the geometric stiffness) is in. So, in a curve of radius `R`: the car body's centre sits
//! `x_k^2 / (2 R)` inside the line through its bogie pivots (the chord), the bogies turn by
//! `x_k / R` against the body, and the wheelsets by `a / R` against their bogie, each
//! resisted by the secondary and primary longitudinal stiffness.
//!
//! # Wheel-rail contact in a curve
//! The wheelset turns with the track, at the absolute yaw rate `psi' + V k`. The point of the
//! wheel at lateral `+-l` then moves forward at `V - l (psi' + V k)`, so the longitudinal
//! creepage of [`crate::dynamics`] gains `l k`:
//! `nu_x = -+ (alpha u / r_0 + l psi' / V + l k)` (the outer wheel must roll further). It
//! vanishes, with `psi' = 0`, at the **pure-rolling shift** `u = -r_0 l k / alpha`, outwards
//! (`r_0 l / (alpha R)`); the spin creepage gains the same `k` (`psi' / V + k -+ alpha / r_0`).
//! The lateral creepage is relative to the rails and unchanged. The gyroscopic moment uses the
//! absolute roll rate, `phi_w' + V phi_d'`. The lateral load transfer gains the wheelset's own
//! D'Alembert force at its axle height: `l (N_L - N_R) = ... - r_0 m_w a_nc`. Where the curve
//! needs more shift than the flange clearance, the flange stop of [`crate::contact`] carries the
//! rest (`flange_contact`).
//!
//! # Sensors
//! Their frames are those of their bodies: the axle-box accelerometer reads `a_nc - r_0 alpha`
//! on top of the straight-track specific force, the bogie frame's accelerometer
//! `a_nc + a V^2 k' - h_b alpha` at the bogie's distance (the frame's tangential acceleration
//! at `a` ahead of the pivot), the yaw gyroscope `psi' + V k`, the roll gyroscope
//! `phi_w' + V phi_d'`.

use crate::dynamics::{GRAVITY, Vehicle};
use crate::line::DesignLine;

/// Bodies in the order of [`crate::dynamics`]: car, bogie 0, bogie 1, wheelsets 0-3.
const NBODY: usize = 7;

/// The design line's terms at one instant, per body (module docs).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Curving {
    /// The body's frame seen from the car body's: (lateral offset of the centre of gravity
    /// `dy - h dphi` \[m\], roll `dphi` \[rad\], yaw `dpsi` \[rad\]).
    pub offset: [[f64; 3]; NBODY],
    /// Their time derivatives.
    pub offset_rate: [[f64; 3]; NBODY],
    /// Uncompensated lateral acceleration `a_nc = V^2 k - g c / (2 l)` at the body \[m/s2\].
    pub lateral: [f64; NBODY],
    /// The frame's yaw acceleration `V^2 k'` \[rad/s2\].
    pub yaw_acceleration: [f64; NBODY],
    /// Curvature `k` at the body \[1/m\].
    pub curvature: [f64; NBODY],
    /// The frame's roll `phi_d` \[rad\] and roll rate `V phi_d'` \[rad/s\].
    pub roll: [f64; NBODY],
    /// See `roll`.
    pub roll_rate: [f64; NBODY],
    /// The frame's roll acceleration `V^2 phi_d''` \[rad/s2\] (in the roundings).
    pub roll_acceleration: [f64; NBODY],
}

/// Distances of the bodies from the car body's centre, forward positive \[m\].
pub fn body_positions(vehicle: &Vehicle) -> [f64; NBODY] {
    [
        0.0,
        vehicle.bogie_x(0),
        vehicle.bogie_x(1),
        vehicle.wheelset_x[0],
        vehicle.wheelset_x[1],
        vehicle.wheelset_x[2],
        vehicle.wheelset_x[3],
    ]
}

/// Heights of the bodies' centres of gravity above rail level \[m\].
pub fn body_heights(vehicle: &Vehicle) -> [f64; NBODY] {
    let p = &vehicle.params;
    let r0 = p.wheelset.rolling_radius;
    [
        p.car_body.cg_height,
        p.bogie.cg_height,
        p.bogie.cg_height,
        r0,
        r0,
        r0,
        r0,
    ]
}

impl Curving {
    /// The terms with the leading wheelset at `s_lead`, at speed `v`.
    pub fn at(line: &DesignLine, vehicle: &Vehicle, s_lead: f64, v: f64) -> Curving {
        let two_l = 2.0 * vehicle.params.wheelset.half_gauge;
        let x = body_positions(vehicle);
        let h = body_heights(vehicle);
        let s_c = s_lead - x[3];
        let c = line.at(s_c);
        let mut out = Curving::default();
        for i in 0..NBODY {
            let d = if i == 0 { c } else { line.at(s_c + x[i]) };
            let roll = -d.cant / two_l;
            let droll = roll + c.cant / two_l;
            let droll_rate = v * (-d.cant_ds + c.cant_ds) / two_l;
            let dy = d.heading_integral - c.heading_integral - x[i] * c.heading;
            let dy_rate = v * (d.heading - c.heading - x[i] * c.curvature);
            out.offset[i] = [dy - h[i] * droll, droll, d.heading - c.heading];
            out.offset_rate[i] = [
                dy_rate - h[i] * droll_rate,
                droll_rate,
                v * (d.curvature - c.curvature),
            ];
            out.lateral[i] = v * v * d.curvature - GRAVITY * d.cant / two_l;
            out.yaw_acceleration[i] = v * v * d.curvature_ds;
            out.curvature[i] = d.curvature;
            out.roll[i] = roll;
            out.roll_rate[i] = -v * d.cant_ds / two_l;
            out.roll_acceleration[i] = -v * v * d.cant_ds2 / two_l;
        }
        out
    }
}
