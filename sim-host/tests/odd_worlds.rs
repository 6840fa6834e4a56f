//! Odd scenario files: whatever the numbers in them (zero, huge, tiny,
//! negative, not finite; a robot of a micrometre or of 30 cm;
//! obstacles on the start, outside the walls or a million metres away;
//! moving obstacles at any speed), a file is either refused with the key
//! and the rule it breaks or it runs, and nothing panics: not the parser,
//! not the world, not the route map, not any of the planners. FORMAT.md's rules and
//! ours (positions within ±32.767 m) are checked in `scenario`'s unit tests;
//! this is the net under them. Collisions are not counted against the
//! planners here: these worlds hold moving obstacles at any speed, and posts
//! of a few centimetres that the five beams pass by (the commit history, "Known
//! failures").

use clap::ValueEnum;
use planner_core::maps::liquid::LiquidConfig;
use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};
use sim_host::planners::PlannerKind;
use sim_host::scenario::Scenario;
use sim_host::sim::{run, SimConfig};
use std::cell::Cell;
use std::path::Path;

/// A number as written in the file: mostly one inside `[lo, hi]`, else one
/// of the odd ones (TOML writes infinities and NaN as `inf` and `nan`).
fn number(lo: f64, hi: f64) -> impl Strategy<Value = String> {
    let odd = prop::sample::select(vec![
        "0.0", "1e-9", "5e-324", "-1.0", "32.767", "-32.767", "32.768", "1e6", "1e300", "-1e300",
        "inf", "-inf", "nan",
    ]);
    prop_oneof![
        60 => (lo..=hi).prop_map(|v| format!("{v:?}")),
        1 => odd.prop_map(str::to_string),
    ]
}

/// Points, mostly as many as `usual` says, now and then fewer (none
/// included).
fn points(b: [f64; 4], usual: std::ops::Range<usize>) -> impl Strategy<Value = Vec<String>> {
    let few = 0..usual.start;
    prop_oneof![20 => usual, 1 => few].prop_flat_map(move |n| prop::collection::vec(point(b), n))
}

fn point(b: [f64; 4]) -> impl Strategy<Value = String> {
    (number(b[0], b[2]), number(b[1], b[3])).prop_map(|(x, y)| format!("[{x}, {y}]"))
}

/// A scenario file's text: a world up to 10 m across somewhere within
/// ±32.767 m (sometimes beyond), and whatever is in it.
fn scenario_text() -> impl Strategy<Value = String> {
    let corner = prop_oneof![20 => -32.767..22.7f64, 1 => -33.0..33.0f64];
    let bounds = (
        corner.clone(),
        corner,
        prop::sample::select(vec![0.3, 1.0, 4.0, 10.0]),
        prop::sample::select(vec![0.3, 1.0, 4.0, 10.0]),
    )
        .prop_map(|(x, y, w, h)| [x, y, x + w, y + h]);
    bounds.prop_flat_map(|b| {
        // The start and the goal: in the middle half, mostly.
        let (w, h) = (b[2] - b[0], b[3] - b[1]);
        let middle = [
            b[0] + w / 4.0,
            b[1] + h / 4.0,
            b[2] - w / 4.0,
            b[3] - h / 4.0,
        ];
        let circle = (point(b), number(0.005, 0.3))
            .prop_map(|(c, r)| format!("[[circle]]\ncenter = {c}\nradius = {r}\n"));
        // Polygons about a point, within 0.4 m of it.
        let near = (b[0]..b[2], b[1]..b[3])
            .prop_flat_map(|(x, y)| points([x - 0.4, y - 0.4, x + 0.4, y + 0.4], 3..7));
        let polygon = near.prop_map(|ps| format!("[[polygon]]\npoints = [{}]\n", ps.join(", ")));
        let moving = (
            point(b),
            number(0.01, 0.5),
            number(0.0, 2.0),
            points(b, 1..4),
        )
            .prop_map(|(c, r, v, w)| {
                format!(
                    "[[moving]]\ncenter = {c}\nradius = {r}\nspeed = {v}\nwaypoints = [{}]\n",
                    w.join(", ")
                )
            });
        (
            number(1e-6, 0.3),
            point(middle),
            point(middle),
            prop::option::of(number(-720.0, 720.0)),
            prop::collection::vec(circle, 0..4),
            prop::collection::vec(polygon, 0..3),
            prop::collection::vec(moving, 0..2),
        )
            .prop_map(move |(radius, start, goal, heading, cs, ps, ms)| {
                let mut t = format!(
                    "format = 1\nname = \"odd\"\nbounds = [{:?}, {:?}, {:?}, {:?}]\n\
                     robot_radius = {radius}\nstart = {start}\ngoal = {goal}\n",
                    b[0], b[1], b[2], b[3]
                );
                if let Some(h) = heading {
                    t += &format!("start_heading = {h}\n");
                }
                for part in cs.iter().chain(&ps).chain(&ms) {
                    t += part;
                }
                t
            })
    })
}

