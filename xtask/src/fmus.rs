//! The FMUs this workspace ships. Adding one is one more entry in [`FMUS`], and one in
//! `fmu-describe` (the program that prints its model description and documentation).

/// What the packager needs to know about one FMU crate.
pub struct FmuSpec {
    /// Cargo package name, built with `cargo build --release -p <package>`.
    pub package: &'static str,
    /// The library target's name (`[lib] name`), which names the built shared library.
    pub lib_name: &'static str,
    /// `CoSimulation/@modelIdentifier`: names the .fmu, the binary inside it and must match the
    /// XML (`fmu-describe` checks it).
    pub model_identifier: &'static str,
    /// Directory (relative to the workspace root) whose files go to `resources/`, if any.
    pub resources: Option<&'static str>,
}

pub const FMUS: &[FmuSpec] = &[
    FmuSpec {
        package: "fmu-estimator-export",
        lib_name: "fmu_estimator_export",
        model_identifier: "AlignmentEstimator",
        resources: Some("fmu-estimator/resources"),
    },
    FmuSpec {
        package: "fmu-vehicle-export",
        lib_name: "fmu_vehicle_export",
        model_identifier: "RailVehicle",
        resources: Some("fmu-vehicle/resources"),
    },
    // Trivial FMUs for testing and benchmarking the orchestrator.
    FmuSpec {
        package: "fmu-dahlquist-export",
        lib_name: "fmu_dahlquist_export",
        model_identifier: "Dahlquist",
        resources: None,
    },
    FmuSpec {
        package: "fmu-feedthrough-export",
        lib_name: "fmu_feedthrough_export",
        model_identifier: "Feedthrough",
        resources: None,
    },
];

/// The program that prints each FMU's model description and documentation, built with them.
pub const DESCRIBE: &str = "fmu-describe";
