//! Empty: it exists so that the `[build-dependencies]` of Cargo.toml (compiled for it, in the
//! proc macros' feature domain) unify the FMU build's `syn` with the test build's.

fn main() {}