#[test]
fn an_odd_file_is_refused_with_its_key_or_runs_and_nothing_panics() {
    let mut runner = TestRunner::new(Config {
        cases: 300,
        failure_persistence: None,
        ..Config::default()
    });
    let (ran, refused) = (Cell::new(0), Cell::new(0));
    runner
        .run(&scenario_text(), |text| {
            match Scenario::parse(&text, Path::new("odd.toml")) {
                Err(e) => {
                    refused.set(refused.get() + 1);
                    prop_assert!(!e.key.is_empty() && !e.rule.is_empty(), "{e}");
                }
                Ok(sc) => {
                    ran.set(ran.get() + 1);
                    // Every planner `--planner` offers, and those that
                    // sense with their sensors set back too.
                    let sensing = PlannerKind::value_variants()
                        .iter()
                        .filter(|p| !p.uses_map());
                    let runs = PlannerKind::value_variants()
                        .iter()
                        .map(|&p| (p, false))
                        .chain(sensing.map(|&p| (p, true)));
                    for (planner, set_back) in runs {
                        let cfg = SimConfig {
                            planner,
                            set_back,
                            max_steps: 600,
                            ..SimConfig::default()
                        };
                        let r = run(&sc, &cfg, None);
                        // The map planners plan before they drive: their
                        // steps are the plan's computation steps, bounded
                        // by the liquid planner's own budget, not cycles.
                        let limit = if planner.uses_map() {
                            LiquidConfig::paper(false).budget as usize
                        } else {
                            cfg.max_steps
                        };
                        prop_assert!(r.steps <= limit, "{planner:?}: {} steps", r.steps);
                        prop_assert!(r.path_length.is_finite(), "{planner:?}: {r:?}");
                    }
                }
            }
            Ok(())
        })
        .unwrap();
    // Both ways were taken often enough for the test to mean something.
    println!("{} files ran, {} refused", ran.get(), refused.get());
    assert!(ran.get() >= 30, "only {} of 300 files ran", ran.get());
    assert!(refused.get() >= 30, "only {} of 300 refused", refused.get());
}

proptest! {
    #![proptest_config(ProptestConfig {
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    /// Not even TOML: refused, never a panic.
    #[test]
    fn any_text_is_refused_or_parsed(text in "\\PC{0,200}") {
        if let Err(e) = Scenario::parse(&text, Path::new("any.toml")) {
            prop_assert!(!e.rule.is_empty());
        }
    }
}

/// The file the test above met in a clean-clone CI run (2026-12-03): the
/// liquid planner reached the goal after 839 computation steps, more than
/// the 600 cycles the test allows the planners that drive by sensors. Its
/// steps are the plan's, bounded by its own budget.
#[test]
fn the_map_planners_steps_are_the_plans_computation_steps() {
    let text = "format = 1\nname = \"odd\"\n\
        bounds = [-4.075645284244516, -25.9007480785276, -0.07564528424451566, -15.900748078527599]\n\
        robot_radius = 0.22337045071292053\n\
        start = [-1.7647970494672447, -18.4007480785276]\n\
        goal = [-2.393886493183513, -22.96754034581783]\n\
        [[circle]]\ncenter = [-2.615813392943062, -21.978299885092007]\nradius = 0.005\n\
        [[polygon]]\npoints = [[-2.418456744295631, -22.312278334052756], \
        [-1.6194803232174948, -21.82434141160053], [-1.6194803232174948, -21.990900369657084]]\n";
    let sc = Scenario::parse(text, Path::new("odd.toml")).unwrap();
    let cfg = SimConfig {
        planner: PlannerKind::Liquid,
        max_steps: 600,
        ..SimConfig::default()
    };
    let r = run(&sc, &cfg, None);
    assert_eq!(r.outcome, sim_host::sim::Outcome::Reached);
    assert!(r.steps > cfg.max_steps, "{} steps", r.steps);
    assert!(r.steps <= LiquidConfig::paper(true).budget as usize);
}
