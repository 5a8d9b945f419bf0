//! The rules of FMI 2.0 section 2.2.7 (causality, variability, initial) and 2.2.8
//! (ModelStructure) as functions, shared by the validator and by the FMU crates that build
//! their descriptions, so that what we write and what we check follow one reading of the spec.

use crate::types::*;

/// The cases of the spec's table of legal causality/variability combinations; each case fixes
/// the default and the allowed values of `initial`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum InitialCase {
    /// Default exact; only exact allowed (constants, parameters).
    A,
    /// Default calculated; approx or calculated (calculatedParameter, fixed/tunable local).
    B,
    /// Default calculated; exact, approx or calculated (discrete/continuous output and local).
    C,
    /// No `initial`; a start value is required (inputs).
    D,
    /// No `initial` and no start value (the independent variable).
    E,
}

impl InitialCase {
    pub fn default_initial(self) -> Option<Initial> {
        match self {
            InitialCase::A => Some(Initial::Exact),
            InitialCase::B | InitialCase::C => Some(Initial::Calculated),
            InitialCase::D | InitialCase::E => None,
        }
    }

    pub fn allows(self, initial: Initial) -> bool {
        match self {
            InitialCase::A => initial == Initial::Exact,
            InitialCase::B => initial != Initial::Exact,
            InitialCase::C => true,
            InitialCase::D | InitialCase::E => false,
        }
    }
}

/// The table's case for a combination, or why the combination is illegal.
pub(crate) fn initial_case(
    causality: Causality,
    variability: Variability,
) -> Result<InitialCase, &'static str> {
    use Causality as C;
    use Variability as V;
    match (causality, variability) {
        (C::Output | C::Local, V::Constant) => Ok(InitialCase::A),
        (C::Parameter, V::Fixed | V::Tunable) => Ok(InitialCase::A),
        (C::CalculatedParameter | C::Local, V::Fixed | V::Tunable) => Ok(InitialCase::B),
        (C::Input, V::Discrete | V::Continuous) => Ok(InitialCase::D),
        (C::Output | C::Local, V::Discrete | V::Continuous) => Ok(InitialCase::C),
        (C::Independent, V::Continuous) => Ok(InitialCase::E),
        (C::Parameter | C::CalculatedParameter | C::Input, V::Constant) => Err(
            "a constant cannot be a parameter or an input: those are set by the environment, a constant never changes",
        ),
        (C::Parameter | C::CalculatedParameter, V::Discrete | V::Continuous) => {
            Err("a parameter or calculatedParameter must be fixed or tunable")
        }
        (C::Input, V::Fixed | V::Tunable) => Err(
            "an input must be discrete or continuous (a fixed or tunable value set from outside is a parameter)",
        ),
        (C::Output, V::Fixed | V::Tunable) => Err(
            "an output must be constant, discrete or continuous (a fixed or tunable computed value is a calculatedParameter)",
        ),
        (C::Independent, _) => Err("the independent variable must be continuous"),
    }
}

impl ScalarVariable {
    /// The `initial` that applies: the attribute when present, otherwise the spec's default for
    /// the causality/variability combination (exact for constants and parameters, calculated
    /// for calculatedParameters and for outputs and locals). `None` for inputs and the
    /// independent variable, which must not have `initial` at all (even if the file gives one).
    pub fn effective_initial(&self) -> Option<Initial> {
        match self.causality {
            Causality::Input | Causality::Independent => None,
            _ => self
                .initial
                .or(match initial_case(self.causality, self.variability) {
                    Ok(case) => case.default_initial(),
                    // Illegal combination (validate reports it): fall back on the causality alone.
                    Err(_) => Some(match self.causality {
                        Causality::Parameter => Initial::Exact,
                        _ if self.variability == Variability::Constant => Initial::Exact,
                        _ => Initial::Calculated,
                    }),
                }),
        }
    }

    /// The start value as given, whatever the type.
    pub fn has_start(&self) -> bool {
        match &self.kind {
            VariableKind::Real(r) => r.start.is_some(),
            VariableKind::Integer(i) | VariableKind::Enumeration(i) => i.start.is_some(),
            VariableKind::Boolean { start, .. } => start.is_some(),
            VariableKind::String { start, .. } => start.is_some(),
        }
    }

