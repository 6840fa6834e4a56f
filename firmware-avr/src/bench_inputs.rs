//! The `costs` bench's inputs that its checker (`tests/tests/avr_costs.rs`)
//! needs and the bench does not print: this one file is compiled into both
//! (`#[path]`), so that the two cannot drift apart.

use planner_core::eapf::escape::{Escape, EscapeConfig};
use planner_core::{Point, Reading};

/// Readings for the free-distance rule with obstacles in sight.
pub const NEAR: [Reading; 5] = [
    Reading::Range(300),
    Reading::Range(180),
    Reading::Clear,
    Reading::Range(420),
    Reading::TooClose,
];

/// Cycles of the drop sequence at most ([`creep`] drops the escape's
/// capacity of virtual obstacles well within them).
pub const CREEP_CYCLES: i16 = 400;

/// Where the virtual obstacles' force is timed from: beside the middle of
/// the row [`creep`] lays, so that all 24 are in reach.
pub const VO_PROBE: Point = Point::new(575, -200);

/// The escape's configuration for the drop sequence: the default with a
/// give-up budget long enough for the whole sequence (the default's 200
/// cycles without progress end it after 16 drops).
pub const CREEP_ESCAPE: EscapeConfig = EscapeConfig {
    give_up_steps: 1_000,
    ..EscapeConfig::DEFAULT
};

/// Cycle `k` of the drop sequence: a rover creeping 50 mm every twelve
/// cycles is stuck and drops a virtual obstacle each time (see `escape`).
pub fn creep(escape: &mut Escape, cfg: &EscapeConfig, k: i16) {
    let _ = escape.observe(cfg, Point::new(50 * (k / 12), 0), 5_000);
}

/// The sweeps' pseudo-random numbers: a multiplicative hash of `x`.
fn mix(x: u32) -> u32 {
    let x = x.wrapping_mul(0x9e37_79b1);
    x ^ (x >> 15)
}

/// How many divisions the division sweep checks.
pub const DIV_SWEEP: u32 = 4_000;

/// The sweep's case `k`: a pseudo-random dividend and divisor, the
/// dividend one to four bytes long and the divisor four to one (in turn,
/// so that every entry of the AVR's division, `firmware-avr/asm/
/// udivmodsi4.S`, is taken), and the edges of each entry first.
pub fn div_case(k: u32) -> (u32, u32) {
    const EDGES: [(u32, u32); 10] = [
        (u32::MAX, 1),
        (u32::MAX, u32::MAX),
        (u32::MAX, 0xff),
        (u32::MAX, 0x100),
        (u32::MAX, 0xffff),
        (u32::MAX, 0x1_0000),
        (u32::MAX, 0xff_ffff),
        (u32::MAX, 0x100_0000),
        (0x00ff_ffff, 0x100_0000),
        (0, 0x100_0000),
    ];
    if let Some(&edge) = EDGES.get(k as usize) {
        return edge;
    }
    let n = mix(k) >> (8 * (k / 4 % 4));
    let d = mix(n ^ k ^ 0x5bd1_e995) >> (8 * (k % 4));
    (n, d.max(1))
}

/// What the division sweep answers: a checksum of the quotients and one
/// of the remainders.
pub fn div_sweep(div: impl Fn(u32, u32) -> (u32, u32)) -> (u32, u32) {
    let (mut q_sum, mut r_sum) = (0u32, 0u32);
    for k in 0..DIV_SWEEP {
        let (n, d) = div_case(k);
        let (q, r) = div(n, d);
        q_sum = q_sum.rotate_left(5) ^ q;
        r_sum = r_sum.rotate_left(5) ^ r;
    }
    (q_sum, r_sum)
}

/// How many multiplies the multiply sweep checks.
pub const MUL_SWEEP: u32 = 4_000;

/// The multiply sweep's answer: a checksum of the 32-bit products of
/// pseudo-random operands of one to four bytes each (signed and unsigned
/// are the same bits).
pub fn mul_sweep(mul: impl Fn(u32, u32) -> u32) -> u32 {
    // The edges of both ways through the AVR's multiply (`firmware-avr/
    // asm/mulsi3.S`): the largest operands below 2^16, and the first above.
    let mut sum = mul(u32::MAX, u32::MAX);
    for (a, b) in [(0xffff, 0xffff), (0xffff, 0x1_0000), (0x1_0000, 0xffff)] {
        sum = sum.rotate_left(5) ^ mul(a, b);
    }
    for k in 0..MUL_SWEEP {
        let a = mix(k) >> (8 * (k % 4));
        let b = mix(a ^ 0x5bd1_e995) >> (8 * (k / 4 % 4));
        sum = sum.rotate_left(5) ^ mul(a, b);
    }
    sum
}
