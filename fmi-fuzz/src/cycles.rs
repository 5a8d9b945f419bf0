//! Memory cycles: instantiate, initialize, step, save/restore/serialize/deserialize/free FMU
//! states, provoke a few errors, terminate and free, many times over. Meant to run under
//! valgrind (memcheck): every allocation the FMU makes in a cycle must be released by the end
//! of it, and no call may touch memory it does not own.
//!
//! Every status is checked, and the outputs of every cycle must equal the first cycle's bit
//! for bit (an instance that inherited anything from an earlier, freed one would differ).

use crate::api::{Base, Target};
use crate::log::LogSink;
use anyhow::{Result, bail, ensure};
use fmi_abi::types::{fmi2Component, fmi2FMUstate};
use model_description::Causality;
use std::ffi::{CStr, CString, c_char, c_int};

/// What the cycles did.
#[derive(Debug, Default)]
pub struct CycleReport {
    /// Cycles completed (instantiate to free).
    pub cycles: u64,
    /// FMI calls made in all, every one's status checked.
    pub calls: u64,
    /// fmi2DoStep calls.
    pub steps: u64,
    /// FMU-state round trips checked: save and restore, serialize, deserialize and restore, and
    /// the reuse of an existing state (three per cycle).
    pub states: u64,
}

struct Ctx<'t> {
    t: &'t Target,
    calls: u64,
    cycle: u64,
}

impl Ctx<'_> {
    fn ok(&mut self, what: &str, status: c_int) -> Result<()> {
        self.calls += 1;
        ensure!(
            status == 0 || status == 1,
            "cycle {}: {what} returned status {status}",
            self.cycle
        );
        Ok(())
    }

    fn error(&mut self, what: &str, status: c_int) -> Result<()> {
        self.calls += 1;
        ensure!(
            status == 3,
            "cycle {}: {what} returned status {status}, not fmi2Error",
            self.cycle
        );
        Ok(())
    }
}

/// Runs `cycles` cycles on the FMU at `path`, with `presets` (variable name, value) set after
/// each instantiation and `steps` communication steps of `h` seconds per cycle.
pub fn run(
    path: &std::path::Path,
    cycles: u64,
    steps: u64,
    h: f64,
    presets: &[(String, String)],
) -> Result<CycleReport> {
    let t = Target::open(path)?;
    let mut ctx = Ctx {
        t: &t,
        calls: 0,
        cycle: 0,
    };
    let mut report = CycleReport::default();
    let mut first: Option<Vec<u64>> = None;
    let reals: Vec<u32> = t.vars_of(Base::Real).map(|v| v.vr).collect();
    let ints: Vec<u32> = t.vars_of(Base::Integer).map(|v| v.vr).collect();
    let bools: Vec<u32> = t.vars_of(Base::Boolean).map(|v| v.vr).collect();
    let strings: Vec<u32> = t.vars_of(Base::String).map(|v| v.vr).collect();
    let inputs: Vec<(u32, f64)> = t
        .vars_of(Base::Real)
        .filter(|v| v.causality == Causality::Input)
        .map(|v| (v.vr, if v.name.contains("speed") { 20.0 } else { 0.01 }))
        .collect();
    let unknown = reals.iter().max().map_or(0, |m| m + 1000);
    for cycle in 0..cycles {
        ctx.cycle = cycle;
        let api = t.api;
        let sink = Box::new(LogSink::default());
        let callbacks = Box::new(sink.callbacks(true, true));
        let name = CString::new(format!("cycle{cycle}"))?;
        let wrong = CString::new("not-the-guid")?;
        // A refused instantiation allocates nothing that survives.
        // SAFETY: valid strings and callbacks that outlive the call.
        let none = unsafe {
            (api.instantiate)(
                name.as_ptr(),
                1,
                wrong.as_ptr(),
                t.resource_uri.as_ptr(),
                &*callbacks,
                0,
                0,
            )
        };
        ensure!(none.is_null(), "a wrong GUID was accepted");
        // SAFETY: as above.
        let c: fmi2Component = unsafe {
            (api.instantiate)(
                name.as_ptr(),
                1,
                t.guid.as_ptr(),
                t.resource_uri.as_ptr(),
                &*callbacks,
                0,
                (cycle % 3 == 0) as c_int,
            )
        };
        ensure!(!c.is_null(), "cycle {cycle}: fmi2Instantiate returned NULL");
        ctx.calls += 2;
        let result = one_cycle(
            &mut ctx,
            c,
            cycle,
            steps,
            h,
            presets,
            &reals,
            &ints,
            &bools,
            &strings,
            &inputs,
            unknown,
            &mut report,
        );
        // SAFETY: our live instance; freed once.
        unsafe { (api.free_instance)(c) };
        ctx.calls += 1;
        let logged = sink.take();
        let outputs = result?;
        if let Some(bad) = logged
            .iter()
            .find(|r| r.category.is_none() || r.instance.is_none() || r.message.is_none())
        {
            bail!("cycle {cycle}: malformed logger call {bad:?}");
        }
        match &first {
            None => first = Some(outputs),
            Some(f) => ensure!(
                *f == outputs,
                "cycle {cycle}: outputs differ from the first cycle's (state leaked between instances?)"
            ),
        }
        report.cycles += 1;
    }
    report.calls = ctx.calls;
    Ok(report)
}

