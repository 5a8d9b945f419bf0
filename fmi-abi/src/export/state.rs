//! FMU states: get, set and free them, and (de)serialize them to bytes. A state is a boxed
//! snapshot tagged like an instance, so a pointer of another FMU is refused.

use super::{model_magic, ok, slice, slice_mut, with};
use crate::instance::{Snapshot, deserialize, serialize};
use crate::model::Model;
use crate::types::*;

/// A boxed FMU state, tagged like an instance.
#[repr(C)]
struct StateBox<M: Model> {
    magic: u64,
    snap: Snapshot<M>,
}

/// The state box behind `s`, if it is one of this model's.
///
/// # Safety
/// `s` must be NULL or a pointer the caller got from our fmi2GetFMUstate or
/// fmi2DeSerializeFMUstate (the FMI contract); the tag is still checked.
unsafe fn state_box<'a, M: Model>(s: fmi2FMUstate) -> Option<&'a mut StateBox<M>> {
    if s.is_null() {
        return None;
    }
    let b = s as *mut StateBox<M>;
    // SAFETY: per the contract above `b` points to readable memory at least one u64 long.
    if unsafe { (*b).magic } != const { model_magic(M::INFO.guid) } {
        return None;
    }
    // SAFETY: the tag matched: `b` is one of our live state boxes.
    Some(unsafe { &mut *b })
}

fn new_state<M: Model>(snap: Snapshot<M>) -> fmi2FMUstate {
    Box::into_raw(Box::new(StateBox {
        magic: const { model_magic(M::INFO.guid) },
        snap,
    })) as fmi2FMUstate
}

/// # Safety
/// FMI contract.
pub unsafe fn get_fmu_state<M: Model>(c: fmi2Component, state: *mut fmi2FMUstate) -> fmi2Status {
    // SAFETY: `c` is NULL or an instance of ours (FMI contract); `with` checks its tag and contains panics.
    unsafe {
        with::<M>(c, "fmi2GetFMUstate", |inst| {
            let slot = slice_mut(inst, state, 1, "FMUstate", "fmi2GetFMUstate")?;
            if slot[0].is_null() {
                slot[0] = new_state(inst.snapshot());
                return Ok(fmi2Status::OK);
            }
            match state_box::<M>(slot[0]) {
                Some(b) => {
                    b.snap.clone_from(&inst.sim);
                    Ok(fmi2Status::OK)
                }
                None => {
                    inst.log.error(
                        "fmi2GetFMUstate: *FMUstate is neither NULL nor a state of this FMU",
                    );
                    Err(fmi2Status::Error)
                }
            }
        })
    }
}

/// # Safety
/// FMI contract.
pub unsafe fn set_fmu_state<M: Model>(c: fmi2Component, state: fmi2FMUstate) -> fmi2Status {
    // SAFETY: `c` is NULL or an instance of ours (FMI contract); `with` checks its tag and contains panics.
    unsafe {
        with::<M>(c, "fmi2SetFMUstate", |inst| match state_box::<M>(state) {
            Some(b) => ok(inst.restore(&b.snap)),
            None => {
                inst.log
                    .error("fmi2SetFMUstate: FMUstate is NULL or not a state of this FMU");
                Err(fmi2Status::Error)
            }
        })
    }
}

/// # Safety
/// FMI contract.
pub unsafe fn free_fmu_state<M: Model>(c: fmi2Component, state: *mut fmi2FMUstate) -> fmi2Status {
    // SAFETY: `c` is NULL or an instance of ours (FMI contract); `with` checks its tag and contains panics.
    unsafe {
        with::<M>(c, "fmi2FreeFMUstate", |inst| {
            if state.is_null() || (*state).is_null() {
                return Ok(fmi2Status::OK);
            }
            match state_box::<M>(*state) {
                Some(b) => {
                    b.magic = 0;
                    drop(Box::from_raw(b as *mut StateBox<M>));
                    *state = std::ptr::null_mut();
                    Ok(fmi2Status::OK)
                }
                None => {
                    inst.log
                        .error("fmi2FreeFMUstate: FMUstate is not a state of this FMU");
                    Err(fmi2Status::Error)
                }
            }
        })
    }
}

