//! Fingerprints the sources (`VEHICLE_STATE_LAYOUT`, see the `state-layout` crate): the FMU
//! writes it into its serialized states, so that a state saved by another build, whose internal
//! layout may differ, is refused with a message instead of being decoded into wrong values.
//! The sources and Cargo.lock make the fingerprint. Extended by the package version, the
//! built-in vehicle files and the crates that write the modelDescription.xml, it is the FMU's GUID (`VEHICLE_GUID`): a new one whenever the FMU changes.

use std::path::PathBuf;

fn main() {
    let manifest = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets it"));
    let mut layout = state_layout::Fingerprint::of_sources();
    // The serialized state's encoding also follows the dependencies (serde, postcard).
    layout.add_text_file(&manifest.join("..").join("Cargo.lock"));
    println!("cargo::rustc-env=VEHICLE_STATE_LAYOUT={}", layout.hex());
    let mut guid = layout;
    guid.add(env!("CARGO_PKG_VERSION").as_bytes());
    for file in ["ml95.toml", "manchester.toml"] {
        guid.add_text_file(&manifest.join("resources").join(file));
    }
    for dep in ["fmi-abi", "modelDescription"] {
        guid.add_crate(&manifest.join("..").join(dep));
    }
    println!("cargo::rustc-env=VEHICLE_GUID={}", guid.guid());
}
