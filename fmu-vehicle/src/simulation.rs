//! Time integration of the vehicle on its track, and the virtual sensors.
//!
//! # Integration
//! Classical fourth-order Runge-Kutta with a fixed internal step inside each communication step,
//! so the FMU lands exactly on every communication point. The internal step is at most
//! `max_internal_step` and at most `0.5 / lambda`, where `lambda` estimates the fastest creep
//! decay rate `max(2 f22 / (V m_w), 2 f11 l^2 / (V I_wz))`: the creep forces grow stiff as the
//! speed falls. Within a communication step the speed input is held (zero-order hold) and the
//! leading wheelset's position advances as `s + V t`. The accuracy claim (halving the internal
//! step changes the sensor signals by less than 0.1 % rms) is a test of this crate.
//!
//! # Run-in
//! All irregularities are multiplied by a smooth ramp `x^2 (3 - 2 x)`, `x = s / ramp_length`, over
//! the first `ramp_length` metres, and are zero behind the start (`s < 0`, where the trailing
//! wheelsets begin). The vehicle therefore starts in its static equilibrium on a perfect track
//! instead of being released from a deflected track. The truth outputs report the ramped values,
//! the ones the wheels actually meet.
//!
//! # Sensors (at the leading wheelset and above it)
//! - axle-box accelerometer: the specific force along the wheelset's axle,
//!   `y_w'' + g phi_w`, with `phi_w` the wheelset's roll (cross-level plus cone roll): gravity
//!   enters through roll, as in a real axle-box accelerometer;
//! - yaw gyroscope on the same wheelset: `psi_w'` (0 standing: the held state keeps the
//!   velocities it stopped with, which no sensor would read);
//! - bogie-frame accelerometer above the leading wheelset, at the frame's centre-of-gravity
//!   height and `a` (semi-wheelbase) ahead of its centre: the specific force along the frame's
//!   lateral axis, `y_b'' + a psi_b'' - z_s phi_b'' + g phi_b` with `z_s = 0`;
//! - roll gyroscope on the leading wheelset: `phi_w'`, the time derivative of the `ws_roll`
//!   output (same sign: left side rising is positive). The wheelset's roll is not a degree of
//!   freedom but a function of the state and the track (see `dynamics`, "Contact-level
//!   displacement"): with `c = alpha / l` and `k = 1 / (1 - r_0 c)`,
//!   `phi_w = xi_cl(s) / (2 l) + c k (y - xi_al(s) + r_0 xi_cl(s) / (2 l))`,
//!   `s` the wheelset's position (`s' = V`) and `y` its lateral displacement (`y' = ws_vy`, a
//!   state). Differentiating along the motion, with `(.)_s` the derivative along the track,
//!   `phi_w' = V xi_cl_s / (2 l) + c k (y' - V xi_al_s + r_0 V xi_cl_s / (2 l))`.
//!   This is `Diagnostics::wheelset_roll_rate`, computed by the same code that computes the
//!   roll (and used by the dynamics in the lateral creepage and the gyroscopic moment), so the
//!   two outputs cannot drift apart. It is exact, not a finite difference: the track's
//!   `_s` derivatives are those of its quintic Hermite interpolant (and of the run-in ramp's
//!   product rule), not separate estimates. `V` is the speed held over the last step, so the
//!   rate is the derivative from the left at the communication point (it jumps with the speed
//!   input, as `forward_speed` does). Standing still (below `min_speed`) the state and `s`
//!   are held, `ws_roll` does not change, and the rate is 0.
//!
//! Noise: independent Gaussian samples added at every communication point (one sample per
//! output per step), from a xoshiro256++ generator seeded by `noise_seed`; its state is part of
//! the FMU state, so restoring a state replays the same noise. The roll gyroscope draws from a
//! second generator, the first one jumped ahead by 2^128 draws (Vigna's `jump`): a stream of
//! its own that never overlaps the first in any run, so adding it left the other sensors' noise
//! (and every output that depends on it) bit for bit as it was, for every seed and whatever
//! `sigma_roll_gyro` is. Both generators are part of the FMU state.
//!
//! Sensor errors (bias, drift, scale, misalignment, anti-alias filter, noise density, range,
//! quantization) are [`crate::sensors`]; all off by default. The `_clean` and `_true` outputs
//! stay the true quantities, without them.

