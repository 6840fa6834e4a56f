//! The `replay` binary: the firmware's planner behind the replay protocol
//! (`R x y`, then frames; `planner_core::rover::protocol`), each guard look and
//! step timed in cycles, and `M` for the stack's peak. The emulator tests
//! replay recorded traces through it, bit for bit against the host, and
//! time them; the production image (`firmware-avr`) does not carry it. It
//! drives no motors and samples no sensors.
#![no_std]
#![no_main]
#![feature(abi_avr_interrupt)]

#[path = "../bench.rs"]
mod bench;
#[path = "../board.rs"]
#[allow(dead_code)]
mod board;
#[path = "../clock.rs"]
#[allow(dead_code)]
mod clock;
#[path = "../progmem.rs"]
mod progmem;
#[path = "../replay.rs"]
mod replay;
#[path = "../serial.rs"]
#[allow(dead_code)]
mod serial;
#[path = "../stack.rs"]
mod stack;
#[path = "../timed.rs"]
mod timed;

use core::sync::atomic::{compiler_fence, Ordering};
use planner_core::rover::protocol::{self, Request};
use planner_core::{Config, Guard, Output, Planner, Point, Pose, RawCounts};
use ufmt::uwriteln;

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    bench::halt()
}

/// The guard looks and steps run with interrupts off, so that their cycle
/// counts are theirs alone: a Timer1 overflow interrupt (47 cycles) or a
/// received byte (146) inside the span would be counted too, depending on
/// when the harness's bytes arrived. The clock still reads exactly: one
/// overflow pending while interrupts are off is counted by
/// `clock::Stamp::cycles`. A span of 65,536 cycles or more can hide a
/// second one; the lap flag (`clock::arm_lap`) catches it, and the span is
/// answered [`replay::UNTIMED`] (the profiler's own count checks the rest,
/// `tests/tests/avr_profile.rs`).
struct Timed<'a>(&'a mut Planner);

/// `span` with interrupts off and the lap flag armed: its result and
/// cycles, or [`replay::UNTIMED`] if it came round.
fn lap_checked<T>(span: impl FnOnce() -> (T, u32)) -> (T, u32) {
    avr_device::interrupt::free(|_| {
        clock::arm_lap();
        let (t, cycles) = span();
        (
            t,
            if clock::lapped() {
                replay::UNTIMED
            } else {
                cycles
            },
        )
    })
}

impl replay::Replay for Timed<'_> {
    fn guard(&mut self, raw: &RawCounts, remaining_mm: u16) -> (Guard, u32) {
        lap_checked(|| {
            let t0 = clock::stamp();
            compiler_fence(Ordering::SeqCst);
            let g = self.0.guard_raw(
                core::hint::black_box(raw),
                core::hint::black_box(remaining_mm),
            );
            let g = core::hint::black_box(g);
            compiler_fence(Ordering::SeqCst);
            let t1 = clock::stamp();
            (g, t1.cycles().wrapping_sub(t0.cycles()))
        })
    }
    fn step(&mut self, pose: Pose, raw: &RawCounts) -> (Output, u32) {
        lap_checked(|| timed::step(self.0, pose, raw))
    }
}

#[avr_device::entry]
fn main() -> ! {
    stack::paint();
    bench::init();
    // Built in place and loaded out of flash, as the firmware does.
    let mut planner = Planner::new(Config::UNSET, Point::new(0, 0));
    planner.load_config(progmem::load_config);
    let mut out = bench::Serial;
    let _ = uwriteln!(out, "READY");
    let mut lines = protocol::LineReader::new();
    loop {
        // No millisecond clock here: no line goes stale.
        let Some(req) = lines.feed(serial::read_blocking(), 0) else {
            continue;
        };
        match req {
            Some(Request::Replay(x, y)) => {
                let _ = uwriteln!(out, "OK");
                planner.set_goal(Point::new(x, y));
                replay::serve(&mut Timed(&mut planner));
                let _ = uwriteln!(out, "OK");
            }
            Some(Request::Memory) => {
                let _ = uwriteln!(out, "M stack_peak={}", stack::peak() as u32);
            }
            _ => {
                let _ = uwriteln!(out, "ERR");
            }
        }
    }
}
