//! Compiles the C shim for the variadic fmi2CallbackLogger (see csrc/logger.c and the crate docs).

fn main() {
    println!("cargo:rerun-if-changed=csrc/logger.c");
    cc::Build::new()
        .file("csrc/logger.c")
        .warnings(true)
        .extra_warnings(true)
        .compile("fmi_import_logger");
}