use crate::curving::Curving;
use crate::dynamics::{Diagnostics, Dof, GRAVITY, Vehicle, WheelsetTrack, dof};
use crate::line::DesignLine;
use crate::sensors::{SensorSpec, Sensors};
use crate::track::{Irregularity, Track};
use serde::{Deserialize, Serialize};

/// A small, serializable, seedable generator (xoshiro256++, Blackman and Vigna), with normal
/// deviates by Marsaglia's polar method.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NoiseRng {
    s: [u64; 4],
    spare: Option<f64>,
}

impl NoiseRng {
    /// A generator whose state is `seed` expanded by SplitMix64 (as Blackman and Vigna
    /// recommend), so nearby seeds give unrelated streams.
    pub fn new(seed: u64) -> NoiseRng {
        // splitmix64 expands the seed into the four words of state.
        let mut x = seed;
        let mut next = || {
            x = x.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = x;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            z ^ (z >> 31)
        };
        NoiseRng {
            s: [next(), next(), next(), next()],
            spare: None,
        }
    }

    /// The same generator advanced by 2^128 draws (the `jump` of Blackman and Vigna's reference
    /// implementation): the start of a stream that does not overlap this one's next 2^128
    /// draws. The spare normal deviate is not carried over.
    pub fn jumped(&self) -> NoiseRng {
        const JUMP: [u64; 4] = [
            0x180e_c6d3_3cfd_0aba,
            0xd5a6_1266_f0c9_392c,
            0xa958_2618_e03f_c9aa,
            0x39ab_dc45_29b1_661c,
        ];
        let mut walk = NoiseRng {
            s: self.s,
            spare: None,
        };
        let mut acc = [0u64; 4];
        for word in JUMP {
            for bit in 0..64 {
                if word & (1u64 << bit) != 0 {
                    for (a, s) in acc.iter_mut().zip(walk.s) {
                        *a ^= s;
                    }
                }
                walk.next_u64();
            }
        }
        NoiseRng {
            s: acc,
            spare: None,
        }
    }

    /// The next 64 uniform bits (xoshiro256++).
    pub fn next_u64(&mut self) -> u64 {
        let s = &mut self.s;
        let result = s[0].wrapping_add(s[3]).rotate_left(23).wrapping_add(s[0]);
        let t = s[1] << 17;
        s[2] ^= s[0];
        s[3] ^= s[1];
        s[1] ^= s[2];
        s[0] ^= s[3];
        s[2] ^= t;
        s[3] = s[3].rotate_left(45);
        result
    }

    /// Uniform on (-1, 1).
    fn symmetric(&mut self) -> f64 {
        ((self.next_u64() >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }

    /// A standard normal deviate (mean 0, variance 1); the polar method makes two at a time and
    /// keeps the second for the next call, which is part of the FMU state.
    pub fn normal(&mut self) -> f64 {
        if let Some(x) = self.spare.take() {
            return x;
        }
        loop {
            let (u, v) = (self.symmetric(), self.symmetric());
            let s = u * u + v * v;
            if s > 0.0 && s < 1.0 {
                let f = (-2.0 * s.ln() / s).sqrt();
                self.spare = Some(v * f);
                return u * f;
            }
        }
    }
}

/// Sensor noise configuration.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SensorNoise {
    /// Off: every sensor output equals its `_clean` twin and no deviate is drawn.
    pub enabled: bool,
    /// Standard deviation per sample of both accelerometers \[m/s2\] (white, Gaussian).
    pub sigma_acc: f64,
    /// Standard deviation per sample of the yaw gyroscope \[rad/s\].
    pub sigma_gyro: f64,
    /// Of the wheelset roll gyroscope, which has its own generator.
    pub sigma_roll_gyro: f64,
}

/// How the simulation integrates and starts.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SimConfig {
    /// Upper bound of the Runge-Kutta step \[s\]; the step also shrinks with the speed (module
    /// docs).
    pub max_internal_step: f64,
    /// Length of the run-in ramp of the irregularities \[m\] (module docs); 0: none.
    pub ramp_length: f64,
    /// Below this speed the vehicle is taken to stand still: the state is held.
    pub min_speed: f64,
}

