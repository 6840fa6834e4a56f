//! The results page: every planner on every set of worlds the project has,
//! several seeds, one table per set and one overall, ranked by SPL, and one
//! picture per set of one world with every planner's path on it. Written
//! by `sim-host results` (`cargo xtask results`), never by hand.

use crate::bench::{self, Row};
use crate::fault::{self, Fault};
use crate::generate::{self, Kind};
use crate::planners::PlannerKind;
use crate::reference;
use crate::scenario::{collect, Scenario};
use crate::sim::{self, SimConfig};
use crate::svg;
use indicatif::{ProgressBar, ProgressStyle};
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// Every planner the page compares, the product first.
pub const PLANNERS: [PlannerKind; 10] = [
    PlannerKind::Eapf,
    PlannerKind::EapfPlain,
    PlannerKind::FreeSpace,
    PlannerKind::Bug2,
    PlannerKind::TangentBug,
    PlannerKind::Vfh,
    PlannerKind::Apf,
    PlannerKind::Liquid,
    PlannerKind::LiquidOnline,
    PlannerKind::Route,
];

/// The sensor-only planners the product is measured against.
pub const PEERS: [PlannerKind; 3] = [PlannerKind::Bug2, PlannerKind::TangentBug, PlannerKind::Vfh];

/// One set of worlds.
pub struct Set {
    /// Its name on the page.
    pub name: String,
    /// Where it comes from (a folder, or the `gen` command).
    pub source: String,
    /// Whether its worlds hold moving circles (reported beside the still
    /// sets, not in the overall table).
    pub moving: bool,
    /// The worlds: a path (for the rows) and the scenario.
    pub worlds: Vec<(PathBuf, Scenario)>,
    /// For a generated set, the `gen` options of its kind (`" --kind
    /// boxes"`, empty for circles): its worlds are made again by
    /// `gen FILE --seed N` with them.
    pub generated: Option<String>,
}

/// The generated sets: kind, first seed.
const GENERATED: [(Kind, &str, u64); 5] = [
    (Kind::Circles, "circle worlds", 100),
    (Kind::Boxes, "box worlds", 1),
    (Kind::Walled, "walled worlds", 1),
    (Kind::Rooms, "indoor floors", 1),
    (Kind::Moving, "moving circles", 1),
];

/// The sets: the shared BARN, BARN-tight and examples (`shared` is the
/// folder that holds them), the library (`library`), and `count` worlds of
/// each generated kind, made in memory (the `gen` command's worlds, seeds
/// as the README gives them).
pub fn sets(shared: &Path, library: &Path, count: u64) -> Result<Vec<Set>, String> {
    let mut sets = Vec::new();
    for (name, dir) in [
        ("BARN", shared.join("barn")),
        ("BARN-tight", shared.join("barn-tight")),
        ("library", library.to_path_buf()),
        ("examples", shared.join("examples")),
    ] {
        let files = collect(std::slice::from_ref(&dir))?;
        let worlds = files
            .into_iter()
            .map(|f| {
                Scenario::load(&f)
                    .map(|s| (f, s))
                    .map_err(|e| e.to_string())
            })
            .collect::<Result<Vec<_>, _>>()?;
        if worlds.is_empty() {
            return Err(format!("{}: no scenario files", dir.display()));
        }
        sets.push(Set {
            name: name.into(),
            source: format!("`{}`", dir.display()),
            moving: false,
            worlds,
            generated: None,
        });
    }
    let (start, goal) = ([6.0, 7.3], [12.7, 9.75]);
    for (kind, name, first) in GENERATED {
        let worlds = (first..first + count)
            .map(|seed| {
                let stem = format!("{}-{seed}", kind.prefix());
                let path = PathBuf::from(format!("gen/{stem}.toml"));
                let text = generate::world(kind, &stem, start, goal, seed)?;
                Scenario::parse(&text, &path)
                    .map(|s| (path, s))
                    .map_err(|e| e.to_string())
            })
            .collect::<Result<Vec<_>, _>>()?;
        let kind_arg = match kind {
            Kind::Circles => "",
            Kind::Boxes => " --kind boxes",
            Kind::Walled => " --kind walled",
            Kind::Rooms => " --kind rooms",
            Kind::Moving => " --kind moving",
        };
        sets.push(Set {
            name: name.into(),
            source: format!("`sim-host gen DIR --count {count} --seed {first}{kind_arg}`"),
            moving: kind == Kind::Moving,
            worlds,
            generated: Some(kind_arg.to_string()),
        });
    }
    Ok(sets)
}

