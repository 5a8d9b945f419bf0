//! Checking a [`ModelDescription`] against the FMI 2.0 rules (and our co-simulation needs).
//!
//! `validate` collects every problem instead of stopping at the first, so a generated file can
//! be fixed in one pass. Each problem names the variable it is about when there is one.

use std::collections::{HashMap, HashSet};
use std::fmt;

use crate::structure::{InitialCase, initial_case};
use crate::types::*;

/// One broken rule.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Violation {
    /// The variable the rule is about, if any.
    pub variable: Option<String>,
    /// The rule and what broke it, phrased for the author of the file (e.g. which attribute to
    /// add).
    pub message: String,
}

impl fmt::Display for Violation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.variable {
            Some(name) => write!(f, "variable '{name}': {}", self.message),
            None => f.write_str(&self.message),
        }
    }
}

impl ModelDescription {
    /// Checks the description; an empty result means it is valid. Checked:
    /// - root: fmiVersion "2.0", non-empty modelName and guid, variableNamingConvention;
    /// - CoSimulation present (this toolkit only runs co-simulation FMUs) with a modelIdentifier
    ///   that is a C identifier; canSerializeFMUstate only with canGetAndSetFMUstate;
    /// - unit, type and variable names unique; SimpleType base types; DefaultExperiment
    ///   start <= stop, stepSize and tolerance > 0;
    /// - value references unique per base type (Enumeration shares Integer's);
    /// - causality/variability/initial combinations (spec 2.2.7 table), start present or
    ///   absent as `initial` demands, inputs with a start and no `initial`, at most one
    ///   independent variable (Real, no start), no continuous non-Real variables;
    /// - min <= start <= max, min <= max; units and display units defined; declaredType defined
    ///   and of the same base type; Enumeration start among the items; `derivative` indices;
    /// - ModelStructure: Outputs exactly the outputs, Derivatives Real with `derivative`,
    ///   InitialUnknowns exactly the required set, each list ascending without repeats, every
    ///   index and dependency a valid 1-based index, dependenciesKind consistent.
    pub fn validate(&self) -> Vec<Violation> {
        let mut c = Checker {
            md: self,
            out: Vec::new(),
        };
        c.root();
        c.units_and_types();
        c.variables();
        c.model_structure();
        c.out
    }
}

struct Checker<'a> {
    md: &'a ModelDescription,
    out: Vec<Violation>,
}

const DEPENDENCY_KINDS: [&str; 5] = ["dependent", "constant", "fixed", "tunable", "discrete"];

impl<'a> Checker<'a> {
    fn model(&mut self, message: impl Into<String>) {
        self.out.push(Violation {
            variable: None,
            message: message.into(),
        });
    }

    fn var(&mut self, v: &ScalarVariable, message: impl Into<String>) {
        self.out.push(Violation {
            variable: Some(v.name.clone()),
            message: message.into(),
        });
    }

    fn root(&mut self) {
        let md = self.md;
        if md.fmi_version != "2.0" {
            self.model(format!(
                "fmiVersion is \"{}\", expected \"2.0\"",
                md.fmi_version
            ));
        }
        if md.model_name.trim().is_empty() {
            self.model("modelName is empty");
        }
        if md.guid.trim().is_empty() {
            self.model("guid is empty");
        }
        if let Some(c) = &md.variable_naming_convention
            && c != "flat"
            && c != "structured"
        {
            self.model(format!(
                "variableNamingConvention is \"{c}\", expected \"flat\" or \"structured\""
            ));
        }
        match &md.co_simulation {
            None => {
                self.model("no CoSimulation element: this toolkit only runs co-simulation FMUs")
            }
            Some(cs) => {
                if cs.model_identifier.is_empty() {
                    self.model("CoSimulation modelIdentifier is empty");
                } else if !is_c_identifier(&cs.model_identifier) {
                    self.model(format!(
                        "CoSimulation modelIdentifier \"{}\" is not a C identifier (it names the binary and prefixes its functions)",
                        cs.model_identifier
                    ));
                }
                if cs.can_serialize_fmu_state && !cs.can_get_and_set_fmu_state {
                    self.model(
                        "canSerializeFMUstate=\"true\" requires canGetAndSetFMUstate=\"true\"",
                    );
                }
            }
        }
        if let Some(id) = &md.model_exchange_identifier
            && !is_c_identifier(id)
        {
            self.model(format!(
                "ModelExchange modelIdentifier \"{id}\" is not a C identifier"
            ));
        }
        if let Some(de) = &md.default_experiment {
            if let (Some(start), Some(stop)) = (de.start_time, de.stop_time)
                && start > stop
            {
                self.model(format!(
                    "DefaultExperiment startTime {start} is after stopTime {stop}"
                ));
            }
            if let Some(h) = de.step_size
                && h.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
            {
                self.model(format!("DefaultExperiment stepSize {h} must be > 0"));
            }
            if let Some(tol) = de.tolerance
                && tol.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
            {
                self.model(format!("DefaultExperiment tolerance {tol} must be > 0"));
            }
        }
    }

