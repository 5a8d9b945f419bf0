//! Compiles the C shim for the variadic fmi2CallbackLogger (csrc/logger.c).

fn main() {
    println!("cargo:rerun-if-changed=csrc/logger.c");
    cc::Build::new()
        .file("csrc/logger.c")
        .warnings(true)
        .extra_warnings(true)
        .compile("fmi_fuzz_logger");
}
