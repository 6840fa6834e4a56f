//! The product planner's step and guard on any goal, poses and counts, on
//! either board's ADC: no panic, and every step keeps the rules of
//! `Output::broken_rule` (the safety rule among them), but the wedge's
//! back-out, which goes back along the way the disc has just swept (the
//! property test `the_safety_rule_holds_over_long_closed_loop_runs` holds
//! its guard): that one is within the sensors' range.

#![no_main]

use arbitrary::Arbitrary;
use libfuzzer_sys::fuzz_target;
use planner_core::{AdcProfile, Angle, BrokenRule, ConfigBuilder, Planner, Point, Pose, RawCounts};

#[derive(Arbitrary, Debug)]
struct Cycle {
    x: i16,
    y: i16,
    heading: u16,
    raw: RawCounts,
    /// Counts the guard sees during the advance that follows.
    guard: Vec<RawCounts>,
}

#[derive(Arbitrary, Debug)]
struct Run {
    stm32: bool,
    goal: (i16, i16),
    cycles: Vec<Cycle>,
}

fuzz_target!(|run: Run| {
    let adc = if run.stm32 {
        AdcProfile::STM32_12BIT_3V3
    } else {
        AdcProfile::AVR_10BIT_5V
    };
    let cfg = ConfigBuilder::new(adc)
        .build()
        .expect("the default configuration");
    let mut planner = Planner::new(cfg, Point::new(run.goal.0, run.goal.1));
    for c in run.cycles.iter().take(256) {
        let pose = Pose {
            position: Point::new(c.x, c.y),
            heading: Angle(c.heading),
        };
        let out = planner.step_raw(pose, &c.raw);
        let rule = match planner.backing_out() {
            true => {
                (out.command.step_mm > cfg.sensor_range_mm()).then_some(BrokenRule::BeyondRange)
            }
            false => out.broken_rule(&cfg, planner.last_readings(), pose),
        };
        if let Some(rule) = rule {
            panic!("{rule:?}: {out:?} at {pose:?} from {:?}", c.raw);
        }
        for g in c.guard.iter().take(8) {
            let _ = planner.guard_raw(g, out.command.step_mm);
        }
    }
});