    fn units_and_types(&mut self) {
        let md = self.md;
        let mut seen = HashSet::new();
        for u in &md.unit_definitions {
            if !seen.insert(u.name.as_str()) {
                self.model(format!(
                    "unit '{}' is defined twice in UnitDefinitions",
                    u.name
                ));
            }
            let mut display = HashSet::new();
            for d in &u.display_units {
                if !display.insert(d.name.as_str()) {
                    self.model(format!(
                        "unit '{}': DisplayUnit '{}' is defined twice",
                        u.name, d.name
                    ));
                }
            }
        }
        let mut seen = HashSet::new();
        for t in &md.type_definitions {
            if !seen.insert(t.name.as_str()) {
                self.model(format!(
                    "type '{}' is defined twice in TypeDefinitions",
                    t.name
                ));
            }
            match BaseType::from_xml_name(&t.base_type) {
                None => self.model(format!(
                    "type '{}': base type \"{}\" is not Real, Integer, Boolean, String or Enumeration",
                    t.name, t.base_type
                )),
                Some(BaseType::Enumeration) if t.items.is_empty() => {
                    self.model(format!("type '{}': an Enumeration needs at least one Item", t.name));
                }
                _ => {}
            }
            if let Some(problem) = self.unit_problem(t.unit.as_deref(), t.display_unit.as_deref()) {
                self.model(format!("type '{}': {problem}", t.name));
            }
        }
    }

    /// Why a (unit, displayUnit) pair is not defined, if it is not.
    fn unit_problem(&self, unit: Option<&str>, display_unit: Option<&str>) -> Option<String> {
        let Some(unit) = unit else {
            return display_unit.map(|d| format!("displayUnit '{d}' is given without a unit"));
        };
        let Some(defined) = self.md.unit_definitions.iter().find(|u| u.name == unit) else {
            return Some(format!("unit '{unit}' is not defined in UnitDefinitions"));
        };
        match display_unit {
            Some(d) if !defined.display_units.iter().any(|du| du.name == d) => Some(format!(
                "displayUnit '{d}' is not a DisplayUnit of unit '{unit}' in UnitDefinitions"
            )),
            _ => None,
        }
    }

    fn variables(&mut self) {
        let md = self.md;
        let mut names: HashMap<&str, usize> = HashMap::new();
        let mut value_references: HashMap<(BaseType, u32), &str> = HashMap::new();
        let mut independent: Option<&str> = None;
        for (i, v) in md.model_variables.iter().enumerate() {
            if v.name.is_empty() {
                self.var(v, format!("variable {} has an empty name", i + 1));
            }
            if let Some(first) = names.insert(&v.name, i + 1) {
                names.insert(&v.name, first);
                self.var(
                    v,
                    format!("the name is used twice (variables {first} and {})", i + 1),
                );
            }
            let space = v.kind.base_type().value_reference_space();
            match value_references.get(&(space, v.value_reference)) {
                Some(other) => self.var(
                    v,
                    format!(
                        "value reference {} ({space}) is also used by variable '{other}'",
                        v.value_reference
                    ),
                ),
                None => {
                    value_references.insert((space, v.value_reference), &v.name);
                }
            }
            if v.causality == Causality::Independent {
                if let Some(other) = independent {
                    self.var(v, format!("there can be at most one independent variable, '{other}' is one already"));
                }
                independent = Some(&v.name);
                if v.kind.base_type() != BaseType::Real {
                    self.var(v, "the independent variable must be Real");
                }
            }
            self.combination(v);
            self.type_rules(v);
        }
    }

