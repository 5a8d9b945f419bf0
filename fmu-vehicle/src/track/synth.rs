//! Harmonic superposition: drawing the components and evaluating them on the grid.

use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

/// Number of lanes of the partial sums in the grid kernel. The sum over components is split
/// into this many interleaved partial sums (component `k` into lane `k % LANES`) that are added
/// at the end in a fixed order: two 256-bit vectors per field, and the same result bit for bit
/// from the portable and the AVX2 code, on any machine, for any part of the grid.
const LANES: usize = 8;

/// The harmonic components of one channel: `xi(s) = sum_k a_k cos(omega_k s + phi_k)`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub(super) struct Components {
    pub omega: Vec<f64>,
    pub amplitude: Vec<f64>,
    pub phase: Vec<f64>,
}

/// Integral of `f` over `[a, b]` by Simpson's rule on 8 panels.
fn simpson(f: &impl Fn(f64) -> f64, a: f64, b: f64) -> f64 {
    const PANELS: usize = 8;
    let h = (b - a) / PANELS as f64;
    let mut sum = f(a) + f(b);
    for i in 1..PANELS {
        sum += if i % 2 == 1 { 4.0 } else { 2.0 } * f(a + i as f64 * h);
    }
    sum * h / 3.0
}

/// A 64-bit mix (splitmix64's finalizer) to derive independent per-channel seeds.
fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// The random-number stream of channel `channel` (0 alignment, 1 vertical, 2 cross-level) for
/// the track seed `seed`: `StdRng` (ChaCha12 in rand 0.10) seeded with a mix of both, so the
/// channels are independent streams of one seed.
pub(super) fn channel_rng(seed: u64, channel: u64) -> StdRng {
    let stream = mix64(seed ^ mix64(channel.wrapping_add(1).wrapping_mul(0x9e37_79b9_7f4a_7c15)));
    StdRng::seed_from_u64(stream)
}

impl Components {
    /// `n` components with wavenumbers in `n` equal bins of `[omega_min, omega_max]`, each drawn
    /// uniformly within its bin, phase uniform on `[0, 2 pi)`, and amplitude `sqrt(2 P_k)` with
    /// `P_k` the integral of the spectrum over the bin (Simpson's rule on 8 panels; equal to
    /// `S(omega_k) d_omega` to first order, and exact for the variance whatever the draw). Draw
    /// order per component: wavenumber, then phase.
    pub fn draw(
        psd: impl Fn(f64) -> f64,
        omega_min: f64,
        omega_max: f64,
        n: usize,
        rng: &mut StdRng,
    ) -> Components {
        let d_omega = (omega_max - omega_min) / n as f64;
        let mut c = Components {
            omega: Vec::with_capacity(n),
            amplitude: Vec::with_capacity(n),
            phase: Vec::with_capacity(n),
        };
        for k in 0..n {
            let lo = omega_min + k as f64 * d_omega;
            let u: f64 = rng.random();
            let omega = lo + u * d_omega;
            let phase = TAU * rng.random::<f64>();
            c.omega.push(omega);
            c.amplitude
                .push((2.0 * simpson(&psd, lo, lo + d_omega)).sqrt());
            c.phase.push(phase);
        }
        c
    }

    /// Value and first and second derivative at `s` by direct summation (exact, `O(n)`).
    pub fn eval(&self, s: f64) -> [f64; 3] {
        let mut out = [0.0; 3];
        for k in 0..self.omega.len() {
            let o = self.omega[k];
            let a = self.amplitude[k];
            let (sin, cos) = (o * s + self.phase[k]).sin_cos();
            out[0] += a * cos;
            out[1] -= a * o * sin;
            out[2] -= a * o * o * cos;
        }
        out
    }

    /// Variance `sum a_k^2 / 2` of the components with wavenumber in `[lo, hi)`.
    #[cfg(test)]
    pub fn variance_in(&self, lo: f64, hi: f64) -> f64 {
        self.omega
            .iter()
            .zip(&self.amplitude)
            .filter(|(o, _)| **o >= lo && **o < hi)
            .map(|(_, a)| 0.5 * a * a)
            .sum()
    }
}

/// Eight components' phasors and constants, laid out for 256-bit vectors (two of four lanes
/// per field).
#[derive(Debug, Clone, Copy, Default)]
#[repr(C, align(64))]
struct Group {
    zr: [f64; LANES],
    zi: [f64; LANES],
    cr: [f64; LANES],
    ci: [f64; LANES],
    om: [f64; LANES],
    om2: [f64; LANES],
}

