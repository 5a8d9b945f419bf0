//! The pointer cases every function shares: a component or FMU state that is NULL or memory
//! of another kind (the foreign block), and arrays passed as NULL or with an nvr that is not
//! their length. In one place so that each function draws them from the generator in the same
//! way, and a seed keeps meaning the same sequence.

use super::Fuzzer;
use crate::api::as_ptr;
use fmi_abi::types::fmi2Component;

/// A pointer that is not what the callee expects.
#[derive(Clone, Copy)]
pub(super) enum Bad {
    Null,
    /// Owned memory of another kind: a conforming FMU tells it from its own by the type tag.
    Foreign,
}

impl Bad {
    pub fn name(self) -> &'static str {
        match self {
            Bad::Null => "NULL",
            Bad::Foreign => "FOREIGN",
        }
    }
}

/// The component a call goes to.
#[derive(Clone, Copy)]
pub(super) enum Comp {
    Inst(usize),
    Bad(Bad),
}

/// `p`, or NULL for the cases that pass NULL.
pub(super) fn or_null<T>(null: bool, p: *const T) -> *const T {
    if null { std::ptr::null() } else { p }
}

/// `p`, or NULL for the cases that pass NULL.
pub(super) fn or_null_mut<T>(null: bool, p: *mut T) -> *mut T {
    if null { std::ptr::null_mut() } else { p }
}

/// How a getter or setter passes its arrays.
pub(super) struct Arrays {
    /// The nvr passed: the array length, or less (the FMU must touch only the first nvr),
    /// or up to `usize::MAX` with NULL arrays.
    pub n: usize,
    pub null_vr: bool,
    pub null_val: bool,
}

impl Arrays {
    /// The value references as the trace shows them.
    pub fn show_vrs(&self, vrs: &[u32]) -> String {
        if self.null_vr {
            "NULL".into()
        } else {
            format!("{:?}", &vrs[..self.n.min(vrs.len())])
        }
    }
}

impl Fuzzer<'_> {
    /// NULL more often than foreign: NULL is the careless caller's mistake.
    pub(super) fn pick_bad(&mut self) -> Bad {
        if self.rng.chance(60) {
            Bad::Null
        } else {
            Bad::Foreign
        }
    }

    pub(super) fn bad_ptr<T>(&self, b: Bad) -> *mut T {
        match b {
            Bad::Null => std::ptr::null_mut(),
            Bad::Foreign => as_ptr(&self.foreign).cast(),
        }
    }

    /// A live instance, NULL or a foreign pointer.
    pub(super) fn pick_comp(&mut self) -> Comp {
        if !self.insts.is_empty() && self.rng.chance(92) {
            return Comp::Inst(self.rng.below(self.insts.len()));
        }
        Comp::Bad(self.pick_bad())
    }

    pub(super) fn who(&self, comp: Comp) -> String {
        match comp {
            Comp::Inst(i) => format!("i{}", self.insts[i].id),
            Comp::Bad(b) => b.name().into(),
        }
    }

    pub(super) fn comp_ptr(&self, comp: Comp) -> fmi2Component {
        match comp {
            Comp::Inst(i) => self.insts[i].c,
            Comp::Bad(b) => self.bad_ptr(b),
        }
    }

    /// Records the call about to be made on `comp` and gives the pointer to pass.
    pub(super) fn begin_on(&mut self, comp: Comp, text: String) -> fmi2Component {
        let who = self.who(comp);
        self.begin(&who, text);
        self.comp_ptr(comp)
    }

    /// The array cases of a getter or setter (hostile only): NULL value references, NULL
    /// values, both with a huge nvr, or arrays longer than nvr. A non-NULL array of value
    /// references is padded to nvr, so that the FMU is never handed a short array (reading
    /// past it would be the caller's bug, not the FMU's).
    pub(super) fn arrays(&mut self, hostile: bool, vrs: &mut Vec<u32>) -> Arrays {
        let mut n = vrs.len();
        let (mut null_vr, mut null_val) = (false, false);
        if hostile {
            match self.rng.below(100) {
                0..5 => null_vr = true,
                5..10 => null_val = true,
                10..13 => {
                    null_vr = true;
                    null_val = true;
                    n = *self.rng.pick(&[1, usize::MAX, usize::MAX / 8]);
                }
                13..18 => n = self.rng.below(n + 1),
                _ => {}
            }
        }
        if null_vr || null_val {
            n = n.max(1);
            if !null_vr && vrs.len() < n {
                vrs.resize(n, 0);
            }
        }
        Arrays {
            n,
            null_vr,
            null_val,
        }
    }
}