    /// The `declaredType` attribute of the type element, whatever the type.
    pub fn declared_type(&self) -> Option<&str> {
        match &self.kind {
            VariableKind::Real(r) => r.declared_type.as_deref(),
            VariableKind::Integer(i) | VariableKind::Enumeration(i) => i.declared_type.as_deref(),
            VariableKind::Boolean { declared_type, .. }
            | VariableKind::String { declared_type, .. } => declared_type.as_deref(),
        }
    }
}

impl ModelStructure {
    /// Builds the ModelStructure the spec requires for `variables`:
    /// - Outputs: every `causality="output"` variable, in index order, with the dependencies
    ///   `output_dependencies` gives (1-based indices; `None` = depends on all knowns,
    ///   `Some(vec![])` = no direct feedthrough);
    /// - Derivatives: every Real variable with a `derivative` attribute, in index order
    ///   (none for our co-simulation FMUs), dependencies `None`;
    /// - InitialUnknowns: [`expected_initial_unknowns`](Self::expected_initial_unknowns), each
    ///   with dependencies `None`.
    pub fn derive(
        variables: &[ScalarVariable],
        output_dependencies: impl Fn(&ScalarVariable) -> Option<Vec<u32>>,
    ) -> ModelStructure {
        let unknown = |i: usize, dependencies| Unknown {
            index: (i + 1) as u32,
            dependencies,
            dependencies_kind: None,
        };
        let outputs = variables
            .iter()
            .enumerate()
            .filter(|(_, v)| v.causality == Causality::Output)
            .map(|(i, v)| unknown(i, output_dependencies(v)))
            .collect();
        let derivatives: Vec<Unknown> = variables
            .iter()
            .enumerate()
            .filter(|(_, v)| matches!(&v.kind, VariableKind::Real(r) if r.derivative.is_some()))
            .map(|(i, _)| unknown(i, None))
            .collect();
        let derivative_indices: Vec<u32> = derivatives.iter().map(|d| d.index).collect();
        let initial_unknowns =
            ModelStructure::expected_initial_unknowns(variables, &derivative_indices)
                .into_iter()
                .map(|index| Unknown {
                    index,
                    dependencies: None,
                    dependencies_kind: None,
                })
                .collect();
        ModelStructure {
            outputs,
            derivatives,
            initial_unknowns,
        }
    }

    /// The sorted 1-based indices InitialUnknowns must list (FMI 2.0 section 2.2.8): outputs
    /// whose effective initial is approx or calculated, every calculatedParameter, and the
    /// state derivatives listed in Derivatives (`derivatives`, 1-based) and their states when
    /// their effective initial is approx or calculated.
    pub fn expected_initial_unknowns(
        variables: &[ScalarVariable],
        derivatives: &[u32],
    ) -> Vec<u32> {
        let not_exact = |v: &ScalarVariable| {
            matches!(
                v.effective_initial(),
                Some(Initial::Approx | Initial::Calculated)
            )
        };
        let mut wanted = vec![false; variables.len()];
        for (i, v) in variables.iter().enumerate() {
            wanted[i] = match v.causality {
                Causality::Output => not_exact(v),
                Causality::CalculatedParameter => true,
                _ => false,
            };
        }
        for &d in derivatives {
            let Some(der) = d.checked_sub(1).and_then(|i| variables.get(i as usize)) else {
                continue;
            };
            if not_exact(der) {
                wanted[d as usize - 1] = true;
            }
            if let VariableKind::Real(RealAttributes {
                derivative: Some(s),
                ..
            }) = &der.kind
                && let Some(state) = s.checked_sub(1).and_then(|i| variables.get(i as usize))
                && not_exact(state)
            {
                wanted[*s as usize - 1] = true;
            }
        }
        wanted
            .iter()
            .enumerate()
            .filter(|(_, w)| **w)
            .map(|(i, _)| (i + 1) as u32)
            .collect()
    }
}

impl ModelDescription {
    /// The variable with this name.
    pub fn variable(&self, name: &str) -> Option<&ScalarVariable> {
        self.model_variables.iter().find(|v| v.name == name)
    }

    /// The 1-based FMI index of the variable with this name: the number ModelStructure uses
    /// (`Unknown::index`, `dependencies`, `derivative`), so `model_variables[i - 1]` is the
    /// variable. It is NOT a 0-based position.
    pub fn variable_index(&self, name: &str) -> Option<usize> {
        self.model_variables
            .iter()
            .position(|v| v.name == name)
            .map(|i| i + 1)
    }
}
