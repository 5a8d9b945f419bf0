//! Value transfer: moving values along the connections (the caller's external inputs are
//! `inputs`).
//!
//! Values move through flat buffers: each component's connected outputs of one type occupy a
//! contiguous range, read with one fmi2GetXxx call per component and type; each component's
//! inputs are gathered (with their linear transformation) and written with one fmi2SetXxx call.
//! Nothing is allocated here once a run has started: this is the master's per-step cost.

use crate::resolve::Link;
use crate::system::Linear;
use fmi_import::{FmiError, Instance};
use model_description::BaseType;

/// A value type that can cross a connection.
trait Port: Copy + Default {
    fn get(inst: &mut Instance, vr: &[u32], out: &mut [Self]) -> Result<(), FmiError>;
    fn set(inst: &mut Instance, vr: &[u32], values: &[Self]) -> Result<(), FmiError>;
    fn apply(self, t: Option<Linear>) -> Self;
}

impl Port for f64 {
    fn get(inst: &mut Instance, vr: &[u32], out: &mut [f64]) -> Result<(), FmiError> {
        inst.get_real(vr, out)
    }
    fn set(inst: &mut Instance, vr: &[u32], values: &[f64]) -> Result<(), FmiError> {
        inst.set_real(vr, values)
    }
    fn apply(self, t: Option<Linear>) -> f64 {
        match t {
            Some(l) => l.factor * self + l.offset,
            None => self,
        }
    }
}

impl Port for i32 {
    fn get(inst: &mut Instance, vr: &[u32], out: &mut [i32]) -> Result<(), FmiError> {
        inst.get_integer(vr, out)
    }
    fn set(inst: &mut Instance, vr: &[u32], values: &[i32]) -> Result<(), FmiError> {
        inst.set_integer(vr, values)
    }
    fn apply(self, _: Option<Linear>) -> i32 {
        self
    }
}

impl Port for bool {
    fn get(inst: &mut Instance, vr: &[u32], out: &mut [bool]) -> Result<(), FmiError> {
        inst.get_boolean(vr, out)
    }
    fn set(inst: &mut Instance, vr: &[u32], values: &[bool]) -> Result<(), FmiError> {
        inst.set_boolean(vr, values)
    }
    fn apply(self, _: Option<Linear>) -> bool {
        self
    }
}

/// The links of one value type, laid out for one-call-per-component transfers.
struct Transfer<T: Port> {
    /// Per component: the output value references it feeds, and where they start in `slots`.
    out_vr: Vec<Vec<u32>>,
    out_start: Vec<usize>,
    /// Per component: its connected input value references, the slot feeding each, and the
    /// transformation.
    in_vr: Vec<Vec<u32>>,
    in_slot: Vec<Vec<usize>>,
    in_transform: Vec<Vec<Option<Linear>>>,
    slots: Vec<T>,
    scratch: Vec<T>,
}

impl<T: Port> Transfer<T> {
    fn new(n: usize, links: &[&Link]) -> Transfer<T> {
        let mut out_vr: Vec<Vec<u32>> = vec![vec![]; n];
        // Each distinct (component, output) gets one slot; links sharing an output share it.
        for l in links {
            if !out_vr[l.from].contains(&l.from_vr) {
                out_vr[l.from].push(l.from_vr);
            }
        }
        let mut out_start = vec![0; n];
        let mut total = 0;
        for c in 0..n {
            out_start[c] = total;
            total += out_vr[c].len();
        }
        let mut in_vr = vec![vec![]; n];
        let mut in_slot = vec![vec![]; n];
        let mut in_transform = vec![vec![]; n];
        for l in links {
            let slot = out_start[l.from]
                + out_vr[l.from]
                    .iter()
                    .position(|&v| v == l.from_vr)
                    .expect("registered above");
            in_vr[l.to].push(l.to_vr);
            in_slot[l.to].push(slot);
            in_transform[l.to].push(l.transform);
        }
        let widest = in_vr.iter().map(Vec::len).max().unwrap_or(0);
        Transfer {
            out_vr,
            out_start,
            in_vr,
            in_slot,
            in_transform,
            slots: vec![T::default(); total],
            scratch: vec![T::default(); widest],
        }
    }

