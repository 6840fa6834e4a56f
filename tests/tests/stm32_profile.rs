//! The instruction profiler (`cargo xtask stm32-profile`) accounts for the
//! steps the STM32 firmware counts itself: the same steps, the same
//! instructions (within two of the SysTick ticks the firmware counts in),
//! every instruction charged once in each table.

use planner_core::AdcProfile;
use rover_tests::standard_traces;
use rover_tests::stm32_profile::{profile, OWN_CODE};

#[test]
fn the_profile_accounts_for_the_counted_steps() {
    let traces = standard_traces(AdcProfile::STM32_12BIT_3V3);
    let frames: usize = traces.iter().map(|t| t.frames.len()).sum();
    let p = profile(&traces);
    assert_eq!(p.mismatches, 0, "the firmware's commands are the host's");
    assert_eq!(p.counted.len(), frames, "one profiled step per frame");
    assert_eq!(p.timed.len(), frames, "one counted step per frame");
    // SysTick counts 168 MHz against QEMU's 1 GHz of instructions: a tick
    // is ~6 instructions, and both reads and the overhead round to one.
    let worst_gap = (p.counted.iter().zip(&p.timed))
        .map(|(&c, &t)| c.abs_diff(t))
        .max()
        .unwrap_or(0);
    println!("stm32 profile: the counts differ from the firmware's by {worst_gap} at most");
    assert!(
        worst_gap <= 12,
        "{worst_gap} instructions off the firmware's count"
    );
    let total = |rows: &[(String, u64)]| rows.iter().map(|(_, n)| n).sum::<u64>();
    let all = total(&p.by_callee);
    assert_eq!(total(&p.by_symbol), all, "each instruction once by symbol");
    assert_eq!(total(&p.by_source), all, "each instruction once by source");
    let counted: u64 = p.counted.iter().map(|&c| c as u64).sum();
    assert!(all >= counted, "the spans hold the counted instructions");
    // The worst step is the worst the firmware counted, give or take a tick.
    let (i, w) = &p.worst;
    let firmware_worst = *p.timed.iter().max().unwrap();
    assert!(p.counted[*i].abs_diff(firmware_worst) <= 12);
    assert!(total(w) >= p.counted[*i] as u64);
    // The step's parts are named: its own code, and the escape's force
    // (the dead end's virtual obstacles), among what it calls.
    let names: Vec<&str> = p.by_callee.iter().map(|(n, _)| n.as_str()).collect();
    assert!(names.contains(&OWN_CODE), "{names:?}");
    assert!(
        names.iter().any(|n| n.contains("Escape::force")),
        "{names:?}"
    );
}
