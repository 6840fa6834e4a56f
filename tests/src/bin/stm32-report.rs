//! `cargo xtask stm32-report`: the STM32 firmware's size (real-board build,
//! `llvm-size`) and its planner-step instruction counts (the `qemu` build
//! in QEMU with `-icount shift=0`, replaying the standard traces), measured
//! now, nothing typed in.

use planner_core::AdcProfile;
use rover_tests::stm32::{board_elf, elf_size, instructions, run_traces};
use rover_tests::{mean_worst, mode_lines, standard_traces};

fn main() {
    let (text, data, bss) = elf_size(&board_elf());
    let traces = standard_traces(AdcProfile::STM32_12BIT_3V3);
    let run = run_traces(&traces);
    let mismatches = run.mismatches(&traces);
    let counts: Vec<u32> = run.steps.iter().map(|&(_, t)| instructions(t)).collect();
    let (mean, worst) = mean_worst(&counts);
    println!("stm32 size: text={text} data={data} bss={bss}");
    println!("stm32 step instructions: mean={mean} worst={worst}");
    for line in mode_lines("stm32", &traces, &counts) {
        println!("{line}");
    }
    if mismatches > 0 {
        eprintln!("stm32-report: {mismatches} steps differ from the host core");
        std::process::exit(1);
    }
}