// Kept a frame of its own: a leak report (valgrind) names the cycle that allocated, whatever the
// optimizer would inline (tests/valgrind.rs looks for it).
#[allow(clippy::too_many_arguments)]
#[inline(never)]
fn one_cycle(
    ctx: &mut Ctx,
    c: fmi2Component,
    cycle: u64,
    steps: u64,
    h: f64,
    presets: &[(String, String)],
    reals: &[u32],
    ints: &[u32],
    bools: &[u32],
    strings: &[u32],
    inputs: &[(u32, f64)],
    unknown: u32,
    report: &mut CycleReport,
) -> Result<Vec<u64>> {
    let t = ctx.t;
    let api = t.api;
    // SAFETY: for the whole block, `c` is our live instance and every array passed matches the
    // length passed with it.
    unsafe {
        initialize(ctx, c, presets, Some(100.0))?;
        let (in_vr, in_val): (Vec<u32>, Vec<f64>) = inputs.iter().copied().unzip();
        let mut time = 0.0;
        let mut out = vec![0.0; reals.len()];
        let mut step = |ctx: &mut Ctx, time: &mut f64| -> Result<()> {
            ctx.ok(
                "fmi2SetReal(inputs)",
                (api.set_real)(c, in_vr.as_ptr(), in_vr.len(), in_val.as_ptr()),
            )?;
            ctx.ok("fmi2DoStep", (api.do_step)(c, *time, h, 1))?;
            *time += h;
            report.steps += 1;
            Ok(())
        };
        for _ in 0..steps {
            step(ctx, &mut time)?;
            ctx.ok(
                "fmi2GetReal(all)",
                (api.get_real)(c, reals.as_ptr(), reals.len(), out.as_mut_ptr()),
            )?;
        }
        let outputs: Vec<u64> = out.iter().map(|x| x.to_bits()).collect();

        // FMU state: save, step on, restore, and the same outputs come back.
        let mut s1: fmi2FMUstate = std::ptr::null_mut();
        ctx.ok("fmi2GetFMUstate", (api.get_fmu_state)(c, &mut s1))?;
        let t_saved = time;
        step(ctx, &mut time)?;
        step(ctx, &mut time)?;
        ctx.ok("fmi2SetFMUstate", (api.set_fmu_state)(c, s1))?;
        time = t_saved;
        ctx.ok(
            "fmi2GetReal(after restore)",
            (api.get_real)(c, reals.as_ptr(), reals.len(), out.as_mut_ptr()),
        )?;
        ensure!(
            out.iter().map(|x| x.to_bits()).collect::<Vec<_>>() == outputs,
            "cycle {cycle}: outputs after fmi2SetFMUstate differ from those saved"
        );
        // Serialize, deserialize into a new state, restore that.
        let mut size = 0usize;
        ctx.ok(
            "fmi2SerializedFMUstateSize",
            (api.serialized_fmu_state_size)(c, s1, &mut size),
        )?;
        let mut bytes = vec![0u8; size];
        ctx.ok(
            "fmi2SerializeFMUstate",
            (api.serialize_fmu_state)(c, s1, bytes.as_mut_ptr() as *mut c_char, size),
        )?;
        let mut s2: fmi2FMUstate = std::ptr::null_mut();
        ctx.ok(
            "fmi2DeSerializeFMUstate",
            (api.deserialize_fmu_state)(c, bytes.as_ptr() as *const c_char, size, &mut s2),
        )?;
        step(ctx, &mut time)?;
        ctx.ok("fmi2SetFMUstate(deserialized)", (api.set_fmu_state)(c, s2))?;
        time = t_saved;
        ctx.ok(
            "fmi2GetReal(after deserialized restore)",
            (api.get_real)(c, reals.as_ptr(), reals.len(), out.as_mut_ptr()),
        )?;
        ensure!(
            out.iter().map(|x| x.to_bits()).collect::<Vec<_>>() == outputs,
            "cycle {cycle}: outputs after restoring the deserialized state differ"
        );
        // Reuse an existing state (GetFMUstate into s2, DeSerialize into s1).
        step(ctx, &mut time)?;
        ctx.ok("fmi2GetFMUstate(reuse)", (api.get_fmu_state)(c, &mut s2))?;
        ctx.ok(
            "fmi2DeSerializeFMUstate(reuse)",
            (api.deserialize_fmu_state)(c, bytes.as_ptr() as *const c_char, size, &mut s1),
        )?;
        // A corrupt copy is refused and allocates nothing.
        if size > 8 {
            let mut bad = bytes.clone();
            bad[size / 2] ^= 0x40;
            bad.truncate(size - 3);
            let mut s3: fmi2FMUstate = std::ptr::null_mut();
            ctx.error(
                "fmi2DeSerializeFMUstate(corrupt)",
                (api.deserialize_fmu_state)(c, bad.as_ptr() as *const c_char, bad.len(), &mut s3),
            )?;
            ensure!(s3.is_null(), "a refused deserialization returned a state");
        }
        ctx.ok("fmi2FreeFMUstate", (api.free_fmu_state)(c, &mut s1))?;
        ctx.ok("fmi2FreeFMUstate", (api.free_fmu_state)(c, &mut s2))?;
        ensure!(
            s1.is_null() && s2.is_null(),
            "fmi2FreeFMUstate left a pointer"
        );
        report.states += 3;

        // The other getters (strings are read: their memory must be valid).
        let mut iv = vec![0; ints.len()];
        ctx.ok(
            "fmi2GetInteger",
            (api.get_integer)(c, ints.as_ptr(), ints.len(), iv.as_mut_ptr()),
        )?;
        let mut bv = vec![0; bools.len()];
        ctx.ok(
            "fmi2GetBoolean",
            (api.get_boolean)(c, bools.as_ptr(), bools.len(), bv.as_mut_ptr()),
        )?;
        let mut sv: Vec<*const c_char> = vec![std::ptr::null(); strings.len()];
        ctx.ok(
            "fmi2GetString",
            (api.get_string)(c, strings.as_ptr(), strings.len(), sv.as_mut_ptr()),
        )?;
        let _total: usize = sv.iter().map(|p| CStr::from_ptr(*p).to_bytes().len()).sum();

        // Errors: logged, and the instance still answers.
        ctx.error(
            "fmi2GetReal(unknown vr)",
            (api.get_real)(c, &unknown, 1, out.as_mut_ptr()),
        )?;
        ctx.error("fmi2DoStep(h = NaN)", (api.do_step)(c, time, f64::NAN, 1))?;
        ctx.error(
            "fmi2EnterInitializationMode(late)",
            (api.enter_initialization_mode)(c),
        )?;

        // Every other cycle: reset and initialize again.
        if cycle % 2 == 1 {
            ctx.ok("fmi2Reset", (api.reset)(c))?;
            initialize(ctx, c, presets, None)?;
            time = 0.0;
            step(ctx, &mut time)?;
        }
        ctx.ok("fmi2Terminate", (api.terminate)(c))?;
        ctx.ok(
            "fmi2GetReal(after terminate)",
            (api.get_real)(c, reals.as_ptr(), reals.len(), out.as_mut_ptr()),
        )?;
        Ok(outputs)
    }
}

