//! The `costs` bench: what the planner step's parts cost on the ATmega328P.
//!
//! Times the fixed-point primitives the step is built of (a 32-bit
//! division and multiply, the square root, `hypot`, `atan2`, the sine,
//! `1/d²`, the free-distance rule), sweeps the firmware's own division and
//! multiply (`asm/`) through every path, and times the virtual obstacles' force with
//! 1 to 24 obstacles in reach (the escape's capacity), each on fixed
//! inputs, and prints one line per call: `C name a b result_x result_y
//! cycles`, then `END`. The figures are
//! what a call costs in place, with its operands passed through
//! `black_box` (which matters for the cheapest ones, a multiply); the
//! `nothing` lines time an empty span, the measurement's own residual. The
//! test that runs it (`tests/tests/avr_costs.rs`) checks every result
//! against the host's and prints the cycles. It drives no motors and reads
//! no input.
#![no_std]
#![no_main]
#![feature(abi_avr_interrupt)]

#[path = "../bench.rs"]
mod bench;
#[path = "../bench_inputs.rs"]
mod bench_inputs;
#[path = "../board.rs"]
#[allow(dead_code)]
mod board;
#[path = "../clock.rs"]
#[allow(dead_code)]
mod clock;
#[path = "../progmem.rs"]
mod progmem;
#[path = "../serial.rs"]
#[allow(dead_code)]
mod serial;

use bench::Serial;
use core::hint::black_box;
use core::sync::atomic::{compiler_fence, Ordering};
use planner_core::eapf::command::free_distance_mm;
use planner_core::eapf::escape::{Escape, VIRTUAL_CAPACITY};
use planner_core::fixed::{hypot, inverse_square_force, isqrt};
use planner_core::{Angle, Reading};
use ufmt::uwriteln;

/// Timings of the long span, and its square roots (`isqrt(10^6)`, 873
/// cycles each: about 59,000 cycles, past half of the 65,536).
const LONG_SPANS: i32 = 16;
const LONG_SPAN_ROOTS: u8 = 68;

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    bench::halt()
}

/// Cycles of `f()`, fenced so that the compiler cannot move work out of the
/// measured span, less `overhead`. One shape for every measurement (not
/// inlined, `f` called through a pointer), so that the cost of the
/// measurement itself is the same each time and `overhead` can be it.
#[inline(never)]
fn timed(overhead: u32, f: &mut dyn FnMut() -> (i32, i32)) -> ((i32, i32), u32) {
    let t0 = clock::stamp();
    compiler_fence(Ordering::SeqCst);
    let r = black_box(f());
    compiler_fence(Ordering::SeqCst);
    let t1 = clock::stamp();
    (
        r,
        t1.cycles().wrapping_sub(t0.cycles()).wrapping_sub(overhead),
    )
}

/// One result line.
fn report(name: &str, a: i32, b: i32, ((x, y), cycles): ((i32, i32), u32)) {
    let _ = uwriteln!(Serial, "C {} {} {} {} {} {}", name, a, b, x, y, cycles);
}

