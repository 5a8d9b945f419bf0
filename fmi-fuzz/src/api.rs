//! An FMU under test: unpacked by `fmi_import`, its library opened again here so that every
//! one of the 34 functions can be called raw (NULL pointers, unknown references, any state).

use anyhow::{Result, anyhow, bail};
use libloading::Library;
use model_description::{Causality, Initial, Variability, VariableKind};
use std::ffi::{CString, c_void};
use std::path::{Path, PathBuf};

/// The 34 functions as raw pointers (statuses as `c_int`, so a value outside the enum is seen as it
/// is) and their names: fmi-import's own table.
pub use fmi_import::raw::{Functions as Api, NAMES};

/// The four FMI base types a value reference can belong to: the export layer's own enum.
pub use fmi_abi::variables::Base;

/// What the fuzzer needs to know about one variable.
#[derive(Debug, Clone)]
pub struct Var {
    /// The variable's name, for reports and `--preset`.
    pub name: String,
    /// Its value reference within `base`.
    pub vr: u32,
    /// Which fmi2Get/fmi2Set family addresses it (Enumeration counts as Integer).
    pub base: Base,
    /// With `variability` and `initial`, decides where the oracle expects a set to be accepted.
    pub causality: Causality,
    /// With `causality` and `initial`, decides where the oracle expects a set to be accepted.
    pub variability: Variability,
    /// `initial`, or its default from the spec's table when the attribute is absent.
    pub initial: Option<Initial>,
}

impl Var {
    /// Whether the FMI 2.0 co-simulation state table lets a master set this variable in
    /// `instantiated` (exact/approx, non-constant), `initializationMode` (exact or input) and
    /// `stepComplete` (inputs and tunable parameters). Inputs count as settable in
    /// `instantiated`: importers do it (Compliance Checker) and the spec allows a start value.
    pub fn settable(&self, state: crate::oracle::State) -> bool {
        use crate::oracle::State as S;
        let input = self.causality == Causality::Input;
        match state {
            S::Instantiated => {
                self.variability != Variability::Constant
                    && (input || matches!(self.initial, Some(Initial::Exact | Initial::Approx)))
            }
            S::InitializationMode => {
                input
                    || (self.variability != Variability::Constant
                        && self.initial == Some(Initial::Exact))
            }
            S::StepComplete => {
                input
                    || (self.causality == Causality::Parameter
                        && self.variability == Variability::Tunable)
            }
            _ => false,
        }
    }
}

/// The default `initial` of FMI 2.0 table 2 (section 2.2.7) for an absent attribute.
fn default_initial(c: Causality, v: Variability) -> Option<Initial> {
    match (c, v) {
        (Causality::Parameter, _) => Some(Initial::Exact),
        (Causality::CalculatedParameter, _) => Some(Initial::Calculated),
        (Causality::Input | Causality::Independent, _) => None,
        (_, Variability::Constant) => Some(Initial::Exact),
        _ => Some(Initial::Calculated),
    }
}

/// An FMU opened for raw calls.
pub struct Target {
    /// Keeps the unpacked directory (and the importer's own handle of the library) alive.
    _fmu: fmi_import::Fmu,
    /// The 34 entry points of the FMU's library, for raw calls.
    pub api: Api,
    _lib: Library,
    /// The `.fmu` file, for reports and replay commands.
    pub path: PathBuf,
    /// `modelName`, for reports.
    pub model_name: String,
    /// The GUID to pass to fmi2Instantiate (the fuzzer also passes wrong ones).
    pub guid: CString,
    /// The `file://` URI of the unpacked resources, for fmi2Instantiate.
    pub resource_uri: CString,
    /// Every declared variable, in document order.
    pub vars: Vec<Var>,
    /// The names of the declared log categories.
    pub log_categories: Vec<String>,
    /// (providesDirectionalDerivative, canInterpolateInputs, maxOutputDerivativeOrder > 0).
    pub caps: (bool, bool, bool),
}

impl Target {
    /// Unpacks and checks the FMU with fmi-import, then loads its library a second time for
    /// the raw calls; errors name the file and what is missing.
    pub fn open(path: &Path) -> Result<Target> {
        let fmu = fmi_import::Fmu::open(path)
            .map_err(|e| anyhow!("cannot open {}: {e}", path.display()))?;
        let md = fmu.model_description();
        let binary = fmi_import::platform_binary(fmu.model_identifier())
            .ok_or_else(|| anyhow!("FMI 2.0 names no binaries folder for this platform"))?;
        let lib_path = fmu.unpacked_dir().join(binary);
        let lib = load(&lib_path)?;
        let api = Api::resolve(&lib).map_err(|missing| {
            anyhow!(
                "{}: symbols missing: {}",
                lib_path.display(),
                missing.join(", ")
            )
        })?;
        let mut vars = Vec::new();
        for v in &md.model_variables {
            let base = match v.kind {
                VariableKind::Real(_) => Base::Real,
                VariableKind::Integer(_) | VariableKind::Enumeration(_) => Base::Integer,
                VariableKind::Boolean { .. } => Base::Boolean,
                VariableKind::String { .. } => Base::String,
            };
            vars.push(Var {
                name: v.name.clone(),
                vr: v.value_reference,
                base,
                causality: v.causality,
                variability: v.variability,
                initial: v
                    .initial
                    .or_else(|| default_initial(v.causality, v.variability)),
            });
        }
        if vars.is_empty() {
            bail!("{} declares no variables", path.display());
        }
        let caps = md
            .co_simulation
            .as_ref()
            .map_or((false, false, false), |cs| {
                (
                    cs.provides_directional_derivative,
                    cs.can_interpolate_inputs,
                    cs.max_output_derivative_order > 0,
                )
            });
        Ok(Target {
            log_categories: md.log_categories.iter().map(|c| c.name.clone()).collect(),
            caps,
            path: path.to_path_buf(),
            model_name: md.model_name.clone(),
            guid: CString::new(md.guid.clone())?,
            resource_uri: CString::new(fmu.resource_uri())?,
            vars,
            api,
            _lib: lib,
            _fmu: fmu,
        })
    }

    /// The variables of one base type, e.g. to pick a valid value reference for a get or set.
    pub fn vars_of(&self, base: Base) -> impl Iterator<Item = &Var> {
        self.vars.iter().filter(move |v| v.base == base)
    }

    /// The variable a (base type, value reference) pair addresses, if declared.
    pub fn var(&self, base: Base, vr: u32) -> Option<&Var> {
        self.vars.iter().find(|v| v.base == base && v.vr == vr)
    }

    /// The variable of this name, e.g. for a `--preset`.
    pub fn var_named(&self, name: &str) -> Option<&Var> {
        self.vars.iter().find(|v| v.name == name)
    }
}

fn load(path: &Path) -> Result<Library> {
    fmi_import::raw::load(path).map_err(|e| anyhow!("cannot load {}: {e}", path.display()))
}

/// A NUL-terminated byte buffer that is not a C string the FMU made: used as a "pointer to
/// something that is not an instance/state" argument. 256 zeroed-then-filled bytes, so an FMU
/// that reads a tag at the start reads owned memory.
pub fn foreign_block(fill: u8) -> Box<[u64; 32]> {
    let b = u64::from_ne_bytes([fill; 8]);
    Box::new([b; 32])
}

/// The buffer as the `void*` an FMI function takes, to pass where an instance or state belongs.
pub fn as_ptr(b: &[u64; 32]) -> *mut c_void {
    b.as_ptr() as *mut c_void
}