    /// Causality, variability, initial and start (spec 2.2.7).
    fn combination(&mut self, v: &ScalarVariable) {
        if v.kind.base_type() != BaseType::Real && v.variability == Variability::Continuous {
            self.var(
                v,
                format!("a {} variable cannot be continuous (only Real can; state variability explicitly)", v.kind.base_type()),
            );
        }
        let case = match initial_case(v.causality, v.variability) {
            Ok(case) => case,
            Err(why) => {
                self.var(
                    v,
                    format!(
                        "causality {} with variability {} is not allowed: {why}",
                        v.causality, v.variability
                    ),
                );
                // Still check start against the attribute, if any.
                match v.initial {
                    Some(Initial::Calculated) if v.has_start() => self.var(
                        v,
                        "initial is calculated, so it must not have a start value",
                    ),
                    Some(Initial::Exact | Initial::Approx) if !v.has_start() => self.var(
                        v,
                        format!(
                            "initial is {}, so it needs a start value",
                            v.initial.unwrap()
                        ),
                    ),
                    _ => {}
                }
                return;
            }
        };
        match case {
            InitialCase::D => {
                if let Some(initial) = v.initial {
                    self.var(
                        v,
                        format!(
                            "input must not have an initial attribute (found initial=\"{initial}\")"
                        ),
                    );
                }
                if !v.has_start() {
                    self.var(v, "an input needs a start value");
                }
            }
            InitialCase::E => {
                if v.initial.is_some() {
                    self.var(
                        v,
                        "the independent variable must not have an initial attribute",
                    );
                }
                if v.has_start() {
                    self.var(v, "the independent variable must not have a start value (its start is the start time)");
                }
            }
            InitialCase::A | InitialCase::B | InitialCase::C => {
                if let Some(initial) = v.initial
                    && !case.allows(initial)
                {
                    let allowed = match case {
                        InitialCase::A => "exact",
                        _ => "approx or calculated",
                    };
                    self.var(
                        v,
                        format!(
                            "initial=\"{initial}\" is not allowed for causality {} with variability {} (allowed: {allowed})",
                            v.causality, v.variability
                        ),
                    );
                }
                let effective = v.initial.or(case.default_initial());
                match effective {
                    Some(Initial::Exact | Initial::Approx) if !v.has_start() => {
                        let what = if v.variability == Variability::Constant {
                            "a constant".to_string()
                        } else if v.initial.is_some() {
                            format!("initial is {}, so it", effective.unwrap())
                        } else {
                            format!("initial defaults to {} here, so it", effective.unwrap())
                        };
                        self.var(v, format!("{what} needs a start value"));
                    }
                    Some(Initial::Calculated) if v.has_start() => {
                        let how = if v.initial.is_some() {
                            "is"
                        } else {
                            "defaults to"
                        };
                        self.var(
                            v,
                            format!("initial {how} calculated, so it must not have a start value"),
                        );
                    }
                    _ => {}
                }
            }
        }
    }

