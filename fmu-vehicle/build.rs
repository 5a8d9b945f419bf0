//! Fingerprints the sources (`VEHICLE_STATE_LAYOUT`, see the `state-layout` crate): the FMU
//! writes it into its serialized states, so that a state saved by another build, whose internal
//! layout may differ, is refused with a message instead of being decoded into wrong values.

fn main() {
    let layout = state_layout::Fingerprint::of_sources();
    println!("cargo::rustc-env=VEHICLE_STATE_LAYOUT={}", layout.hex());
}
