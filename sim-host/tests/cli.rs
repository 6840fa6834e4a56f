//! The command line as users call it.

use std::path::{Path, PathBuf};
use std::process::Command;

fn corridor() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenarios/traps/corridor.toml")
}

/// `sim-host ARGS… PATHS…`, which must `succeed` or fail: its standard
/// output, or its standard error.
fn sim_host_ends(succeed: bool, args: &[&str], paths: &[&Path]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_sim-host"))
        .args(args)
        .args(paths)
        .output()
        .unwrap();
    let (want, other) = if succeed {
        (out.stdout, out.stderr)
    } else {
        (out.stderr, out.stdout)
    };
    assert_eq!(
        out.status.success(),
        succeed,
        "{}",
        String::from_utf8_lossy(&other)
    );
    String::from_utf8(want).unwrap()
}

/// `sim-host ARGS… PATHS…`, which must succeed: its standard output.
fn sim_host(args: &[&str], paths: &[&Path]) -> String {
    sim_host_ends(true, args, paths)
}

/// A fresh scratch folder for one test, and the JSON-lines file in it.
fn scratch(name: &str) -> (PathBuf, PathBuf) {
    let dir = std::env::temp_dir().join(format!("sim-host-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let json = dir.join("runs.jsonl");
    (dir, json)
}

/// Field `key` of every line of a `--json` file.
fn json_field(json: &Path, key: &str) -> Vec<serde_json::Value> {
    std::fs::read_to_string(json)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap()[key].clone())
        .collect()
}

#[test]
fn bench_over_several_seeds_prints_each_and_the_aggregate() {
    let (dir, json) = scratch("cli");
    let text = sim_host(
        &["bench", "--seed", "4", "--seeds", "2", "--json"],
        &[&json, &corridor()],
    );
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 3, "{text}");
    assert!(lines[0].starts_with("seed 4: runs 1 |"), "{text}");
    assert!(lines[1].starts_with("seed 5: runs 1 |"), "{text}");
    assert!(lines[2].starts_with("all seeds: runs 2 |"), "{text}");
    assert_eq!(json_field(&json, "seed"), [4, 5]);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn zero_seeds_is_a_usage_error() {
    let out = Command::new(env!("CARGO_BIN_EXE_sim-host"))
        .args(["bench", "--seeds", "0"])
        .arg(corridor())
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--seeds"));
}

#[test]
fn a_reader_that_leaves_early_is_no_panic() {
    // `sim-host run … | head -1`: stdout closes before the report is
    // written; `println!` would panic on the broken pipe.
    let mut child = Command::new(env!("CARGO_BIN_EXE_sim-host"))
        .arg("run")
        .arg(corridor())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn run_with_the_route_layer_reports_its_route_and_draws_it() {
    let dir = std::env::temp_dir().join(format!("sim-host-route-{}", std::process::id()));
    let svg = dir.join("corridor.svg");
    let text = sim_host(
        &["run", "--planner", "route", "--svg"],
        &[&svg, &corridor()],
    );
    assert!(text.contains("outcome      reached"), "{text}");
    let route = text.lines().find(|l| l.starts_with("route ")).unwrap_or("");
    assert!(route.contains(" waypoints, "), "{text}");
    let pic = std::fs::read_to_string(&svg).unwrap();
    assert!(pic.contains(">route</text>"), "the legend names the route");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn gen_count_writes_a_folder_of_worlds_that_bench_reads() {
    let dir = std::env::temp_dir().join(format!("sim-host-gen-{}", std::process::id()));
    let text = sim_host(&["gen", "--count", "3", "--seed", "40"], &[&dir]);
    assert_eq!(
        text,
        format!("wrote 3 worlds (seeds 40 to 42) to {}\n", dir.display())
    );
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["gen-40.toml", "gen-41.toml", "gen-42.toml"]);
    // Each the world `gen` writes alone for its seed.
    let one = dir.join("one").join("gen-41.toml");
    sim_host(&["gen", "--seed", "41"], &[&one]);
    assert_eq!(
        std::fs::read_to_string(&one).unwrap(),
        std::fs::read_to_string(dir.join("gen-41.toml")).unwrap()
    );
    std::fs::remove_dir_all(dir.join("one")).unwrap();
    let table = sim_host(&["bench", "--summary"], &[&dir]);
    assert!(table.starts_with("runs 3 |"), "{table}");
    std::fs::remove_dir_all(&dir).ok();
}

/// `gen --kind boxes` writes box worlds (`box-<seed>.toml` with
/// `--count`), each the one it writes alone for that seed, which bench reads;
/// no circle in them, and an unknown kind is a usage error.
#[test]
fn gen_writes_box_worlds() {
    let (dir, _) = scratch("gen-boxes");
    let text = sim_host(
        &["gen", "--kind", "boxes", "--count", "2", "--seed", "7"],
        &[&dir],
    );
    assert_eq!(
        text,
        format!("wrote 2 worlds (seeds 7 to 8) to {}\n", dir.display())
    );
    let one = dir.join("one").join("box-8.toml");
    sim_host(&["gen", "--kind", "boxes", "--seed", "8"], &[&one]);
    let written = std::fs::read_to_string(dir.join("box-8.toml")).unwrap();
    assert_eq!(std::fs::read_to_string(&one).unwrap(), written);
    assert!(written.contains("[[polygon]]") && !written.contains("[[circle]]"));
    std::fs::remove_dir_all(dir.join("one")).unwrap();
    let table = sim_host(&["bench", "--summary"], &[&dir]);
    assert!(table.starts_with("runs 2 |"), "{table}");
    let out = Command::new(env!("CARGO_BIN_EXE_sim-host"))
        .args(["gen", "--kind", "mazes", "unused.toml"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--kind"));
    std::fs::remove_dir_all(&dir).ok();
}

/// `run` prints the shortest way for the disc plus the planners' 40 mm as
/// well as the disc's: through a gap 0.25 m wide the disc (0.2 m) passes,
/// with 40 mm either side it does not.
#[test]
fn run_prints_the_way_with_the_planners_margin() {
    let (dir, _) = scratch("margin");
    let file = dir.join("gap.toml");
    let wall = |gap: f64| {
        let (a, b) = (1.5 - gap / 2.0, 1.5 + gap / 2.0);
        format!(
            "format = 1\nname = \"gap\"\nbounds = [0.0, 0.0, 4.0, 3.0]\nstart = [0.5, 1.5]\ngoal = [3.5, 1.5]\n\
             [[polygon]]\npoints = [[1.9, -0.1], [2.1, -0.1], [2.1, {a}], [1.9, {a}]]\n\
             [[polygon]]\npoints = [[1.9, {b}], [2.1, {b}], [2.1, 3.1], [1.9, 3.1]]\n"
        )
    };
    std::fs::write(&file, wall(0.25)).unwrap();
    let text = sim_host(&["run"], &[&file]);
    assert!(text.contains("reference    3.000 m"), "{text}");
    assert!(
        text.contains("with_margin  none (no path for the disc + 40 mm)"),
        "{text}"
    );
    std::fs::write(&file, wall(0.5)).unwrap();
    let text = sim_host(&["run"], &[&file]);
    assert!(
        text.contains("with_margin  3.000 m (the disc + 40 mm)"),
        "{text}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn gen_count_zero_is_a_usage_error() {
    let out = Command::new(env!("CARGO_BIN_EXE_sim-host"))
        .args(["gen", "--count", "0", "unused"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--count"));
}

/// `bench --svg DIR` writes one picture per run, named by file, planner and
/// seed, each the picture `run --svg` draws of the same run.
#[test]
fn bench_draws_every_run_as_run_does() {
    let dir = std::env::temp_dir().join(format!("sim-host-pictures-{}", std::process::id()));
    let pictures = dir.join("pictures");
    let two_obstacles =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenarios/traps/two-obstacles.toml");
    sim_host(
        &["bench", "--seed", "2", "--seeds", "2", "--summary", "--svg"],
        &[&pictures, &corridor(), &two_obstacles],
    );
    let mut names: Vec<String> = std::fs::read_dir(&pictures)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names,
        [
            "corridor-eapf-seed2.svg",
            "corridor-eapf-seed3.svg",
            "two-obstacles-eapf-seed2.svg",
            "two-obstacles-eapf-seed3.svg"
        ]
    );
    for (file, seed) in [(corridor(), "2"), (two_obstacles.clone(), "3")] {
        let alone = dir.join("alone.svg");
        sim_host(&["run", "--seed", seed, "--svg"], &[&alone, &file]);
        let stem = file.file_stem().unwrap().to_string_lossy().into_owned();
        let benched = pictures.join(format!("{stem}-eapf-seed{seed}.svg"));
        let (a, b) = (
            std::fs::read_to_string(&alone).unwrap(),
            std::fs::read_to_string(&benched).unwrap(),
        );
        assert!(a.starts_with("<svg"), "{a:.40}");
        assert_eq!(
            a, b,
            "{stem}, seed {seed}: bench and run draw the run alike"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Two scenario files with one name would overwrite each other's pictures:
/// refused before anything runs, naming both.
#[test]
fn bench_pictures_of_two_files_with_one_name_are_refused() {
    let dir = std::env::temp_dir().join(format!("sim-host-same-name-{}", std::process::id()));
    let other = dir.join("elsewhere");
    std::fs::create_dir_all(&other).unwrap();
    let copy = other.join("corridor.toml");
    std::fs::copy(corridor(), &copy).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_sim-host"))
        .args(["bench", "--svg"])
        .arg(dir.join("pictures"))
        .arg(corridor())
        .arg(&copy)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{err}");
    assert!(
        err.contains("overwrite") && err.contains("elsewhere"),
        "{err}"
    );
    assert!(
        !dir.join("pictures").exists(),
        "nothing ran, no folder made"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// Several planners in one bench: each one's summary says whose it is, a
/// table compares them, and the JSON lines carry each run's planner; a
/// planner named twice runs once.
#[test]
fn bench_compares_several_planners() {
    let (dir, json) = scratch("planners");
    let text = sim_host(
        &[
            "bench",
            "--planner",
            "eapf,apf",
            "--planner",
            "route,eapf",
            "--summary",
            "--json",
        ],
        &[&json, &corridor()],
    );
    let lines: Vec<&str> = text.lines().collect();
    assert!(lines[0].starts_with("eapf runs 1 |"), "{text}");
    assert!(lines[1].starts_with("apf runs 1 |"), "{text}");
    assert!(lines[2].starts_with("route runs 1 |"), "{text}");
    assert!(lines[4].starts_with("| planner |"), "{text}");
    for (line, p) in lines[6..9].iter().zip(["eapf", "apf", "route"]) {
        assert!(line.starts_with(&format!("| {p} | 1 |")), "{text}");
    }
    assert_eq!(json_field(&json, "planner"), ["eapf", "apf", "route"]);
    std::fs::remove_dir_all(&dir).ok();
}

/// Two circles 0.25 m apart: the disc (0.2 m across) passes between them,
/// the disc plus the planners' 40 mm does not. `bounds_y` shuts the way
/// round them or leaves it open.
fn gap_world(dir: &Path, name: &str, bounds_y: (f64, f64)) -> PathBuf {
    let file = dir.join(format!("{name}.toml"));
    let text = format!(
        "format = 1\nname = \"{name}\"\nbounds = [0.0, {}, 7.0, {}]\n\
         start = [1.0, 3.0]\ngoal = [6.0, 3.0]\nrobot_radius = 0.1\n\n\
         [[circle]]\ncenter = [3.5, 2.425]\nradius = 0.45\n\
         [[circle]]\ncenter = [3.5, 3.575]\nradius = 0.45\n",
        bounds_y.0, bounds_y.1
    );
    std::fs::create_dir_all(dir).unwrap();
    std::fs::write(&file, text).unwrap();
    file
}

/// The picture draws the way with the planners' margin where it is longer
/// than the disc's, and says so where there is none; where the two lie on
/// one another it draws the reference alone.
#[test]
fn the_picture_shows_the_way_with_the_planners_margin() {
    let dir = std::env::temp_dir().join(format!("sim-host-margin-{}", std::process::id()));
    let svg = dir.join("pic.svg");
    let figures = |pic: &str| {
        let at = pic
            .find(r#"<text x="10" y="48""#)
            .expect("the figures line");
        pic[at..].lines().next().unwrap_or_default().to_string()
    };

    let round = gap_world(&dir, "round", (0.0, 6.0));
    let text = sim_host(&["run", "--planner", "apf", "--svg"], &[&svg, &round]);
    let wider = text.lines().find(|l| l.starts_with("with_margin")).unwrap();
    let wider_m: f64 = wider.split_whitespace().nth(1).unwrap().parse().unwrap();
    assert!(wider_m > 5.2, "{text}");
    let pic = std::fs::read_to_string(&svg).unwrap();
    assert!(pic.contains(">with margin</text>"), "the legend names it");
    assert!(pic.contains(r##"stroke="#1b7c83""##), "and it is drawn");
    let line = figures(&pic);
    let drawn_m: f64 = line
        .split(" m with the margin)")
        .next()
        .and_then(|l| l.rsplit('(').next())
        .and_then(|m| m.parse().ok())
        .unwrap_or_else(|| panic!("{line}"));
    assert!((drawn_m - wider_m).abs() < 0.006, "{line} against {wider}");

    let shut = gap_world(&dir, "shut", (1.9, 4.1));
    let text = sim_host(&["run", "--planner", "apf", "--svg"], &[&svg, &shut]);
    assert!(text.contains("with_margin  none"), "{text}");
    let pic = std::fs::read_to_string(&svg).unwrap();
    assert!(!pic.contains(">with margin</text>"));
    assert!(figures(&pic).contains("(no way with the margin)"));

    sim_host(&["run", "--planner", "apf", "--svg"], &[&svg, &corridor()]);
    let pic = std::fs::read_to_string(&svg).unwrap();
    assert!(!pic.contains(">with margin</text>"));
    assert!(!figures(&pic).contains("margin"), "{}", figures(&pic));
    std::fs::remove_dir_all(&dir).ok();
}

/// A tall world (BARN's are 3.4 m by 9.6 m or so) draws a narrow map: the
/// title, the figures line and the legend keep the picture's width, with the
/// map in its middle, and nothing is drawn left of the picture's edge.
#[test]
fn a_tall_world_draws_its_legend_inside_the_picture() {
    let dir = std::env::temp_dir().join(format!("sim-host-tall-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let tall = dir.join("tall.toml");
    std::fs::write(
        &tall,
        "format = 1\nname = \"tall\"\nbounds = [0.0, 0.0, 2.0, 7.0]\n\
         start = [1.0, 1.0]\ngoal = [1.0, 6.0]\nrobot_radius = 0.1\n\n\
         [[circle]]\ncenter = [1.0, 3.5]\nradius = 0.3\n",
    )
    .unwrap();
    let svg = dir.join("tall.svg");
    sim_host(&["run", "--svg"], &[&svg, &tall]);
    let pic = std::fs::read_to_string(&svg).unwrap();
    let width: f64 = pic
        .split("width=\"")
        .nth(1)
        .and_then(|w| w.split('"').next())
        .and_then(|w| w.parse().ok())
        .unwrap();
    assert_eq!(width, 900.0, "{pic:.200}");
    let xs: Vec<f64> = pic
        .split(" x=\"")
        .skip(1)
        .filter_map(|x| x.split('"').next()?.parse().ok())
        .collect();
    assert!(xs.len() > 5, "{pic:.200}");
    for x in xs {
        assert!((0.0..width).contains(&x), "x = {x} outside 0..{width}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// `--set-back` mounts the sensors behind the rim: `run` says so, and the
/// rover drives another way than with them on the rim (the option reaches
/// the planner and the virtual sensors): in the U-trap, the paths' lengths
/// differ.
#[test]
fn set_back_sensors_are_said_and_drive_another_way() {
    let u_trap = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenarios/traps/u-trap.toml");
    let rim = sim_host(&["run"], &[&u_trap]);
    let back = sim_host(&["run", "--set-back"], &[&u_trap]);
    let said = "sensors      set back from the rim by their minimum range";
    assert!(back.contains(said), "{back}");
    assert!(!rim.contains(said), "{rim}");
    let length = |text: &str| {
        let line = text.lines().find(|l| l.starts_with("path_length"));
        line.unwrap_or_default().to_string()
    };
    assert_ne!(length(&rim), length(&back), "the same path:\n{rim}\n{back}");
    // A planner over the map has no sensors to set back: refused.
    let out = Command::new(env!("CARGO_BIN_EXE_sim-host"))
        .args(["run", "--planner", "liquid", "--set-back"])
        .arg(&u_trap)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--set-back: planner liquid plans over the map"),
        "{err}"
    );
}

#[test]
fn compare_reads_two_benches_run_by_run() {
    let (dir, before) = scratch("compare");
    let after = dir.join("after.jsonl");
    for (seed, json) in [("1", &before), ("1", &after)] {
        sim_host(
            &[
                "bench",
                "--summary",
                "--seed",
                seed,
                "--seeds",
                "2",
                "--json",
            ],
            &[json, &corridor()],
        );
    }
    // The same build twice: the same runs, nothing moved.
    let text = sim_host(&["compare", "--runs"], &[&before, &after]);
    let lines: Vec<&str> = text.lines().collect();
    assert!(lines[0].starts_with("before: runs 2 |"), "{text}");
    assert!(lines[1].starts_with("after:  runs 2 |"), "{text}");
    assert!(lines.contains(&"outcomes changed: 0 of 2 runs"), "{text}");
    // One run's outcome edited: it is listed, with the way it moved.
    let edited = std::fs::read_to_string(&after).unwrap().replacen(
        "\"outcome\":\"reached\"",
        "\"outcome\":\"timeout\"",
        1,
    );
    std::fs::write(&after, edited).unwrap();
    let text = sim_host(&["compare", "--runs"], &[&before, &after]);
    assert!(text.contains("outcomes changed: 1 of 2 runs"), "{text}");
    assert!(text.contains("  reached -> timeout: 1\n"), "{text}");
    assert!(text.contains("corridor seed 1 (eapf): reached ("), "{text}");
    // A file that is not a bench's: a clear error, exit code 2.
    std::fs::write(&after, "not json\n").unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_sim-host"))
        .arg("compare")
        .args([&before, &after])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("after.jsonl:1: not a bench run"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

/// `sim-host ARGS… PATHS…`, which must fail: its standard error.
fn sim_host_fails(args: &[&str], paths: &[&Path]) -> String {
    sim_host_ends(false, args, paths)
}

/// An output never overwrites a world: a scenario file as `--json` or
/// `--trace` is refused before anything runs; `gen` over a file that
/// exists asks for `--force`; a `--json` that cannot be written is an
/// error before the bench runs, not after.
#[test]
fn outputs_never_overwrite_inputs() {
    let (dir, _) = scratch("outputs");
    let world = dir.join("w.toml");
    std::fs::copy(corridor(), &world).unwrap();
    let before = std::fs::read_to_string(&world).unwrap();
    let e = sim_host_fails(&["run", "--trace"], &[&world, &world]);
    assert!(e.contains("may not be a scenario file"), "{e}");
    let e = sim_host_fails(&["bench", "--json", world.to_str().unwrap()], &[&dir]);
    assert!(e.contains("may not be a scenario file"), "{e}");
    assert_eq!(std::fs::read_to_string(&world).unwrap(), before);
    let e = sim_host_fails(&["gen"], &[&world]);
    assert!(e.contains("exists; --force"), "{e}");
    assert_eq!(std::fs::read_to_string(&world).unwrap(), before);
    sim_host(&["gen", "--force"], &[&world]);
    assert_ne!(std::fs::read_to_string(&world).unwrap(), before);
    // A folder where the JSON file should go: refused at once.
    let blocked = dir.join("blocked");
    std::fs::create_dir_all(blocked.join("runs.jsonl")).unwrap();
    let e = sim_host_fails(
        &[
            "bench",
            "--json",
            blocked.join("runs.jsonl").to_str().unwrap(),
        ],
        &[&corridor()],
    );
    assert!(e.contains("runs.jsonl"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

/// `bench --fault NAME` runs for every fault name and records it in each
/// run's JSON; a dead sensor is flagged by the planner on every run (the
/// rover stands), a bad fault is refused before anything runs.
#[test]
fn bench_takes_every_fault_and_records_it() {
    let (dir, json) = scratch("faults");
    for name in sim_host::fault::NAMES {
        let text = sim_host(
            &["bench", "--summary", "--fault", name, "--json"],
            &[&json, &corridor()],
        );
        assert!(text.starts_with("runs 1 |"), "{name}: {text}");
        let faults = json_field(&json, "faults");
        let recorded = faults[0][0].as_str().unwrap();
        assert!(recorded.starts_with(name), "{name}: {recorded}");
        if name == "dead" {
            assert!(text.contains("sensor fault flagged in 1"), "{text}");
            assert_eq!(json_field(&json, "outcome"), ["timeout"]);
        }
    }
    // Two at once, with parameters.
    let text = sim_host(
        &[
            "run",
            "--fault",
            "spikes:rate=0.1",
            "--fault",
            "overshoot:fraction=0.2",
        ],
        &[&corridor()],
    );
    assert!(text.contains("fault        spikes:rate=0.1"), "{text}");
    assert!(
        text.contains("fault        overshoot:fraction=0.2"),
        "{text}"
    );
    let err = sim_host_ends(
        false,
        &["bench", "--fault", "dead:sensor=9"],
        &[&corridor()],
    );
    assert!(err.contains("sensor=9 is not 0..=4"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

/// `calibrate` fits a sensor's card counts into the `K` line that stores
/// them, the one the core's fit gives; counts no working sensor gives are
/// an error that says why.
#[test]
fn calibrate_prints_the_k_line_or_why_not() {
    use planner_core::rover::calibration::{datasheet_row, fit};
    let adc = planner_core::AdcProfile::AVR_10BIT_5V;
    // A unit reading 12 % high.
    let row = datasheet_row(adc).map(|c| (u32::from(c) * 112 / 100) as u16);
    let k = fit(adc, &row).unwrap();
    let counts: Vec<String> = row.iter().map(u16::to_string).collect();
    let out = Command::new(env!("CARGO_BIN_EXE_sim-host"))
        .args(["calibrate", "--sensor", "3"])
        .args(&counts)
        .output()
        .unwrap();
    assert!(out.status.success());
    assert_eq!(
        String::from_utf8_lossy(&out.stdout),
        format!("K 3 {} {}\n", k.gain_q8, k.offset)
    );
    assert_ne!(k.gain_q8, 256, "a correction, not none");
    // The card at 800 mm read as near as at 700: not falling.
    let mut bad = counts.clone();
    bad[7] = bad[6].clone();
    let out = Command::new(env!("CARGO_BIN_EXE_sim-host"))
        .args(["calibrate", "--sensor", "3"])
        .args(&bad)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("NotFalling"));
}
