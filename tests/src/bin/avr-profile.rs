//! `cargo xtask avr-profile`: where the ATmega328P firmware's planner step
//! spends its cycles, over the standard traces (those of `cargo xtask
//! avr-report`); see [`rover_tests::profile`].

use planner_core::AdcProfile;
use rover_tests::avr::replay_firmware_elf;
use rover_tests::profile::profile;
use rover_tests::{
    at_new_position, print_by_bounds, print_by_position, print_table, standard_traces,
};

fn main() {
    let traces = standard_traces(AdcProfile::AVR_10BIT_5V);
    let p = profile(&replay_firmware_elf(), &traces);
    let steps = p.steps.max(1);
    println!(
        "avr profile: {} steps, {} cycles per step (the firmware timed {} per step)",
        p.steps,
        p.cycles / steps,
        p.timed() / steps
    );
    print_table(
        "by function (where the instruction is)",
        &p.by_function,
        p.cycles,
        steps,
        25,
    );
    print_table(
        "by what the step calls (callees included)",
        &p.by_callee,
        p.cycles,
        steps,
        25,
    );
    let (worst, w) = &p.worst;
    print_table(
        &format!("the worst step ({worst} cycles), by what it calls"),
        w,
        *worst,
        1,
        25,
    );
    // How the steps stand against issue 5's budget (8,000) and aim (3,000).
    println!("\nsteps by cycles (as the firmware timed them):");
    let bounds = [3_000, 8_000, 15_000, 20_000, 25_000, u32::MAX];
    print_by_bounds(&p.step_cycles, &bounds);
    // Where the budget is missed: a turn on the spot keeps the answers that
    // depend on the position only; a step somewhere new works them out.
    println!("\nsteps by where the rover stands (as the firmware timed them):");
    print_by_position(&p.step_cycles, &at_new_position(&traces), 8_000);
    let o = &p.operands;
    let muls: u64 = o.mul.iter().sum();
    let pct = |n: u64, of: u64| n as f64 * 100.0 / of.max(1) as f64;
    println!(
        "\nmultiplies: {:.1}/step; both operands below 2^16 {:.1} %, both 16-bit signed {:.1} %, wider {:.1} %",
        muls as f64 / steps as f64,
        pct(o.mul[0], muls),
        pct(o.mul[1], muls),
        pct(o.mul[2], muls)
    );
    let divs: u64 = o.div.iter().flatten().sum();
    println!(
        "divisions: {:.1}/step; by quotient and divisor bytes (q/d: count):",
        divs as f64 / steps as f64
    );
    for (q, row) in o.div.iter().enumerate() {
        for (d, n) in row.iter().enumerate().filter(|(_, n)| **n > 0) {
            println!("  q{}/d{}: {n}", q + 1, d + 1);
        }
    }
    println!("\nthe costliest instructions (avr-objdump -d the ELF to read them):");
    for (a, name, c) in p.by_address.iter().take(12) {
        println!("{:>7}/step  0x{a:04x}  {name}", c / steps);
    }
}
