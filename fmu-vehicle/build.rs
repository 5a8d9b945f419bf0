//! Fingerprints the sources (`VEHICLE_STATE_LAYOUT`, see the `state-layout` crate): the FMU
//! writes it into its serialized states, so that a state saved by another build, whose internal
//! layout may differ, is refused with a message instead of being decoded into wrong values.
//! That fingerprint, extended by the built-in vehicle files and the crates that write the
//! modelDescription.xml, is the FMU's GUID (`VEHICLE_GUID`): a new one whenever the FMU changes.

use std::path::PathBuf;

fn main() {
    let layout = state_layout::Fingerprint::of_sources();
    println!("cargo::rustc-env=VEHICLE_STATE_LAYOUT={}", layout.hex());
    let manifest = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets it"));
    let mut guid = layout;
    for file in ["ml95.toml", "manchester.toml"] {
        guid.add_file(&manifest.join("resources").join(file));
    }
    for dep in ["fmi-abi", "modelDescription"] {
        guid.add_crate(&manifest.join("..").join(dep));
    }
    println!("cargo::rustc-env=VEHICLE_GUID={}", guid.guid());
}