/// Every planner of `planners` on every set, seeds `seed ..
/// seed + seeds`, with one progress bar over all the runs: each set's rows.
pub fn run(
    sets: &[Set],
    planners: &[PlannerKind],
    seed: u64,
    seeds: u64,
    progress: bool,
) -> Vec<Vec<Row>> {
    let runs: usize =
        sets.iter().map(|s| s.worlds.len()).sum::<usize>() * planners.len() * seeds as usize;
    let bar = progress_bar(runs, progress);
    let out = sets
        .iter()
        .map(|set| {
            let mut rows = Vec::new();
            for &planner in planners {
                bar.set_message(format!("{} {}", set.name, planner.name()));
                rows.extend(set_rows(set, planner, seed, seeds, &[], &bar));
            }
            rows
        })
        .collect();
    bar.finish_and_clear();
    out
}

/// `planner` on every world of `set`, seeds `seed .. seed + seeds`, with
/// `faults`. A planner over the known map senses nothing: its runs do not
/// depend on the seed, so it runs once and its rows stand for every seed.
fn set_rows(
    set: &Set,
    planner: PlannerKind,
    seed: u64,
    seeds: u64,
    faults: &[Fault],
    bar: &ProgressBar,
) -> Vec<Row> {
    let cfg = |seed| SimConfig {
        planner,
        seed,
        faults: faults.to_vec(),
        ..SimConfig::default()
    };
    let once = planner
        .uses_map()
        .then(|| bench::run_scenarios(&set.worlds, &cfg(seed), bar));
    let mut rows = Vec::new();
    for s in seed..seed + seeds {
        match &once {
            Some(first) if s == seed => rows.extend(first.iter().cloned()),
            Some(first) => {
                bar.inc(first.len() as u64);
                rows.extend(first.iter().map(|r| Row {
                    seed: s,
                    ..r.clone()
                }));
            }
            None => rows.extend(bench::run_scenarios(&set.worlds, &cfg(s), bar)),
        }
    }
    rows
}

