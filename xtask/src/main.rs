//! Project tasks: `cargo xtask ci` runs every check the project has (the
//! README's test command); `cargo xtask avr-report` and `cargo xtask
//! stm32-report` print the firmware figures, `cargo xtask avr-profile` and
//! `cargo xtask stm32-profile` where the AVR step spends its cycles and the
//! STM32 step its instructions; `cargo xtask results` writes
//! `docs/results.md`, every planner on every set of worlds; `cargo xtask
//! fuzz` runs the fuzz targets for long (`ci` runs each briefly).
//!
//! `ci` installs what it needs on a fresh Debian machine of the project's
//! kind: rustup targets and components always, Debian packages when it runs
//! as root (otherwise it stops and prints the exact command to run).

use std::path::{Path, PathBuf};
use std::process::{exit, Command};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("xtask lives one level below the workspace root")
        .to_path_buf()
}

/// Run a command in `dir`, echoing it; exit on failure.
fn run(dir: &Path, cmd: &str, args: &[&str], envs: &[(&str, &str)]) {
    eprintln!("\n==> {cmd} {}", args.join(" "));
    let status = Command::new(cmd)
        .args(args)
        .current_dir(dir)
        .envs(envs.iter().copied())
        // The firmware workspaces pick their own toolchains; do not leak ours.
        .env_remove("RUSTUP_TOOLCHAIN")
        .env_remove("CARGO")
        .status()
        .unwrap_or_else(|e| {
            eprintln!("xtask: cannot start {cmd}: {e}");
            exit(1)
        });
    if !status.success() {
        eprintln!("xtask: `{cmd} {}` failed ({status})", args.join(" "));
        exit(1);
    }
}

fn output(cmd: &str, args: &[&str]) -> String {
    Command::new(cmd)
        .args(args)
        .env_remove("RUSTUP_TOOLCHAIN")
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).into_owned())
        .unwrap_or_default()
}

const DEBIAN_PACKAGES: &[&str] = &[
    "gcc-avr",
    "avr-libc",
    "simavr",
    "qemu-system-arm",
    "libclang-dev",
    "libelf-dev",
    "libzstd-dev",
    "pkg-config",
    "zlib1g-dev",
];

/// Make sure the toolchains, targets, components and Debian packages exist.
fn ensure_tools() {
    let dir = root();
    let targets = output(
        "rustup",
        &["target", "list", "--installed", "--toolchain", "stable"],
    );
    if !targets.contains("thumbv7em-none-eabihf") {
        run(
            &dir,
            "rustup",
            &[
                "target",
                "add",
                "thumbv7em-none-eabihf",
                "--toolchain",
                "stable",
            ],
            &[],
        );
    }
    let comps = output(
        "rustup",
        &["component", "list", "--installed", "--toolchain", "stable"],
    );
    for c in ["rustfmt", "clippy", "llvm-tools"] {
        if !comps.contains(c) {
            run(
                &dir,
                "rustup",
                &["component", "add", c, "--toolchain", "stable"],
                &[],
            );
        }
    }
    let nightly = output(
        "rustup",
        &["component", "list", "--installed", "--toolchain", "nightly"],
    );
    if nightly.is_empty() {
        eprintln!(
            "xtask: the `nightly` toolchain is missing; run: rustup toolchain install nightly"
        );
        exit(1);
    }
    for c in ["rust-src", "llvm-tools"] {
        if !nightly.contains(c) {
            run(
                &dir,
                "rustup",
                &["component", "add", c, "--toolchain", "nightly"],
                &[],
            );
        }
    }
    // Cargo-installed tools, each checked by running it: `cargo size`
    // reads the firmware images' sizes (the firmware READMEs' command; the
    // tests check it against avr-size and llvm-size), cargo-fuzz runs the
    // fuzz targets (fuzz/), defmt-print decodes the emulated STM32
    // firmware's log.
    for (cmd, args, krate) in [
        ("cargo", &["size", "--version"][..], "cargo-binutils"),
        ("cargo", &["fuzz", "--version"][..], "cargo-fuzz"),
        ("defmt-print", &["--version"][..], "defmt-print"),
    ] {
        if output(cmd, args).is_empty() {
            run(
                &dir,
                "cargo",
                &["+stable", "install", "--locked", krate],
                &[],
            );
        }
    }
    let missing: Vec<&str> = DEBIAN_PACKAGES
        .iter()
        .copied()
        .filter(|p| {
            !Command::new("dpkg")
                .args(["-s", p])
                .output()
                .map(|o| o.status.success())
                .unwrap_or(false)
        })
        .collect();
    if !missing.is_empty() {
        let is_root = output("id", &["-u"]).trim() == "0";
        if !is_root {
            eprintln!(
                "xtask: missing Debian packages; run:\n  sudo apt-get update && sudo apt-get install -y --no-install-recommends {}",
                missing.join(" ")
            );
            exit(1);
        }
        run(&dir, "apt-get", &["update", "-qq"], &[]);
        let mut args = vec!["install", "-y", "-qq", "--no-install-recommends"];
        args.extend(missing.iter().copied());
        run(
            &dir,
            "apt-get",
            &args,
            &[("DEBIAN_FRONTEND", "noninteractive")],
        );
    }
}

/// planner-core for the two MCU targets.
fn cross_builds() {
    let dir = root();
    run(
        &dir,
        "cargo",
        &[
            "+stable",
            "build",
            "--release",
            "-p",
            "planner-core",
            "--features",
            "hal02",
            "--target",
            "thumbv7em-none-eabihf",
        ],
        &[],
    );
    run(
        &dir,
        "cargo",
        &[
            "+nightly",
            "build",
            "--release",
            "-p",
            "planner-core",
            "--target",
            "avr-none",
            "-Zbuild-std=core",
            "--target-dir",
            "target/avr",
        ],
        &[("RUSTFLAGS", "-C target-cpu=atmega328p")],
    );
}