    /// Bounds, units, declared types and derivative references.
    fn type_rules(&mut self, v: &ScalarVariable) {
        let md = self.md;
        let declared = v
            .declared_type()
            .map(|name| (name, md.type_definitions.iter().find(|t| t.name == name)));
        if let Some((name, found)) = declared {
            match found {
                None => self.var(
                    v,
                    format!("declaredType '{name}' is not defined in TypeDefinitions"),
                ),
                Some(t) if t.base_type != v.kind.base_type().as_str() => self.var(
                    v,
                    format!(
                        "declaredType '{name}' is a {} type but the variable is {}",
                        t.base_type,
                        v.kind.base_type()
                    ),
                ),
                Some(_) => {}
            }
        }
        let declared = declared
            .and_then(|(_, t)| t)
            .filter(|t| t.base_type == v.kind.base_type().as_str());
        match &v.kind {
            VariableKind::Real(r) => {
                self.bounds(v, r.min, r.max, r.start);
                let unit = r
                    .unit
                    .as_deref()
                    .or(declared.and_then(|t| t.unit.as_deref()));
                let display_unit = r
                    .display_unit
                    .as_deref()
                    .or(declared.and_then(|t| t.display_unit.as_deref()));
                if let Some(problem) = self.unit_problem(unit, display_unit) {
                    self.var(v, problem);
                }
                if let Some(d) = r.derivative {
                    match d
                        .checked_sub(1)
                        .and_then(|i| md.model_variables.get(i as usize))
                    {
                        None => self.var(
                            v,
                            format!(
                                "derivative index {d} is not a variable ({})",
                                self.index_range()
                            ),
                        ),
                        Some(state) if state.kind.base_type() != BaseType::Real => self.var(
                            v,
                            format!(
                                "derivative index {d} refers to '{}', which is not Real",
                                state.name
                            ),
                        ),
                        Some(_) => {}
                    }
                }
            }
            VariableKind::Integer(i) => self.bounds(v, i.min, i.max, i.start),
            VariableKind::Enumeration(i) => {
                self.bounds(v, i.min, i.max, i.start);
                if i.declared_type.is_none() {
                    self.var(v, "an Enumeration variable needs a declaredType");
                }
                if let (Some(t), Some(start)) = (declared, i.start)
                    && !t.items.is_empty()
                    && !t.items.iter().any(|(_, value)| *value == start)
                {
                    self.var(
                        v,
                        format!("start {start} is not a value of enumeration '{}'", t.name),
                    );
                }
            }
            VariableKind::Boolean { .. } | VariableKind::String { .. } => {}
        }
    }

    fn bounds<T: PartialOrd + fmt::Display + Copy>(
        &mut self,
        v: &ScalarVariable,
        min: Option<T>,
        max: Option<T>,
        start: Option<T>,
    ) {
        if let (Some(min), Some(max)) = (min, max)
            && min > max
        {
            self.var(v, format!("min {min} is greater than max {max}"));
        }
        if let Some(start) = start {
            if let Some(min) = min
                && start < min
            {
                self.var(v, format!("start {start} is below min {min}"));
            }
            if let Some(max) = max
                && start > max
            {
                self.var(v, format!("start {start} is above max {max}"));
            }
        }
    }

    fn index_range(&self) -> String {
        match self.md.model_variables.len() {
            0 => "there are no variables".to_string(),
            n => format!("valid indices are 1..={n}"),
        }
    }

