//! The cycle profiler (`cargo xtask avr-profile`) accounts for the steps
//! the firmware times itself: same steps, same cycles (to the same few
//! the firmware's own clock reads and call add to each), every cycle charged once, and
//! the operands of every 32-bit multiply and division read.

use planner_core::AdcProfile;
use rover_tests::avr::{replay_firmware_elf, set_back_replay_firmware_elf, Avr};
use rover_tests::profile::{profile, Profile, OWN_CODE};
use rover_tests::{at_new_position, standard_traces, standard_traces_with};

/// The profiled span is the whole call (entry to return), the timed one
/// the planner step between two clock reads inside it: the same few cycles
/// more on every step, or the firmware's timing counts something that is
/// not the step (an interrupt, a clock read that costs more on some
/// values, a missed overflow). Those few cycles.
fn timing_overhead(p: &Profile) -> i64 {
    let around: Vec<i64> = p
        .step_counted
        .iter()
        .zip(&p.step_cycles)
        .map(|(&counted, &timed)| counted as i64 - i64::from(timed))
        .collect();
    assert!(
        around.iter().all(|&a| a == around[0]) && (0..400).contains(&around[0]),
        "profiled minus timed cycles differ between steps: {:?}",
        {
            let mut d = around.clone();
            d.sort();
            d.dedup();
            d
        }
    );
    around[0]
}

/// The set-back build's steps run past half of Timer1's period, where the
/// counter's value alone no longer tells whether an overflow left pending
/// (interrupts are off) came before the read or just after it: the
/// firmware reads the flag on both sides (`clock::stamp`), and its timed
/// steps are the profiled ones here too.
#[test]
fn the_set_back_steps_past_half_the_period_are_timed_exactly() {
    let traces = standard_traces_with(AdcProfile::AVR_10BIT_5V, true);
    let p = profile(&set_back_replay_firmware_elf(), &traces);
    assert_eq!(p.mismatches, 0, "the firmware's commands are the host's");
    let frames: usize = traces.iter().map(|t| t.frames.len()).sum();
    assert_eq!(p.step_counted.len(), frames, "one counted step per frame");
    let long = p.step_cycles.iter().filter(|&&c| c > 32_768).count();
    println!(
        "avr set-back profile: {long} steps over 32,768 cycles, the profiled call {} cycles more than each timed step",
        timing_overhead(&p)
    );
    assert!(long > 0, "a step past half the period");
}