    fn read_outputs(&mut self, c: usize, inst: &mut Instance) -> Result<(), FmiError> {
        let n = self.out_vr[c].len();
        if n == 0 {
            return Ok(());
        }
        let s = self.out_start[c];
        T::get(inst, &self.out_vr[c], &mut self.slots[s..s + n])
    }

    fn write_inputs(&mut self, c: usize, inst: &mut Instance) -> Result<(), FmiError> {
        let n = self.in_vr[c].len();
        if n == 0 {
            return Ok(());
        }
        for i in 0..n {
            self.scratch[i] = self.slots[self.in_slot[c][i]].apply(self.in_transform[c][i]);
        }
        T::set(inst, &self.in_vr[c], &self.scratch[..n])
    }
}

/// The connections of every type, in the order the master moves them: Real, Integer, Boolean.
pub(super) struct Transfers {
    real: Transfer<f64>,
    integer: Transfer<i32>,
    boolean: Transfer<bool>,
}

impl Transfers {
    pub fn new(n: usize, links: &[Link]) -> Transfers {
        let by_type = |b: BaseType| links.iter().filter(|l| l.base == b).collect::<Vec<_>>();
        Transfers {
            real: Transfer::new(n, &by_type(BaseType::Real)),
            integer: Transfer::new(n, &by_type(BaseType::Integer)),
            boolean: Transfer::new(n, &by_type(BaseType::Boolean)),
        }
    }

    /// Sets component `c`'s connected inputs from the outputs last read.
    #[inline]
    pub fn write_inputs(&mut self, c: usize, inst: &mut Instance) -> Result<(), FmiError> {
        self.real.write_inputs(c, inst)?;
        self.integer.write_inputs(c, inst)?;
        self.boolean.write_inputs(c, inst)
    }

    /// Reads component `c`'s connected outputs.
    #[inline]
    pub fn read_outputs(&mut self, c: usize, inst: &mut Instance) -> Result<(), FmiError> {
        self.real.read_outputs(c, inst)?;
        self.integer.read_outputs(c, inst)?;
        self.boolean.read_outputs(c, inst)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::system::Endpoint;

    fn link(from: usize, from_vr: u32, to: usize, to_vr: u32, factor: Option<f64>) -> Link {
        Link {
            from,
            from_vr,
            to,
            to_vr,
            base: BaseType::Real,
            transform: factor.map(|factor| Linear {
                factor,
                offset: 1.0,
            }),
            from_name: Endpoint::new(&format!("c{from}"), &format!("v{from_vr}")),
            to_name: Endpoint::new(&format!("c{to}"), &format!("v{to_vr}")),
        }
    }

    #[test]
    fn each_output_gets_one_slot_in_a_range_per_component_and_inputs_point_into_them() {
        // Component 2 feeds two inputs of 0 from one output, and one of 1; component 0 feeds 1.
        let links = [
            link(2, 7, 0, 1, None),
            link(0, 3, 1, 4, None),
            link(2, 7, 0, 2, Some(2.0)),
            link(2, 9, 1, 5, None),
        ];
        let t: Transfer<f64> = Transfer::new(3, &links.iter().collect::<Vec<_>>());
        assert_eq!(t.out_vr, [vec![3], vec![], vec![7, 9]]);
        assert_eq!(t.out_start, [0, 1, 1]);
        assert_eq!(t.slots.len(), 3);
        assert_eq!(t.in_vr, [vec![1, 2], vec![4, 5], vec![]]);
        assert_eq!(t.in_slot, [vec![1, 1], vec![0, 2], vec![]]);
        assert_eq!(t.scratch.len(), 2, "as wide as the widest input set");
        let f = t.in_transform[0][1].expect("the second input of 0 is transformed");
        assert_eq!(3.0_f64.apply(Some(f)), 7.0);
        assert_eq!(3.0_f64.apply(None), 3.0);
    }

    #[test]
    fn links_are_split_by_type() {
        let mut b = link(1, 2, 0, 3, None);
        b.base = BaseType::Boolean;
        let all = Transfers::new(2, &[link(1, 1, 0, 1, None), b]);
        assert_eq!(all.real.in_vr, [vec![1], vec![]]);
        assert_eq!(all.integer.slots.len(), 0);
        assert_eq!(all.boolean.in_vr, [vec![3], vec![]]);
        assert_eq!(all.boolean.out_vr, [vec![], vec![2]]);
    }
}