/// SetupExperiment (with a stop time when given), the presets, Enter- and
/// ExitInitializationMode, each required to return OK.
///
/// # Safety
/// `c` is a live instance of `ctx`'s FMU in the instantiated state.
unsafe fn initialize(
    ctx: &mut Ctx,
    c: fmi2Component,
    presets: &[(String, String)],
    stop: Option<f64>,
) -> Result<()> {
    let api = ctx.t.api;
    // SAFETY: the caller's contract.
    unsafe {
        ctx.ok(
            "fmi2SetupExperiment",
            (api.setup_experiment)(c, 0, 0.0, 0.0, stop.is_some() as i32, stop.unwrap_or(0.0)),
        )?;
        apply_presets(ctx, c, presets)?;
        ctx.ok(
            "fmi2EnterInitializationMode",
            (api.enter_initialization_mode)(c),
        )?;
        ctx.ok(
            "fmi2ExitInitializationMode",
            (api.exit_initialization_mode)(c),
        )
    }
}

/// Sets the presets (variable name, value) on a freshly instantiated or reset instance.
fn apply_presets(ctx: &mut Ctx, c: fmi2Component, presets: &[(String, String)]) -> Result<()> {
    let t = ctx.t;
    let api = t.api;
    for (name, value) in presets {
        let Some(v) = t.var_named(name) else { continue };
        let vr = v.vr;
        // SAFETY: our live instance; one value per reference.
        let s = unsafe {
            match v.base {
                Base::Real => (api.set_real)(c, &vr, 1, &value.parse::<f64>()?),
                Base::Integer => (api.set_integer)(c, &vr, 1, &value.parse::<c_int>()?),
                Base::Boolean => {
                    let b = matches!(value.as_str(), "true" | "1") as c_int;
                    (api.set_boolean)(c, &vr, 1, &b)
                }
                Base::String => {
                    let s = CString::new(value.as_str())?;
                    let p = s.as_ptr();
                    (api.set_string)(c, &vr, 1, &p)
                }
            }
        };
        ctx.ok(&format!("setting preset {name}"), s)?;
    }
    Ok(())
}
