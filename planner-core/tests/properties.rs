//! Property tests of the planner's invariants over any input.

use planner_core::eapf::command::guard;
use planner_core::maps::route::{RouteConfig, RouteMap, RoutePlanner};
use planner_core::rover::protocol::{parse, LineReader, Request, LINE_CAPACITY, STALE_MS};
use planner_core::{
    AdcProfile, Angle, Config, ConfigBuilder, EscapeConfig, Guard, Output, Planner, Point, Pose,
    RawCounts, Reading, Readings, Status,
};
use proptest::prelude::*;

fn pose() -> impl Strategy<Value = Pose> {
    (any::<i16>(), any::<i16>(), any::<u16>()).prop_map(|(x, y, h)| Pose {
        position: Point::new(x, y),
        heading: Angle(h),
    })
}

/// Mostly counts a sensor can give (so the planner moves), sometimes any.
fn counts() -> impl Strategy<Value = u16> {
    prop_oneof![12 => 0u16..700, 1 => any::<u16>()]
}

/// The step keeps the rules of [`Output::broken_rule`] for the readings it
/// was planned from.
fn step_keeps_the_rules(
    cfg: &Config,
    readings: &Readings,
    pose: Pose,
    out: Output,
) -> Result<(), TestCaseError> {
    prop_assert_eq!(out.broken_rule(cfg, readings, pose), None, "{:?}", out);
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 3_000, ..ProptestConfig::default() })]

    /// Any raw counts, any pose, any goal, several cycles: no panic; the
    /// step is within [0, range]; the safety rule holds; a heading outside
    /// the sensed sector is a pure turn; stops have a zero step.
    #[test]
    fn invariants_hold_for_any_input(
        goal in (any::<i16>(), any::<i16>()),
        cycles in prop::collection::vec((pose(), prop::array::uniform5(counts())), 1..6),
        stm32 in any::<bool>(),
    ) {
        let adc = if stm32 { AdcProfile::STM32_12BIT_3V3 } else { AdcProfile::AVR_10BIT_5V };
        let cfg = ConfigBuilder::new(adc).build().unwrap();
        let mut p = Planner::new(cfg, Point::new(goal.0, goal.1));
        for (pose, raw) in cycles {
            let out = p.step_raw(pose, &raw);
            step_keeps_the_rules(&cfg, p.last_readings(), pose, out)?;
            // The guard never panics.
            let _ = p.guard_raw(&raw, out.command.step_mm);
        }
    }

    /// The route layer over any small map (edges naming missing nodes
    /// refused), any goal, any poses and counts: no panic; each step keeps
    /// the safety rule of the planner it drives, and stops have a zero
    /// step.
    #[test]
    fn the_route_layer_keeps_the_invariants_over_any_map(
        nodes in prop::collection::vec((any::<i16>(), any::<i16>()), 0..8),
        edges in prop::collection::vec((0u16..10, 0u16..10, any::<u16>()), 0..20),
        goal in (any::<i16>(), any::<i16>()),
        cycles in prop::collection::vec((pose(), prop::array::uniform5(counts())), 1..8),
    ) {
        let cfg = ConfigBuilder::new(AdcProfile::AVR_10BIT_5V).build().unwrap();
        let mut map: RouteMap<8, 16> = RouteMap::new();
        for (x, y) in nodes {
            map.add_node(Point::new(x, y)).unwrap();
        }
        for (a, b, clearance) in edges {
            // A missing node, a loop or a full map: refused, not a panic.
            let _ = map.add_edge(a, b, clearance);
        }
        let mut p = RoutePlanner::new(cfg, map, RouteConfig::default(), Point::new(goal.0, goal.1));
        for (pose, raw) in cycles {
            let out = p.step_raw(pose, &raw);
            step_keeps_the_rules(&cfg, p.planner().last_readings(), pose, out)?;
            let _ = p.guard_raw(&raw, out.command.step_mm);
        }
    }

    /// Any configuration values: building never panics; a built
    /// configuration runs.
    #[test]
    fn any_config_builds_or_is_an_error(
        radius in any::<u16>(), range in any::<u16>(), offset in any::<u16>(),
        angles in prop::array::uniform5(any::<i16>()),
        gains in (any::<i32>(), any::<i32>(), any::<i32>()),
        tol in (any::<u16>(), any::<u16>(), any::<u16>()),
        t in (any::<i16>(), any::<i16>()),
        esc in (any::<bool>(), any::<u16>(), any::<u16>(), any::<u16>(), any::<u16>(), any::<i32>(), any::<u16>()),
        bits in any::<u8>(), vref in any::<u16>(),
        raw in prop::array::uniform5(any::<u16>()),
    ) {
        let escape = EscapeConfig {
            enabled: esc.0,
            window_steps: esc.1,
            stuck_mm: esc.2,
            crumb_mm: esc.3,
            revisit_mm: esc.4,
            k_v: esc.5,
            give_up_drops: esc.6,
            ..EscapeConfig::default()
        };
        let built = ConfigBuilder::new(AdcProfile { bits, vref_mv: vref })
            .robot_radius_mm(radius)
            .sensor_range_mm(range)
            .sensor_offset_mm(offset)
            .sensor_angles_deg(angles)
            .gains_q10(gains.0, gains.1, gains.2)
            .goal_tolerance_mm(tol.0)
            .clearance_mm(tol.1)
            .standoff_mm(tol.2)
            .tolerances_deg(t.0, t.1)
            .escape(escape)
            .build();
        if let Ok(cfg) = built {
            let mut p = Planner::new(cfg, Point::new(1_000, 1_000));
            let out = p.step_raw(Pose::default(), &raw);
            prop_assert!(out.command.step_mm <= range);
        }
    }

    /// Any bytes on the serial line, with any pauses between them: the
    /// reader never panics, answers once per `\n`, and a line it kept whole
    /// since the last pause of more than `STALE_MS` means what `parse` says
    /// of it; a longer one is refused.
    #[test]
    fn the_line_reader_takes_any_bytes(
        bytes in prop::collection::vec(
            (
                prop_oneof![4 => any::<u8>(), 1 => Just(b'\n'), 2 => Just(b' '), 3 => b'0'..=b'9'],
                prop_oneof![8 => 0..=2u32, 1 => 0..=2 * STALE_MS, 1 => any::<u32>()],
            ),
            0..200,
        ),
        start in any::<u32>(),
    ) {
        let mut reader = LineReader::new();
        let mut line = Vec::new();
        let mut now = start;
        for &(b, pause) in &bytes {
            now = now.wrapping_add(pause);
            if pause > STALE_MS {
                line.clear();
            }
            let got = reader.feed(b, now);
            if b == b'\n' {
                let want = if line.len() <= LINE_CAPACITY { parse(&line) } else { None };
                prop_assert_eq!(got, Some(want));
                line.clear();
            } else {
                prop_assert_eq!(got, None);
                line.push(b);
            }
        }
    }

    /// Every command, written as the protocol's text, parses back to itself.
    #[test]
    fn every_command_line_parses_back(x in any::<i16>(), y in any::<i16>(), deg in any::<i16>(), which in 0u8..5) {
        let (text, want) = match which {
            0 => (format!("G {x} {y}"), Request::Goal(x, y)),
            1 => (format!("P {x} {y} {deg}\r"), Request::Pose(x, y, deg)),
            2 => ("S".to_string(), Request::Stop),
            3 => ("M".to_string(), Request::Memory),
            _ => (format!("R  {x} {y}"), Request::Replay(x, y)),
        };
        prop_assert_eq!(parse(text.as_bytes()), Some(want), "{}", text);
    }
}

