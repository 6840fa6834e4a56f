//! The STM32 firmware's `qemu` build in `qemu-system-arm -M netduinoplus2`:
//! build it with a recorded trace compiled in, run it, decode its defmt log
//! with `defmt-print`, and read back its commands and step counts.

use crate::{clean_cargo, repo_root, Answer, Trace};
use planner_core::{Angle, Command, Output, Status};
use std::io::Write;
use std::path::PathBuf;
use std::process::{Command as Cmd, Stdio};

/// QEMU's netduinoplus2 CPU clock, which SysTick counts: 168 MHz.
pub const QEMU_SYSCLK_MHZ: u32 = 168;

/// The trace file format of `firmware-stm32/src/emulated.rs`.
pub fn encode(traces: &[Trace]) -> Vec<u8> {
    let mut b = Vec::new();
    for t in traces {
        b.extend(t.goal.x.to_le_bytes());
        b.extend(t.goal.y.to_le_bytes());
        b.extend((t.frames.len() as u16).to_le_bytes());
        for f in &t.frames {
            b.extend((f.guards.len() as u16).to_le_bytes());
            f.encode_le(&mut b);
        }
    }
    b
}

/// The real-board build (default features); the ELF path.
pub fn board_elf() -> PathBuf {
    let dir = repo_root().join("firmware-stm32");
    let ok = clean_cargo(&dir)
        .args(["build", "--release", "--quiet"])
        .status()
        .expect("cargo for firmware-stm32")
        .success();
    assert!(ok, "firmware-stm32 board build failed");
    dir.join("target/thumbv7em-none-eabihf/release/firmware-stm32")
}

/// Section sizes (text, data, bss) of an ARM ELF, from `llvm-size` of the
/// stable toolchain's llvm-tools or, failing that, `size` (GNU binutils).
pub fn elf_size(elf: &std::path::Path) -> (u32, u32, u32) {
    let sysroot = Cmd::new("rustc")
        .args(["+stable", "--print", "sysroot"])
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_default();
    let llvm_size =
        PathBuf::from(sysroot).join("lib/rustlib/x86_64-unknown-linux-gnu/bin/llvm-size");
    let tool = if llvm_size.exists() {
        llvm_size
    } else {
        PathBuf::from("size")
    };
    let out = Cmd::new(&tool)
        .arg(elf)
        .output()
        .expect("llvm-size or size");
    let text = String::from_utf8_lossy(&out.stdout);
    crate::parse_size(&text).unwrap_or_else(|| panic!("{} output: {text}", tool.display()))
}

/// What the emulated firmware reported.
#[derive(Debug)]
pub struct QemuRun {
    /// `(loop instructions, SysTick ticks)` of the calibration loop.
    pub calibration: (u32, u32),
    /// Answer and SysTick ticks of each step, all segments in order.
    pub steps: Vec<(Answer, u32)>,
}

/// The `qemu` build's ELF (as [`run_traces`] last built it).
pub fn qemu_elf() -> PathBuf {
    qemu_elf_with(false)
}

/// The `qemu` build's ELF with the sensors on the rim, or `set_back` (as
/// [`run_traces_with`] last built it).
pub fn qemu_elf_with(set_back: bool) -> PathBuf {
    qemu_elf_in(qemu_build(set_back).1)
}

/// The `qemu` build's features and target folder: the sensors on the rim,
/// or `set_back`.
fn qemu_build(set_back: bool) -> (&'static str, &'static str) {
    if set_back {
        ("qemu,set-back", QEMU_SET_BACK_TARGET)
    } else {
        ("qemu", QEMU_TARGET)
    }
}

/// Where the `qemu` build goes: the sensors on the rim, and set back.
const QEMU_TARGET: &str = "target/qemu";
const QEMU_SET_BACK_TARGET: &str = "target/qemu-set-back";

fn qemu_elf_in(target_dir: &str) -> PathBuf {
    let elf = "thumbv7em-none-eabihf/release/firmware-stm32";
    repo_root()
        .join("firmware-stm32")
        .join(target_dir)
        .join(elf)
}

