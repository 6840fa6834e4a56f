//! `cargo xtask avr-report`: the ATmega328P firmware's size (from the ELF)
//! and its planner-step cycle counts (simavr, replaying the standard
//! traces), measured now, nothing typed in.

use planner_core::AdcProfile;
use rover_tests::avr::{elf_size, firmware_elf, Avr};
use rover_tests::{mean_worst, standard_traces};

fn main() {
    let (text, data, bss) = elf_size(&firmware_elf());
    let mut avr = Avr::boot();
    let mut cycles = Vec::new();
    let mut mismatches = 0;
    for t in standard_traces(AdcProfile::AVR_10BIT_5V) {
        for ((out, c), want) in avr.replay(t.goal, &t.frames).iter().zip(&t.outputs) {
            mismatches += usize::from(out != want);
            cycles.push(*c);
        }
    }
    let peak = avr
        .request("M")
        .and_then(|l| l.strip_prefix("M stack_peak=").map(str::to_owned))
        .unwrap_or_else(|| "unknown".into());
    let (mean, worst) = mean_worst(&cycles);
    println!("avr size: text={text} data={data} bss={bss} stack_peak={peak}");
    // No f32 build of the planner exists yet, so there is no float figure.
    println!("avr step cycles: mean={mean} worst={worst} f32_worst=unmeasured");
    if mismatches > 0 {
        eprintln!("avr-report: {mismatches} steps differ from the host core");
        std::process::exit(1);
    }
}
