//! A planner step timed in CPU cycles: the telemetry's `cycles`, and replay
//! mode's (the `replay` binary).

use crate::clock;
use core::sync::atomic::{compiler_fence, Ordering};
use planner_core::{Output, Planner, Pose, RawCounts};

/// One planner step and its cycles. The fences keep the compiler from
/// moving work across the two clock reads.
#[inline(never)]
pub fn step(planner: &mut Planner, pose: Pose, raw: &RawCounts) -> (Output, u32) {
    let t0 = clock::stamp();
    compiler_fence(Ordering::SeqCst);
    let out = planner.step_raw(core::hint::black_box(pose), core::hint::black_box(raw));
    let out = core::hint::black_box(out);
    compiler_fence(Ordering::SeqCst);
    let t1 = clock::stamp();
    (out, t1.cycles().wrapping_sub(t0.cycles()))
}
