//! The getters and setters of the four types: value references known, unknown and not
//! settable now, edge values, the array cases, and values read back against what was written.

use super::books::{Known, key, same};
use super::check::{Expect, fmt_f};
use super::pointers::{Comp, or_null, or_null_mut};
use super::{CANARY_INT, CANARY_REAL, Fuzzer};
use crate::api::{Base, NAMES, Var};
use crate::oracle::{Call, States};
use fmi_abi::types::fmi2String;
use model_description::Causality;
use std::ffi::{CStr, CString, c_char, c_int};

pub(super) const REAL_EDGES: [f64; 15] = [
    0.0,
    -0.0,
    1.0,
    -1.0,
    f64::NAN,
    f64::INFINITY,
    f64::NEG_INFINITY,
    f64::MAX,
    f64::MIN,
    f64::MIN_POSITIVE,
    5e-324,
    1e300,
    -1e300,
    1e-300,
    1e6,
];

const INT_EDGES: [i32; 10] = [0, 1, -1, 2, 3, 4, 5, i32::MIN, i32::MAX, 1000];

fn string_edges() -> Vec<Vec<u8>> {
    vec![
        b"".to_vec(),
        b"ml95.toml".to_vec(),
        b"manchester.toml".to_vec(),
        b"no-such-file.toml".to_vec(),
        b"/nonexistent/dir/track.csv".to_vec(),
        b"%s%s%n%x%p 100%".to_vec(),
        "\u{fc}\u{20ac}\u{1d11e}".as_bytes().to_vec(),
        vec![b'a'; 10_000],
        vec![0xff, 0xfe, 0x80, b'x'],
        b"calibration.toml".to_vec(),
    ]
}

/// A value to set.
#[derive(Debug, Clone)]
enum Val {
    Real(f64),
    Int(c_int),
    Bool(c_int),
    Str(Option<Vec<u8>>),
}

impl Val {
    fn show(&self) -> String {
        match self {
            Val::Real(x) => fmt_f(*x),
            Val::Int(x) => x.to_string(),
            Val::Bool(x) => format!("b{x}"),
            Val::Str(None) => "NULL".into(),
            Val::Str(Some(b)) if b.len() > 40 => format!("<{} bytes>", b.len()),
            Val::Str(Some(b)) => format!("{:?}", String::from_utf8_lossy(b)),
        }
    }

    /// What a getter must return after this was set (None: not predictable, e.g. a string
    /// that is not UTF-8).
    fn known(&self) -> Option<Known> {
        match self {
            Val::Real(x) => Some(Known::Real(x.to_bits())),
            Val::Int(x) => Some(Known::Int(*x)),
            Val::Bool(x) => Some(Known::Bool(*x != 0)),
            Val::Str(Some(b)) => std::str::from_utf8(b).ok().map(|s| Known::Str(s.into())),
            Val::Str(None) => None,
        }
    }
}