/// One progress bar over `runs` runs (hidden without `progress`).
fn progress_bar(runs: usize, progress: bool) -> ProgressBar {
    let bar = if progress {
        ProgressBar::new(runs as u64)
    } else {
        ProgressBar::hidden()
    };
    bar.set_style(
        ProgressStyle::with_template(
            "{bar:40} {pos}/{len} runs {elapsed_precise} (eta {eta}) {msg}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar
}

/// The planners of `rows` ranked by SPL (best first), each with its totals.
fn ranked(rows: &[Row]) -> Vec<(String, bench::Totals)> {
    let mut names: Vec<&str> = Vec::new();
    for r in rows {
        if !names.contains(&r.planner.as_str()) {
            names.push(&r.planner);
        }
    }
    let mut out: Vec<(String, bench::Totals)> = names
        .into_iter()
        .map(|p| {
            let theirs: Vec<Row> = rows.iter().filter(|r| r.planner == p).cloned().collect();
            (p.to_string(), bench::totals(&theirs))
        })
        .collect();
    out.sort_by(|a, b| {
        let key = |t: &bench::Totals| t.spl.unwrap_or(-1.0);
        key(&b.1).total_cmp(&key(&a.1))
    });
    out
}

/// A table of planners ranked by SPL.
fn table(rows: &[Row]) -> String {
    let f = |v: Option<f64>| v.map_or_else(|| "–".to_string(), |v| format!("{v:.3}"));
    let mut s = String::from(
        "| planner | SPL | reached | collisions | wrongly unreachable | walled-in reported | timeouts | path ratio | time ratio |\n|---|---|---|---|---|---|---|---|---|\n",
    );
    for (p, t) in ranked(rows) {
        let pct = if t.solvable > 0 {
            format!(" ({:.1} %)", 100.0 * t.reached as f64 / t.solvable as f64)
        } else {
            String::new()
        };
        let _ = writeln!(
            s,
            "| {p} | {} | {}/{}{pct} | {} | {} | {}/{} | {} | {} | {} |",
            f(t.spl),
            t.reached,
            t.solvable,
            t.collisions,
            t.wrongly_unreachable,
            t.unreachable_correct,
            t.runs - t.solvable,
            t.timeouts,
            f(t.mean_ratio),
            f(t.time_ratio),
        );
    }
    s
}

/// Whether the product planner's SPL is above every peer's in `rows`:
/// its SPL and the best peer's, by name.
fn product_against_peers(rows: &[Row]) -> Option<(f64, String, f64)> {
    let r = ranked(rows);
    let eapf = r.iter().find(|(p, _)| p == "eapf")?.1.spl?;
    let (best, spl) = r
        .iter()
        .filter(|(p, _)| PEERS.iter().any(|k| k.name() == p))
        .filter_map(|(p, t)| t.spl.map(|s| (p.clone(), s)))
        .max_by(|a, b| a.1.total_cmp(&b.1))?;
    Some((eapf, best, spl))
}

/// The world of a set drawn with every planner's path: the first world
/// (by file) that the product planner does not reach, or the first world.
fn pictured(set: &Set, rows: &[Row], seed: u64) -> usize {
    set.worlds
        .iter()
        .position(|(f, _)| {
            rows.iter()
                .any(|r| &r.file == f && r.planner == "eapf" && r.seed == seed && !r.correct())
        })
        .unwrap_or(0)
}

/// The picture of world `i` of `set` with every planner's run (seed
/// `seed`), as SVG.
fn picture(set: &Set, i: usize, planners: &[PlannerKind], seed: u64) -> String {
    let (_, sc) = &set.worlds[i];
    let runs: Vec<(&str, sim::RunResult)> = planners
        .iter()
        .map(|&planner| {
            let cfg = SimConfig {
                planner,
                seed,
                ..SimConfig::default()
            };
            let refl = reference::shortest_path(sc).map(|r| r.length);
            (planner.name(), sim::run(sc, &cfg, refl))
        })
        .collect();
    let refp = reference::shortest_path(sc);
    let borrowed: Vec<(&str, &sim::RunResult)> = runs.iter().map(|(n, r)| (*n, r)).collect();
    svg::overlay(sc, &borrowed, refp.as_ref())
}

/// What wrote the page: the command, and the commit it ran at.
pub struct Provenance {
    /// The command line.
    pub command: String,
    /// The commit (and whether the tree had changes beyond it).
    pub commit: String,
}

/// The page, and the pictures to write beside it (file name, SVG): one
/// per set, in `pictures` (a folder name relative to the page).
pub fn page(
    sets: &[Set],
    rows: &[Vec<Row>],
    planners: &[PlannerKind],
    seed: u64,
    seeds: u64,
    pictures: &str,
    made: &Provenance,
) -> (String, Vec<(String, String)>) {
    let mut s = String::new();
    let _ = writeln!(s, "# Results\n");
    let _ = writeln!(
        s,
        "Written by `{}` at commit {}; nothing here is typed by hand. Every planner runs with the same \
         virtual Sharp sensors, executor, guard and safety rule; seeds {}–{} (sensor noise). \
         SPL is success weighted by path length (Anderson et al. 2018): the mean over reachable runs \
         of S·ℓ/max(p, ℓ). The time ratio is the simulated time to the goal (turns and stands \
         included) over the reference at cruise speed (0.25 m/s), where reached. `liquid`, \
         `liquid-online` and `route` know the map; the others sense. `liquid` and \
         `liquid-online` sense nothing, so their runs do not depend on the seed: each world runs \
         once and counts once per seed.\n",
        made.command,
        made.commit,
        seed,
        seed + seeds - 1
    );
    let still: Vec<Row> = sets
        .iter()
        .zip(rows)
        .filter(|(set, _)| !set.moving)
        .flat_map(|(_, r)| r.iter().cloned())
        .collect();
    let _ = writeln!(
        s,
        "## Overall\n\nEvery still-world set together ({} runs per planner), ranked by SPL.\n",
        still.len() / planners.len().max(1)
    );
    s.push_str(&table(&still));
    let _ = writeln!(
        s,
        "\n## The product against the peers\n\n| set | `eapf` SPL | best peer | its SPL | `eapf` ahead |\n|---|---|---|---|---|"
    );
    for (set, r) in sets.iter().zip(rows) {
        if let Some((e, p, ps)) = product_against_peers(r) {
            let _ = writeln!(
                s,
                "| {} | {e:.3} | {p} | {ps:.3} | {} |",
                set.name,
                if e > ps { "yes" } else { "no" }
            );
        }
    }
    let mut svgs = Vec::new();
    for (set, r) in sets.iter().zip(rows) {
        let _ = writeln!(
            s,
            "\n## {}\n\n{} worlds from {}{}.\n",
            set.name,
            set.worlds.len(),
            set.source,
            if set.moving {
                "; moving circles, so not in the overall table"
            } else {
                ""
            }
        );
        s.push_str(&table(r));
        let i = pictured(set, r, seed);
        let file = format!("{}.svg", set.name.replace(' ', "-").to_lowercase());
        let _ = writeln!(
            s,
            "\n![{}, every planner]({pictures}/{file})\n\n{} with seed {seed}.",
            set.worlds[i].1.name, set.worlds[i].1.name
        );
        svgs.push((file, picture(set, i, planners, seed)));
    }
    (s, svgs)
}

/// The faults page's rows: for no fault and then each named fault (with
/// its defaults), `planner` on every still set, seeds `seed .. seed +
/// seeds`; per fault, each set's rows.
pub fn run_faults(
    sets: &[Set],
    planner: PlannerKind,
    seed: u64,
    seeds: u64,
    progress: bool,
) -> Vec<(String, Vec<Vec<Row>>)> {
    let still: Vec<&Set> = sets.iter().filter(|s| !s.moving).collect();
    let faults: Vec<Option<Fault>> = std::iter::once(None)
        .chain(fault::NAMES.iter().map(|n| Fault::named(n)))
        .collect();
    let runs = still.iter().map(|s| s.worlds.len()).sum::<usize>() * faults.len() * seeds as usize;
    let bar = progress_bar(runs, progress);
    let out = faults
        .iter()
        .map(|fault| {
            let name = fault.map_or("none", |f| f.name()).to_string();
            bar.set_message(name.clone());
            let faults: Vec<Fault> = fault.iter().copied().collect();
            let rows = still
                .iter()
                .map(|set| set_rows(set, planner, seed, seeds, &faults, &bar))
                .collect();
            (name, rows)
        })
        .collect();
    bar.finish_and_clear();
    out
}

/// The faults page: one row per fault, one column per still set; each cell
/// reached of reachable, collisions, runs with a sensor fault flagged and
/// runs astray.
pub fn fault_page(
    sets: &[Set],
    rows: &[(String, Vec<Vec<Row>>)],
    planner: PlannerKind,
    seed: u64,
    seeds: u64,
    made: &Provenance,
) -> String {
    let still: Vec<&Set> = sets.iter().filter(|s| !s.moving).collect();
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# Faults\n\nWritten by `{}` at commit {}; nothing here is typed by hand. `{}` with one \
         fault at a time, its parameters the defaults of `sim-host/README.md` (\"Faults\"), seeds \
         {}–{}. Each cell: reached of the reachable runs · collisions · runs in which the planner \
         flagged a sensor fault · runs astray (stopped as arrived away from the goal: odometry \
         cannot know).\n",
        made.command,
        made.commit,
        planner.name(),
        seed,
        seed + seeds - 1
    );
    let _ = write!(s, "| fault |");
    for set in &still {
        let _ = write!(s, " {} |", set.name);
    }
    let _ = write!(s, "\n|---|");
    for _ in &still {
        let _ = write!(s, "---|");
    }
    s.push('\n');
    for (name, per_set) in rows {
        let _ = write!(s, "| `{name}` |");
        for set_rows in per_set {
            let t = bench::totals(set_rows);
            let _ = write!(
                s,
                " {}/{} · {} · {} · {} |",
                t.reached, t.solvable, t.collisions, t.flagged, t.astray
            );
        }
        s.push('\n');
    }
    s
}

/// The known-failures page: for `planner` on every set, each world it
/// fails on some seed (a reachable goal not reached, a walled-in goal not
/// reported, or a collision), with the outcome on each such seed and the
/// commands that replay the first.
pub fn failures_page(
    sets: &[Set],
    rows: &[Vec<Row>],
    planner: PlannerKind,
    seed: u64,
    seeds: u64,
    made: &Provenance,
) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# Known failures\n\nWritten by `{}` at commit {}; nothing here is typed by hand. `{}` on \
         every set, seeds {}–{}. A run fails when a reachable goal is not reached, a walled-in \
         goal is not reported, or the rover collides. One line a world: the outcome on each \
         seed it fails, and the commands that replay the first (`sim-host` is `cargo run \
         --release -p sim-host --`, run at the top of the repository; `--svg out.svg` draws it); \
         at most {FAILURES_LISTED} worlds a set, by file name.",
        made.command,
        made.commit,
        planner.name(),
        seed,
        seed + seeds - 1
    );
    for (set, rows) in sets.iter().zip(rows) {
        let failed: Vec<&Row> = rows.iter().filter(|r| !r.correct()).collect();
        let _ = writeln!(
            s,
            "\n## {} ({} of {} runs)\n",
            set.name,
            failed.len(),
            rows.len()
        );
        let mut files: Vec<&PathBuf> = failed.iter().map(|r| &r.file).collect();
        files.sort();
        files.dedup();
        if files.is_empty() {
            s.push_str("None.\n");
        }
        let more = files.len().saturating_sub(FAILURES_LISTED);
        for file in files.into_iter().take(FAILURES_LISTED) {
            let theirs: Vec<&&Row> = failed.iter().filter(|r| &r.file == file).collect();
            let outcomes: Vec<String> = theirs
                .iter()
                .map(|r| format!("seed {} {}", r.seed, r.outcome.as_str()))
                .collect();
            let first = theirs[0].seed;
            let stem = file.file_stem().unwrap_or_default().to_string_lossy();
            let replay = match &set.generated {
                Some(kind) => {
                    let world_seed = stem.rsplit('-').next().unwrap_or("1");
                    let tmp = format!("/tmp/{stem}.toml");
                    format!(
                        "`sim-host gen {tmp} --seed {world_seed}{kind} --force && sim-host run {tmp} --seed {first}`"
                    )
                }
                None => format!("`sim-host run {} --seed {first}`", file.display()),
            };
            let _ = writeln!(s, "- `{stem}`: {}. {replay}", outcomes.join(", "));
        }
        if more > 0 {
            let _ = writeln!(s, "- and {more} more worlds.");
        }
    }
    s
}

