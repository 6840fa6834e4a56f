//! The host console (`sim-host drive`, `sim_host::console`) against the
//! ATmega328P firmware in simavr, closed loop: it sets the pose, sends the
//! goal, follows the telemetry to the goal, logs it and draws it; Ctrl-C's
//! stop reaches the rover.

use rover_tests::avr::EmulatedRover;
use rover_tests::scenario;
use sim_host::console::{drive, picture, replay, End, Plan, Record, CSV_HEADER};
use sim_host::geom::V2;
use sim_host::scenario::Scenario;
use std::sync::atomic::{AtomicBool, Ordering};

/// The emulated rover booted at the start of the built-in scenario
/// `path` (sensor noise `seed`), and the console's plan for it.
fn start(path: &str, seed: u64) -> (Scenario, EmulatedRover, Plan) {
    let sc = scenario(path);
    let (rover, pose) = EmulatedRover::new(&sc, seed, None, false);
    let plan = plan(&sc, &pose);
    (sc, rover, plan)
}

/// The host's core configured as the firmware, for the replay of its log.
fn firmware_config() -> planner_core::Config {
    planner_core::ConfigBuilder::new(planner_core::AdcProfile::AVR_10BIT_5V)
        .build()
        .unwrap()
}

/// The console's plan for `sc` from the pose line the rover starts at.
fn plan(sc: &Scenario, pose: &str) -> Plan {
    let p: Vec<i16> = pose
        .split(' ')
        .skip(1)
        .map(|v| v.parse().unwrap())
        .collect();
    let mm = |m: f64| (m * 1e3).round() as i16;
    Plan {
        pose: Some((p[0], p[1], p[2])),
        goal: (mm(sc.goal[0]), mm(sc.goal[1])),
    }
}

#[test]
fn the_console_drives_the_emulated_rover_to_its_goal_and_draws_it() {
    let (sc, mut rover, plan) = start("paper/env1-ex1.toml", 1);
    let stop = AtomicBool::new(false);
    let mut shown = Vec::new();
    let (records, end) = drive(&mut rover, plan, &stop, |r| {
        shown.push(r.status_line(plan.goal))
    })
    .unwrap();
    assert_eq!(end, End::Arrived, "{:?}", records.last());
    assert!(!rover.collided, "no collision");
    let goal = V2::new(sc.goal[0], sc.goal[1]);
    assert!(rover.p.dist(goal) < 0.2, "at {:?}", rover.p);
    assert!(records.len() > 5 && shown.len() == records.len());
    assert!(shown.last().unwrap().contains("arrived"), "{shown:?}");
    // The log: one row per telemetry line, in order, each parsing back.
    let rows: Vec<String> = records.iter().map(Record::csv_row).collect();
    assert_eq!(CSV_HEADER.split(',').count(), rows[0].split(',').count());
    assert!(records.windows(2).all(|w| w[0].ms < w[1].ms));
    assert_eq!(
        records[0].cal,
        planner_core::rover::calibration::Source::Datasheet,
        "no calibration stored"
    );
    // The log replayed through the host's core, configured as the
    // firmware: every step decided alike, bit for bit.
    let cfg = firmware_config();
    let replayed = replay(cfg, plan.goal, &records);
    assert_eq!(replayed.differ, Vec::<usize>::new());
    // The picture: the world behind the odometry's path, how it ended, and
    // what the replayed planner saw.
    let svg = picture(&records, end, plan.goal, Some(&sc), Some(&replayed));
    assert!(
        svg.starts_with("<svg") && svg.contains("reached"),
        "{}",
        &svg[..200]
    );
    assert!(svg.contains(&sc.name));
    let out = std::env::temp_dir().join("rover-console-env1-ex1.svg");
    std::fs::write(&out, &svg).unwrap();
    println!(
        "console: {} steps, {end:?}; the picture: {}",
        records.len(),
        out.display()
    );
}

#[test]
fn a_stop_from_the_console_stops_the_rover() {
    let (_, mut rover, plan) = start("paper/env1-ex1.toml", 2);
    let stop = AtomicBool::new(false);
    // Ctrl-C at the first step.
    let (records, end) = drive(&mut rover, plan, &stop, |_| {
        stop.store(true, Ordering::Relaxed)
    })
    .unwrap();
    assert_eq!(end, End::Stopped);
    assert_eq!(records.len(), 1);
    // The `S` reaches the firmware: its OK, then the motors stay off.
    let mut ok = false;
    let mut high = 0;
    for ms in 0..200 {
        let pulses = rover.tick();
        while let Some(l) = rover.take_line() {
            ok |= l == "OK";
        }
        if ms >= 20 {
            high += pulses;
        }
    }
    assert!(ok, "S answered");
    assert_eq!(high, 0, "motors off after the stop");
}

/// Through the U-trap the guard keeps flank points, and the rover logs the
/// looks that did: with them the host's core decides every step as the
/// firmware did; with the looks or the counts changed, it does not.
#[test]
fn a_logged_run_replays_bit_for_bit_with_its_guard_looks() {
    let (sc, mut rover, plan) = start("traps/u-trap.toml", 3);
    let stop = AtomicBool::new(false);
    let (records, end) = drive(&mut rover, plan, &stop, |_| {}).unwrap();
    assert_eq!(end, End::Arrived);
    let looks: usize = records.iter().map(|r| r.looks.len()).sum();
    println!(
        "console: u-trap, {} steps, {looks} guard looks logged",
        records.len()
    );
    assert!(looks > 0, "no look changed the flank points");
    let cfg = firmware_config();
    let replayed = replay(cfg, plan.goal, &records);
    assert_eq!(replayed.differ, Vec::<usize>::new());
    assert!(
        !replayed.seen.is_empty(),
        "the collision points the planner saw"
    );
    let out = std::env::temp_dir().join("rover-console-u-trap.svg");
    std::fs::write(
        &out,
        picture(&records, end, plan.goal, Some(&sc), Some(&replayed)),
    )
    .unwrap();
    println!("console: the picture: {}", out.display());
    // The replay is a check that can fail: with every look reading a wall
    // 100 mm off all round, or with the front count of every step raised,
    // some step differs. (Whether dropping the looks changes a step
    // depends on the run: a flank point matters only in the way.)
    let near =
        planner_core::rover::calibration::datasheet_row(planner_core::AdcProfile::AVR_10BIT_5V)[0];
    let mut walled = records.clone();
    for r in &mut walled {
        r.looks.iter_mut().for_each(|l| l.counts = [near; 5]);
    }
    let mut changed = records.clone();
    for r in &mut changed {
        r.counts[2] = r.counts[2].saturating_add(150);
    }
    let (walled, changed) = (
        replay(cfg, plan.goal, &walled).differ,
        replay(cfg, plan.goal, &changed).differ,
    );
    println!(
        "console: with the looks walled {} steps differ, with the counts changed {}",
        walled.len(),
        changed.len()
    );
    assert!(!walled.is_empty(), "the looks are replayed");
    assert!(!changed.is_empty(), "a changed count is seen");
}