fn ci() {
    // CI builds each crate once: no incremental caches (they took 600 MB of
    // its disk).
    std::env::set_var("CARGO_INCREMENTAL", "0");
    ensure_tools();
    let dir = root();
    run(&dir, "cargo", &["+stable", "fmt", "--all", "--check"], &[]);
    run(
        &dir,
        "cargo",
        &[
            "+stable",
            "clippy",
            "--workspace",
            "--all-targets",
            "--",
            "-D",
            "warnings",
        ],
        &[],
    );
    for fw in ["firmware-avr", "firmware-stm32", "fuzz"] {
        let manifest = format!("{fw}/Cargo.toml");
        if dir.join(&manifest).exists() {
            run(
                &dir,
                "cargo",
                &["+stable", "fmt", "--check", "--manifest-path", &manifest],
                &[],
            );
        }
    }
    run(
        &dir.join("firmware-avr"),
        "cargo",
        &["clippy", "--release", "--", "-D", "warnings"],
        &[],
    );
    // The API docs build without warnings (broken or private links).
    run(
        &dir,
        "cargo",
        &["+stable", "doc", "--workspace", "--no-deps", "--quiet"],
        &[("RUSTDOCFLAGS", "-D warnings")],
    );
    // The host tests include the emulated firmware tests (they build the
    // firmware themselves).
    run(&dir, "cargo", &["+stable", "test", "--workspace"], &[]);
    cross_builds();
    // Each fuzz target for a short, fixed number of inputs: a smoke test.
    fuzz(&["-runs=20000"]);
    eprintln!("\nxtask ci: all checks passed");
}

/// The cargo-fuzz targets in `fuzz/` (nightly, with the address sanitizer).
const FUZZ_TARGETS: [&str; 3] = ["planner_step", "line_reader", "scenario"];

/// Every fuzz target in turn with libFuzzer's `options`; each prints
/// `Done N runs in S second(s)` and stops at the first failure, which it
/// writes to `fuzz/artifacts/<target>/`.
fn fuzz(options: &[&str]) {
    for target in FUZZ_TARGETS {
        let mut args = vec!["+nightly", "fuzz", "run", target, "--"];
        args.extend_from_slice(options);
        run(&root(), "cargo", &args, &[]);
    }
}

/// `cargo run --release -p PACKAGE ARGS…` with the arguments after the
/// task's name appended.
fn cargo_run(args: &[&str]) {
    let mut all = vec!["+stable", "run", "--quiet", "--release"];
    all.extend_from_slice(args);
    let extra: Vec<String> = std::env::args().skip(2).collect();
    all.extend(extra.iter().map(String::as_str));
    run(&root(), "cargo", &all, &[]);
}

/// Firmware figures, measured now: `avr-report` (simavr) or `stm32-report`
/// (QEMU), binaries of the tests crate.
fn report(bin: &str) {
    cargo_run(&["-p", "rover-tests", "--bin", bin, "--"]);
}

/// The results page: `sim-host results` (every planner on every set).
fn results() {
    cargo_run(&["-p", "sim-host", "--", "results"]);
}

fn main() {
    let task = std::env::args().nth(1).unwrap_or_default();
    match task.as_str() {
        "ci" => ci(),
        "cross" => cross_builds(),
        "avr-report" => report("avr-report"),
        "stm32-report" => report("stm32-report"),
        "avr-profile" => report("avr-profile"),
        "avr-size" => report("avr-size"),
        "stm32-profile" => report("stm32-profile"),
        "results" => results(),
        "faults" => cargo_run(&["-p", "sim-host", "--", "faults"]),
        "failures" => cargo_run(&["-p", "sim-host", "--", "failures"]),
        "fuzz" => {
            // Ten minutes a target unless told otherwise (libFuzzer options).
            let options: Vec<String> = std::env::args().skip(2).collect();
            let options: Vec<&str> = match options.is_empty() {
                true => vec!["-max_total_time=600"],
                false => options.iter().map(String::as_str).collect(),
            };
            fuzz(&options);
        }
        _ => {
            eprintln!(
                "usage: cargo xtask <ci|cross|results|faults|failures|fuzz|avr-report|stm32-report|avr-profile|avr-size|stm32-profile>"
            );
            eprintln!(
                "  ci     every check: fmt, clippy, tests, cross builds (installs what it needs)"
            );
            eprintln!("  cross  planner-core for thumbv7em-none-eabihf and avr-none");
            eprintln!("  results       write docs/results.md: every planner on every set (sim-host results)");
            eprintln!("  faults        write docs/faults.md: eapf under each fault on every still set (sim-host faults)");
            eprintln!("  failures      write docs/failures.md: each world eapf fails, with its replay (sim-host failures)");
            eprintln!("  fuzz          each fuzz target for ten minutes (or the libFuzzer options given, e.g. -runs=1000000)");
            eprintln!("  avr-report    firmware-avr size and step cycles (simavr)");
            eprintln!("  stm32-report  firmware-stm32 size and step instructions (QEMU)");
            eprintln!("  avr-profile   where firmware-avr's step spends its cycles (simavr)");
            eprintln!(
                "  avr-size      where firmware-avr's flash goes, by part (--set-back: that build)"
            );
            eprintln!("  stm32-profile where firmware-stm32's step spends its instructions (QEMU; --set-back: the build for sensors set back)");
            exit(2);
        }
    }
}
