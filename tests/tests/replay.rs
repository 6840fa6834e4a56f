//! A recorded sensor trace replayed through the core's scripted source gives
//! the same commands, bit for bit, as the live run that recorded it: the
//! core is deterministic and its only inputs are pose and raw counts. This is
//! the host half of the bit-exactness check the firmware builds share.

use planner_core::{AdcProfile, ConfigBuilder, Planner, RawCounts, ScriptedSensors};
use rover_tests::{record, scenario};

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
    for (f, want) in t.frames.iter().zip(&t.outputs) {
        let got = replay.step(f.pose, &mut script).unwrap();
        assert_eq!(&got, want);
    }
    assert!(t.outputs.iter().any(|o| o.command.step_mm > 0));
    assert_eq!(script.remaining(), 0);
}
