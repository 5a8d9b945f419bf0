//! External inputs: values the caller sets on named inputs of any component before every step
//! (and once at the start, in initialization mode), as a function of time.
//!
//! The names are resolved once, before anything is created, so that an unknown component or
//! variable, a variable that is not an input, or an input a connection already feeds is
//! refused by name; the stepping then only fills a buffer and sets the values.

use super::{Address, Cosimulation, RunError};
use crate::resolve::carrier;
use crate::system::Endpoint;
use fmi_import::{FmiError, Instance};
use model_description::{BaseType, Causality};

/// Fills `values` with the external inputs' values at time `t`, one per input in the order
/// they were named: a Real as it is, an Integer or Enumeration as a whole number, a Boolean as
/// 0 or 1 (any other number is true).
pub type InputFn<'a> = dyn Fn(f64, &mut [f64]) + 'a;

/// The inputs of a run that has none.
pub fn no_inputs(_: f64, _: &mut [f64]) {}

/// The resolved inputs with the buffer they are filled into (reused from step to step).
pub(super) struct External<'a> {
    targets: Vec<Address>,
    fill: &'a InputFn<'a>,
    values: Vec<f64>,
}

impl<'a> External<'a> {
    /// Resolves `names` against the system: each must be an input (of a type a number can
    /// drive) that no connection feeds, named once.
    pub fn new(
        cosim: &Cosimulation,
        names: &[Endpoint],
        fill: &'a InputFn<'a>,
    ) -> Result<External<'a>, RunError> {
        let mut targets = Vec::with_capacity(names.len());
        for (i, name) in names.iter().enumerate() {
            let refuse = |why: String| RunError::Config(format!("external input {name}: {why}"));
            let (c, v) = cosim.find(name, &format!("external input {name}"))?;
            if v.causality != Causality::Input {
                return Err(refuse(format!(
                    "'{}' is not an input (causality {:?})",
                    v.name, v.causality
                )));
            }
            let base = v.kind.base_type();
            if base == BaseType::String {
                return Err(refuse(format!(
                    "'{}' is a String input, which a number cannot drive",
                    v.name
                )));
            }
            let target = Address {
                component: c,
                base,
                vr: v.value_reference,
            };
            if let Some(l) = cosim
                .plan()
                .links
                .iter()
                .find(|l| l.to == c && l.to_vr == target.vr && l.base == carrier(base))
            {
                return Err(refuse(format!(
                    "the connection {} -> {} already feeds it",
                    l.from_name, l.to_name
                )));
            }
            if names[..i].contains(name) {
                return Err(refuse("named twice".into()));
            }
            targets.push(target);
        }
        Ok(External {
            values: vec![0.0; targets.len()],
            targets,
            fill,
        })
    }

    /// Sets the inputs for time `t`: nothing, in the stepping loop itself, for a run without.
    #[inline]
    pub fn apply(&mut self, instances: &mut [Instance], t: f64) -> Result<(), FmiError> {
        if self.targets.is_empty() {
            return Ok(());
        }
        self.set(instances, t)
    }

    #[inline(never)]
    fn set(&mut self, instances: &mut [Instance], t: f64) -> Result<(), FmiError> {
        (self.fill)(t, &mut self.values);
        for (a, &x) in self.targets.iter().zip(&self.values) {
            let inst = &mut instances[a.component];
            match a.base {
                BaseType::Real => inst.set_real(&[a.vr], &[x])?,
                BaseType::Integer | BaseType::Enumeration => {
                    inst.set_integer(&[a.vr], &[x as i32])?
                }
                BaseType::Boolean => inst.set_boolean(&[a.vr], &[x != 0.0])?,
                BaseType::String => {}
            }
        }
        Ok(())
    }
}
