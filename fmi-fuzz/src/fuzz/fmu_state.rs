//! FMU states: get (new and reusing), set, free, size, serialize into buffers around the size,
//! and deserialize genuine and corrupted bytes. A restored state must give back what was
//! written when it was taken, so each saved state carries a copy of the books.

use super::books::{Blob, KnownMap, SavedState};
use super::check::Expect;
use super::pointers::{Bad, Comp, or_null, or_null_mut};
use super::{CANARY_BYTE, Fuzzer, MAX_STATES};
use crate::oracle::{Call, State, States};
use fmi_abi::types::fmi2FMUstate;
use std::ffi::c_char;

impl Fuzzer<'_> {
    /// A state of `comp` to use, or NULL / foreign (always when it has none, and sometimes
    /// when hostile).
    fn pick_state(
        &mut self,
        comp: Comp,
        hostile: bool,
    ) -> (fmi2FMUstate, Option<usize>, &'static str) {
        if let Comp::Inst(i) = comp
            && !self.insts[i].states.is_empty()
            && (!hostile || self.rng.chance(75))
        {
            let k = self.rng.below(self.insts[i].states.len());
            return (self.insts[i].states[k].ptr, Some(k), "state");
        }
        let b = self.pick_bad();
        (self.bad_ptr(b), None, b.name())
    }

    pub(super) fn get_fmu_state(&mut self, comp: Comp, hostile: bool) {
        let fidx = 18;
        let can_add = matches!(comp, Comp::Inst(i) if self.insts[i].states.len() < MAX_STATES);
        // 0 new (slot NULL), 1 reuse a state, 2 NULL slot pointer, 3 foreign in slot.
        let mode = if hostile {
            self.rng.weighted(&[5, 3, 1, 1])
        } else {
            self.rng.weighted(&[5, 3, 0, 0])
        };
        let mode = match (mode, comp) {
            (1, Comp::Inst(i)) if self.insts[i].states.is_empty() => 0,
            (1, Comp::Inst(_)) => 1,
            (1, _) => 0,
            (m, _) => m,
        };
        if mode == 0 && !can_add && matches!(comp, Comp::Inst(_)) {
            return;
        }
        let mut slot: fmi2FMUstate = std::ptr::null_mut();
        let mut reuse = None;
        if mode == 1
            && let Comp::Inst(i) = comp
        {
            let k = self.rng.below(self.insts[i].states.len());
            slot = self.insts[i].states[k].ptr;
            reuse = Some(k);
        }
        if mode == 3 {
            slot = self.bad_ptr(Bad::Foreign);
        }
        let c = self.begin_on(
            comp,
            format!(
                "fmi2GetFMUstate(FMUstate={})",
                ["&NULL", "&existing", "NULL", "&FOREIGN"][mode]
            ),
        );
        let slot_p = or_null_mut(mode == 2, &mut slot);
        // SAFETY: slot_p is NULL or points to our slot.
        let status = unsafe { (self.t.api.get_fmu_state)(c, slot_p) };
        let expect = self.expect(
            comp,
            Call::FmuState,
            Expect::Ok("legal".into()),
            |_| match mode {
                2 => Some(Expect::Error("FMUstate pointer is NULL".into())),
                3 => Some(Expect::Error("*FMUstate is not a state of this FMU".into())),
                _ => None,
            },
        );
        let before = match comp {
            Comp::Inst(i) => Some((
                self.insts[i].possible,
                self.insts[i].time,
                self.insts[i].known.clone(),
            )),
            _ => None,
        };
        self.finish(fidx, comp, Call::FmuState, status, expect, |s| s);
        let Comp::Inst(i) = comp else {
            if !slot.is_null() && mode == 0 {
                self.fail("fmi2GetFMUstate on a non-instance wrote a state".into());
            }
            return;
        };
        let (possible, time, known) = before.unwrap();
        if (0..=1).contains(&status) && (mode == 0 || mode == 1) {
            if slot.is_null() {
                self.fail("fmi2GetFMUstate succeeded but returned a NULL state".into());
                return;
            }
            let rec = SavedState {
                ptr: slot,
                possible: possible.minus(States::one(State::Fatal)),
                time,
                known,
                size: None,
            };
            match reuse {
                Some(k) => {
                    if self.insts[i].states[k].ptr != slot {
                        // A new allocation replaced ours: the old one is the FMU's to free.
                        self.fail(
                            "fmi2GetFMUstate with a non-NULL *FMUstate did not reuse it".into(),
                        );
                    }
                    self.insts[i].states[k] = rec;
                }
                None => self.insts[i].states.push(rec),
            }
        } else if mode == 0 && !slot.is_null() {
            self.fail("fmi2GetFMUstate failed but wrote a state pointer".into());
        }
    }

    pub(super) fn set_fmu_state(&mut self, comp: Comp, hostile: bool) {
        let fidx = 19;
        let (s, k, kind) = self.pick_state(comp, hostile);
        let c = self.begin_on(comp, format!("fmi2SetFMUstate({kind})"));
        // SAFETY: `s` is a live state of this instance, NULL or foreign.
        let status = unsafe { (self.t.api.set_fmu_state)(c, s) };
        let expect = self.expect(comp, Call::FmuState, Expect::Ok("legal".into()), |_| {
            k.is_none()
                .then(|| Expect::Error(format!("FMUstate is {kind}")))
        });
        self.finish(fidx, comp, Call::FmuState, status, expect, |s| s);
        if let (Comp::Inst(i), Some(k)) = (comp, k)
            && (0..=1).contains(&status)
        {
            let inst = &mut self.insts[i];
            let rec = &inst.states[k];
            inst.possible = rec.possible;
            inst.time = rec.time;
            inst.known = rec.known.clone();
            inst.params_touched = true;
        }
    }

    pub(super) fn free_state_at(&mut self, i: usize, k: usize) {
        let fidx = 20;
        let c = self.begin_on(Comp::Inst(i), "fmi2FreeFMUstate(&state)".into());
        let mut slot = self.insts[i].states[k].ptr;
        // SAFETY: a live state of this instance.
        let status = unsafe { (self.t.api.free_fmu_state)(c, &mut slot) };
        let expect = self.demand(i, Call::FmuState, Expect::Ok("legal".into()));
        self.finish(fidx, Comp::Inst(i), Call::FmuState, status, expect, |s| s);
        if (0..=1).contains(&status) && !slot.is_null() {
            self.fail("fmi2FreeFMUstate succeeded but did not set *FMUstate to NULL".into());
        }
        // Forget it whatever the outcome: freed, or refused (then it is leaked rather than
        // risk a second free, which would be undefined behaviour).
        if self.insts[i].fatal {
            self.insts[i].states.clear();
        } else {
            self.insts[i].states.remove(k);
        }
    }

    pub(super) fn free_fmu_state(&mut self, comp: Comp, hostile: bool) {
        let fidx = 20;
        if let Comp::Inst(i) = comp
            && !self.insts[i].states.is_empty()
            && (!hostile || self.rng.chance(70))
        {
            let k = self.rng.below(self.insts[i].states.len());
            self.free_state_at(i, k);
            return;
        }
        // NULL pointer, pointer to NULL, or foreign state.
        let mode = self.rng.below(3);
        let mut slot: fmi2FMUstate = self.bad_ptr(if mode == 2 { Bad::Foreign } else { Bad::Null });
        let c = self.begin_on(
            comp,
            format!("fmi2FreeFMUstate({})", ["NULL", "&NULL", "&FOREIGN"][mode]),
        );
        let p = or_null_mut(mode == 0, &mut slot);
        // SAFETY: NULL, or our slot holding NULL or the foreign block (never freed by a
        // conforming FMU: it is not one of its states).
        let status = unsafe { (self.t.api.free_fmu_state)(c, p) };
        let if_legal = Expect::Ok("freeing NULL is a no-op".into());
        let expect = self.expect(comp, Call::FmuState, if_legal, |_| {
            (mode == 2).then(|| Expect::Error("not a state of this FMU".into()))
        });
        self.finish(fidx, comp, Call::FmuState, status, expect, |s| s);
    }

    pub(super) fn serialized_size(&mut self, comp: Comp, hostile: bool) -> Option<usize> {
        let fidx = 21;
        let (s, k, kind) = self.pick_state(comp, hostile);
        let null_size = hostile && self.rng.chance(8);
        let mut size: usize = 0xDEAD;
        let c = self.begin_on(
            comp,
            format!(
                "fmi2SerializedFMUstateSize({kind}, size={})",
                if null_size { "NULL" } else { "&size" }
            ),
        );
        let p = or_null_mut(null_size, &mut size);
        // SAFETY: live state / NULL / foreign; p is NULL or ours.
        let status = unsafe { (self.t.api.serialized_fmu_state_size)(c, s, p) };
        let expect = self.expect(comp, Call::FmuState, Expect::Ok("legal".into()), |_| {
            if k.is_none() {
                Some(Expect::Error(format!("FMUstate is {kind}")))
            } else if null_size {
                Some(Expect::Error("size is NULL".into()))
            } else {
                None
            }
        });
        self.finish(fidx, comp, Call::FmuState, status, expect, |s| s);
        if let (Comp::Inst(i), Some(k)) = (comp, k)
            && (0..=1).contains(&status)
            && !null_size
        {
            self.insts[i].states[k].size = Some(size);
            return Some(size);
        }
        None
    }

    pub(super) fn serialize(&mut self, comp: Comp, hostile: bool) {
        // Ask for the size first (a call of its own), as a master does.
        let size = if let Comp::Inst(i) = comp
            && !self.insts[i].states.is_empty()
        {
            self.serialized_size(comp, false)
        } else {
            None
        };
        let Comp::Inst(i) = comp else {
            self.serialize_call(comp, std::ptr::null_mut(), None, 16, false, hostile);
            return;
        };
        let (s, k) = match (
            size,
            self.insts[i].states.iter().position(|r| r.size == size),
        ) {
            (Some(_), Some(k)) if !hostile || self.rng.chance(80) => {
                (self.insts[i].states[k].ptr, Some(k))
            }
            _ => {
                let (s, k, _) = self.pick_state(comp, hostile);
                (s, k)
            }
        };
        let need = k.and_then(|k| self.insts[i].states[k].size);
        let buf_len = match need {
            Some(n) if !hostile || self.rng.chance(60) => n + *self.rng.pick(&[0, 0, 1, 100]),
            Some(n) => *self.rng.pick(&[0, n.saturating_sub(1), n / 2]),
            None => *self.rng.pick(&[0, 16, 4096]),
        };
        let null_buf = hostile && self.rng.chance(8);
        self.serialize_call(comp, s, k, buf_len, null_buf, hostile);
    }

    fn serialize_call(
        &mut self,
        comp: Comp,
        s: fmi2FMUstate,
        k: Option<usize>,
        buf_len: usize,
        null_buf: bool,
        _hostile: bool,
    ) {
        let fidx = 22;
        let need = match comp {
            Comp::Inst(i) => k.and_then(|k| self.insts[i].states[k].size),
            _ => None,
        };
        let mut buf = vec![CANARY_BYTE; buf_len + 8];
        let c = self.begin_on(
            comp,
            format!(
                "fmi2SerializeFMUstate({}, buffer={}, size={buf_len}) [needs {need:?}]",
                if k.is_some() {
                    "state"
                } else if s.is_null() {
                    "NULL"
                } else {
                    "FOREIGN"
                },
                if null_buf { "NULL" } else { "&buffer" }
            ),
        );
        let p = or_null_mut(null_buf, buf.as_mut_ptr() as *mut c_char);
        // SAFETY: the buffer holds buf_len (+8 canary) bytes unless NULL.
        let status = unsafe { (self.t.api.serialize_fmu_state)(c, s, p, buf_len) };
        if buf[buf_len..].iter().any(|b| *b != CANARY_BYTE) {
            self.fail(format!(
                "fmi2SerializeFMUstate wrote past the {buf_len} bytes it was given"
            ));
        }
        let if_legal = Expect::Ok("legal, buffer large enough".into());
        let expect = self.expect(comp, Call::FmuState, if_legal, |_| {
            if k.is_none() {
                Some(Expect::Error("FMUstate is not a state".into()))
            } else if null_buf {
                Some(Expect::Error("buffer is NULL".into()))
            } else if need.is_some_and(|n| buf_len < n) {
                Some(Expect::Error(
                    "buffer smaller than fmi2SerializedFMUstateSize".into(),
                ))
            } else if need.is_none() {
                Some(Expect::Any)
            } else {
                None
            }
        });
        self.finish(fidx, comp, Call::FmuState, status, expect, |s| s);
        if let (Comp::Inst(i), Some(k), Some(n)) = (comp, k, need)
            && (0..=1).contains(&status)
            && !null_buf
            && buf_len >= n
        {
            let rec = &self.insts[i].states[k];
            let blob = Blob {
                bytes: buf[..n].to_vec(),
                possible: rec.possible,
                time: rec.time,
                known: rec.known.clone(),
            };
            if self.blobs.len() >= 4 {
                self.blobs.remove(0);
            }
            self.blobs.push(blob);
        }
    }

    pub(super) fn deserialize(&mut self, comp: Comp, hostile: bool) {
        let fidx = 23;
        // The bytes: a genuine serialized state, or a corrupted one.
        let genuine = (!self.blobs.is_empty()).then(|| self.rng.below(self.blobs.len()));
        let mut bytes: Vec<u8>;
        let mut corrupt: Option<String> = None;
        let mut null_bytes = false;
        match genuine {
            Some(b) => {
                bytes = self.blobs[b].bytes.clone();
                if hostile && self.rng.chance(50) {
                    let how = self.corrupt(&mut bytes);
                    if bytes != self.blobs[b].bytes {
                        corrupt = Some(how);
                    }
                }
            }
            None => {
                bytes = (0..self.rng.range(0, 300))
                    .map(|_| self.rng.u64() as u8)
                    .collect();
                corrupt = Some("random bytes".into());
                if hostile && self.rng.chance(20) {
                    null_bytes = true;
                }
            }
        }
        let size = if null_bytes {
            *self.rng.pick(&[0, 16, usize::MAX])
        } else {
            bytes.len()
        };
        // The slot: new (NULL), an existing state of the instance, or a NULL pointer.
        let can_add = matches!(comp, Comp::Inst(i) if self.insts[i].states.len() < MAX_STATES);
        let mut reuse = None;
        let mut slot: fmi2FMUstate = std::ptr::null_mut();
        let null_slot = hostile && self.rng.chance(8);
        if let Comp::Inst(i) = comp
            && !self.insts[i].states.is_empty()
            && (!can_add || self.rng.chance(40))
        {
            let k = self.rng.below(self.insts[i].states.len());
            slot = self.insts[i].states[k].ptr;
            reuse = Some(k);
        }
        let c = self.begin_on(
            comp,
            format!(
                "fmi2DeSerializeFMUstate(bytes={}, size={size}, FMUstate={})",
                if null_bytes {
                    "NULL".to_string()
                } else {
                    format!(
                        "<{} bytes{}>",
                        bytes.len(),
                        corrupt.as_ref().map_or(String::new(), |c| format!(", {c}"))
                    )
                },
                if null_slot {
                    "NULL"
                } else if reuse.is_some() {
                    "&existing"
                } else {
                    "&NULL"
                }
            ),
        );
        let bp = or_null(null_bytes, bytes.as_ptr() as *const c_char);
        let sp = or_null_mut(null_slot, &mut slot);
        // SAFETY: `bytes` holds `size` bytes unless NULL; the slot is ours or NULL.
        let status = unsafe { (self.t.api.deserialize_fmu_state)(c, bp, size, sp) };
        let if_legal = Expect::Ok("legal, genuine bytes".into());
        let expect = self.expect(comp, Call::FmuState, if_legal, |_| {
            if null_slot {
                Some(Expect::Error("FMUstate pointer is NULL".into()))
            } else if null_bytes && size > 0 {
                Some(Expect::Error("serializedState is NULL".into()))
            } else {
                corrupt
                    .as_ref()
                    .map(|how| Expect::Error(format!("corrupt serialized state ({how})")))
            }
        });
        let refused = matches!(expect, Expect::Error(_));
        self.finish(fidx, comp, Call::FmuState, status, expect, |s| s);
        let Comp::Inst(i) = comp else { return };
        if !(0..=1).contains(&status) || null_slot {
            return;
        }
        if slot.is_null() {
            self.fail("fmi2DeSerializeFMUstate succeeded but returned a NULL state".into());
            return;
        }
        let (possible, time, known) = match (genuine, refused) {
            (Some(b), false) => (
                self.blobs[b].possible,
                self.blobs[b].time,
                self.blobs[b].known.clone(),
            ),
            // Accepted corrupt bytes (already reported): anything may be in there.
            _ => (
                States::of(&State::ALL).minus(States::one(State::Fatal)),
                None,
                KnownMap::new(),
            ),
        };
        let rec = SavedState {
            ptr: slot,
            possible,
            time,
            known,
            size: None,
        };
        match reuse {
            Some(k) => {
                if self.insts[i].states[k].ptr != slot {
                    self.fail("fmi2DeSerializeFMUstate did not reuse the given state".into());
                }
                self.insts[i].states[k] = rec;
            }
            None => self.insts[i].states.push(rec),
        }
    }

    /// Corrupts serialized bytes in one of several ways; returns how.
    fn corrupt(&mut self, b: &mut Vec<u8>) -> String {
        let n = b.len();
        match self.rng.below(6) {
            0 if n > 0 => {
                let k = self.rng.below(n);
                let bit = self.rng.below(8);
                b[k] ^= 1 << bit;
                format!("bit {bit} of byte {k} flipped")
            }
            1 if n > 0 => {
                let keep = self.rng.below(n);
                b.truncate(keep);
                format!("truncated to {keep} bytes")
            }
            2 => {
                let extra = self.rng.range(1, 64);
                b.extend((0..extra).map(|_| self.rng.u64() as u8));
                format!("{extra} bytes appended")
            }
            3 if n > 0 => {
                let flips = self.rng.range(2, 20);
                for _ in 0..flips {
                    let k = self.rng.below(n);
                    b[k] = self.rng.u64() as u8;
                }
                format!("{flips} bytes overwritten")
            }
            4 if n > 8 => {
                // Past the header: damage the body only.
                let k = self.rng.range(n / 2, n - 1);
                b[k] = b[k].wrapping_add(1);
                format!("byte {k} incremented")
            }
            _ => {
                b.clear();
                "empty".into()
            }
        }
    }

    // ----- unsupported capabilities and status ----------------------------------------------
}
