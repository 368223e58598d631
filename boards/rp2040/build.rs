//! Puts memory.x where the linker (cortex-m-rt's link.x) finds it.
use std::path::PathBuf;

fn main() {
    let out = PathBuf::from(std::env::var_os("OUT_DIR").unwrap());
    std::fs::copy("memory.x", out.join("memory.x")).unwrap();
    println!("cargo:rerun-if-changed=memory.x");
    println!("cargo:rerun-if-env-changed=IMU_EMU_MODEL");
    println!("cargo:rerun-if-env-changed=IMU_EMU_SEED");
    println!("cargo:rustc-link-search={}", out.display());
}
