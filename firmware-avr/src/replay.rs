//! Replay mode's frame loop (protocol in `planner_core::protocol`): read
//! pose and raw counts, run a timed planner step, answer with the command,
//! status and cycle count, until a frame starts with anything but `0xA5`.
//! Shared by the firmware and the `f32-step` bench.

use crate::{clock, serial};
use core::sync::atomic::{compiler_fence, Ordering};
use planner_core::{Angle, Output, Point, Pose, RawCounts};

/// Serve frames with `step`, which returns the output and the cycles of
/// the step it timed; the cost of the timing itself is subtracted.
pub fn serve(mut step: impl FnMut(Pose, &RawCounts) -> (Output, u32)) {
    let overhead = {
        let t0 = clock::cycles();
        compiler_fence(Ordering::SeqCst);
        clock::cycles().wrapping_sub(t0)
    };
    while serial::read_blocking() == 0xa5 {
        let x = serial::read_u16_le() as i16;
        let y = serial::read_u16_le() as i16;
        let heading = Angle(serial::read_u16_le());
        let mut raw = [0u16; 5];
        for r in raw.iter_mut() {
            *r = serial::read_u16_le();
        }
        let pose = Pose {
            position: Point::new(x, y),
            heading,
        };
        let (out, cycles) = step(pose, &raw);
        serial::write(0x5a);
        serial::write_all(&out.command.heading.0.to_le_bytes());
        serial::write_all(&out.command.step_mm.to_le_bytes());
        serial::write(out.status.code());
        serial::write_all(&cycles.saturating_sub(overhead).to_le_bytes());
    }
}
