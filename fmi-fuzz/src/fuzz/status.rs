//! The status queries, and the capabilities our FMUs do not declare (directional derivatives,
//! input and output derivatives), which must be refused rather than half-answered.

use super::check::{Expect, fmt_f};
use super::pointers::{Comp, or_null, or_null_mut};
use super::{CANARY_INT, CANARY_REAL, Fuzzer};
use crate::api::{Base, NAMES};
use crate::oracle::Call;
use fmi_abi::types::fmi2String;
use model_description::Causality;
use std::ffi::c_int;

impl Fuzzer<'_> {
    pub(super) fn directional(&mut self, comp: Comp) {
        let fidx = 24;
        let vrs: Vec<u32> = self.t.vars_of(Base::Real).map(|v| v.vr).take(3).collect();
        let known = vec![1.0; vrs.len()];
        let mut out = vec![0.0; vrs.len()];
        let null = self.rng.chance(30);
        let c = self.begin_on(
            comp,
            format!(
                "fmi2GetDirectionalDerivative(nUnknown={}, nKnown={}, arrays={})",
                vrs.len(),
                vrs.len(),
                if null { "NULL" } else { "valid" }
            ),
        );
        let (vp, kp, op) = (
            or_null(null, vrs.as_ptr()),
            or_null(null, known.as_ptr()),
            or_null_mut(null, out.as_mut_ptr()),
        );
        // SAFETY: arrays hold vrs.len() elements unless NULL.
        let status = unsafe {
            (self.t.api.get_directional_derivative)(c, vp, vrs.len(), vp, vrs.len(), kp, op)
        };
        let expect = self.capability_expect(
            comp,
            Call::GetDirectionalDerivative,
            self.caps.directional,
            "providesDirectionalDerivative is false",
        );
        self.finish(
            fidx,
            comp,
            Call::GetDirectionalDerivative,
            status,
            expect,
            |s| s,
        );
    }

    pub(super) fn input_derivatives(&mut self, comp: Comp) {
        let fidx = 25;
        let vrs: Vec<u32> = self
            .t
            .vars_of(Base::Real)
            .filter(|v| v.causality == Causality::Input)
            .map(|v| v.vr)
            .collect();
        let order = vec![1; vrs.len()];
        let vals = vec![0.5; vrs.len()];
        let c = self.begin_on(
            comp,
            format!("fmi2SetRealInputDerivatives(nvr={})", vrs.len()),
        );
        // SAFETY: arrays hold vrs.len() elements.
        let status = unsafe {
            (self.t.api.set_real_input_derivatives)(
                c,
                vrs.as_ptr(),
                vrs.len(),
                order.as_ptr(),
                vals.as_ptr(),
            )
        };
        let expect = self.capability_expect(
            comp,
            Call::SetRealInputDerivatives,
            self.caps.interpolate,
            "canInterpolateInputs is false",
        );
        self.finish(
            fidx,
            comp,
            Call::SetRealInputDerivatives,
            status,
            expect,
            |s| s,
        );
    }

    pub(super) fn output_derivatives(&mut self, comp: Comp) {
        let fidx = 26;
        let vrs: Vec<u32> = self
            .t
            .vars_of(Base::Real)
            .filter(|v| v.causality == Causality::Output)
            .map(|v| v.vr)
            .take(4)
            .collect();
        let order = vec![1; vrs.len()];
        let mut vals = vec![0.0; vrs.len()];
        let c = self.begin_on(
            comp,
            format!("fmi2GetRealOutputDerivatives(nvr={})", vrs.len()),
        );
        // SAFETY: arrays hold vrs.len() elements.
        let status = unsafe {
            (self.t.api.get_real_output_derivatives)(
                c,
                vrs.as_ptr(),
                vrs.len(),
                order.as_ptr(),
                vals.as_mut_ptr(),
            )
        };
        let expect = self.capability_expect(
            comp,
            Call::GetRealOutputDerivatives,
            self.caps.output_derivatives,
            "maxOutputDerivativeOrder is 0",
        );
        self.finish(
            fidx,
            comp,
            Call::GetRealOutputDerivatives,
            status,
            expect,
            |s| s,
        );
    }

    /// A capability the model description does not declare must be refused.
    fn capability_expect(&self, comp: Comp, call: Call, supported: bool, why: &str) -> Expect {
        self.expect(comp, call, Expect::Any, |_| {
            (!supported).then(|| Expect::Error(why.into()))
        })
    }

    pub(super) fn status(&mut self, fidx: usize, comp: Comp, hostile: bool) {
        let kind: c_int = if hostile {
            *self.rng.pick(&[0, 1, 2, 3, -1, 99])
        } else {
            *self.rng.pick(&[2, 3])
        };
        let null = hostile && self.rng.chance(10);
        let mut real = f64::from_bits(CANARY_REAL);
        let mut int: c_int = CANARY_INT;
        let mut string: fmi2String = std::ptr::null();
        let c = self.begin_on(
            comp,
            format!(
                "{}(kind={kind}, value={})",
                NAMES[fidx],
                if null { "NULL" } else { "&value" }
            ),
        );
        let (real_p, int_p, string_p) = (
            or_null_mut(null, &mut real),
            or_null_mut(null, &mut int),
            or_null_mut(null, &mut string),
        );
        let api = &self.t.api;
        // SAFETY: the out pointer is NULL or ours.
        let status = unsafe {
            match NAMES[fidx] {
                "fmi2GetStatus" => (api.get_status)(c, kind, int_p),
                "fmi2GetRealStatus" => (api.get_real_status)(c, kind, real_p),
                "fmi2GetIntegerStatus" => (api.get_integer_status)(c, kind, int_p),
                "fmi2GetBooleanStatus" => (api.get_boolean_status)(c, kind, int_p),
                _ => (api.get_string_status)(c, kind, string_p),
            }
        };
        let if_legal = Expect::Ok("legal (Discard for an unsupported kind)".into());
        let expect = self.expect(comp, Call::GetStatus, if_legal, |_| {
            null.then(|| Expect::Error("value is NULL".into()))
        });
        self.finish(fidx, comp, Call::GetStatus, status, expect, |s| s);
        let Comp::Inst(i) = comp else { return };
        if null || !(0..=1).contains(&status) {
            return;
        }
        if NAMES[fidx] == "fmi2GetRealStatus"
            && kind == 2
            && let Some(t) = self.insts[i].time
            && real != t
            && !((real - t).abs() <= 1e-9 * t.abs().max(1.0))
        {
            self.fail(format!(
                "fmi2GetRealStatus(fmi2LastSuccessfulTime) = {} but the steps reached {}",
                fmt_f(real),
                fmt_f(t)
            ));
        }
        if NAMES[fidx] == "fmi2GetBooleanStatus" && kind == 3 && int != 0 && int != 1 {
            self.fail(format!(
                "fmi2GetBooleanStatus(fmi2Terminated) returned {int}"
            ));
        }
    }
}
