//! The `f32-step` bench: the same planner step in `f32` with `libm`
//! (`planner-float`), on the same MCU, in replay mode, so that the fixed-
//! point step's cycle count can be compared with a floating-point port.
//! It speaks the firmware's replay protocol (`R x y`, then frames) and
//! nothing else; it drives no motors.
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

use core::f32::consts::TAU;
use core::sync::atomic::{compiler_fence, Ordering};
use planner_core::rover::protocol::{self, Request};
use planner_core::{Angle, Command, Config, Guard, Output, Pose, RawCounts};
use planner_float::{FloatPlanner, Math};
use ufmt::uwriteln;

// avr-libc's math library (its `double` is 32-bit), as an Arduino sketch
// would use: compact assembly, unlike a Rust port of musl's.
#[link(name = "m")]
extern "C" {
    fn sin(x: f32) -> f32;
    fn cos(x: f32) -> f32;
    fn atan2(y: f32, x: f32) -> f32;
    fn hypot(x: f32, y: f32) -> f32;
    fn sqrt(x: f32) -> f32;
}

/// avr-libc as the float planner's math.
struct AvrLibc;

impl Math<f32> for AvrLibc {
    fn sin(x: f32) -> f32 {
        // SAFETY: pure functions of their arguments.
        unsafe { sin(x) }
    }
    fn cos(x: f32) -> f32 {
        // SAFETY: as above.
        unsafe { cos(x) }
    }
    fn atan2(y: f32, x: f32) -> f32 {
        // SAFETY: as above.
        unsafe { atan2(y, x) }
    }
    fn hypot(x: f32, y: f32) -> f32 {
        // SAFETY: as above.
        unsafe { hypot(x, y) }
    }
    fn sqrt(x: f32) -> f32 {
        // SAFETY: as above.
        unsafe { sqrt(x) }
    }
}

/// The float step behind the replay protocol. It has no flank points
/// (planner-float is the EAPF step alone), so the guard's samples only
/// need an answer. Its steps are timed with interrupts on, unlike the
/// firmware's: they run longer than the 65,536 cycles between two Timer1
/// overflows, which only the overflow interrupt counts, so each overflow's
/// 47 cycles are in a float step's count.
struct FloatReplay<'a> {
    planner: FloatPlanner<f32, AvrLibc>,
    cfg: &'a Config,
}

impl replay::Replay for FloatReplay<'_> {
    fn guard(&mut self, _: &RawCounts, _: u16) -> (Guard, u32) {
        (Guard::Continue, 0)
    }

    fn step(&mut self, pose: Pose, raw: &RawCounts) -> (Output, u32) {
        let (px, py) = (pose.position.x as f32, pose.position.y as f32);
        let h = pose.heading.signed() as f32 * (TAU / 65_536.0);
        let t0 = clock::stamp();
        compiler_fence(Ordering::SeqCst);
        let (fh, fs, status) = self.planner.step(
            self.cfg,
            core::hint::black_box(px),
            core::hint::black_box(py),
            core::hint::black_box(h),
            core::hint::black_box(raw),
        );
        let (fh, fs) = core::hint::black_box((fh, fs));
        compiler_fence(Ordering::SeqCst);
        let t1 = clock::stamp();
        let command = Command {
            heading: Angle((fh * (65_536.0 / TAU)) as i32 as u16),
            step_mm: fs as u16,
        };
        (
            Output { command, status },
            t1.cycles().wrapping_sub(t0.cycles()),
        )
    }
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    bench::halt()
}

#[avr_device::entry]
fn main() -> ! {
    let cfg = bench::start();
    let mut out = bench::Serial;
    let _ = uwriteln!(out, "READY");
    let mut lines = protocol::LineReader::new();
    loop {
        // No millisecond clock here (the bench stops the tick): no line
        // goes stale.
        let Some(req) = lines.feed(serial::read_blocking(), 0) else {
            continue;
        };
        let Some(Request::Replay(x, y)) = req else {
            let _ = uwriteln!(out, "ERR");
            continue;
        };
        let _ = uwriteln!(out, "OK");
        let planner = FloatPlanner::<f32, AvrLibc>::new((x as f32, y as f32), false);
        replay::serve(&mut FloatReplay { planner, cfg: &cfg });
        let _ = uwriteln!(out, "OK");
    }
}
