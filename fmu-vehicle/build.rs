//! Fingerprints the sources and Cargo.lock (`VEHICLE_STATE_LAYOUT`, see the `state-layout`
//! crate): the FMU writes it into its serialized states, so that a state saved by another build,
//! whose internal layout may differ, is refused with a message instead of being decoded into
//! wrong values. Extended by the package version, the built-in vehicle files and the crates that
//! write the modelDescription.xml, it is the FMU's GUID (`VEHICLE_GUID`): a new one whenever the
//! FMU changes.

use std::path::PathBuf;

fn main() {
    let manifest = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets it"));
    let mut layout = state_layout::Fingerprint::of_fmu_crate();
    // The design line lives in its own crate and in the vehicle's state.
    layout.add_crate(&manifest.join("..").join("design-line"));
    println!("cargo::rustc-env=VEHICLE_STATE_LAYOUT={}", layout.hex());
    let vehicles = ["ml95.toml", "manchester.toml"].map(|f| manifest.join("resources").join(f));
    println!(
        "cargo::rustc-env=VEHICLE_GUID={}",
        layout.fmu_guid(&vehicles)
    );
}
