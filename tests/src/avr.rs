//! The ATmega328P firmware in simavr (through avr-tester): build it, replay
//! recorded traces through its planner, read its size.

use crate::{repo_root, Frame};
use avr_tester::AvrTester;
use planner_core::{Angle, Command, Output, Point, Status};
use std::path::PathBuf;
use std::process::Command as Cmd;
use std::sync::Mutex;

/// CPU clock of the board, Hz.
pub const F_CPU: u32 = 16_000_000;

static BUILT: Mutex<Option<PathBuf>> = Mutex::new(None);

/// A command for `cargo` in `dir` that uses that folder's own toolchain
/// file and config, not the ones of the cargo that runs these tests.
pub fn clean_cargo(dir: &std::path::Path) -> Cmd {
    let mut c = Cmd::new("cargo");
    c.current_dir(dir);
    for (k, _) in std::env::vars_os() {
        let k = k.to_string_lossy().to_string();
        let inherited = k == "CARGO"
            || (k.starts_with("CARGO_") && k != "CARGO_HOME")
            || k.starts_with("RUSTC")
            || k.starts_with("RUSTDOC")
            || k == "RUSTUP_TOOLCHAIN"
            || k == "RUSTFLAGS";
        if inherited {
            c.env_remove(&k);
        }
    }
    c
}

/// Build the firmware (release) once per process; the ELF path.
pub fn firmware_elf() -> PathBuf {
    let mut built = BUILT.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(p) = built.as_ref() {
        return p.clone();
    }
    let dir = repo_root().join("firmware-avr");
    let status = clean_cargo(&dir)
        .args(["build", "--release", "--quiet"])
        .status()
        .expect("run cargo for firmware-avr");
    assert!(status.success(), "firmware-avr build failed");
    let elf = dir.join("target/avr-none/release/firmware-avr.elf");
    *built = Some(elf.clone());
    elf
}

/// Section sizes of an AVR ELF: (text, data, bss), from `avr-size` (binutils
/// for AVR, installed with gcc-avr) in Berkeley format.
pub fn elf_size(elf: &std::path::Path) -> (u32, u32, u32) {
    let out = Cmd::new("avr-size")
        .arg(elf)
        .output()
        .expect("avr-size (Debian gcc-avr/binutils-avr)");
    let text = String::from_utf8_lossy(&out.stdout);
    crate::parse_size(&text).unwrap_or_else(|| panic!("avr-size output: {text}"))
}

/// The firmware running in simavr at 16 MHz.
pub struct Avr {
    /// The emulator.
    pub avr: AvrTester,
    rx: Vec<u8>,
}

impl Avr {
    /// Boot the firmware and wait for its `READY` line.
    pub fn boot() -> Avr {
        let avr = AvrTester::atmega328p()
            .with_clock(F_CPU)
            .load(firmware_elf());
        let mut a = Avr {
            avr,
            rx: Vec::new(),
        };
        let line = a.read_line(200);
        assert_eq!(line.as_deref(), Some("READY"), "boot line");
        a
    }

    /// Run the emulator for `us` microseconds, collecting serial output.
    pub fn run_us(&mut self, us: u64) {
        self.avr.run_for_us(us);
        while let Some(b) = self.avr.uart0().read::<Option<u8>>() {
            self.rx.push(b);
        }
    }

    /// Send bytes on the serial line.
    pub fn send(&mut self, bytes: &[u8]) {
        self.avr.uart0().write(bytes);
    }

    /// The next line received within `ms` emulated milliseconds.
    pub fn read_line(&mut self, ms: u64) -> Option<String> {
        for _ in 0..ms * 10 {
            if let Some(i) = self.rx.iter().position(|&b| b == b'\n') {
                let line: Vec<u8> = self.rx.drain(..=i).collect();
                return Some(String::from_utf8_lossy(&line).trim_end().to_string());
            }
            self.run_us(100);
        }
        None
    }

    /// `n` raw bytes received within `ms` emulated milliseconds.
    pub fn read_bytes(&mut self, n: usize, ms: u64) -> Option<Vec<u8>> {
        for _ in 0..ms * 10 {
            if self.rx.len() >= n {
                return Some(self.rx.drain(..n).collect());
            }
            self.run_us(100);
        }
        None
    }

    /// A command line and its one-line reply.
    pub fn request(&mut self, line: &str) -> Option<String> {
        self.send(format!("{line}\n").as_bytes());
        self.read_line(100)
    }

    /// Replay frames toward `goal` in the firmware's replay mode: its
    /// outputs and the cycles of each planner step.
    pub fn replay(&mut self, goal: Point, frames: &[Frame]) -> Vec<(Output, u32)> {
        let ok = self.request(&format!("R {} {}", goal.x, goal.y));
        assert_eq!(ok.as_deref(), Some("OK"), "enter replay");
        let mut got = Vec::new();
        for (k, f) in frames.iter().enumerate() {
            let mut msg = vec![0xa5];
            msg.extend(f.pose.position.x.to_le_bytes());
            msg.extend(f.pose.position.y.to_le_bytes());
            msg.extend(f.pose.heading.0.to_le_bytes());
            for r in f.raw {
                msg.extend(r.to_le_bytes());
            }
            self.send(&msg);
            let r = self.read_bytes(10, 500).expect("replay answer");
            assert_eq!(
                r[0],
                0x5a,
                "replay answer header, frame {k}: {r:?} then {:?}",
                String::from_utf8_lossy(&self.rx)
            );
            let status = Status::from_code(r[5]).expect("status code");
            let out = Output {
                command: Command {
                    heading: Angle(u16::from_le_bytes([r[1], r[2]])),
                    step_mm: u16::from_le_bytes([r[3], r[4]]),
                },
                status,
            };
            got.push((out, u32::from_le_bytes([r[6], r[7], r[8], r[9]])));
        }
        self.send(&[0x00]);
        assert_eq!(self.read_line(100).as_deref(), Some("OK"), "leave replay");
        got
    }
}