/// # Safety
/// FMI contract.
pub unsafe fn serialized_fmu_state_size<M: Model>(
    c: fmi2Component,
    state: fmi2FMUstate,
    size: *mut usize,
) -> fmi2Status {
    // SAFETY: `c` is NULL or an instance of ours (FMI contract); `with` checks its tag and contains panics.
    unsafe {
        with::<M>(c, "fmi2SerializedFMUstateSize", |inst| {
            let out = slice_mut(inst, size, 1, "size", "fmi2SerializedFMUstateSize")?;
            let Some(b) = state_box::<M>(state) else {
                inst.log.error(
                    "fmi2SerializedFMUstateSize: FMUstate is NULL or not a state of this FMU",
                );
                return Err(fmi2Status::Error);
            };
            match serialize(&b.snap) {
                Ok(bytes) => {
                    out[0] = bytes.len();
                    Ok(fmi2Status::OK)
                }
                Err(e) => {
                    inst.log.error(&e);
                    Err(fmi2Status::Error)
                }
            }
        })
    }
}

/// # Safety
/// FMI contract.
pub unsafe fn serialize_fmu_state<M: Model>(
    c: fmi2Component,
    state: fmi2FMUstate,
    bytes: *mut fmi2Byte,
    size: usize,
) -> fmi2Status {
    // SAFETY: `c` is NULL or an instance of ours (FMI contract); `with` checks its tag and contains panics.
    unsafe {
        with::<M>(c, "fmi2SerializeFMUstate", |inst| {
            let Some(b) = state_box::<M>(state) else {
                inst.log
                    .error("fmi2SerializeFMUstate: FMUstate is NULL or not a state of this FMU");
                return Err(fmi2Status::Error);
            };
            let data = serialize(&b.snap).map_err(|e| {
                inst.log.error(&e);
                fmi2Status::Error
            })?;
            if size < data.len() {
                inst.log.error(&format!(
                    "fmi2SerializeFMUstate: buffer of {size} bytes is smaller than the {} bytes fmi2SerializedFMUstateSize reports",
                    data.len()
                ));
                return Err(fmi2Status::Error);
            }
            let out = slice_mut(
                inst,
                bytes as *mut u8,
                data.len(),
                "serializedState",
                "fmi2SerializeFMUstate",
            )?;
            out.copy_from_slice(&data);
            Ok(fmi2Status::OK)
        })
    }
}

/// # Safety
/// FMI contract.
pub unsafe fn deserialize_fmu_state<M: Model>(
    c: fmi2Component,
    bytes: *const fmi2Byte,
    size: usize,
    state: *mut fmi2FMUstate,
) -> fmi2Status {
    // SAFETY: `c` is NULL or an instance of ours (FMI contract); `with` checks its tag and contains panics.
    unsafe {
        with::<M>(c, "fmi2DeSerializeFMUstate", |inst| {
            let data = slice(
                inst,
                bytes as *const u8,
                size,
                "serializedState",
                "fmi2DeSerializeFMUstate",
            )?;
            let slot = slice_mut(inst, state, 1, "FMUstate", "fmi2DeSerializeFMUstate")?;
            match deserialize::<M>(data) {
                Ok(snap) => {
                    if let Some(b) = state_box::<M>(slot[0]) {
                        b.snap = snap;
                    } else {
                        slot[0] = new_state(snap);
                    }
                    Ok(fmi2Status::OK)
                }
                Err(e) => {
                    inst.log.error(&format!("fmi2DeSerializeFMUstate: {e}"));
                    Err(fmi2Status::Error)
                }
            }
        })
    }
}