impl Default for SimConfig {
    fn default() -> Self {
        SimConfig {
            max_internal_step: 1e-3,
            ramp_length: 10.0,
            min_speed: 0.5,
        }
    }
}

/// Everything the FMU reports after a step.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Outputs {
    /// Axle-box accelerometer on the leading wheelset, with noise: `y_w'' + g phi_w` \[m/s2\]
    /// (module docs, "Sensors").
    pub ws_acc_y: f64,
    /// Yaw gyroscope on the leading wheelset, with noise \[rad/s\], nose left positive.
    pub ws_yaw_rate: f64,
    /// Lateral accelerometer on the leading bogie frame above the leading wheelset, with noise
    /// \[m/s2\].
    pub frame_acc_y: f64,
    /// `ws_acc_y` without noise.
    pub ws_acc_y_clean: f64,
    /// `ws_yaw_rate` without noise: the true yaw rate.
    pub ws_yaw_rate_clean: f64,
    /// `frame_acc_y` without noise.
    pub frame_acc_y_clean: f64,
    /// Position of the leading wheelset along the track \[m\].
    pub distance: f64,
    /// Ramped alignment at the leading wheelset \[m\]: the truth an estimator is scored against.
    pub alignment: f64,
    /// Ramped vertical profile at the leading wheelset \[m\].
    pub vertical_profile: f64,
    /// Ramped cross-level at the leading wheelset, left rail minus right rail height \[m\].
    pub cross_level: f64,
    /// Leading wheelset lateral displacement from the ideal centre line \[m\], left positive.
    pub ws_y: f64,
    /// Leading wheelset yaw \[rad\].
    pub ws_yaw: f64,
    /// Leading wheelset lateral velocity \[m/s\].
    pub ws_vy: f64,
    /// Leading wheelset roll, cross-level plus cone roll \[rad\], left side up positive.
    pub ws_roll: f64,
    /// Lateral displacement of the leading bogie frame at the point above the leading wheelset,
    /// `y_b + a psi_b` \[m\].
    pub frame_y: f64,
    /// Lateral velocity of that point \[m/s\].
    pub frame_vy: f64,
    /// Leading bogie frame lateral displacement at its centre of gravity \[m\].
    pub bogie_y: f64,
    /// Leading bogie frame roll \[rad\].
    pub bogie_roll: f64,
    /// Leading bogie frame yaw \[rad\].
    pub bogie_yaw: f64,
    /// Car body lateral displacement \[m\].
    pub body_y: f64,
    /// Car body roll \[rad\].
    pub body_roll: f64,
    /// Car body yaw \[rad\].
    pub body_yaw: f64,
    /// Car body bounce from static equilibrium, up positive \[m\].
    pub body_z: f64,
    /// Normal load on the leading wheelset's left wheel \[N\], static plus dynamic.
    pub wheel_load_left: f64,
    /// Normal load on the leading wheelset's right wheel \[N\].
    pub wheel_load_right: f64,
    /// The speed run at over the last step \[m/s\]; 0 when standing (below `min_speed`).
    pub forward_speed: f64,
    /// Roll gyroscope on the leading wheelset, with noise: the time derivative of `ws_roll`
    /// \[rad/s\] (module docs).
    pub ws_roll_rate: f64,
    /// `ws_roll_rate` without noise; 0 when standing.
    pub ws_roll_rate_clean: f64,
    /// Design curvature at the leading wheelset \[1/m\], left positive ([`crate::line`](mod@crate::line)).
    pub design_curvature: f64,
    /// Design cant at the leading wheelset, right rail above left \[m\].
    pub design_cant: f64,
}

