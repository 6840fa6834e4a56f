//! The QEMU build: replay a recorded trace (the guard's samples of each
//! advance, then pose and raw counts per step, compiled in from
//! `ROVER_TRACE`) through the planner, time each step with SysTick, log
//! command, count and the guard's verdicts with defmt over semihosting,
//! then exit QEMU. The host test decodes the log with `defmt-print` and
//! compares each answer with the host core's, bit for bit.
//!
//! Trace format (little-endian u16 words), one segment per recorded run:
//! goal x, y (i16), frame count, then frames of: the number of guard
//! samples, each as the step still to go and five raw counts; pose x, y
//! (i16), heading, five raw counts.
//!
//! What is counted: SysTick runs on the CPU clock (168 MHz in QEMU's
//! netduinoplus2); with `-icount shift=0` every instruction takes 1 ns of
//! virtual time, so instructions = ticks × 1000 / 168. The count covers
//! the call of `Planner::step` on the scripted source, minus the cost of
//! the two SysTick reads (measured on an empty region).

use core::sync::atomic::{compiler_fence, Ordering};
use cortex_m::peripheral::syst::SystClkSource;
use defmt_semihosting as _;
use planner_core::{Angle, Guard, Planner, Point, Pose, ScriptedSensors};

static TRACE: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/trace.bin"));

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    defmt::error!("panic");
    cortex_m_semihosting::debug::exit(cortex_m_semihosting::debug::EXIT_FAILURE);
    loop {
        cortex_m::asm::wfi();
    }
}

fn word(i: usize) -> u16 {
    match TRACE.get(i..i + 2) {
        Some(b) => u16::from_le_bytes([b[0], b[1]]),
        None => 0,
    }
}

/// SysTick's count. Out of line, so that `cargo xtask stm32-profile`
/// finds the timed spans in QEMU's instruction log: each lies between the
/// return from one call of this function and the entry of the next. The
/// call costs the same few instructions in every span, the empty one that
/// measures the overhead included.
#[inline(never)]
fn stamp() -> u32 {
    cortex_m::peripheral::SYST::get_current()
}

pub fn run() -> ! {
    let mut cp = cortex_m::Peripherals::take().unwrap_or_else(|| panic!());
    cp.SYST.set_clock_source(SystClkSource::Core);
    cp.SYST.set_reload(0x00ff_ffff);
    cp.SYST.clear_current();
    cp.SYST.enable_counter();
    let now = stamp;
    // SysTick counts down, 24 bits.
    let ticks = |t0: u32, t1: u32| t0.wrapping_sub(t1) & 0x00ff_ffff;
    let overhead = {
        let t0 = now();
        compiler_fence(Ordering::SeqCst);
        let t1 = now();
        ticks(t0, t1)
    };

    // Calibration: `asm::delay(n)` runs n + 1 iterations of a two-instruction
    // loop (`subs`, `bne`); the host checks that SysTick counted
    // 2(n + 1) · 168 / 1000 ticks for them.
    let t0 = now();
    cortex_m::asm::delay(100_000);
    let t1 = now();
    defmt::info!(
        "calibration {=u32} {=u32}",
        100_000,
        ticks(t0, t1).saturating_sub(overhead)
    );

    let mut planner = Planner::new(crate::CONFIG, Point::new(0, 0));
    let raw_at = |at: usize| core::array::from_fn::<u16, 5, _>(|i| word(at + 2 * i));
    // Segments: goal x, y (i16), frame count (u16), then the frames.
    let mut at = 0;
    while at + 6 <= TRACE.len() {
        let goal = Point::new(word(at) as i16, word(at + 2) as i16);
        let n = word(at + 4) as usize;
        at += 6;
        defmt::info!(
            "segment {=usize} frames, goal {=i16} {=i16}",
            n,
            goal.x,
            goal.y
        );
        planner.set_goal(goal);
        for _ in 0..n {
            let mut stops = 0u8;
            let samples = word(at) as u32;
            at += 2;
            for i in 0..samples {
                let remaining = word(at);
                let raw = raw_at(at + 2);
                at += 12;
                if planner.guard_raw(&raw, remaining) == Guard::Stop {
                    stops |= 1u8.wrapping_shl(i);
                }
            }
            let pose = Pose {
                position: Point::new(word(at) as i16, word(at + 2) as i16),
                heading: Angle(word(at + 4)),
            };
            let raw = [raw_at(at + 6)];
            at += 16;
            let mut sensors = ScriptedSensors::new(&raw);
            let t0 = now();
            compiler_fence(Ordering::SeqCst);
            let out = planner.step(core::hint::black_box(pose), &mut sensors);
            compiler_fence(Ordering::SeqCst);
            let t1 = now();
            let Ok(out) = out else {
                defmt::error!("trace ended early");
                break;
            };
            let t = ticks(t0, t1).saturating_sub(overhead);
            defmt::info!(
                "step {=u16} {=u16} {=u8} {=u32} {=u8}",
                out.command.heading.0,
                out.command.step_mm,
                out.status.code(),
                t,
                stops
            );
        }
    }
    defmt::info!("done");
    cortex_m_semihosting::debug::exit(cortex_m_semihosting::debug::EXIT_SUCCESS);
    loop {
        cortex_m::asm::wfi();
    }
}