    fn variable_at(&self, index: u32) -> Option<&'a ScalarVariable> {
        index
            .checked_sub(1)
            .and_then(|i| self.md.model_variables.get(i as usize))
    }

    fn model_structure(&mut self) {
        let md = self.md;
        let ms = &md.model_structure;
        let outputs: Vec<u32> = md
            .model_variables
            .iter()
            .enumerate()
            .filter(|(_, v)| v.causality == Causality::Output)
            .map(|(i, _)| (i + 1) as u32)
            .collect();
        self.unknown_list("Outputs", &ms.outputs, &outputs, "an output", |v| {
            (v.causality != Causality::Output)
                .then(|| format!("its causality is {}, not output", v.causality))
        });

        // Derivatives: no required set can be computed (which Real variables are derivatives is
        // what the list declares), but each entry must be a Real with a `derivative` attribute.
        let is_derivative =
            |v: &ScalarVariable| matches!(&v.kind, VariableKind::Real(r) if r.derivative.is_some());
        let derivatives: Vec<u32> = ms
            .derivatives
            .iter()
            .map(|u| u.index)
            .filter(|&i| self.variable_at(i).is_some_and(is_derivative))
            .collect();
        self.unknown_list(
            "Derivatives",
            &ms.derivatives,
            &derivatives,
            "a state derivative",
            |_| Some("it is not a Real variable with a derivative attribute".to_string()),
        );

        let expected = ModelStructure::expected_initial_unknowns(&md.model_variables, &derivatives);
        self.unknown_list(
            "InitialUnknowns",
            &ms.initial_unknowns,
            &expected,
            "an initial unknown",
            |v| {
                Some(match v.causality {
                    Causality::Output => {
                        format!("it is an output with initial {}", initial_name(v))
                    }
                    c => format!("its causality is {c}"),
                })
            },
        );
    }

    /// Checks one ModelStructure list: indices valid, ascending, no repeats, each variable
    /// acceptable (`wrong` says why not), every `expected` index present, dependencies valid.
    fn unknown_list(
        &mut self,
        list: &str,
        unknowns: &[Unknown],
        expected: &[u32],
        role: &str,
        wrong: impl Fn(&ScalarVariable) -> Option<String>,
    ) {
        let mut previous: Option<u32> = None;
        let mut seen = HashSet::new();
        for u in unknowns {
            let Some(v) = self.variable_at(u.index) else {
                self.model(format!(
                    "ModelStructure/{list}: index {} is not a variable ({})",
                    u.index,
                    self.index_range()
                ));
                continue;
            };
            if !seen.insert(u.index) {
                self.var(v, format!("listed more than once in ModelStructure/{list}"));
            } else if let Some(p) = previous
                && u.index < p
            {
                self.var(
                    v,
                    format!(
                        "ModelStructure/{list} is not in ascending order (index {} after {p})",
                        u.index
                    ),
                );
            }
            previous = Some(u.index);
            if !expected.contains(&u.index) {
                let why = wrong(v).unwrap_or_default();
                let why = if why.is_empty() {
                    String::new()
                } else {
                    format!(": {why}")
                };
                self.var(
                    v,
                    format!("listed in ModelStructure/{list} but is not {role}{why}"),
                );
            }
            self.dependencies(list, u, v);
        }
        for &index in expected {
            if !seen.contains(&index)
                && let Some(v) = self.variable_at(index)
            {
                let detail = match v.causality {
                    Causality::Output if list == "InitialUnknowns" => {
                        format!(" (an output with initial {})", initial_name(v))
                    }
                    Causality::CalculatedParameter => " (every calculatedParameter is)".to_string(),
                    _ => String::new(),
                };
                self.var(v, format!("missing from ModelStructure/{list}{detail}"));
            }
        }
    }

    fn dependencies(&mut self, list: &str, u: &Unknown, v: &ScalarVariable) {
        if let Some(deps) = &u.dependencies {
            for &d in deps {
                if self.variable_at(d).is_none() {
                    self.var(
                        v,
                        format!(
                            "ModelStructure/{list} dependency index {d} is not a variable ({})",
                            self.index_range()
                        ),
                    );
                }
            }
        }
        if let Some(kinds) = &u.dependencies_kind {
            match &u.dependencies {
                None => self.var(v, format!("ModelStructure/{list}: dependenciesKind without dependencies")),
                Some(deps) if deps.len() != kinds.len() => self.var(
                    v,
                    format!(
                        "ModelStructure/{list}: {} dependenciesKind for {} dependencies (they must pair up)",
                        kinds.len(),
                        deps.len()
                    ),
                ),
                Some(_) => {}
            }
            for k in kinds {
                if !DEPENDENCY_KINDS.contains(&k.as_str()) {
                    self.var(v, format!("ModelStructure/{list}: dependenciesKind \"{k}\" is not one of {DEPENDENCY_KINDS:?}"));
                }
            }
        }
    }
}

fn initial_name(v: &ScalarVariable) -> String {
    match (v.initial, v.effective_initial()) {
        (Some(i), _) => i.to_string(),
        (None, Some(i)) => format!("{i} (the default)"),
        (None, None) => "absent".to_string(),
    }
}

fn is_c_identifier(s: &str) -> bool {
    let mut chars = s.chars();
    matches!(chars.next(), Some(c) if c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}
