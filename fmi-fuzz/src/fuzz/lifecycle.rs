//! An instance's life: the version queries, fmi2Instantiate with hostile names, GUIDs,
//! resource locations and callbacks, fmi2FreeInstance, the state changes, debug logging,
//! fmi2SetupExperiment and fmi2DoStep.

use super::Fuzzer;
use super::books::{Inst, KnownMap};
use super::check::{Expect, fmt_f};
use super::pointers::Comp;
use super::values::REAL_EDGES;
use crate::api::NAMES;
use crate::log::LogSink;
use crate::oracle::{Call, State, States};
use fmi_abi::types::{fmi2CallbackFunctions, fmi2String};
use std::ffi::{CStr, CString, c_int};

impl Fuzzer<'_> {
    pub(super) fn version(&mut self, f: usize) {
        self.begin("-", format!("{}()", NAMES[f]));
        let (p, want) = if NAMES[f] == "fmi2GetVersion" {
            // SAFETY: no arguments.
            (unsafe { (self.t.api.get_version)() }, "2.0")
        } else {
            // SAFETY: no arguments; the symbol was resolved with the FMI 2.0 signature.
            (unsafe { (self.t.api.get_types_platform)() }, "default")
        };
        self.stats.add(f, 0);
        if p.is_null() {
            self.end("NULL".into());
            self.fail(format!("{} returned NULL", NAMES[f]));
            return;
        }
        // SAFETY: the standard says a static NUL-terminated string.
        let s = unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned();
        self.end(format!("{s:?}"));
        if s != want {
            self.fail(format!("{} returned {s:?}, not {want:?}", NAMES[f]));
        }
    }

    pub(super) fn instantiate(&mut self, valid: bool) {
        let fidx = 3;
        let r = &mut self.rng;
        let id = self.next_id;
        let mut why_null: Vec<&str> = Vec::new();
        let name: Option<Vec<u8>> = if valid || r.chance(70) {
            Some(format!("fuzz{id}").into_bytes())
        } else {
            r.pick(&[
                None,
                Some(b"".to_vec()),
                Some(b"%s%n%x 100% \"quoted\"".to_vec()),
                Some(vec![b'n'; 5000]),
            ])
            .clone()
        };
        let fmu_type: c_int = if valid || r.chance(75) {
            1
        } else {
            *r.pick(&[0, 2, -1, i32::MAX])
        };
        if fmu_type != 1 {
            why_null.push("fmuType is not fmi2CoSimulation");
        }
        let guid_ok = self.t.guid.as_bytes().to_vec();
        let guid: Option<Vec<u8>> = if valid || r.chance(70) {
            Some(guid_ok.clone())
        } else {
            let g = r
                .pick(&[
                    None,
                    Some(b"".to_vec()),
                    Some(b"00000000-0000-0000-0000-000000000000".to_vec()),
                    Some(guid_ok[..guid_ok.len() - 1].to_vec()),
                    Some([&guid_ok[..], b"x"].concat()),
                ])
                .clone();
            why_null.push("the GUID is wrong or NULL");
            g
        };
        let resource_ok = self.t.resource_uri.as_bytes().to_vec();
        let resource: Option<Vec<u8>> = if valid || r.chance(70) {
            Some(resource_ok)
        } else {
            r.pick(&[
                None,
                Some(b"".to_vec()),
                Some(b"garbage".to_vec()),
                Some(b"file:///nonexistent/resources".to_vec()),
                Some(b"http://example.invalid/resources".to_vec()),
            ])
            .clone()
        };
        let no_resources = resource.as_deref() != Some(self.t.resource_uri.as_bytes());
        // Callbacks: 0 full, 1 NULL pointer, 2 NULL logger, 3 NULL environment.
        let cb_kind = if valid || r.chance(70) {
            0
        } else {
            r.range(1, 3)
        };
        let visible = *r.pick(&[0, 1, 2]);
        let logging_on = if r.chance(30) { 1 } else { 0 };

        let sink = Box::new(LogSink::default());
        let callbacks = match cb_kind {
            1 => None,
            2 => Some(Box::new(sink.callbacks(false, true))),
            3 => Some(Box::new(sink.callbacks(true, false))),
            _ => Some(Box::new(sink.callbacks(true, true))),
        };
        let cstr = |b: &Option<Vec<u8>>| b.as_ref().map(|v| CString::new(v.clone()).unwrap());
        let (c_name, c_guid, c_res) = (cstr(&name), cstr(&guid), cstr(&resource));
        let p = |c: &Option<CString>| c.as_ref().map_or(std::ptr::null(), |s| s.as_ptr());
        let show = |b: &Option<Vec<u8>>| match b {
            None => "NULL".to_string(),
            Some(v) if v.len() > 60 => format!("<{} bytes>", v.len()),
            Some(v) => format!("{:?}", String::from_utf8_lossy(v)),
        };
        let text = format!(
            "fmi2Instantiate(name={}, fmuType={fmu_type}, guid={}, resources={}, callbacks={}, visible={visible}, loggingOn={logging_on})",
            show(&name),
            show(&guid),
            show(&resource),
            ["full", "NULL", "NULL logger", "NULL environment"][cb_kind]
        );
        self.begin("-", text);
        let cb_ptr = callbacks
            .as_ref()
            .map_or(std::ptr::null(), |b| &**b as *const fmi2CallbackFunctions);
        // SAFETY: every pointer is NULL or a NUL-terminated string / callback struct that
        // lives until the call returns (the FMU must copy what it keeps).
        let c = unsafe {
            (self.t.api.instantiate)(
                p(&c_name),
                fmu_type,
                p(&c_guid),
                p(&c_res),
                cb_ptr,
                visible,
                logging_on,
            )
        };
        // The strings die here: an FMU that kept a pointer to them reads freed memory
        // (valgrind sees it; the fuzzer sees a wrong instance name in later messages).
        drop((c_name, c_guid, c_res));
        self.stats.add(fidx, if c.is_null() { 3 } else { 0 });
        self.end(if c.is_null() {
            "NULL".into()
        } else {
            format!("i{id}")
        });
        let records = sink.take();
        let logs_to_us = cb_kind == 0;
        let name_s = name.map(|v| String::from_utf8_lossy(&v).into_owned());
        for rec in &records {
            if rec.category.is_none()
                || rec.instance.is_none()
                || rec.message.as_ref().is_none_or(|m| m.is_empty())
                || !(0..=4).contains(&rec.status)
            {
                self.fail(format!("fmi2Instantiate: malformed logger call {rec:?}"));
            }
        }
        if !why_null.is_empty() {
            if !c.is_null() {
                self.fail(format!(
                    "fmi2Instantiate returned an instance although {}",
                    why_null.join(" and ")
                ));
                // It is live all the same: free it.
                // SAFETY: the pointer the FMU just returned.
                unsafe { (self.t.api.free_instance)(c) };
            } else if logs_to_us && !records.iter().any(|r| r.status >= 3) {
                self.fail(format!(
                    "fmi2Instantiate returned NULL ({}) without logging an error",
                    why_null.join(" and ")
                ));
            }
            return;
        }
        if c.is_null() {
            if !no_resources {
                self.fail(format!(
                    "fmi2Instantiate with valid arguments returned NULL; logged {records:?}"
                ));
            }
            return;
        }
        self.next_id += 1;
        self.insts.push(Inst {
            id,
            c,
            sink,
            _callbacks: callbacks,
            name: name_s,
            logs_to_us,
            errors_logged: true,
            categories_off: Default::default(),
            possible: States::one(State::Instantiated),
            time: Some(0.0),
            known: KnownMap::new(),
            states: Vec::new(),
            fatal: false,
            params_touched: false,
            no_resources,
        });
        let i = self.insts.len() - 1;
        if !self.cfg.presets.is_empty() && self.rng.chance(self.cfg.preset_percent) {
            self.apply_presets(i);
        }
    }

    pub(super) fn free_instance(&mut self, comp: Comp) {
        let fidx = 4;
        if let Comp::Inst(i) = comp {
            // Free its states first (the standard frees nothing for us).
            if !self.insts[i].fatal {
                while !self.insts[i].states.is_empty() {
                    self.free_state_at(i, 0);
                    if self.insts[i].fatal {
                        break;
                    }
                }
            }
        }
        let who = self.who(comp);
        self.begin(&who, "fmi2FreeInstance()".into());
        let c = self.comp_ptr(comp);
        // SAFETY: a live instance (then forgotten), NULL, or our foreign block.
        unsafe { (self.t.api.free_instance)(c) };
        self.stats.add(fidx, 0);
        self.end("done".into());
        if let Comp::Inst(i) = comp {
            let inst = self.insts.remove(i);
            for r in inst.sink.take() {
                if r.category.is_none() || r.instance.is_none() || r.message.is_none() {
                    self.fail(format!("logger call during fmi2FreeInstance: {r:?}"));
                }
            }
            // States the FMU could not free (fatal instance) are leaked on purpose.
        } else {
            for j in 0..self.insts.len() {
                let stray = self.insts[j].sink.take();
                if !stray.is_empty() {
                    self.fail(format!(
                        "fmi2FreeInstance({who}) logged into i{}: {stray:?}",
                        self.insts[j].id
                    ));
                }
            }
        }
    }

    /// EnterInitializationMode, ExitInitializationMode, Terminate, Reset, CancelStep.
    pub(super) fn simple(&mut self, fidx: usize, comp: Comp, call: Call) {
        let c = self.begin_on(comp, format!("{}()", NAMES[fidx]));
        let api = &self.t.api;
        // SAFETY: component is live, NULL or foreign.
        let status = unsafe {
            match call {
                Call::EnterInitializationMode => (api.enter_initialization_mode)(c),
                Call::ExitInitializationMode => (api.exit_initialization_mode)(c),
                Call::Terminate => (api.terminate)(c),
                Call::Reset => (api.reset)(c),
                Call::CancelStep => (api.cancel_step)(c),
                _ => unreachable!(),
            }
        };
        let ok = match (call, comp) {
            (Call::ExitInitializationMode, Comp::Inst(i))
                if self.insts[i].params_touched || self.insts[i].no_resources =>
            {
                Expect::Any
            }
            (Call::ExitInitializationMode, _) => {
                Expect::Ok("initialization with the default parameters".into())
            }
            (Call::CancelStep, _) => Expect::Error("no asynchronous step to cancel".into()),
            _ => Expect::Ok("a legal state change".into()),
        };
        let expect = self.expect(comp, call, ok, |_| None);
        self.finish(fidx, comp, call, status, expect, |s| match call {
            Call::EnterInitializationMode => State::InitializationMode,
            Call::ExitInitializationMode => State::StepComplete,
            Call::Terminate => State::Terminated,
            Call::Reset => State::Instantiated,
            _ => s,
        });
        if let Comp::Inst(i) = comp
            && (0..=2).contains(&status)
            && call == Call::Reset
        {
            let inst = &mut self.insts[i];
            inst.time = Some(0.0);
            inst.known.clear();
            inst.params_touched = false;
        }
    }

    pub(super) fn set_debug_logging(&mut self, comp: Comp, hostile: bool) {
        let fidx = 2;
        let cats: Vec<String> = self
            .t
            .log_categories
            .iter()
            .cloned()
            .chain(["noSuchCategory".to_string(), "".to_string()])
            .collect();
        let on = *self.rng.pick(&[0, 1, 1, 2]);
        let mut names: Vec<Option<CString>> = Vec::new();
        let null_array;
        let n;
        let r = self.rng.below(100);
        if hostile && r < 10 {
            null_array = true;
            n = self.rng.range(1, 4);
        } else if r < 40 {
            null_array = self.rng.chance(50);
            n = 0;
        } else {
            null_array = false;
            n = self.rng.range(1, 4);
            for _ in 0..n {
                if hostile && self.rng.chance(10) {
                    names.push(None);
                } else {
                    names.push(Some(CString::new(self.rng.pick(&cats).clone()).unwrap()));
                }
            }
        }
        let ptrs: Vec<fmi2String> = names
            .iter()
            .map(|s| s.as_ref().map_or(std::ptr::null(), |s| s.as_ptr()))
            .collect();
        let arr = if null_array {
            std::ptr::null()
        } else {
            ptrs.as_ptr()
        };
        let shown: Vec<String> = names
            .iter()
            .map(|s| s.as_ref().map_or("NULL".into(), |s| format!("{s:?}")))
            .collect();
        let c = self.begin_on(
            comp,
            format!(
                "fmi2SetDebugLogging(on={on}, n={n}, categories={})",
                if null_array {
                    "NULL".into()
                } else {
                    format!("[{}]", shown.join(", "))
                }
            ),
        );
        // SAFETY: `arr` is NULL or holds `n` entries, each NULL or a C string.
        let status = unsafe { (self.t.api.set_debug_logging)(c, on, n, arr) };
        // A NULL array is refused before the state is looked at.
        let expect = if null_array && n > 0 && matches!(comp, Comp::Inst(_)) {
            Expect::Error("categories is NULL with n > 0".into())
        } else {
            self.expect(
                comp,
                Call::SetDebugLogging,
                Expect::Ok("legal".into()),
                |_| None,
            )
        };
        // Categories switched off: an error is only demanded to be logged while the
        // categories of errors are on.
        if let Comp::Inst(i) = comp
            && (0..=2).contains(&status)
        {
            let all = &self.t.log_categories;
            let off = &mut self.insts[i].categories_off;
            if n == 0 {
                if on != 0 {
                    off.clear();
                } else {
                    off.extend(all.iter().cloned());
                }
            } else {
                for name in names.iter().flatten() {
                    let name = name.to_string_lossy().into_owned();
                    if all.contains(&name) {
                        if on != 0 {
                            off.remove(&name);
                        } else {
                            off.insert(name);
                        }
                    }
                }
            }
            let errors_off = off
                .iter()
                .any(|c| c.contains("Error") || c.contains("error"));
            self.insts[i].errors_logged = !errors_off;
        }
        self.finish(fidx, comp, Call::SetDebugLogging, status, expect, |s| s);
    }

    pub(super) fn setup_experiment(&mut self, comp: Comp, hostile: bool) {
        let fidx = 5;
        let r = &mut self.rng;
        let tol_defined = *r.pick(&[0, 1]);
        let tol = if hostile { *r.pick(&REAL_EDGES) } else { 1e-6 };
        let start = if !hostile || r.chance(60) {
            0.0
        } else if r.chance(40) {
            (r.unit() - 0.5) * 2000.0
        } else {
            *r.pick(&REAL_EDGES)
        };
        let stop_defined = *r.pick(&[0, 1]);
        let stop = if !hostile || r.chance(60) {
            start + 10.0
        } else if r.chance(30) {
            start - 1.0
        } else {
            *r.pick(&REAL_EDGES)
        };
        let c = self.begin_on(
            comp,
            format!(
                "fmi2SetupExperiment(toleranceDefined={tol_defined}, tolerance={}, startTime={}, stopTimeDefined={stop_defined}, stopTime={})",
                fmt_f(tol),
                fmt_f(start),
                fmt_f(stop)
            ),
        );
        // SAFETY: `c` is a live instance, NULL or the foreign block (never a freed instance, see
        // the module docs); the other arguments are scalars.
        let status = unsafe {
            (self.t.api.setup_experiment)(c, tol_defined, tol, start, stop_defined, stop)
        };
        let expect = self.expect(
            comp,
            Call::SetupExperiment,
            Expect::Ok("legal".into()),
            |_| {
                if !start.is_finite() {
                    Some(Expect::Error("startTime is not finite".into()))
                } else if stop_defined != 0 && !(stop >= start) {
                    Some(Expect::Error("stopTime is before startTime or NaN".into()))
                } else {
                    None
                }
            },
        );
        self.finish(fidx, comp, Call::SetupExperiment, status, expect, |s| s);
        if let Comp::Inst(i) = comp
            && (0..=2).contains(&status)
        {
            self.insts[i].time = Some(start);
        }
    }

    pub(super) fn do_step(&mut self, comp: Comp, hostile: bool) {
        let fidx = 27;
        let known_time = match comp {
            Comp::Inst(i) => self.insts[i].time,
            _ => None,
        };
        let r = &mut self.rng;
        let base_t = known_time.unwrap_or(0.0);
        let t = if !hostile || r.chance(80) {
            base_t
        } else if r.chance(50) {
            base_t + *r.pick(&[1.0, -1.0, 1e-3, 0.5])
        } else {
            *r.pick(&REAL_EDGES)
        };
        let h = if !hostile || r.chance(65) {
            r.log_uniform(1e-5, 0.05)
        } else {
            *r.pick(&[
                0.0,
                -0.0,
                -1e-3,
                f64::NAN,
                f64::INFINITY,
                f64::NEG_INFINITY,
                5e-324,
                f64::MIN_POSITIVE,
                1e-300,
                1e300,
                f64::MAX,
                1e9,
                1.0,
            ])
        };
        let no_prior = *r.pick(&[0, 1, 2]);
        let c = self.begin_on(
            comp,
            format!(
                "fmi2DoStep(currentCommunicationPoint={}, communicationStepSize={}, noSetFMUStatePriorToCurrentPoint={no_prior})",
                fmt_f(t),
                fmt_f(h)
            ),
        );
        // SAFETY: `c` is a live instance, NULL or the foreign block (never a freed instance, see
        // the module docs); the other arguments are scalars.
        let status = unsafe { (self.t.api.do_step)(c, t, h, no_prior) };
        let off = known_time.is_some_and(|k| (t - k).abs() > 1e-6 * k.abs().max(1.0) || t.is_nan());
        let expect = self.expect(comp, Call::DoStep, Expect::Any, |_| {
            let why = if !(h > 0.0) || !h.is_finite() {
                "the step size is not a positive finite number".to_string()
            } else if !t.is_finite() {
                "the communication point is not finite".into()
            } else if !(t + h).is_finite() {
                "the step would end beyond the largest finite time".into()
            } else if off {
                format!(
                    "the communication point is not the FMU's time {}",
                    fmt_f(known_time.unwrap_or(f64::NAN))
                )
            } else {
                return None;
            };
            Some(Expect::Error(why))
        });
        self.finish(fidx, comp, Call::DoStep, status, expect, |s| s);
        if let Comp::Inst(i) = comp
            && (0..=2).contains(&status)
        {
            self.insts[i].time = Some(t + h);
        }
    }
}
