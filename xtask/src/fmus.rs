//! The FMUs this workspace ships. Adding one is one more entry in
//! [`FMUS`] plus the crate in xtask's dependencies (for its model description and documentation).

use model_description::ModelDescription;

/// What the packager needs to know about one FMU crate.
pub struct FmuSpec {
    /// Cargo package name, built with `cargo build --release -p <package>`.
    pub package: &'static str,
    /// The library target's name (`[lib] name`), which names the built shared library.
    pub lib_name: &'static str,
    /// `CoSimulation/@modelIdentifier`: names the .fmu, the binary inside it and must match the XML.
    pub model_identifier: &'static str,
    /// The modelDescription.xml content, from the crate's variable table.
    pub model_description: fn() -> ModelDescription,
    /// `documentation/index.html`, given the crate's method description.
    pub documentation: fn(&str) -> String,
    /// The method, an HTML fragment written by the FMU crate.
    pub method_html: &'static str,
    /// Directory (relative to the workspace root) whose files go to `resources/`, if any.
    pub resources: Option<&'static str>,
}

pub const FMUS: &[FmuSpec] = &[
    FmuSpec {
        package: "fmu-estimator-export",
        lib_name: "fmu_estimator_export",
        model_identifier: "AlignmentEstimator",
        model_description: fmu_estimator::model_description,
        documentation: fmi_abi::description::documentation_html::<fmu_estimator::Estimator>,
        method_html: fmu_estimator::METHOD_HTML,
        resources: Some("fmu-estimator/resources"),
    },
    FmuSpec {
        package: "fmu-vehicle-export",
        lib_name: "fmu_vehicle_export",
        model_identifier: "RailVehicle",
        model_description: fmu_vehicle::model_description,
        documentation: fmi_abi::description::documentation_html::<fmu_vehicle::RailVehicle>,
        method_html: fmu_vehicle::METHOD_HTML,
        resources: Some("fmu-vehicle/resources"),
    },
    // Trivial FMUs for testing and benchmarking the orchestrator.
    FmuSpec {
        package: "fmu-dahlquist-export",
        lib_name: "fmu_dahlquist_export",
        model_identifier: "Dahlquist",
        model_description: fmu_dahlquist::model_description,
        documentation: fmi_abi::description::documentation_html::<fmu_dahlquist::Dahlquist>,
        method_html: fmu_dahlquist::METHOD_HTML,
        resources: None,
    },
    FmuSpec {
        package: "fmu-feedthrough-export",
        lib_name: "fmu_feedthrough_export",
        model_identifier: "Feedthrough",
        model_description: fmu_feedthrough::model_description,
        documentation: fmi_abi::description::documentation_html::<fmu_feedthrough::Feedthrough>,
        method_html: fmu_feedthrough::METHOD_HTML,
        resources: None,
    },
];