/// The components of one channel prepared for evaluation on a grid of step `h`: each is a
/// phasor `z_k = a_k exp(i (omega_k s + phi_k))` that advances one node by multiplication with
/// `r_k = exp(i omega_k h) = cr + i ci`. Padded with zero-amplitude components to a multiple of
/// [`LANES`].
pub(super) struct Kernel<'a> {
    comps: &'a Components,
    groups: Vec<Group>,
}

impl<'a> Kernel<'a> {
    pub fn new(comps: &'a Components, h: f64) -> Kernel<'a> {
        let n = comps.omega.len();
        let mut groups = vec![
            Group {
                cr: [1.0; LANES],
                ..Group::default()
            };
            n.div_ceil(LANES)
        ];
        for (i, &o) in comps.omega.iter().enumerate() {
            let g = &mut groups[i / LANES];
            let l = i % LANES;
            let (s, c) = (o * h).sin_cos();
            g.cr[l] = c;
            g.ci[l] = s;
            g.om[l] = o;
            g.om2[l] = o * o;
        }
        Kernel { comps, groups }
    }

    /// Sets the phasors exactly (`sin_cos`) at node `first` (position `first h`).
    fn anchor(&mut self, first: i64, h: f64) {
        let s0 = first as f64 * h;
        let c = self.comps;
        for (i, ((&o, &a), &p)) in c.omega.iter().zip(&c.amplitude).zip(&c.phase).enumerate() {
            let g = &mut self.groups[i / LANES];
            let (s, co) = (o * s0 + p).sin_cos();
            g.zr[i % LANES] = a * co;
            g.zi[i % LANES] = a * s;
        }
    }

    /// Fills `out[j]` with value, first and second derivative at the nodes
    /// `s_j = (first + j) h`, `j = 0 .. out.len()`. The phasors are set exactly at node `first`
    /// and advanced by rotation from there: the caller must always start at the same anchor
    /// nodes (the block starts) for the values to be reproducible bit for bit.
    pub fn fill(&mut self, first: i64, h: f64, out: &mut [[f64; 3]]) {
        self.anchor(first, h);
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: the CPU supports AVX2 (checked just above).
                unsafe { avx2::rotate(&mut self.groups, out) };
                return;
            }
        }
        rotate(&mut self.groups, out);
    }
}

/// The portable kernel: per node, sums the phasors' contributions and advances them by one
/// node. The AVX2 kernel performs exactly the same IEEE operations in the same order per lane
/// (no fused multiply-add) and reduces the lanes in the same order, so both give identical bits.
fn rotate(groups: &mut [Group], out: &mut [[f64; 3]]) {
    for node in out.iter_mut() {
        let mut v = [0.0f64; LANES];
        let mut d1 = [0.0f64; LANES];
        let mut d2 = [0.0f64; LANES];
        for g in groups.iter_mut() {
            for l in 0..LANES {
                let (re, im) = (g.zr[l], g.zi[l]);
                v[l] += re;
                d1[l] += g.om[l] * im;
                d2[l] += g.om2[l] * re;
                g.zr[l] = re * g.cr[l] - im * g.ci[l];
                g.zi[l] = re * g.ci[l] + im * g.cr[l];
            }
        }
        node[0] = lane_sum(&v);
        node[1] = -lane_sum(&d1);
        node[2] = -lane_sum(&d2);
    }
}

/// Sum of the lanes in a fixed order.
#[inline(always)]
fn lane_sum(x: &[f64; LANES]) -> f64 {
    ((x[0] + x[4]) + (x[1] + x[5])) + ((x[2] + x[6]) + (x[3] + x[7]))
}

#[cfg(target_arch = "x86_64")]
mod avx2 {
    use super::{Group, LANES, lane_sum};
    use std::arch::x86_64::*;

    /// A [`Group`] seen as twelve 256-bit vectors: zr, zi, cr, ci, om, om2, two each.
    #[repr(C, align(64))]
    struct GroupV([__m256d; 12]);
    const _: () = assert!(
        std::mem::size_of::<GroupV>() == std::mem::size_of::<Group>()
            && std::mem::align_of::<GroupV>() == std::mem::align_of::<Group>()
            && LANES == 8
    );

