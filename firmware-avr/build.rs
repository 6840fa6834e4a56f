//! Links avr-gcc's own 32-bit division and avr-libc's memory copies in place
//! of compiler-builtins' generic ones.
//!
//! compiler-builtins defines `__divmodsi4` / `__udivmodsi4` for AVR as weak
//! symbols around a generic Rust long division (about 1,575 cycles per i32
//! division, `avr_costs`). Its `memcpy` / `memmove` / `memset` are weak
//! too, and word-at-a-time loops written for wider machines; avr-libc's
//! byte loops in assembly copy the planner's small structs (readings, point
//! lists) faster and are smaller (docs/performance.md).
//! An archive member is only pulled in for an undefined symbol, and the weak
//! ones are already defined, so the object files (with `__negsi2`, which
//! `__divmodsi4` calls) are extracted and passed to the linker directly;
//! their strong definitions win. Same calling convention (LLVM's AVR backend
//! calls these with avr-gcc's), same results (C's truncating division, as
//! Rust's; the C library's copies).
//!
//! The unsigned division (`asm/udivmodsi4.S`) and the 32-bit multiply
//! (`asm/mulsi3.S`) are the firmware's own, assembled here by avr-gcc with
//! libgcc's calling convention; each file's header says how it differs
//! from libgcc's (shorter ways for the operands the planner mostly has).
//! libgcc's signed division calls the unsigned one.
use std::{env, path::PathBuf, process::Command};

/// (what `avr-gcc -print-file-name` is asked for, the members taken from it)
const ARCHIVES: [(&str, &[&str]); 2] = [
    ("-print-libgcc-file-name", &["_divmodsi4.o", "_negsi2.o"]),
    (
        "-print-file-name=libc.a",
        &["memcpy.o", "memmove.o", "memset.o"],
    ),
];

/// Our own routines (`asm/NAME.S`), linked in place of libgcc's.
const ASSEMBLED: [&str; 2] = ["udivmodsi4", "mulsi3"];

/// What to run when avr-gcc or one of its libraries is missing.
const INSTALL: &str =
    "apt-get update && apt-get install -y --no-install-recommends gcc-avr avr-libc";

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    if env::var("CARGO_CFG_TARGET_ARCH").as_deref() != Ok("avr") {
        return;
    }
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    for (ask, members) in ARCHIVES {
        let archive = Command::new("avr-gcc")
            .args(["-mmcu=atmega328p", ask])
            .output()
            .unwrap_or_else(|e| panic!("avr-gcc not found ({e}): {INSTALL}"));
        let archive = String::from_utf8(archive.stdout).expect("avr-gcc printed a path");
        run(Command::new("avr-ar")
            .arg("x")
            .arg(archive.trim())
            .args(members)
            .current_dir(&out));
        for member in members {
            println!("cargo:rustc-link-arg={}", out.join(member).display());
        }
    }
    // Our routines as a static library, which the linker reads before
    // libgcc (link-arg objects come after it, and an object defining a
    // symbol that libgcc already gave would clash).
    let mut objects = Vec::new();
    for name in ASSEMBLED {
        let source = format!("asm/{name}.S");
        println!("cargo:rerun-if-changed={source}");
        let object = out.join(format!("{name}.o"));
        run(Command::new("avr-gcc")
            .args(["-mmcu=atmega328p", "-c", &source, "-o"])
            .arg(&object));
        objects.push(object);
    }
    let archive = out.join("libroverasm.a");
    let _ = std::fs::remove_file(&archive);
    run(Command::new("avr-ar")
        .arg("rcs")
        .arg(&archive)
        .args(&objects));
    println!("cargo:rustc-link-search=native={}", out.display());
    println!("cargo:rustc-link-lib=static=roverasm");
}

/// Run one of avr-gcc's tools; stop the build with what to install if it
/// is missing or fails.
fn run(cmd: &mut Command) {
    let status = cmd
        .status()
        .unwrap_or_else(|e| panic!("{cmd:?}: {e}: {INSTALL}"));
    assert!(status.success(), "{cmd:?} failed: {INSTALL}");
}
