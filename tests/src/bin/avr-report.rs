//! `cargo xtask avr-report`: the ATmega328P firmware's size (from the ELF)
//! and its planner-step cycle counts (simavr, replaying the standard
//! traces), and the replayed steps by the planner's mode with the worst
//! of each, measured now, nothing typed in.

use planner_core::AdcProfile;
use rover_tests::avr::{elf_size, f32_step_cycles, firmware_elf, Avr};
use rover_tests::{mean_worst, mode_lines, standard_traces};

fn main() {
    let (text, data, bss) = elf_size(&firmware_elf());
    let traces = standard_traces(AdcProfile::AVR_10BIT_5V);
    let mut avr = Avr::boot_replay();
    let mut cycles = Vec::new();
    let mut mismatches = 0;
    for t in &traces {
        for (got, want) in avr.replay(t.goal, &t.frames).iter().zip(&t.outputs) {
            mismatches += usize::from(got.answer != *want);
            cycles.push(got.cycles);
        }
    }
    let peak = avr
        .stack_peak()
        .map_or_else(|| "unknown".into(), |p| p.to_string());
    let (mean, worst) = mean_worst(&cycles);
    let (_, f32_worst) = mean_worst(&f32_step_cycles(&traces));
    println!("avr size: text={text} data={data} bss={bss} stack_peak={peak}");
    println!("avr step cycles: mean={mean} worst={worst} f32_worst={f32_worst}");
    for line in mode_lines("avr", &traces, &cycles) {
        println!("{line}");
    }
    if mismatches > 0 {
        eprintln!("avr-report: {mismatches} steps differ from the host core");
        std::process::exit(1);
    }
}
