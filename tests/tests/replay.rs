//! A recorded sensor trace replayed through the core's scripted source gives
//! the same commands, bit for bit, as the live run that recorded it: the
//! core is deterministic and its only inputs are pose and raw counts. This is
//! the host half of the bit-exactness check the firmware builds will share.

use planner_core::{AdcProfile, ConfigBuilder, Output, Planner, Pose, RawCounts, ScriptedSensors};
use sim_host::geom::V2;
use sim_host::planners::{to_angle, to_point, to_rad};
use sim_host::scenario::Scenario;
use sim_host::sensor::{SensorMode, VirtualSensors};
use sim_host::world::World;
use std::path::Path;

#[test]
fn replayed_trace_gives_identical_commands() {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../sim-host/scenarios/traps/u-trap.toml");
    let sc = Scenario::load(&path).unwrap();
    let world = World::from_scenario(&sc);
    let cfg = ConfigBuilder::new(AdcProfile::AVR_10BIT_5V)
        .build()
        .unwrap();
    let goal = to_point(V2::new(sc.goal[0], sc.goal[1]));
    let angles = cfg.sensor_angles().map(to_rad);
    let mut sensors = VirtualSensors::new(
        AdcProfile::AVR_10BIT_5V,
        SensorMode::REALISTIC,
        angles,
        0.1,
        3,
    );
    // Live: a simple walk that follows the commands without physics.
    let mut live = Planner::new(cfg.clone(), goal);
    let (mut p, mut h) = (V2::new(sc.start[0], sc.start[1]), sc.start_heading_rad());
    let mut frames: Vec<RawCounts> = Vec::new();
    let mut poses: Vec<Pose> = Vec::new();
    let mut outs: Vec<Output> = Vec::new();
    for k in 0..60 {
        let raw = sensors.read(&world, p, h, k as f64 * 0.05);
        let pose = Pose {
            position: to_point(p),
            heading: to_angle(h),
        };
        let out = live.step_raw(pose, &raw);
        frames.push(raw);
        poses.push(pose);
        outs.push(out);
        h = to_rad(out.command.heading);
        p = p + V2::from_angle(h) * (out.command.step_mm as f64 / 1000.0);
    }
    // Replay.
    let mut replay = Planner::new(cfg, goal);
    let mut script = ScriptedSensors::new(&frames);
    for (pose, want) in poses.iter().zip(&outs) {
        let got = replay.step(*pose, &mut script).unwrap();
        assert_eq!(&got, want);
    }
    assert!(outs.iter().any(|o| o.command.step_mm > 0));
    assert_eq!(script.remaining(), 0);
}
