//! The peers (Bug2, TangentBug, VFH+) end to end in the simulator, with
//! the product's sensors, executor and guard: none collides in the library
//! or the examples on five seeds, each reaches the U-traps and the paper
//! environments it is known to reach and reports the walled-in goals.
//! Where a peer fails a world on a seed, the results page
//! (`cargo xtask results`) shows it; the tests hold what stands.

use sim_host::bench::{run_all, Row};
use sim_host::planners::PlannerKind;
use sim_host::scenario::collect;
use sim_host::sim::{Outcome, SimConfig};
use std::path::PathBuf;

const PEERS: [PlannerKind; 3] = [PlannerKind::Bug2, PlannerKind::TangentBug, PlannerKind::Vfh];

fn library() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenarios")
}

fn examples() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/scenarios/examples")
}

fn runs(planner: PlannerKind, seed: u64) -> Vec<Row> {
    let files = collect(&[library(), examples()]).unwrap();
    let cfg = SimConfig {
        planner,
        seed,
        ..SimConfig::default()
    };
    run_all(&files, &cfg, false).unwrap()
}

fn outcome(rows: &[Row], name: &str) -> Outcome {
    rows.iter()
        .find(|r| r.name == name)
        .unwrap_or_else(|| panic!("no run of {name}"))
        .outcome
}

#[test]
fn no_peer_collides_in_the_library_or_the_examples() {
    for planner in PEERS {
        for seed in 1..=5 {
            for r in runs(planner, seed) {
                assert!(
                    r.safe(),
                    "{} seed {seed}: {} {:?}",
                    r.planner,
                    r.name,
                    r.outcome
                );
            }
        }
    }
}

/// Seed 1: the U-traps and the paper environments reached, the walled-in
/// goals reported. Bug2 and TangentBug do not reach environment 2's first
/// example (the beams lose the boundary in the cluster and the following
/// goes round another): that one is left out for them.
#[test]
fn each_peer_reaches_the_u_traps_and_the_paper_environments() {
    let reached = ["u-trap", "ex-utrap-1-0", "env1-ex1", "env1-ex2", "env2-ex2"];
    for planner in PEERS {
        let rows = runs(planner, 1);
        for name in reached {
            assert_eq!(
                outcome(&rows, name),
                Outcome::Reached,
                "{planner:?}: {name}"
            );
        }
        if planner == PlannerKind::Vfh {
            assert_eq!(outcome(&rows, "env2-ex1"), Outcome::Reached);
        }
        assert_eq!(
            outcome(&rows, "ex-enclosed-1-0"),
            Outcome::Unreachable,
            "{planner:?}"
        );
        if planner != PlannerKind::TangentBug {
            assert_eq!(
                outcome(&rows, "walled-in"),
                Outcome::Unreachable,
                "{planner:?}"
            );
        }
    }
}

/// Every peer runs through `bench` by name, and its rows carry SPL and
/// the time ratio.
#[test]
fn peers_have_names_and_their_runs_have_spl() {
    for (planner, name) in PEERS.iter().zip(["bug2", "tangentbug", "vfh"]) {
        assert_eq!(planner.name(), name);
        let rows = runs(*planner, 1);
        let r = rows.iter().find(|r| r.name == "env1-ex1").unwrap();
        assert_eq!(r.planner, name);
        let spl = r.spl.unwrap();
        assert!(spl > 0.0 && spl <= 1.0, "{spl}");
        let time = r.time_ratio.unwrap();
        // Turns and stands included: slower than driving the reference.
        assert!(time >= 1.0 / spl - 1e-9, "{time} against {spl}");
    }
}

/// The free-space planner (a candidate for the product's escape, not a
/// peer): no collision in the library or the examples on five seeds; on
/// seed 1 the traps, the paper environments and the rooms reached, the
/// walled-in goals reported. The narrow passage is not: its gap is
/// narrower than the plan's disc plus margin, and the squeezed wave's way
/// through it is refused by the safety rule until the budget runs out.
#[test]
fn freespace_is_safe_in_the_library_and_reaches_the_traps() {
    let planner = PlannerKind::FreeSpace;
    assert_eq!(planner.name(), "freespace");
    for seed in 1..=5 {
        for r in runs(planner, seed) {
            assert!(r.safe(), "seed {seed}: {} {:?}", r.name, r.outcome);
        }
    }
    let rows = runs(planner, 1);
    for name in [
        "u-trap",
        "ex-utrap-1-0",
        "env1-ex1",
        "env1-ex2",
        "env2-ex1",
        "env2-ex2",
        "rooms",
        "ex-rooms-1-0",
        "comb",
        "dead-end",
    ] {
        assert_eq!(outcome(&rows, name), Outcome::Reached, "{name}");
    }
    for name in ["walled-in", "ex-enclosed-1-0"] {
        assert_eq!(outcome(&rows, name), Outcome::Unreachable, "{name}");
    }
}