/// Worlds listed a set on the known-failures page (the page stays short;
/// the count of failed runs is for all of them).
pub const FAILURES_LISTED: usize = 12;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::Outcome;

    /// A page of two worlds and three planners: the tables rank by SPL,
    /// the product is set against the best peer, and each set gets a
    /// picture with every planner's path.
    #[test]
    fn the_page_ranks_by_spl_and_draws_every_planner() {
        let lib = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
        let worlds: Vec<(PathBuf, Scenario)> = ["traps/u-trap.toml", "traps/walled-in.toml"]
            .iter()
            .map(|f| {
                let p = lib.join(f);
                (p.clone(), Scenario::load(&p).unwrap())
            })
            .collect();
        let sets = [Set {
            name: "two traps".into(),
            source: "the library".into(),
            moving: false,
            worlds,
            generated: None,
        }];
        let planners = [PlannerKind::Eapf, PlannerKind::Apf, PlannerKind::Vfh];
        let rows = run(&sets, &planners, 1, 2, false);
        assert_eq!(rows[0].len(), 2 * 3 * 2);
        let made = Provenance {
            command: "sim-host results".into(),
            commit: "`abc`".into(),
        };
        let (page, svgs) = page(&sets, &rows, &planners, 1, 2, "results", &made);
        assert!(page.contains("Written by `sim-host results` at commit `abc`"));
        // Ranked by SPL: each table's SPL column never grows downwards.
        let spls: Vec<f64> = page
            .lines()
            .skip_while(|l| !l.starts_with("## Overall"))
            .filter(|l| {
                l.starts_with("| eapf |") || l.starts_with("| apf |") || l.starts_with("| vfh |")
            })
            .take(3)
            .map(|l| l.split('|').nth(2).unwrap().trim().parse().unwrap())
            .collect();
        assert_eq!(spls.len(), 3, "{page}");
        assert!(spls.windows(2).all(|w| w[0] >= w[1]), "{spls:?}");
        // The product against the best peer (the only one here, vfh).
        assert!(page.contains("| two traps | "), "{page}");
        assert!(page.contains("| vfh | "), "{page}");
        assert_eq!(svgs.len(), 1);
        assert_eq!(svgs[0].0, "two-traps.svg");
        for p in ["eapf", "apf", "vfh"] {
            assert!(svgs[0].1.contains(&format!(">{p} (")), "{p}");
        }
        assert!(
            page.contains("![u-trap, every planner](results/two-traps.svg)")
                || page.contains("![walled-in, every planner](results/two-traps.svg)")
        );
    }

    /// The faults page: a row for no fault and one per named fault, a
    /// column per still set; a dead sensor is flagged and stands.
    #[test]
    fn the_faults_page_has_a_row_per_fault_and_a_column_per_set() {
        let lib = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
        let load = |f: &str| {
            let p = lib.join(f);
            (p.clone(), Scenario::load(&p).unwrap())
        };
        let set = |name: &str, f: &str, moving: bool| Set {
            name: name.into(),
            source: "the library".into(),
            moving,
            worlds: vec![load(f)],
            generated: None,
        };
        let sets = [
            set("corridor", "traps/corridor.toml", false),
            set("u-trap", "traps/u-trap.toml", false),
            set("movers", "traps/corridor.toml", true),
        ];
        let rows = run_faults(&sets, PlannerKind::Eapf, 1, 1, false);
        assert_eq!(rows.len(), 1 + fault::NAMES.len());
        let made = Provenance {
            command: "sim-host faults".into(),
            commit: "`abc`".into(),
        };
        let page = fault_page(&sets, &rows, PlannerKind::Eapf, 1, 1, &made);
        assert!(page.contains("| fault | corridor | u-trap |\n"), "{page}");
        assert!(
            page.contains("| `none` | 1/1 · 0 · 0 · 0 | 1/1 · 0 · 0 · 0 |"),
            "{page}"
        );
        assert!(
            page.contains("| `dead` | 0/1 · 0 · 1 · 0 | 0/1 · 0 · 1 · 0 |"),
            "{page}"
        );
        for name in fault::NAMES {
            assert!(page.contains(&format!("| `{name}` |")), "{name}");
        }
    }

    /// The failures page lists each failed world once, by file name, with
    /// its seeds and a replay command; a generated world is made again
    /// first.
    #[test]
    fn the_failures_page_lists_each_failed_world_with_its_replay() {
        let lib = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
        let u = lib.join("traps/u-trap.toml");
        let walled = lib.join("traps/walled-in.toml");
        let load = |p: &PathBuf| (p.clone(), Scenario::load(p).unwrap());
        let gen = PathBuf::from("gen/box-69.toml");
        let sets = [
            Set {
                name: "traps".into(),
                source: "the library".into(),
                moving: false,
                worlds: vec![load(&u), load(&walled)],
                generated: None,
            },
            Set {
                name: "box worlds".into(),
                source: "gen".into(),
                moving: false,
                worlds: vec![(gen.clone(), load(&u).1)],
                generated: Some(" --kind boxes".into()),
            },
        ];
        let row = |file: &PathBuf, seed, outcome| {
            let mut r = bench::tests::row("eapf", "w", seed, outcome, 5.0);
            r.file = file.clone();
            r
        };
        // Seed by seed, as a bench gives them.
        let rows = vec![
            vec![
                row(&u, 1, Outcome::Reached),
                row(&walled, 2, Outcome::Timeout),
                row(&u, 2, Outcome::Timeout),
                row(&u, 3, Outcome::Timeout),
            ],
            vec![
                row(&gen, 4, Outcome::Collision),
                row(&gen, 5, Outcome::Timeout),
            ],
        ];
        let made = Provenance {
            command: "sim-host failures".into(),
            commit: "`abc`".into(),
        };
        let page = failures_page(&sets, &rows, PlannerKind::Eapf, 1, 5, &made);
        let trap = format!(
            "## traps (3 of 4 runs)\n\n- `u-trap`: seed 2 timeout, seed 3 timeout. `sim-host run {} \
             --seed 2`\n- `walled-in`: seed 2 timeout.",
            u.display()
        );
        assert!(page.contains(&trap), "{page}");
        assert!(page.contains("## box worlds (2 of 2 runs)"), "{page}");
        assert!(
            page.contains(
                "- `box-69`: seed 4 collision, seed 5 timeout. `sim-host gen /tmp/box-69.toml \
                 --seed 69 --kind boxes --force && sim-host run /tmp/box-69.toml --seed 4`"
            ),
            "{page}"
        );
    }
}
