//! The trap suite and the paper environments, end to end: every run is
//! collision-free, the walled-in goal is never "reached", and the scenarios
//! the product planner handles today are reached (all but the narrow
//! passage, which times out). The full table is in the commit history
//! (regenerate with the command there).

use sim_host::bench::{run_all, totals};
use sim_host::scenario::collect;
use sim_host::sim::{Outcome, SimConfig};
use std::path::PathBuf;

fn library() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenarios")
}

/// These files of the library.
fn library_files(rel: &[&str]) -> Vec<PathBuf> {
    rel.iter().map(|f| library().join(f)).collect()
}

#[test]
fn trap_suite_outcomes() {
    let files = collect(&[library()]).unwrap();
    assert!(files.len() >= 13, "library has {} files", files.len());
    let rows = run_all(&files, &SimConfig::default(), false).unwrap();
    for r in &rows {
        assert!(
            r.safe(),
            "{}: {:?}, min clearance {}",
            r.name,
            r.outcome,
            r.min_clearance
        );
    }
    let reached = |name: &str| {
        rows.iter()
            .find(|r| r.name == name)
            .map(|r| r.outcome == Outcome::Reached)
            .unwrap_or(false)
    };
    for name in [
        "env1-ex1",
        "env1-ex2",
        "env2-ex2",
        "u-trap",
        "two-obstacles",
        "gnron",
        "corridor",
        "comb",
        "dead-end",
        "rooms",
        "env2-ex1",
    ] {
        assert!(reached(name), "{name} not reached");
    }
    let t = totals(&rows);
    assert_eq!(t.collisions, 0);
    assert!(t.reached >= 11, "{t:?}");
}

