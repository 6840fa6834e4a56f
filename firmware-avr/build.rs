//! Links avr-gcc's own 32-bit division routines in place of compiler-builtins'.
//!
//! compiler-builtins defines `__divmodsi4` / `__udivmodsi4` for AVR as weak
//! symbols around a generic Rust long division (about 1,575 cycles per i32
//! division, measured in simavr); with libgcc's hand-written AVR versions the
//! planner's worst step went from 75,450 to 62,667 cycles (`cargo xtask
//! avr-report`). An archive member is only pulled in for an undefined
//! symbol, and the weak ones are already defined, so the object files (with
//! `__negsi2`, which `__divmodsi4` calls) are extracted and passed to the
//! linker directly; their strong definitions win.
//! Same calling convention (LLVM's AVR backend calls these with libgcc's), same
//! results (C's truncating division, as Rust's).
use std::{env, path::PathBuf, process::Command};

const MEMBERS: [&str; 3] = ["_divmodsi4.o", "_udivmodsi4.o", "_negsi2.o"];

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    if env::var("CARGO_CFG_TARGET_ARCH").as_deref() != Ok("avr") {
        return;
    }
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    let libgcc = Command::new("avr-gcc")
        .args(["-mmcu=atmega328p", "-print-libgcc-file-name"])
        .output()
        .expect("avr-gcc not found: apt-get update && apt-get install -y --no-install-recommends gcc-avr avr-libc");
    let libgcc = String::from_utf8(libgcc.stdout).expect("avr-gcc printed a path");
    let status = Command::new("avr-ar")
        .arg("x")
        .arg(libgcc.trim())
        .args(MEMBERS)
        .current_dir(&out)
        .status()
        .expect("avr-ar (binutils-avr) not found");
    assert!(
        status.success(),
        "avr-ar could not extract {MEMBERS:?} from {}",
        libgcc.trim()
    );
    for member in MEMBERS {
        println!("cargo:rustc-link-arg={}", out.join(member).display());
    }
}