    /// [`super::rotate`] with 256-bit vectors: lanes 0-3 and 4-7 of each field. The groups
    /// are viewed as vectors (no unaligned-load intrinsics) so that unoptimized test builds,
    /// where every intrinsic is a call, stay tolerably fast too.
    #[target_feature(enable = "avx2")]
    pub(super) fn rotate(groups: &mut [Group], out: &mut [[f64; 3]]) {
        // SAFETY: `Group` is `#[repr(C)]` with six `[f64; 8]` fields (384 bytes, align 64);
        // `GroupV` has the same size and alignment and any bit pattern is a valid `__m256d`.
        let groups: &mut [GroupV] = unsafe {
            std::slice::from_raw_parts_mut(groups.as_mut_ptr().cast::<GroupV>(), groups.len())
        };
        for node in out.iter_mut() {
            let (mut v0, mut v1) = (_mm256_setzero_pd(), _mm256_setzero_pd());
            let (mut a0, mut a1) = (_mm256_setzero_pd(), _mm256_setzero_pd());
            let (mut b0, mut b1) = (_mm256_setzero_pd(), _mm256_setzero_pd());
            for GroupV([zr0, zr1, zi0, zi1, cr0, cr1, ci0, ci1, om0, om1, oq0, oq1]) in
                groups.iter_mut()
            {
                let (re0, re1, im0, im1) = (*zr0, *zr1, *zi0, *zi1);
                v0 = _mm256_add_pd(v0, re0);
                v1 = _mm256_add_pd(v1, re1);
                a0 = _mm256_add_pd(a0, _mm256_mul_pd(*om0, im0));
                a1 = _mm256_add_pd(a1, _mm256_mul_pd(*om1, im1));
                b0 = _mm256_add_pd(b0, _mm256_mul_pd(*oq0, re0));
                b1 = _mm256_add_pd(b1, _mm256_mul_pd(*oq1, re1));
                *zr0 = _mm256_sub_pd(_mm256_mul_pd(re0, *cr0), _mm256_mul_pd(im0, *ci0));
                *zr1 = _mm256_sub_pd(_mm256_mul_pd(re1, *cr1), _mm256_mul_pd(im1, *ci1));
                *zi0 = _mm256_add_pd(_mm256_mul_pd(re0, *ci0), _mm256_mul_pd(im0, *cr0));
                *zi1 = _mm256_add_pd(_mm256_mul_pd(re1, *ci1), _mm256_mul_pd(im1, *cr1));
            }
            node[0] = lane_sum(&lanes(v0, v1));
            node[1] = -lane_sum(&lanes(a0, a1));
            node[2] = -lane_sum(&lanes(b0, b1));
        }
    }

    #[inline(always)]
    fn lanes(lo: __m256d, hi: __m256d) -> [f64; LANES] {
        // SAFETY: `__m256d` is 4 f64 (`[__m256d; 2]` and `[f64; 8]` have the same size).
        unsafe { std::mem::transmute::<[__m256d; 2], [f64; LANES]>([lo, hi]) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn comps() -> Components {
        let mut rng = channel_rng(7, 0);
        Components::draw(
            |o| 1e-7 / (o * o + 0.01),
            TAU / 250.0,
            TAU / 1.0,
            203,
            &mut rng,
        )
    }

    /// The grid kernel agrees with direct summation, for blocks anywhere on the track.
    #[test]
    fn kernel_matches_direct_sum() {
        let c = comps();
        let h = 0.05;
        let mut k = Kernel::new(&c, h);
        for first in [-3 * 1024i64, 0, 40 * 1024] {
            let mut out = vec![[0.0; 3]; 1024];
            k.fill(first, h, &mut out);
            let scale: [f64; 3] = std::array::from_fn(|d| {
                (0..c.omega.len())
                    .map(|i| c.amplitude[i] * c.omega[i].powi(d as i32))
                    .sum::<f64>()
            });
            for j in [0usize, 1, 511, 1023] {
                let exact = c.eval((first + j as i64) as f64 * h);
                for d in 0..3 {
                    let err = (out[j][d] - exact[d]).abs() / scale[d];
                    // The direct sum itself loses about |omega s| eps of phase at large s.
                    assert!(
                        err < 1e-11,
                        "block {first} node {j} derivative {d}: {err:e}"
                    );
                }
            }
        }
    }

    /// The AVX2 kernel gives bit-identical results to the portable one.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn avx2_and_portable_bit_identical() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            return;
        }
        let c = comps();
        let mut k = Kernel::new(&c, 0.05);
        let mut a = vec![[0.0; 3]; 300];
        let mut b = vec![[0.0; 3]; 300];
        k.anchor(5 * 1024, 0.05);
        // SAFETY: AVX2 checked above.
        unsafe { avx2::rotate(&mut k.groups, &mut a) };
        k.anchor(5 * 1024, 0.05);
        rotate(&mut k.groups, &mut b);
        assert_eq!(a, b);
        assert!(a[299][0] != 0.0);
    }

    /// Different channels of one seed, and one channel of different seeds, draw different
    /// numbers.
    #[test]
    fn streams_differ() {
        let mut x: Vec<f64> = Vec::new();
        for (seed, ch) in [(1, 0), (1, 1), (1, 2), (2, 0)] {
            x.push(channel_rng(seed, ch).random());
        }
        for i in 0..x.len() {
            for j in 0..i {
                assert_ne!(x[i], x[j]);
            }
        }
    }
}