/// The running simulation: everything here is part of an FMU state.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Simulation {
    /// The vehicle's constant data.
    pub vehicle: Vehicle,
    /// The irregularities, grown as the vehicle runs.
    pub track: Track,
    /// The design line the irregularities are laid on ([`crate::line`](mod@crate::line)); `None` when it is
    /// straight and level, so no design term is even evaluated.
    pub line: Option<DesignLine>,
    /// Integration and run-in settings.
    pub config: SimConfig,
    /// Sensor noise settings.
    pub noise: SensorNoise,
    /// The accelerometers' and yaw gyroscope's noise generator, seeded by `noise_seed`.
    pub rng: NoiseRng,
    /// The roll gyroscope's generator: `rng` at the start, jumped by 2^128 draws.
    pub roll_rng: NoiseRng,
    /// The sensors' errors and their state (drift generator: `rng` jumped twice).
    pub sensors: Sensors,
    /// Displacements from static equilibrium, laid out as [`dof`] says.
    pub q: Dof,
    /// Velocities, laid out like `q`.
    pub qd: Dof,
    /// Position of the leading wheelset along the track \[m\].
    pub s: f64,
    /// The sensors and truth at the current communication point.
    pub outputs: Outputs,
    /// Runge-Kutta steps taken so far (for the benchmarks and the step-size tests).
    pub substeps: u64,
}

/// Applies the run-in ramp to a value and its two derivatives along s.
fn ramped(s: f64, len: f64, f: (f64, f64, f64)) -> (f64, f64, f64) {
    if s <= 0.0 {
        return (0.0, 0.0, 0.0);
    }
    if len <= 0.0 || s >= len {
        return f;
    }
    let x = s / len;
    let r = x * x * (3.0 - 2.0 * x);
    let r1 = 6.0 * x * (1.0 - x) / len;
    let r2 = (6.0 - 12.0 * x) / (len * len);
    (
        r * f.0,
        r1 * f.0 + r * f.1,
        r2 * f.0 + 2.0 * r1 * f.1 + r * f.2,
    )
}

impl Simulation {
    /// The vehicle at rest in static equilibrium at `s = 0`, its outputs already measured
    /// (without noise); `noise_seed` seeds both noise generators.
    pub fn new(
        vehicle: Vehicle,
        track: Track,
        config: SimConfig,
        noise: SensorNoise,
        noise_seed: u64,
    ) -> Simulation {
        let rng = NoiseRng::new(noise_seed);
        let mut sim = Simulation {
            vehicle,
            track,
            line: None,
            config,
            noise,
            roll_rng: rng.jumped(),
            sensors: Sensors::new([SensorSpec::default(); 4], rng.jumped().jumped()),
            rng,
            q: Dof::zeros(),
            qd: Dof::zeros(),
            s: 0.0,
            outputs: Outputs::default(),
            substeps: 0,
        };
        sim.outputs = sim.measure(0.0, false, 0.0, 0.0);
        sim
    }

    /// These sensor errors ([`crate::sensors`]) on the sensors, the outputs measured again.
    pub fn with_sensors(mut self, spec: [SensorSpec; 4]) -> Simulation {
        self.sensors = Sensors::new(spec, self.rng.jumped().jumped());
        self.outputs = self.measure(0.0, false, 0.0, 0.0);
        self
    }