impl Fuzzer<'_> {
    /// Sets the configured presets one by one (traced like any other call).
    pub(super) fn apply_presets(&mut self, i: usize) {
        let presets = self.cfg.presets.clone();
        for (name, value) in presets {
            let Some(v) = self.t.var_named(&name).cloned() else {
                continue;
            };
            let val = match v.base {
                Base::Real => Val::Real(value.parse().unwrap_or(0.0)),
                Base::Integer => Val::Int(value.parse().unwrap_or(0)),
                Base::Boolean => Val::Bool(matches!(value.as_str(), "true" | "1") as c_int),
                Base::String => Val::Str(Some(value.into_bytes())),
            };
            self.set_exact(i, &v, val);
        }
    }

    /// Value references for a getter or setter: mostly known ones of `base`; when hostile,
    /// sometimes an unknown one or one of the right type that may not be settable now.
    fn vrs(&mut self, base: Base, hostile: bool, settable_only: Option<States>) -> Vec<u32> {
        let vars: Vec<&Var> = self
            .t
            .vars_of(base)
            .filter(|v| settable_only.is_none_or(|p| p.iter().all(|s| v.settable(s))))
            .collect();
        let n = if vars.is_empty() || self.rng.chance(10) {
            0
        } else if self.rng.chance(10) {
            vars.len()
        } else {
            self.rng.range(1, vars.len().min(6))
        };
        let mut out: Vec<u32> = (0..n).map(|_| self.rng.pick(&vars).vr).collect();
        if hostile && self.rng.chance(15) {
            let max = self.t.vars_of(base).map(|v| v.vr).max().unwrap_or(0);
            let unknown = *self.rng.pick(&[
                max.wrapping_add(1),
                max.wrapping_add(1000),
                u32::MAX,
                u32::MAX - 1,
                1 << 31,
            ]);
            let at = self.rng.below(out.len() + 1);
            out.insert(at, unknown);
        } else if hostile && self.rng.chance(10) {
            // A variable of the right type that may not be settable now.
            let any: Vec<u32> = self.t.vars_of(base).map(|v| v.vr).collect();
            if !any.is_empty() {
                out.push(*self.rng.pick(&any));
            }
        }
        out
    }

    pub(super) fn get(&mut self, comp: Comp, base: Base, hostile: bool) {
        let fidx = match base {
            Base::Real => 10,
            Base::Integer => 11,
            Base::Boolean => 12,
            Base::String => 13,
        };
        let mut vrs = self.vrs(base, hostile, None);
        let arrays = self.arrays(hostile, &mut vrs);
        let (n, null_vr, null_val) = (arrays.n, arrays.null_vr, arrays.null_val);
        let unknown: Vec<u32> = vrs[..n.min(vrs.len())]
            .iter()
            .copied()
            .filter(|vr| self.t.var(base, *vr).is_none())
            .collect();
        let room = if null_val { 0 } else { n + 3 };
        let mut reals =
            vec![f64::from_bits(CANARY_REAL); if base == Base::Real { room } else { 0 }];
        let mut ints = vec![CANARY_INT; if base != Base::Real { room } else { 0 }];
        let mut strs: Vec<*const c_char> = vec![
            CANARY_REAL as usize as *const c_char;
            if base == Base::String { room } else { 0 }
        ];
        let c = self.begin_on(
            comp,
            format!(
                "{}(vr={}, nvr={n}, value={})",
                NAMES[fidx],
                arrays.show_vrs(&vrs),
                if null_val {
                    "NULL".into()
                } else {
                    format!("[{} slots]", room)
                }
            ),
        );
        let vr_p = or_null(null_vr, vrs.as_ptr());
        let api = &self.t.api;
        // SAFETY: the arrays hold at least `n` elements unless NULL.
        let status = unsafe {
            match base {
                Base::Real => (api.get_real)(c, vr_p, n, or_null_mut(null_val, reals.as_mut_ptr())),
                Base::Integer => {
                    (api.get_integer)(c, vr_p, n, or_null_mut(null_val, ints.as_mut_ptr()))
                }
                Base::Boolean => {
                    (api.get_boolean)(c, vr_p, n, or_null_mut(null_val, ints.as_mut_ptr()))
                }
                Base::String => {
                    (api.get_string)(c, vr_p, n, or_null_mut(null_val, strs.as_mut_ptr()))
                }
            }
        };
        // Nothing written past nvr.
        if !null_val {
            let bad = match base {
                Base::Real => reals[n..].iter().any(|x| x.to_bits() != CANARY_REAL),
                Base::String => strs[n..]
                    .iter()
                    .any(|p| *p as usize != CANARY_REAL as usize),
                _ => ints[n..].iter().any(|x| *x != CANARY_INT),
            };
            if bad {
                self.fail(format!("{} wrote past element nvr={n}", NAMES[fidx]));
            }
        }
        let if_legal = Expect::Ok("legal, known references".into());
        let expect = self.expect(comp, Call::Get, if_legal, |_| {
            if (null_vr || null_val) && n > 0 {
                Some(Expect::Error("NULL array with nvr > 0".into()))
            } else if !unknown.is_empty() {
                Some(Expect::Error(format!(
                    "unknown value reference(s) {unknown:?}"
                )))
            } else {
                None
            }
        });
        self.finish(fidx, comp, Call::Get, status, expect, |s| s);
        // Values: booleans 0/1, strings readable, and what was written comes back.
        let Comp::Inst(i) = comp else { return };
        if !(0..=1).contains(&status) || null_val || null_vr {
            return;
        }
        for (k, vr) in vrs[..n].iter().enumerate() {
            let got = match base {
                Base::Real => Known::Real(reals[k].to_bits()),
                Base::Integer => Known::Int(ints[k]),
                Base::Boolean => {
                    if ints[k] != 0 && ints[k] != 1 {
                        self.fail(format!(
                            "fmi2GetBoolean returned {} for vr {vr}, not fmi2True/fmi2False",
                            ints[k]
                        ));
                    }
                    Known::Bool(ints[k] != 0)
                }
                Base::String => {
                    if strs[k].is_null() {
                        self.fail(format!("fmi2GetString returned NULL for vr {vr}"));
                        continue;
                    }
                    // SAFETY: valid until the next call on this instance (the standard).
                    let s = unsafe { CStr::from_ptr(strs[k]) };
                    Known::Str(s.to_string_lossy().into_owned())
                }
            };
            if let Some(want) = self.insts[i].known.get(&key(base, *vr))
                && !same(want, &got)
            {
                let msg = format!(
                    "{} read vr {vr} as {got:?} but {want:?} was written (or restored)",
                    NAMES[fidx]
                );
                self.fail(msg);
            }
        }
    }

    pub(super) fn set(&mut self, comp: Comp, base: Base, hostile: bool) {
        let possible = match comp {
            Comp::Inst(i) => Some(self.insts[i].possible),
            _ => None,
        };
        let settable = if hostile { None } else { possible };
        let vrs = self.vrs(base, hostile, settable);
        let vals: Vec<Val> = vrs
            .iter()
            .map(|vr| {
                let var = self.t.var(base, *vr).cloned();
                self.value_for(base, var.as_ref(), hostile)
            })
            .collect();
        self.set_raw(comp, base, vrs, vals, hostile);
    }

    /// Sets one variable with a chosen value (presets).
    fn set_exact(&mut self, i: usize, v: &Var, val: Val) {
        self.set_raw(Comp::Inst(i), v.base, vec![v.vr], vec![val], false);
    }

    fn value_for(&mut self, base: Base, var: Option<&Var>, hostile: bool) -> Val {
        let r = &mut self.rng;
        let edge = hostile && r.chance(40);
        match base {
            Base::Real => Val::Real(if edge {
                *r.pick(&REAL_EDGES)
            } else if var.is_some_and(|v| v.name.contains("speed")) {
                r.unit() * 40.0
            } else if var.is_some_and(|v| v.causality == Causality::Input) {
                (r.unit() - 0.5) * 2.0
            } else {
                // A parameter: keep it near its plausible range (positive, moderate).
                *r.pick(&[0.5, 1.0, 2.0, 0.1])
            }),
            Base::Integer => Val::Int(if edge {
                *r.pick(&INT_EDGES)
            } else {
                r.range(1, 4) as i32
            }),
            Base::Boolean => Val::Bool(if edge {
                *r.pick(&[2, -1, i32::MIN, 255])
            } else {
                r.below(2) as i32
            }),
            Base::String => Val::Str(if hostile && r.chance(10) {
                None
            } else if edge {
                Some(r.pick(&string_edges()).clone())
            } else {
                Some(r.pick(&[b"ml95.toml".to_vec(), b"".to_vec()]).clone())
            }),
        }
    }

    fn set_raw(
        &mut self,
        comp: Comp,
        base: Base,
        mut vrs: Vec<u32>,
        vals: Vec<Val>,
        hostile: bool,
    ) {
        let fidx = match base {
            Base::Real => 14,
            Base::Integer => 15,
            Base::Boolean => 16,
            Base::String => 17,
        };
        let arrays = self.arrays(hostile, &mut vrs);
        let (n, null_vr, null_val) = (arrays.n, arrays.null_vr, arrays.null_val);
        let mut vals = vals;
        if !null_val {
            while vals.len() < n {
                vals.push(self.value_for(base, None, false));
            }
        }
        let used_vrs: Vec<u32> = if null_vr {
            vec![]
        } else {
            vrs[..n.min(vrs.len())].to_vec()
        };
        let used_vals: Vec<Val> = if null_val {
            vec![]
        } else {
            vals[..n.min(vals.len())].to_vec()
        };
        // Arrays (one extra element, which the FMU must not read as a value).
        let reals: Vec<f64> = vals
            .iter()
            .map(|v| if let Val::Real(x) = v { *x } else { 0.0 })
            .chain([1234.5])
            .collect();
        let ints: Vec<c_int> = vals
            .iter()
            .map(|v| match v {
                Val::Int(x) | Val::Bool(x) => *x,
                _ => 0,
            })
            .chain([77])
            .collect();
        let cstrings: Vec<Option<CString>> = vals
            .iter()
            .map(|v| match v {
                Val::Str(Some(b)) => Some(CString::new(b.clone()).unwrap()),
                _ => None,
            })
            .collect();
        let mut sptrs: Vec<fmi2String> = cstrings
            .iter()
            .map(|s| s.as_ref().map_or(std::ptr::null(), |s| s.as_ptr()))
            .collect();
        sptrs.push(std::ptr::null());
        let shown: Vec<String> = used_vals.iter().map(Val::show).collect();
        let c = self.begin_on(
            comp,
            format!(
                "{}(vr={}, nvr={n}, value={})",
                NAMES[fidx],
                arrays.show_vrs(&vrs),
                if null_val {
                    "NULL".into()
                } else {
                    format!("[{}]", shown.join(", "))
                }
            ),
        );
        let vr_p = or_null(null_vr, vrs.as_ptr());
        let api = &self.t.api;
        // SAFETY: arrays hold at least `n` elements unless NULL.
        let status = unsafe {
            match base {
                Base::Real => (api.set_real)(c, vr_p, n, or_null(null_val, reals.as_ptr())),
                Base::Integer => (api.set_integer)(c, vr_p, n, or_null(null_val, ints.as_ptr())),
                Base::Boolean => (api.set_boolean)(c, vr_p, n, or_null(null_val, ints.as_ptr())),
                Base::String => (api.set_string)(c, vr_p, n, or_null(null_val, sptrs.as_ptr())),
            }
        };
        drop(cstrings);
        let expect = self.expect(comp, Call::Set, Expect::Ok("legal, settable".into()), |i| {
            let possible = self.insts[i].possible;
            let unknown: Vec<u32> = used_vrs
                .iter()
                .copied()
                .filter(|vr| self.t.var(base, *vr).is_none())
                .collect();
            let never: Vec<String> = used_vrs
                .iter()
                .filter_map(|vr| self.t.var(base, *vr))
                .filter(|v| possible.iter().all(|s| !v.settable(s)))
                .map(|v| v.name.clone())
                .collect();
            let sometimes = used_vrs
                .iter()
                .filter_map(|vr| self.t.var(base, *vr))
                .any(|v| possible.iter().any(|s| !v.settable(s)));
            if (null_vr || null_val) && n > 0 {
                Some(Expect::Error("NULL array with nvr > 0".into()))
            } else if !unknown.is_empty() {
                Some(Expect::Error(format!(
                    "unknown value reference(s) {unknown:?}"
                )))
            } else if !never.is_empty() {
                Some(Expect::Error(format!(
                    "not settable in {}: {never:?}",
                    possible.names()
                )))
            } else if used_vals.iter().any(|v| matches!(v, Val::Str(None))) {
                Some(Expect::Error("a NULL string".into()))
            } else if sometimes {
                Some(Expect::Any)
            } else {
                None
            }
        });
        let refused = matches!(expect, Expect::Error(_));
        self.finish(fidx, comp, Call::Set, status, expect, |s| s);
        let Comp::Inst(i) = comp else { return };
        if (0..=1).contains(&status) && !refused {
            for (vr, v) in used_vrs.iter().zip(&used_vals) {
                let Some(var) = self.t.var(base, *vr) else {
                    continue;
                };
                if var.causality != Causality::Input {
                    self.insts[i].params_touched = true;
                }
                let k = key(base, *vr);
                if !matches!(var.causality, Causality::Input | Causality::Parameter) {
                    self.insts[i].known.remove(&k);
                    continue;
                }
                match v.known() {
                    Some(x) => self.insts[i].known.insert(k, x),
                    None => self.insts[i].known.remove(&k),
                };
            }
        } else if status == 3 && !refused {
            // Unpredicted refusal: what was written is uncertain.
            for vr in &used_vrs {
                self.insts[i].known.remove(&key(base, *vr));
            }
        }
    }
}