#[test]
fn bad_scenario_is_rejected_before_running() {
    let dir = std::env::temp_dir().join(format!("sim-host-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let f = dir.join("bad.toml");
    std::fs::write(&f, "format = 1\nname = \"b\"\nbounds = [0.0, 0.0, 1.0, 1.0]\nstart = [0.5, 0.5]\ngoal = [0.9, 0.5]\ncolour = 3\n").unwrap();
    let e = run_all(std::slice::from_ref(&f), &SimConfig::default(), false).unwrap_err();
    assert_eq!(e.key, "colour");
    assert!(e.to_string().contains("bad.toml"));
    std::fs::remove_dir_all(&dir).ok();
}

/// The classical APF baseline shows the failures the papers report: it
/// reaches a world without a local minimum but not the U-trap or the two
/// obstacles side by side (it loops in front of them until the time-out).
#[test]
fn classical_apf_fails_where_the_papers_say() {
    use sim_host::planners::PlannerKind;
    let cfg = SimConfig {
        planner: PlannerKind::Apf,
        max_steps: 600,
        ..SimConfig::default()
    };
    let files = library_files(&[
        "paper/env1-ex2.toml",
        "traps/u-trap.toml",
        "traps/two-obstacles.toml",
    ]);
    let rows = run_all(&files, &cfg, false).unwrap();
    let outcome = |name: &str| rows.iter().find(|r| r.name == name).unwrap().outcome;
    assert_eq!(outcome("env1-ex2"), Outcome::Reached);
    assert_ne!(outcome("u-trap"), Outcome::Reached);
    assert_ne!(outcome("two-obstacles"), Outcome::Reached);
}

/// The route layer over the known map (`route`) drives the traps where the
/// sensing planner alone detours (the u-trap, the dead end, the rooms and
/// the comb: 2.6–6.0× the reference with `eapf`, the commit history) within
/// 1.25× of the shortest path, without a collision, and the corridor and
/// `gnron` (a route through a gap) within 1.25× too; the walled-in goal has
/// no route, and is still not reached.
#[test]
fn the_route_layer_drives_the_traps_near_the_shortest_path() {
    use sim_host::planners::PlannerKind;
    let cfg = SimConfig {
        planner: PlannerKind::Route,
        ..SimConfig::default()
    };
    let files = library_files(&[
        "traps/u-trap.toml",
        "traps/dead-end.toml",
        "traps/rooms.toml",
        "traps/comb.toml",
        "traps/corridor.toml",
        "traps/gnron.toml",
        "traps/walled-in.toml",
    ]);
    let rows = run_all(&files, &cfg, false).unwrap();
    for r in &rows {
        assert_ne!(r.outcome, Outcome::Collision, "{} collided", r.name);
        if r.solvable {
            assert_eq!(r.outcome, Outcome::Reached, "{}", r.name);
            let ratio = r.ratio().unwrap();
            assert!(ratio <= 1.25, "{}: {ratio:.2}× the reference", r.name);
        } else {
            assert_ne!(r.outcome, Outcome::Reached, "{}", r.name);
        }
    }
}

/// The narrow passage (a wall with a gap 20 mm wider than the disc and
/// the planner's clearance, which `eapf` alone never finds): the route
/// layer's map has nodes in the gap, and the rover drives through it on
/// each of five seeds without a collision, within 1.5× of the reference
/// (1.03–1.44×; 3.1–3.8× on four seeds when the waypoint before the gap
/// was passed 250 mm early and the rover met the mouth off its axis).
#[test]
fn the_route_layer_drives_the_narrow_passage() {
    use sim_host::planners::PlannerKind;
    let files = library_files(&["traps/narrow-passage.toml"]);
    for seed in 1..=5 {
        let cfg = SimConfig {
            planner: PlannerKind::Route,
            seed,
            ..SimConfig::default()
        };
        let rows = run_all(&files, &cfg, false).unwrap();
        let r = &rows[0];
        assert_eq!(r.outcome, Outcome::Reached, "seed {seed}");
        let ratio = r.ratio().unwrap();
        assert!(ratio <= 1.5, "seed {seed}: {ratio:.2}× the reference");
    }
}

/// The world `gen --seed SEED` writes (the paper's environment 2
/// parameters, its default start and goal), named `gen-SEED`, and its file
/// text.
fn generated(seed: u64) -> (String, String) {
    use sim_host::generate::RandomWorld;
    let name = format!("gen-{seed}");
    let world = RandomWorld::paper_env2(&name, [6.0, 7.3], [12.7, 9.75], seed);
    let text = world.to_toml(&format!("gen --seed {seed}")).unwrap();
    (name, text)
}

/// Boundary following once the escape gives up (planner-core's `follow`
/// module). gen-102 is a world `gen` writes for seed 102 (the paper's
/// environment 2 parameters; no rule was tuned on it): with seed 1 the
/// escape works round a cluster of circles for its whole budget and
/// reports the goal unreachable (so it does with `follow` off); the
/// follower then went round a small obstacle with the goal beside it,
/// outside the beams, and closed its loop (unreachable again), until it
/// learnt to look towards the goal past the boundary's nearest point
/// (`follow`'s look). Now it reaches the goal. (The follower's first test
/// world, gen-144 with seed 1, reached before the look and times out
/// with it: the commit history.) The walled-in goal is still reported
/// unreachable: the follower goes round its wall and closes the loop.
#[test]
fn the_boundary_follower_reaches_a_goal_the_escape_gave_up_on() {
    let dir = std::env::temp_dir().join(format!("follow-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (name, text) = generated(102);
    let file = dir.join(format!("{name}.toml"));
    std::fs::write(&file, text).unwrap();
    let rows = run_all(&[file], &SimConfig::default(), false).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(rows[0].outcome, Outcome::Reached, "{:?}", rows[0]);

    for seed in 1..=3 {
        let outcome = library_outcome("traps/walled-in.toml", seed);
        assert_eq!(outcome, Outcome::Unreachable, "seed {seed}");
    }
}

/// The outcome of the library file `rel` with noise seed `seed`.
fn library_outcome(rel: &str, seed: u64) -> Outcome {
    let cfg = SimConfig {
        seed,
        ..SimConfig::default()
    };
    run_all(&library_files(&[rel]), &cfg, false).unwrap()[0].outcome
}

/// The longest time, s, the rover stayed within 5 cm of one spot.
fn longest_on_one_spot(trace: &[sim_host::sim::TraceRow]) -> f64 {
    let mut longest = 0.0f64;
    for (i, a) in trace.iter().enumerate() {
        let left = trace[i..]
            .iter()
            .find(|b| (b.x - a.x).hypot(b.y - a.y) > 0.05)
            .map_or(trace.last().map_or(a.t, |l| l.t), |b| b.t);
        longest = longest.max(left - a.t);
    }
    longest
}

/// gen-117 (a world `gen` writes for seed 117, as gen-102 above), seed 1:
/// after the escape gave up, the follower turned towards the boundary to
/// a heading the guard refused after the turn (a face only the turned
/// beams saw), turned away, and from there took the refused heading again:
/// 800 cycles on one spot, then "unreachable" (planner-core's
/// `Follow::turns_to_skip`). Now each refusal on the spot passes over one
/// more turn and the rover gets off it. Measured here (no reference, so
/// the simulator's budget is the straight line's): 428.8 s within 5 cm of
/// one spot without the rule, 132.4 s with it (the escape's rocking in the
/// same pocket before it gives up, steps of 1–6 cm); 53.0 s since the
/// escape hands over after 200 cycles and the follower's turns count for
/// the fold-back filter (the commit history); 44.7 s with the wedge rule.
#[test]
fn the_boundary_follower_does_not_retake_a_refused_turn() {
    let stuck_s = longest_on_one_spot_in(117, 1);
    assert!(stuck_s < 200.0, "{stuck_s:.1} s on one spot");
}

/// Drive `generated(seed)` with noise seed `noise_seed` and no reference
/// (the simulator's budget is the straight line's), print the outcome,
/// check it is no collision, and return the longest time, s, within 5 cm
/// of one spot.
fn longest_on_one_spot_in(seed: u64, noise_seed: u64) -> f64 {
    use sim_host::scenario::Scenario;
    let (name, text) = generated(seed);
    let sc = Scenario::parse(&text, format!("{name}.toml").as_ref()).unwrap();
    let cfg = SimConfig {
        seed: noise_seed,
        ..SimConfig::default()
    };
    let run = sim_host::sim::run(&sc, &cfg, None);
    let stuck_s = longest_on_one_spot(&run.trace);
    println!(
        "{name}: {:?} after {} cycles, {:.2} m; longest on one spot {stuck_s:.1} s",
        run.outcome, run.steps, run.path_length
    );
    assert_ne!(run.outcome, Outcome::Collision, "{name}");
    stuck_s
}

/// gen-223 (a world `gen` writes for seed 223, as gen-102 above), seed 1:
/// following a boundary into a tight pocket, the rover turned on the spot
/// and each outer beam's view of a free way read "too close" (the
/// fold-back filter compared it with that beam's own last look, at the
/// wall), so no heading was ever free. The turns on the spot while
/// following did not count towards the filter's "held" (three full turns:
/// then each sensor is compared with the one that looked its way the
/// cycle before), as they do in the potential field. Now they do, and the
/// rover turns its way out (planner-core's `Planner::count_turn`).
#[test]
fn the_follower_turning_in_a_pocket_trusts_the_beams_that_looked_there() {
    let stuck_s = longest_on_one_spot_in(223, 1);
    assert!(stuck_s < 60.0, "{stuck_s:.1} s on one spot");
}

/// gen-269 with noise seed 3: the rover crept into a pocket whose walls
/// are nearer than the sensors' minimum range, where every heading has a
/// beam in the disc's way that reads too close, and turned on the spot for
/// 2,427 cycles until the follower's budget called the goal unreachable.
/// Now after four full turns it backs out the way it came (planner-core's
/// wedge rule, `Planner::back_out`; the commit history, "The wedge").
#[test]
fn a_wedged_rover_backs_out_the_way_it_came() {
    let stuck_s = longest_on_one_spot_in(269, 3);
    assert!(stuck_s < 60.0, "{stuck_s:.1} s on one spot");
}

/// The U-trap with five noise seeds. With seed 5 the escape gave up inside
/// the U, the follower looked out of it, sought back in to the hit point
/// from the other side and closed a false loop ("unreachable"); now only
/// following into the hit point's radius closes the loop (planner-core's
/// `Follow::pass_hit`).
#[test]
fn the_u_trap_is_reached_with_every_seed() {
    for seed in 1..=5 {
        let outcome = library_outcome("traps/u-trap.toml", seed);
        assert_eq!(outcome, Outcome::Reached, "seed {seed}");
    }
}

/// The worlds and seeds of the three collisions over five seeds of 200 box
/// worlds (`gen --kind boxes --count 200 --seed 1`), run with the sensors
/// on the rim or `set_back`: each run's name, seed and outcome.
fn known_collision_box_runs(set_back: bool) -> Vec<(String, u64, Outcome)> {
    box_runs(&[(145, 2), (200, 3), (105, 4)], set_back)
}

/// Generated box worlds (`gen --kind boxes`, each `box-<world seed>`), each
/// run with its seed and the sensors on the rim or `set_back`: each run's
/// name, seed and outcome.
fn box_runs(runs: &[(u64, u64)], set_back: bool) -> Vec<(String, u64, Outcome)> {
    generated_runs(sim_host::generate::Kind::Boxes, runs, set_back)
}

/// [`box_runs`] for generated worlds of any `kind` (each
/// `<prefix>-<world seed>`).
fn generated_runs(
    kind: sim_host::generate::Kind,
    runs: &[(u64, u64)],
    set_back: bool,
) -> Vec<(String, u64, Outcome)> {
    use sim_host::generate::world;
    let dir = std::env::temp_dir().join(format!(
        "{}-{set_back}-{}-{}",
        kind.prefix(),
        std::process::id(),
        runs[0].0
    ));
    std::fs::create_dir_all(&dir).unwrap();
    let mut out = Vec::new();
    for &(world_seed, seed) in runs {
        let name = format!("{}-{world_seed}", kind.prefix());
        let file = dir.join(format!("{name}.toml"));
        let text = world(kind, &name, [6.0, 7.3], [12.7, 9.75], world_seed).unwrap();
        std::fs::write(&file, text).unwrap();
        let cfg = SimConfig {
            seed,
            set_back,
            ..SimConfig::default()
        };
        let rows = run_all(&[file], &cfg, false).unwrap();
        println!(
            "{name} seed {seed}: {} after {} cycles",
            rows[0].outcome.as_str(),
            rows[0].steps
        );
        out.push((name, seed, rows[0].outcome));
    }
    std::fs::remove_dir_all(&dir).ok();
    out
}

/// Box worlds where the boundary follower went round in a circle of nine
/// 40° turns (the sector's edge towards the boundary, free each time, with
/// what it had met ahead), back to the same seek and hit, until the
/// simulator's budget ran out. After a whole circle the follower passes
/// what blocks on its side (`follow::Follow::hug`); with `note_turn` never
/// counting a turn, each of these times out.
#[test]
fn box_world_followers_leave_their_circles() {
    for (name, seed, outcome) in box_runs(&[(51, 1), (144, 1), (69, 4)], false) {
        assert_eq!(outcome, Outcome::Reached, "{name} with seed {seed}");
    }
}

/// The three collisions with the sensors on the rim (the commit history, "Known
/// failures"): box corners beyond the beams that no view saw, grazed after
/// turns on one spot, and a fold-back read after an advance. Ignored until
/// a rule keeps them off: `cargo test --release -p sim-host --test
/// trap_suite -- --ignored` runs them.
#[test]
#[ignore = "collides: the commit history, Known failures, collisions in box worlds"]
fn box_worlds_known_collisions() {
    for (name, seed, outcome) in known_collision_box_runs(false) {
        assert_ne!(outcome, Outcome::Collision, "{name} with seed {seed}");
    }
}

/// The same runs with the sensors set back from the rim by their minimum
/// range (`ConfigBuilder::sensors_set_back`, the commit history "Sensors set
/// back"): nothing outside the body is in their fold-back region, and none
/// of the three collides.
#[test]
fn set_back_sensors_keep_off_the_known_box_world_collisions() {
    for (name, seed, outcome) in known_collision_box_runs(true) {
        println!("{name} seed {seed}, sensors set back: {}", outcome.as_str());
        assert_ne!(outcome, Outcome::Collision, "{name} with seed {seed}");
    }
}

/// Indoor floors (`gen --kind rooms --seed 1`) whose reachable goal is
/// reported unreachable with seed 1. In rooms-19 the follower passes a
/// doorway beside its hit point and counts that as a loop round the
/// boundary, twice (the commit history, "Indoor floors"); rooms-22 and rooms-26
/// were not traced. Ignored until a rule mends them:
/// `cargo test --release -p sim-host --test trap_suite -- --ignored` runs
/// them.
#[test]
#[ignore = "reported unreachable: the commit history, Indoor floors"]
fn indoor_floor_goals_wrongly_reported_unreachable() {
    let runs = [(19, 1), (22, 1), (26, 1)];
    for (name, seed, outcome) in generated_runs(sim_host::generate::Kind::Rooms, &runs, false) {
        assert_eq!(outcome, Outcome::Reached, "{name} with seed {seed}");
    }
}

/// Walled worlds no rule was tuned on (`gen --kind walled`: box worlds with
/// a closed ring of walls round the goal, odd seeds, or the start, even
/// ones), generated by their world seeds and run with seed 1: every one
/// must be reported unreachable.
fn assert_walled_reported(world_seeds: &[u64]) {
    use sim_host::generate::{world, Kind};
    let dir =
        std::env::temp_dir().join(format!("walled-{}-{}", std::process::id(), world_seeds[0]));
    std::fs::create_dir_all(&dir).unwrap();
    let files: Vec<PathBuf> = world_seeds
        .iter()
        .map(|&world_seed| {
            let name = format!("walled-{world_seed}");
            let file = dir.join(format!("{name}.toml"));
            let text = world(Kind::Walled, &name, [6.0, 7.3], [12.7, 9.75], world_seed).unwrap();
            std::fs::write(&file, text).unwrap();
            file
        })
        .collect();
    let rows = run_all(&files, &SimConfig::default(), false).unwrap();
    std::fs::remove_dir_all(&dir).ok();
    for r in &rows {
        println!(
            "{} seed 1: {} after {} cycles",
            r.name,
            r.outcome.as_str(),
            r.steps
        );
        assert!(!r.solvable, "{}", r.name);
        assert_eq!(r.outcome, Outcome::Unreachable, "{}", r.name);
    }
}

/// The first twelve walled worlds. With a follower's budget of 12 give-up
/// budgets (`follow::BUDGET_GIVE_UPS` is 5), walled-11 runs out of the
/// simulator's budget first, the rover going round islands that do not
/// hold the goal.
#[test]
fn generated_walled_in_goals_are_reported_unreachable() {
    assert_walled_reported(&(1..=12).collect::<Vec<_>>());
}

/// Walled worlds whose first loop round the ring hands back to the
/// potential field, so that the report comes from a second round. Given a
/// second round as long as the first (`follow::SECOND_GIVE_UPS` as
/// `follow::BUDGET_GIVE_UPS`), walled-71 runs out of the simulator's budget
/// before the second loop closes.
#[test]
fn walled_in_goals_are_reported_after_a_shorter_second_round() {
    assert_walled_reported(&[47, 71, 79, 87]);
}

/// A walled world whose first round meets a second hit point, 1.5 m from
/// the goal, and follows on from there round the ring and the boxes
/// beside it (`SIM_DEBUG=1 sim-host run`): with a first round of 6
/// give-up budgets (`follow::BUDGET_GIVE_UPS` is 5), it runs out of the
/// simulator's budget before the budget says "unreachable".
#[test]
fn a_walled_in_goal_is_reported_within_the_first_rounds_budget() {
    assert_walled_reported(&[45]);
}

/// A walled world whose follower went round in a circle of nine 40° turns
/// beside the ring (as in `box_world_followers_leave_their_circles`) until
/// the simulator's budget ran out: with `note_turn` never counting a turn,
/// it times out after 2,197 cycles (checked; with `CIRCLE_TURNS` at 255
/// the rule still comes, after 255 turns in a row, and it is reported).
#[test]
fn a_walled_in_goal_is_reported_after_a_circle() {
    assert_walled_reported(&[35]);
}