#[test]
fn the_profile_accounts_for_the_timed_steps() {
    let traces = standard_traces(AdcProfile::AVR_10BIT_5V);
    let frames: usize = traces.iter().map(|t| t.frames.len()).sum();
    let p = profile(&replay_firmware_elf(), &traces);
    assert_eq!(p.steps as usize, frames, "one profiled step per frame");
    assert_eq!(p.step_cycles.len(), frames, "one timed step per frame");
    assert_eq!(p.mismatches, 0, "the firmware's commands are the host's");
    assert_eq!(
        p.unbalanced, 0,
        "every call the step made returned ({} of {} steps did not)",
        p.unbalanced, p.steps
    );
    // avr-profile's split by where the rover stands: one flag per timed
    // step, the first of each trace somewhere new.
    let new = at_new_position(&traces);
    assert_eq!(new.len(), p.step_cycles.len(), "one flag per step");
    let mut first = 0;
    for t in &traces {
        assert!(new[first], "{}: its first step is somewhere new", t.name);
        first += t.frames.len();
    }
    assert!(new.contains(&false), "some steps turn on the spot");
    let per_step = p.cycles / p.steps;
    let timed = p.timed() / p.steps;
    println!("avr profile: {per_step} cycles per step, the firmware timed {timed}");
    for (name, c) in p.by_callee.iter().take(8) {
        println!("{:>7}/step  {name}", c / p.steps);
    }
    // The profiled span is the whole call (entry to return), the timed
    // one the planner step between two clock reads inside it: the same
    // few cycles more on every step, or the firmware's timing counts
    // something that is not the step (an interrupt, a clock read that
    // costs more on some values, a missed overflow).
    assert_eq!(p.step_counted.len(), frames, "one counted step per frame");
    let around = timing_overhead(&p);
    println!("avr profile: the profiled call is {around} cycles more than the timed step");
    let split = |v: &[(String, u64)]| v.iter().map(|(_, c)| c).sum::<u64>();
    assert_eq!(split(&p.by_function), p.cycles, "each cycle charged once");
    assert_eq!(split(&p.by_callee), p.cycles, "each cycle charged once");
    assert_eq!(split(&p.worst.1), p.worst.0, "the worst step's split");
    assert!(
        p.worst.0 > per_step,
        "the worst step costs more than the mean"
    );
    // Calls are charged to what the step called: the division inside
    // `atan2` to `atan2`, and the step's own code is part, not all.
    let cycles_of = |split: &[(String, u64)], name: &str| {
        split
            .iter()
            .find(|(n, _)| n.ends_with(name))
            .map_or(0, |(_, c)| *c)
    };
    let of = |name: &str| cycles_of(&p.by_callee, name);
    assert!(of("Angle::atan2") > 0, "atan2 has its share");
    // The worst step is in the dead end, among the virtual obstacles.
    // (`force_kept` works it out, or takes it as kept, on the AVR out of
    // line.)
    let worst_force =
        cycles_of(&p.worst.1, "Escape::force") + cycles_of(&p.worst.1, "Escape::force_kept");
    assert!(
        worst_force > p.worst.0 / 10,
        "the virtual obstacles' force {worst_force} of the worst step's {}",
        p.worst.0
    );
    let own = of(OWN_CODE);
    assert!(
        own > 0 && own < p.cycles / 2,
        "own code {own} of {}",
        p.cycles
    );
    // The operands were read at every call of the 32-bit multiply: its
    // cycles per call (its `ret` included, the caller's `call` not) lie
    // between its shorter way's 28 and its full way's 51
    // (`firmware-avr/asm/mulsi3.S`).
    let o = &p.operands;
    let muls: u64 = o.mul.iter().sum();
    let per_mul = cycles_of(&p.by_function, "__mulsi3") as f64 / muls.max(1) as f64;
    println!("{muls} multiplies, {per_mul:.1} cycles each");
    assert!(
        (28.0..=51.0).contains(&per_mul),
        "{per_mul} cycles a multiply"
    );
    assert!(o.div.iter().flatten().sum::<u64>() > 0, "divisions seen");
    assert_eq!(o.div_by_zero, 0, "no division by zero");
    let inside_atan2 = cycles_of(&p.by_function, "Angle::atan2");
    assert!(
        of("Angle::atan2") > inside_atan2,
        "atan2's callees (its division) are charged to it"
    );
}

/// `avr-report` (avr-tester) and `avr-profile` (simavr one instruction at
/// a time) send the frames at different moments, yet the firmware times
/// every step the same in both: the timing is of the step alone. (It was
/// not: an interrupt in the clock's calibration made one trace's steps
/// read 146 cycles short in one of them, and a Timer1 overflow inside a
/// step added 47.)
#[test]
fn both_harnesses_time_every_step_alike() {
    let traces = standard_traces(AdcProfile::AVR_10BIT_5V);
    let p = profile(&replay_firmware_elf(), &traces);
    let mut avr = Avr::boot_replay();
    let report: Vec<u32> = traces
        .iter()
        .flat_map(|t| avr.replay(t.goal, &t.frames))
        .map(|r| r.cycles)
        .collect();
    let differ = report
        .iter()
        .zip(&p.step_cycles)
        .filter(|(a, b)| a != b)
        .count();
    assert_eq!(report.len(), p.step_cycles.len(), "one timing per step");
    assert_eq!(differ, 0, "steps timed differently by the two harnesses");
}
