//! A recorded sensor trace replayed through the core's scripted source gives
//! the same commands, bit for bit, as the live run that recorded it: the
//! core is deterministic and its only inputs are pose and raw counts (of
//! the steps and of the guard's looks during the advances). This is the
//! host half of the bit-exactness check the firmware builds share.

use planner_core::{AdcProfile, ConfigBuilder, Mode, Planner, RawCounts, ScriptedSensors};
use rover_tests::{record, run_guards, scenario, Answer};

#[test]
fn replayed_trace_gives_identical_commands() {
    let t = record(
        &scenario("traps/u-trap.toml"),
        AdcProfile::AVR_10BIT_5V,
        60,
        3,
    );
    let cfg = ConfigBuilder::new(AdcProfile::AVR_10BIT_5V)
        .build()
        .unwrap();
    let frames: Vec<RawCounts> = t.frames.iter().map(|f| f.raw).collect();
    let mut replay = Planner::new(cfg, t.goal);
    let mut script = ScriptedSensors::new(&frames);
    let mut with_flank = 0;
    for (f, want) in t.frames.iter().zip(&t.outputs) {
        let guard_stops = run_guards(&mut replay, &f.guards);
        with_flank += usize::from(!replay.flank().points().is_empty());
        let output = replay.step(f.pose, &mut script).unwrap();
        assert_eq!(
            &Answer {
                guard_stops,
                output
            },
            want
        );
    }
    assert!(t.outputs.iter().any(|o| o.output.command.step_mm > 0));
    // The trace exercises the guard and the flank points it keeps.
    assert!(t.frames.iter().any(|f| !f.guards.is_empty()));
    assert!(with_flank > 0, "no step with flank points");
    assert_eq!(script.remaining(), 0);
}

/// The standard traces, which both firmwares replay and time, run every
/// mode of the planner (for both sensor mountings and both ADCs), so that
/// the reports' worst step covers the field, the escape and the follower.
#[test]
fn standard_traces_run_every_mode() {
    for adc in [AdcProfile::AVR_10BIT_5V, AdcProfile::STM32_12BIT_3V3] {
        for set_back in [false, true] {
            let traces = rover_tests::standard_traces_with(adc, set_back);
            for mode in [Mode::Field, Mode::Escape, Mode::Follow] {
                let n: usize = traces
                    .iter()
                    .map(|t| t.modes.iter().filter(|&&m| m == mode).count())
                    .sum();
                assert!(n >= 20, "{adc:?} set_back={set_back}: {n} {mode:?} steps");
            }
        }
    }
}