/// Counts an arbitrary world could give, in regimes of 30 cycles: open
/// ground, any readings, a wedge (every beam "too close", walls nearer than
/// the sensors' minimum range), and a mix of near and far.
struct World {
    state: u64,
    regime: u8,
    left: u16,
    near: u16,
}

impl World {
    fn new(seed: u64, near: u16) -> World {
        World {
            state: seed | 1,
            regime: 0,
            left: 0,
            near,
        }
    }

    fn next(&mut self) -> u64 {
        // xorshift64*
        self.state ^= self.state >> 12;
        self.state ^= self.state << 25;
        self.state ^= self.state >> 27;
        self.state.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }

    fn counts(&mut self) -> RawCounts {
        if self.left == 0 {
            self.regime = (self.next() % 4) as u8;
            self.left = 30;
        }
        self.left -= 1;
        let mut raw = [57; 5];
        for c in &mut raw {
            let r = self.next();
            *c = match self.regime {
                0 => 50 + (r % 15) as u16,
                1 => (r % 700) as u16,
                2 => self.near,
                _ if r.is_multiple_of(2) => self.near,
                _ => 50 + (r % 600) as u16,
            };
        }
        raw
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    /// The safety rule over long closed-loop runs (3,000 cycles each, the
    /// rover where its commands and the guard took it, the counts of an
    /// arbitrary world, the wedge's among them): every step is at most the
    /// sensors' range; a step planned from the view is within the sector
    /// and its free way; the wedge's back-out is the only other step, and
    /// its guard, like every other, stops for a ranged reading or an
    /// implausible one in the way.
    #[test]
    fn the_safety_rule_holds_over_long_closed_loop_runs(
        seed in any::<u64>(),
        goal in (-20_000i16..20_000, -20_000i16..20_000),
    ) {
        let cfg = ConfigBuilder::new(AdcProfile::AVR_10BIT_5V).build().unwrap();
        let near = cfg.calibration().full_scale() / 2 + 100;
        let mut world = World::new(seed, near);
        let mut p = Planner::new(cfg, Point::new(goal.0, goal.1));
        let mut pose = Pose::default();
        let mut backed_out = 0;
        let mut cycles = 0;
        for _ in 0..3_000 {
            cycles += 1;
            let out = p.step_raw(pose, &world.counts());
            let step = out.command.step_mm;
            prop_assert!(step <= cfg.sensor_range_mm(), "step {} > the range", step);
            if out.status != Status::Moving {
                prop_assert_eq!(step, 0);
                if out.status == Status::SensorFault {
                    continue;
                }
                break;
            }
            if step > 0 && p.backing_out() {
                backed_out += 1;
            } else if step > 0 {
                step_keeps_the_rules(&cfg, p.last_readings(), pose, out)?;
            }
            pose.heading = out.command.heading;
            // The advance: the guard before every 10 mm with fresh counts.
            let mut done = 0;
            while done < step {
                let raw = world.counts();
                let verdict = p.guard_raw(&raw, step - done);
                let mut ranged = *p.last_readings();
                for (r, c) in ranged.iter_mut().zip(raw) {
                    *r = cfg.calibration().reading(c);
                    if *r == Reading::TooClose {
                        *r = Reading::Clear;
                    }
                }
                if guard(&cfg, &ranged, step - done) == Guard::Stop {
                    prop_assert_eq!(verdict, Guard::Stop);
                }
                if verdict == Guard::Stop {
                    break;
                }
                let piece = (step - done).min(10);
                pose.position = pose.position.offset(pose.heading, piece);
                done += piece;
            }
        }
        // Not a property: how long a run lasts and how often the wedge was
        // met are the world's (`PROPTEST_VERBOSE`-free print for a look).
        if std::env::var_os("LONG_RUNS").is_some() {
            eprintln!("{cycles} cycles, {backed_out} back-outs, {pose:?}");
        }
    }
}
