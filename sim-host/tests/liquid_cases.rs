//! The liquid-movement paper's four cases (docs/algorithms.md §3), on worlds of
//! our own from the scenario library: with no local minimum both the
//! classical APF and the liquid planners reach the goal; with two obstacles
//! making a local minimum, an obstacle near the goal, and a narrow passage
//! to an enclosed goal region, the liquid planners (offline and online)
//! reach it, while APF stops or loops. Prints the counts the paper reports
//! next to the paper's own (its worlds are not ours: its obstacles are tiny
//! against its step, so its pits need fewer virtual obstacles).

use sim_host::bench::run_all;
use sim_host::planners::PlannerKind;
use sim_host::scenario::Scenario;
use sim_host::sim::{plan_known_map, Outcome, SimConfig};
use std::path::PathBuf;

fn scenario(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("scenarios")
        .join(rel)
}

#[test]
fn the_four_cases() {
    // (case, file, must APF fail?)
    let cases = [
        ("no local minimum", "paper/env1-ex2.toml", false),
        (
            "two obstacles, local minimum",
            "traps/two-obstacles.toml",
            true,
        ),
        ("obstacle near the goal", "traps/gnron.toml", false),
        (
            "narrow passage, enclosed goal region",
            "traps/narrow-passage.toml",
            true,
        ),
    ];
    println!("paper, example 2: offline 10 VOs / 288 computation / 35 motion steps (case 1), 4 / 110 / 47 (case 2); online 16 VOs / 81 steps, 2 / 53 / 33");
    for (case, file, apf_fails) in cases {
        let sc = Scenario::load(&scenario(file)).unwrap();
        for restart in [true, false] {
            let plan = plan_known_map(&sc, restart)
                .unwrap_or_else(|e| panic!("{case}: liquid (restart {restart}): {e:?}"));
            println!(
                "{case:38} {:14} {:4} VOs {:6} computation {:5} motion steps",
                if restart { "liquid" } else { "liquid-online" },
                plan.virtual_obstacles.len(),
                plan.computation_steps,
                plan.motion_steps
            );
        }
        // Driven by the simulator, collision-free, and APF for comparison.
        for kind in [
            PlannerKind::Liquid,
            PlannerKind::LiquidOnline,
            PlannerKind::Apf,
        ] {
            let cfg = SimConfig {
                planner: kind,
                max_steps: 800,
                ..SimConfig::default()
            };
            let row = &run_all(&[scenario(file)], &cfg, false).unwrap()[0];
            println!("{case:38} {:14} {:?}", kind.name(), row.outcome);
            match kind {
                PlannerKind::Apf if apf_fails => {
                    assert_ne!(row.outcome, Outcome::Reached, "{case}")
                }
                PlannerKind::Apf => {}
                _ => assert_eq!(row.outcome, Outcome::Reached, "{case}: {}", kind.name()),
            }
        }
    }
}