#[avr_device::entry]
fn main() -> ! {
    let cfg = bench::start();
    let _ = uwriteln!(Serial, "READY");
    // The measurement's own cost: a span that only passes a value through.
    let overhead = timed(0, &mut || black_box((0, 0))).1;

    // The same span again: what is left is the measurement's error.
    for v in [1i32, 2] {
        report("nothing", v, 0, timed(overhead, &mut || black_box((v, 0))));
    }
    for (a, b) in [
        (1_024_000_000u32, 8_281u32),
        (123_456_789, 1_234),
        (5_000, 7),
    ] {
        let t = timed(overhead, &mut || ((black_box(a) / black_box(b)) as i32, 0));
        report("div_u32", a as i32, b as i32, t);
    }
    // Every entry of the division against the host's (the cycles are
    // the sweep's, all of it).
    let t = timed(overhead, &mut || {
        let (q, r) = bench_inputs::div_sweep(|n, d| (black_box(n) / d, black_box(n) % d));
        (q as i32, r as i32)
    });
    report("div_sweep", bench_inputs::DIV_SWEEP as i32, 0, t);
    let t = timed(overhead, &mut || {
        let p = bench_inputs::mul_sweep(|a, b| black_box(a).wrapping_mul(b));
        (p as i32, 0)
    });
    report("mul_sweep", bench_inputs::MUL_SWEEP as i32, 0, t);
    for (a, b) in [(123_456i32, -789i32), (46_341, 46_340)] {
        let t = timed(overhead, &mut || {
            (black_box(a).wrapping_mul(black_box(b)), 0)
        });
        report("mul_i32", a, b, t);
    }
    for v in [99u32, 65_535, 1_000_000, 6_500_000, 2_000_000_000] {
        let t = timed(overhead, &mut || (isqrt(black_box(v)) as i32, 0));
        report("isqrt", v as i32, 0, t);
    }
    for (dx, dy) in [(150i32, 20i32), (3_000, -4_000), (-12_000, 9_000)] {
        let t = timed(overhead, &mut || {
            (hypot(black_box(dx), black_box(dy)) as i32, 0)
        });
        report("hypot", dx, dy, t);
    }
    for (y, x) in [(1i32, 1_000i32), (-700, 300), (2_500, -2_400)] {
        let t = timed(overhead, &mut || {
            (Angle::atan2(black_box(y), black_box(x)).0 as i32, 0)
        });
        report("atan2", y, x, t);
    }
    for deg in [10i16, 100, -135] {
        let a = Angle::from_deg(deg);
        let t = timed(overhead, &mut || (black_box(a).sin(), 0));
        report("sin", deg as i32, 0, t);
    }
    for d in [91u16, 200, 1_500] {
        let t = timed(overhead, &mut || (inverse_square_force(black_box(d)), 0));
        report("inverse_square", d as i32, 0, t);
    }
    let clear = [Reading::Clear; 5];
    for (name, readings) in [("free_clear", clear), ("free_near", bench_inputs::NEAR)] {
        for deg in [0i16, 25] {
            let rel = Angle::from_deg(deg);
            let t = timed(overhead, &mut || {
                let f = free_distance_mm(&cfg, black_box(&readings), black_box(rel));
                (f as i32, 0)
            });
            report(name, deg as i32, 0, t);
        }
    }
    // Virtual obstacles: the force is timed as each is dropped, up to the
    // escape's capacity (all 24 in reach: the worst case).
    let esc = bench_inputs::CREEP_ESCAPE;
    let mut escape = Escape::new();
    let (mut held, mut k) = (0, 0i16);
    while held < VIRTUAL_CAPACITY && k < bench_inputs::CREEP_CYCLES {
        bench_inputs::creep(&mut escape, &esc, k);
        k += 1;
        if escape.len() > held {
            held = escape.len();
            let probe = bench_inputs::VO_PROBE;
            let t = timed(overhead, &mut || {
                let f = escape.force(black_box(probe), black_box(Angle::ZERO));
                (f.x, f.y)
            });
            report("vo_force", held as i32, 0, t);
        }
    }
    // The clock over a span longer than half of Timer1's period, timed
    // with interrupts off as the replay times a step, from different
    // points of the period (each report line moves the next start): where
    // the overflow comes more than half a period before the span ends, the
    // counter alone no longer tells whether it came before the read.
    for k in 0..LONG_SPANS {
        let t = avr_device::interrupt::free(|_| {
            timed(overhead, &mut || {
                let mut x = 0;
                for _ in 0..LONG_SPAN_ROOTS {
                    x ^= isqrt(black_box(1_000_000)) as i32;
                }
                (x, 0)
            })
        });
        report("long_span", k, 0, t);
    }
    // The lap flag (`clock::arm_lap`) over the long span, and over one
    // twice as long, past the counter's period: only the second laps.
    for roots in [LONG_SPAN_ROOTS, 2 * LONG_SPAN_ROOTS] {
        let t = avr_device::interrupt::free(|_| {
            clock::arm_lap();
            timed(overhead, &mut || {
                for _ in 0..roots {
                    black_box(isqrt(black_box(1_000_000)));
                }
                (i32::from(clock::lapped()), 0)
            })
        });
        report("lap", roots as i32, 0, t);
    }
    let _ = uwriteln!(Serial, "END");
    bench::halt()
}