    /// The vehicle on this design line (straight and level: as without one), the outputs
    /// measured again.
    pub fn with_line(mut self, line: DesignLine) -> Simulation {
        self.line = (!line.is_straight()).then_some(line);
        self.outputs = self.measure(0.0, false, 0.0, 0.0);
        self
    }

    /// The design line's terms with the leading wheelset at `s`, at speed `v`; `None` on a
    /// straight line.
    fn curving(&self, s: f64, v: f64) -> Option<Curving> {
        self.line
            .as_ref()
            .map(|line| Curving::at(line, &self.vehicle, s, v))
    }

    /// The (ramped) irregularities at track position `s`.
    pub fn irregularity(&self, s: f64) -> Irregularity {
        if s <= 0.0 {
            return Irregularity::default();
        }
        let i = self.track.at(s);
        let len = self.config.ramp_length;
        let a = ramped(s, len, (i.alignment, i.alignment_ds, i.alignment_ds2));
        let v = ramped(s, len, (i.vertical, i.vertical_ds, i.vertical_ds2));
        let c = ramped(s, len, (i.cross_level, i.cross_level_ds, i.cross_level_ds2));
        Irregularity {
            alignment: a.0,
            alignment_ds: a.1,
            alignment_ds2: a.2,
            vertical: v.0,
            vertical_ds: v.1,
            vertical_ds2: v.2,
            cross_level: c.0,
            cross_level_ds: c.1,
            cross_level_ds2: c.2,
        }
    }

    fn track_for(&self, s_lead: f64) -> [WheelsetTrack; 4] {
        std::array::from_fn(|j| WheelsetTrack {
            irr: self.irregularity(s_lead - self.vehicle.wheelset_offset(j)),
        })
    }

    fn accelerations(&self, q: &Dof, qd: &Dof, v: f64, s: f64) -> (Dof, Diagnostics) {
        let curving = self.curving(s, v);
        self.vehicle
            .accelerations(q, qd, v, &self.track_for(s), curving.as_ref())
    }

    /// The internal step for speed `v` (see the module docs).
    pub fn internal_step(&self, v: f64) -> f64 {
        let p = &self.vehicle.params.wheelset;
        let c = self
            .vehicle
            .creep_law()
            .at_load(self.vehicle.static_wheel_load[0]);
        let lambda = (2.0 * c.f22 / (v * p.mass))
            .max(2.0 * c.f11 * p.half_gauge * p.half_gauge / (v * p.yaw_inertia));
        let step = self.config.max_internal_step.min(0.5 / lambda);
        self.sensors.filter_step().map_or(step, |f| step.min(f))
    }

    /// Advances by `h` at speed `v` (held over the step) and updates the outputs.
    pub fn step(&mut self, h: f64, v: f64) {
        let moving = v.is_finite() && v >= self.config.min_speed;
        if moving {
            let ahead = self.s + v * h + 1.0;
            let behind = self.s - self.vehicle.wheelset_offset(3) - 1.0;
            self.track.ensure_covers(behind.min(0.0), ahead);
            // A master's clock rounding (h a few ulps over the step) must not add a substep.
            let n = fmi_abi::step::substeps(h, self.internal_step(v));
            let dt = h / n as f64;
            let filtering = self.sensors.filter_step().is_some();
            for k in 0..n {
                self.rk4(dt, v);
                // The anti-alias filters see every substep; the last one's end is measured below.
                if filtering && k + 1 < n {
                    self.feed_filters(v, dt, 1);
                }
            }
            self.substeps += n as u64;
            self.outputs = self.measure(v, true, dt, h);
            return;
        }
        // Standing, the filters still run at substeps they are designed for (the state, so the
        // sensed signals, are constant over the step).
        let n = self
            .sensors
            .filter_step()
            .map_or(1, |f| fmi_abi::step::substeps(h, f));
        let dt = h / n as f64;
        self.feed_filters(0.0, dt, n - 1);
        self.outputs = self.measure(0.0, true, dt, h);
    }

