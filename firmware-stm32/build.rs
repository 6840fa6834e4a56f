//! Feeds the top-level `memory.x` (STM32F411: 384 of its 512 KB of flash for
//! the program, 128 KB RAM) to
//! cortex-m-rt's `link.x`, and, for the QEMU build, the recorded input trace
//! named by `ROVER_TRACE` (empty when unset).

use std::path::PathBuf;
use std::{env, fs};

fn main() {
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("OUT_DIR"));
    let memory = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../memory.x");
    fs::copy(&memory, out.join("memory.x")).expect("copy ../memory.x");
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed=../memory.x");

    let trace = match env::var_os("ROVER_TRACE") {
        Some(p) => fs::read(&p).expect("read ROVER_TRACE"),
        None => Vec::new(),
    };
    fs::write(out.join("trace.bin"), trace).expect("write trace.bin");
    println!("cargo:rerun-if-env-changed=ROVER_TRACE");
    if let Some(p) = env::var_os("ROVER_TRACE") {
        println!("cargo:rerun-if-changed={}", PathBuf::from(p).display());
    }
}
