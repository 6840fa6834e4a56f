//! Replay mode's frame loop (protocol in `planner_core::rover::protocol`): read
//! the guard's samples and run the guard on each, read pose and raw counts,
//! run a timed planner step, answer with the command, status, cycle count,
//! the guard's verdicts and its costliest look's cycles, until a frame
//! starts with anything but `0xA5`.
//! Shared by the firmware and the `f32-step` bench.

use crate::{clock, serial};
use core::sync::atomic::{compiler_fence, Ordering};
use planner_core::{Angle, Guard, Output, Point, Pose, RawCounts};

/// The cycles answered for a span too long to time exactly (65,536 cycles
/// or more with interrupts off: `clock::arm_lap`).
pub const UNTIMED: u32 = u32::MAX;

/// A span's cycles less the timing's own, [`UNTIMED`] kept as it is.
fn less(cycles: u32, overhead: u32) -> u32 {
    if cycles == UNTIMED {
        UNTIMED
    } else {
        cycles.saturating_sub(overhead)
    }
}

/// What replay mode runs: a timed guard look on a sample, and a timed step.
pub trait Replay {
    /// The guard's verdict on raw counts with `remaining_mm` to go, and
    /// the cycles it took.
    fn guard(&mut self, raw: &RawCounts, remaining_mm: u16) -> (Guard, u32);
    /// A planner step: its output and the cycles it took.
    fn step(&mut self, pose: Pose, raw: &RawCounts) -> (Output, u32);
}

fn read_raw() -> RawCounts {
    let mut raw = [0u16; 5];
    for r in raw.iter_mut() {
        *r = serial::read_u16_le();
    }
    raw
}

/// Serve frames with `r`; the cost of the timing itself is subtracted
/// from the step's cycles ([`UNTIMED`] stays as it is).
pub fn serve(r: &mut impl Replay) {
    // With interrupts off: an interrupt here would make every step of
    // this replay read short (a received byte did: 146 cycles a step).
    let overhead = avr_device::interrupt::free(|_| {
        let t0 = clock::stamp();
        compiler_fence(Ordering::SeqCst);
        let t1 = clock::stamp();
        t1.cycles().wrapping_sub(t0.cycles())
    });
    while serial::read_blocking() == 0xa5 {
        let (mut stops, mut guard_worst) = (0u8, 0u32);
        for i in 0..serial::read_blocking() {
            let remaining = serial::read_u16_le();
            let raw = read_raw();
            let (verdict, cycles) = r.guard(&raw, remaining);
            if verdict == Guard::Stop {
                stops |= 1u8.wrapping_shl(i as u32);
            }
            guard_worst = guard_worst.max(less(cycles, overhead));
        }
        let x = serial::read_u16_le() as i16;
        let y = serial::read_u16_le() as i16;
        let heading = Angle(serial::read_u16_le());
        let raw = read_raw();
        let pose = Pose {
            position: Point::new(x, y),
            heading,
        };
        let (out, cycles) = r.step(pose, &raw);
        serial::write(0x5a);
        serial::write_all(&out.command.heading.0.to_le_bytes());
        serial::write_all(&out.command.step_mm.to_le_bytes());
        serial::write(out.status.code());
        serial::write_all(&less(cycles, overhead).to_le_bytes());
        serial::write(stops);
        serial::write_all(&guard_worst.to_le_bytes());
    }
}