    /// Feeds the anti-alias filters the sensed signals at the current state `times` times,
    /// each a substep of `dt` (the state does not change between them).
    fn feed_filters(&mut self, v: f64, dt: f64, times: usize) {
        if times == 0 {
            return;
        }
        let (u, c) = self.true_sensors(v);
        let sensed = self.sensors.sensed(u, c);
        for _ in 0..times {
            self.sensors.filter(sensed, dt);
        }
    }

    /// The accelerations and diagnostics at the current state at speed `v`; standing (`v`
    /// 0) the accelerations are 0 and the diagnostics are evaluated at a stand-in speed.
    fn accelerations_now(&self, v: f64) -> (Dof, Diagnostics) {
        if v > 0.0 {
            self.accelerations(&self.q, &self.qd, v, self.s)
        } else {
            (
                Dof::zeros(),
                self.accelerations(&self.q, &self.qd, self.config.min_speed.max(1e-3), self.s)
                    .1,
            )
        }
    }

    /// The four sensors' true quantities at the current state and, for each, the one its
    /// misalignment couples in ([`crate::sensors`]): `(u, c)` in [`crate::sensors::NAMES`]
    /// order. Standing (`v` 0) the accelerations are 0 and the rates too.
    fn true_sensors(&self, v: f64) -> ([f64; 4], [f64; 4]) {
        let (acc, diag) = self.accelerations_now(v);
        let vertical_ds2 = self.irregularity(self.s).vertical_ds2;
        let curving = self.curving(self.s, v);
        self.sensor_values(&acc, &diag, v, vertical_ds2, curving.as_ref())
    }

    /// `(u, c)` of [`Simulation::true_sensors`] from the accelerations, with the vertical
    /// profile's curvature at the leading wheelset (the measurement has it already) and the
    /// design line's terms at speed `v` ([`crate::curving`], "Sensors").
    fn sensor_values(
        &self,
        acc: &Dof,
        diag: &Diagnostics,
        v: f64,
        vertical_ds2: f64,
        curving: Option<&Curving>,
    ) -> ([f64; 4], [f64; 4]) {
        let (q, qd) = (&self.q, &self.qd);
        let a = self.vehicle.params.bogie.semi_wheelbase;
        let w = dof::wheelset(0);
        let b = dof::bogie(0);
        let ws_acc = acc[w] + GRAVITY * diag.wheelset_roll[0];
        // Standing, the state is held with the velocities it stopped with: the rates are 0.
        let gyro = if v > 0.0 { qd[w + 1] } else { 0.0 };
        let frame_acc = acc[b + dof::Y] + a * acc[b + dof::YAW] + GRAVITY * q[b + dof::ROLL];
        // See the module docs; standing, `diag` was evaluated at a stand-in speed.
        let roll_rate = if v > 0.0 {
            diag.wheelset_roll_rate[0]
        } else {
            0.0
        };
        let (ws_acc, gyro, frame_acc, roll_rate) = match curving {
            Some(c) => {
                let h = crate::curving::body_heights(&self.vehicle);
                (
                    ws_acc + c.lateral[3] - h[3] * c.roll_acceleration[3],
                    gyro + v * c.curvature[3],
                    frame_acc + c.lateral[1] + a * c.yaw_acceleration[1]
                        - h[1] * c.roll_acceleration[1],
                    roll_rate + c.roll_rate[3],
                )
            }
            None => (ws_acc, gyro, frame_acc, roll_rate),
        };
        let ws_vertical = GRAVITY + v * v * vertical_ds2;
        let frame_vertical = GRAVITY + acc[b + dof::Z] - a * acc[b + dof::PITCH];
        (
            [ws_acc, gyro, frame_acc, roll_rate],
            [ws_vertical, roll_rate, frame_vertical, gyro],
        )
    }