/// QEMU for the netduinoplus2 running `elf`, instructions counted
/// (`-icount shift=0`), semihosting on (the defmt log on stdout, and the
/// exit).
pub fn qemu_command(elf: &std::path::Path) -> Cmd {
    let mut qemu = Cmd::new("qemu-system-arm");
    qemu.args([
        "-M",
        "netduinoplus2",
        "-nographic",
        "-monitor",
        "none",
        "-serial",
        "none",
        "-semihosting-config",
        "enable=on,target=native",
        "-icount",
        "shift=0",
    ])
    .arg("-kernel")
    .arg(elf);
    qemu
}

impl QemuRun {
    /// Steps whose answer differs from the host core's in `traces` (and
    /// steps one side has and the other has not).
    pub fn mismatches(&self, traces: &[Trace]) -> usize {
        let want: Vec<_> = traces.iter().flat_map(|t| t.outputs.iter()).collect();
        let differ = (self.steps.iter().zip(&want))
            .filter(|((got, _), w)| got != **w)
            .count();
        differ + want.len().abs_diff(self.steps.len())
    }
}

/// Build the `qemu` firmware with `traces` compiled in and run it.
pub fn run_traces(traces: &[Trace]) -> QemuRun {
    run_traces_with(traces, false)
}

/// [`run_traces`] for the firmware built with the sensors on the rim, or
/// `set_back` behind it (its `set-back` feature; in its own target folder,
/// so that the two builds do not undo each other).
pub fn run_traces_with(traces: &[Trace], set_back: bool) -> QemuRun {
    let (features, target_dir) = qemu_build(set_back);
    let dir = repo_root().join("firmware-stm32");
    let trace_path = dir.join(format!("{target_dir}-trace.bin"));
    std::fs::create_dir_all(dir.join("target")).expect("target dir");
    std::fs::write(&trace_path, encode(traces)).expect("write trace");
    let ok = clean_cargo(&dir)
        .args([
            "build",
            "--release",
            "--quiet",
            "--no-default-features",
            "--features",
            features,
            "--target-dir",
            target_dir,
        ])
        .env("ROVER_TRACE", &trace_path)
        .status()
        .expect("cargo for firmware-stm32")
        .success();
    assert!(ok, "firmware-stm32 qemu build failed");
    let elf = qemu_elf_in(target_dir);
    let qemu = qemu_command(&elf)
        .stdin(Stdio::null())
        .output()
        .expect("qemu-system-arm (Debian qemu-system-arm)");
    assert!(
        qemu.status.success(),
        "qemu: {}",
        String::from_utf8_lossy(&qemu.stderr)
    );
    let mut print = Cmd::new("defmt-print")
        .arg("-e")
        .arg(&elf)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .expect("defmt-print (cargo install defmt-print)");
    print
        .stdin
        .take()
        .expect("stdin")
        .write_all(&qemu.stdout)
        .expect("feed defmt-print");
    let log = print.wait_with_output().expect("defmt-print output");
    let text = String::from_utf8_lossy(&log.stdout);
    let mut run = QemuRun {
        calibration: (0, 0),
        steps: Vec::new(),
    };
    let mut done = false;
    for line in text.lines() {
        let f: Vec<&str> = line.split_whitespace().collect();
        let num = |i: usize| f.get(i).and_then(|v| v.parse::<u32>().ok()).unwrap_or(0);
        match f.get(1).copied() {
            Some("calibration") => run.calibration = (2 * (num(2) + 1), num(3)),
            Some("step") => {
                let status = Status::from_code(num(4) as u8).expect("status code");
                let out = Output {
                    command: Command {
                        heading: Angle(num(2) as u16),
                        step_mm: num(3) as u16,
                    },
                    status,
                };
                let answer = Answer {
                    guard_stops: num(6) as u8,
                    output: out,
                };
                run.steps.push((answer, num(5)));
            }
            Some("done") => done = true,
            _ => {}
        }
    }
    assert!(done, "the emulated firmware did not finish:\n{text}");
    run
}

/// SysTick ticks to instructions: with `-icount shift=0` each instruction
/// takes 1 ns of virtual time, and SysTick counts the 168 MHz CPU clock.
pub fn instructions(ticks: u32) -> u32 {
    ((ticks as u64 * 1_000 + QEMU_SYSCLK_MHZ as u64 / 2) / QEMU_SYSCLK_MHZ as u64) as u32
}