    fn rk4(&mut self, dt: f64, v: f64) {
        let (q0, qd0, s0) = (self.q, self.qd, self.s);
        let (a1, _) = self.accelerations(&q0, &qd0, v, s0);
        let (q2, qd2) = (q0 + qd0 * (dt / 2.0), qd0 + a1 * (dt / 2.0));
        let (a2, _) = self.accelerations(&q2, &qd2, v, s0 + v * dt / 2.0);
        let (q3, qd3) = (q0 + qd2 * (dt / 2.0), qd0 + a2 * (dt / 2.0));
        let (a3, _) = self.accelerations(&q3, &qd3, v, s0 + v * dt / 2.0);
        let (q4, qd4) = (q0 + qd3 * dt, qd0 + a3 * dt);
        let (a4, _) = self.accelerations(&q4, &qd4, v, s0 + v * dt);
        self.q = q0 + (qd0 + (qd2 + qd3) * 2.0 + qd4) * (dt / 6.0);
        self.qd = qd0 + (a1 + (a2 + a3) * 2.0 + a4) * (dt / 6.0);
        self.s = s0 + v * dt;
    }

    /// Sensor and truth outputs at the current state; `noisy` draws the sensor noise and
    /// advances the sensors' drift, `dt` being the last substep (for the anti-alias filters)
    /// and the step (for the drift) at once when standing.
    fn measure(&mut self, v: f64, noisy: bool, dt: f64, h: f64) -> Outputs {
        let (acc, diag) = self.accelerations_now(v);
        let a = self.vehicle.params.bogie.semi_wheelbase;
        let w = dof::wheelset(0);
        let b = dof::bogie(0);
        let irr = self.irregularity(self.s);
        let curving = self.curving(self.s, v);
        let (u, c) = self.sensor_values(&acc, &diag, v, irr.vertical_ds2, curving.as_ref());
        let design = self.line.as_ref().map(|l| l.at(self.s)).unwrap_or_default();
        let design_roll = curving.map_or(0.0, |c| c.roll[3]);
        let [ws_acc, gyro, frame_acc, roll_rate] = u;
        let mut n = [0.0; 4];
        if noisy && self.noise.enabled {
            n = [
                self.rng.normal(),
                self.rng.normal(),
                self.rng.normal(),
                self.roll_rng.normal(),
            ];
        }
        let sigma = [
            self.noise.sigma_acc,
            self.noise.sigma_gyro,
            self.noise.sigma_acc,
            self.noise.sigma_roll_gyro,
        ];
        let sensed = self.sensors.sensed(u, c);
        if let Some(longest) = self.sensors.filter_step() {
            // At the start (`dt` 0) the filters only take their steady state.
            let filter_dt = if dt > 0.0 {
                dt
            } else {
                self.config.max_internal_step.min(longest)
            };
            self.sensors.filter(sensed, filter_dt);
        }
        // The communication step, for the drift and the noise density's bandwidth; 0 (no
        // drift, no density noise) when not sampling.
        let h = if noisy { h } else { 0.0 };
        let y = if self.sensors.is_ideal() {
            std::array::from_fn(|i| u[i] + sigma[i] * n[i])
        } else {
            self.sensors.sample(sensed, h, sigma, n)
        };
        let (q, qd) = (&self.q, &self.qd);
        Outputs {
            ws_acc_y: y[0],
            ws_yaw_rate: y[1],
            frame_acc_y: y[2],
            ws_acc_y_clean: ws_acc,
            ws_yaw_rate_clean: gyro,
            frame_acc_y_clean: frame_acc,
            distance: self.s,
            alignment: irr.alignment,
            vertical_profile: irr.vertical,
            cross_level: irr.cross_level,
            ws_y: q[w],
            ws_yaw: q[w + 1],
            ws_vy: qd[w],
            ws_roll: diag.wheelset_roll[0] + design_roll,
            frame_y: q[b + dof::Y] + a * q[b + dof::YAW],
            frame_vy: qd[b + dof::Y] + a * qd[b + dof::YAW],
            bogie_y: q[b + dof::Y],
            bogie_roll: q[b + dof::ROLL],
            bogie_yaw: q[b + dof::YAW],
            body_y: q[dof::CAR + dof::Y],
            body_roll: q[dof::CAR + dof::ROLL],
            body_yaw: q[dof::CAR + dof::YAW],
            body_z: q[dof::CAR + dof::Z],
            wheel_load_left: diag.wheel_loads[0][0],
            wheel_load_right: diag.wheel_loads[0][1],
            forward_speed: v,
            ws_roll_rate: y[3],
            ws_roll_rate_clean: roll_rate,
            design_curvature: design.curvature,
            design_cant: design.cant,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_is_standard_normal() {
        let mut r = NoiseRng::new(42);
        let n = 200_000;
        let xs: Vec<f64> = (0..n).map(|_| r.normal()).collect();
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
        assert!(mean.abs() < 0.01, "{mean}");
        assert!((var - 1.0).abs() < 0.01, "{var}");
        let tail = xs.iter().filter(|x| x.abs() > 1.96).count() as f64 / n as f64;
        assert!((tail - 0.05).abs() < 0.003, "{tail}");
    }

    /// The jump is the state transition raised to the power 2^128. xoshiro256's transition is
    /// linear over GF(2), so its matrix (columns: the images of the 256 unit states) squared
    /// 128 times gives an oracle independent of the jump polynomial's constants.
    #[test]
    fn the_jump_advances_by_two_to_the_128_draws() {
        type State = [u64; 4];
        let step = |s: State| {
            let mut r = NoiseRng { s, spare: None };
            r.next_u64();
            r.s
        };
        let apply = |m: &[State], x: State| {
            let mut y = [0u64; 4];
            for (i, col) in m.iter().enumerate() {
                if x[i / 64] >> (i % 64) & 1 == 1 {
                    for w in 0..4 {
                        y[w] ^= col[w];
                    }
                }
            }
            y
        };
        let mut m: Vec<State> = (0..256)
            .map(|i| {
                let mut e = [0u64; 4];
                e[i / 64] = 1 << (i % 64);
                step(e)
            })
            .collect();
        for _ in 0..128 {
            m = m.iter().map(|&col| apply(&m, col)).collect();
        }
        for seed in [0, 2, 101, u64::MAX] {
            let r = NoiseRng::new(seed);
            assert_eq!(r.jumped().s, apply(&m, r.s), "seed {seed}");
            assert_ne!(r.jumped().s, r.s);
        }
        // And the two streams are uncorrelated normal deviates.
        let (mut a, mut b) = (NoiseRng::new(2), NoiseRng::new(2).jumped());
        let n = 100_000;
        let c = (0..n).map(|_| a.normal() * b.normal()).sum::<f64>() / n as f64;
        assert!(c.abs() < 5.0 / (n as f64).sqrt(), "{c}");
    }

    #[test]
    fn the_ramp_is_smooth_and_complete() {
        let f = (2.0, 0.5, -1.0);
        assert_eq!(ramped(-1.0, 10.0, f), (0.0, 0.0, 0.0));
        assert_eq!(ramped(10.0, 10.0, f), f);
        let (a, b, _) = ramped(9.999999, 10.0, f);
        assert!((a - 2.0).abs() < 1e-6 && (b - 0.5).abs() < 1e-5);
        // derivative by finite differences
        let e = 1e-6;
        let d = (ramped(3.0 + e, 10.0, (f64::sin(3.0 + e), 0.0, 0.0)).0
            - ramped(3.0 - e, 10.0, (f64::sin(3.0 - e), 0.0, 0.0)).0)
            / (2.0 * e);
        let analytic = ramped(3.0, 10.0, (f64::sin(3.0), f64::cos(3.0), -f64::sin(3.0))).1;
        assert!((d - analytic).abs() < 1e-6, "{d} {analytic}");
    }
}
