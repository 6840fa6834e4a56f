//! `sim-host`: run the planner-core in simulated worlds.

use clap::{Parser, Subcommand};
use sim_host::fault::Fault;
use sim_host::planners::PlannerKind;
use sim_host::scenario::{collect, Scenario};
use sim_host::sensor::SensorMode;
use sim_host::sim::{self, SimConfig};
use sim_host::{bench, generate, reference, results, svg};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "sim-host",
    version,
    about = "Simulated worlds for the rover's planner-core"
)]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Subcommand)]
enum Cmd {
    /// One run: prints the outcome and the figures.
    Run {
        /// Scenario file (format 1).
        file: PathBuf,
        /// Planner.
        #[arg(long, value_enum, default_value = "eapf")]
        planner: PlannerKind,
        /// Seed for sensor noise and the faults.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Write a picture of the run.
        #[arg(long)]
        svg: Option<PathBuf>,
        /// Write the true driven path as CSV (t,x,y,heading).
        #[arg(long)]
        trace: Option<PathBuf>,
        /// Noise-free, instant sensors without fold-back.
        #[arg(long)]
        perfect: bool,
        /// The sensors set back from the rim by their minimum range (100
        /// mm), at least at the centre; on the rim otherwise (the sensing
        /// planners: `liquid` and `liquid-online` refuse it).
        #[arg(long)]
        set_back: bool,
        /// Inject a fault (repeatable): dead, stuck, stuck-clear, spikes,
        /// dropouts, crosstalk, ambient, slip, stall, encoder-glitch,
        /// overshoot, latency; parameters as `NAME:KEY=VALUE,…` (defaults
        /// and keys in sim-host/README.md).
        #[arg(long = "fault", value_name = "NAME[:KEY=VALUE,…]")]
        faults: Vec<Fault>,
    },
    /// Every scenario under the given files or folders, in parallel.
    Bench {
        /// Files or folders.
        #[arg(required = true)]
        paths: Vec<PathBuf>,
        /// Planner; several (`--planner eapf,apf,route` or the option
        /// repeated) run the same scenarios and seeds each, and end with a
        /// table comparing them.
        #[arg(long, value_enum, default_value = "eapf", value_delimiter = ',')]
        planner: Vec<PlannerKind>,
        /// Seed (the first one with `--seeds`).
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Run every scenario with this many consecutive seeds and print
        /// one summary line per seed and one over all runs (one seed's
        /// outcomes swing with small planner changes; compare aggregates).
        #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..=1000))]
        seeds: u64,
        /// Worker threads (default: all cores).
        #[arg(long)]
        jobs: Option<usize>,
        /// Write one JSON object per run.
        #[arg(long)]
        json: Option<PathBuf>,
        /// Write a picture of every run into this folder, as
        /// `<file stem>-<planner>-seed<N>.svg`.
        #[arg(long, value_name = "DIR")]
        svg: Option<PathBuf>,
        /// Totals only.
        #[arg(long)]
        summary: bool,
        /// Noise-free sensors.
        #[arg(long)]
        perfect: bool,
        /// The sensors set back from the rim by their minimum range (the
        /// sensing planners).
        #[arg(long)]
        set_back: bool,
        /// Inject a fault (repeatable): dead, stuck, stuck-clear, spikes,
        /// dropouts, crosstalk, ambient, slip, stall, encoder-glitch,
        /// overshoot, latency; parameters as `NAME:KEY=VALUE,…` (defaults
        /// and keys in sim-host/README.md).
        #[arg(long = "fault", value_name = "NAME[:KEY=VALUE,…]")]
        faults: Vec<Fault>,
    },
    /// Two `bench --json` files of the same runs (two builds or settings),
    /// run by run: both totals over the runs in both, and which outcomes
    /// changed which way.
    Compare {
        /// The `--json` file of the first bench.
        before: PathBuf,
        /// The `--json` file of the second.
        after: PathBuf,
        /// Also list every run whose outcome changed.
        #[arg(long)]
        runs: bool,
    },
    /// Write a random world in the paper's environment 2 arena: circles
    /// with its parameters, turned boxes and walls, walled in or not,
    /// circles with moving ones, or an indoor floor of rooms (`--kind`).
    Gen {
        /// Output file (with `--count`, a folder).
        out: PathBuf,
        /// Seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Write this many worlds, seeds SEED, SEED+1, …, into the folder
        /// OUT as `gen-<seed>.toml` (other kinds: below): a set of worlds
        /// no rule was tuned on, for `bench`.
        #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
        count: Option<u64>,
        /// Start x y.
        #[arg(long, num_args = 2, default_values_t = [6.0, 7.3])]
        start: Vec<f64>,
        /// Goal x y.
        #[arg(long, num_args = 2, default_values_t = [12.7, 9.75])]
        goal: Vec<f64>,
        /// What the world is made of: `circles` (the paper's environment
        /// 2), `boxes` (turned boxes and thin walls; with `--count` named
        /// `box-<seed>.toml`), `walled` (a box world with a closed ring
        /// of walls round the goal or the start: unsolvable;
        /// `walled-<seed>.toml`), `moving` (the circle world and six
        /// circles moving across the way; `mov-<seed>.toml`) or `rooms`
        /// (rooms, doorways and furniture; `rooms-<seed>.toml`).
        #[arg(long, value_enum, default_value = "circles")]
        kind: generate::Kind,
        /// Write over files that exist.
        #[arg(long)]
        force: bool,
    },
    /// Write the results page: every planner on every set (BARN,
    /// BARN-tight, the library, the examples and COUNT generated worlds of
    /// each kind), one table per set and one overall, ranked by SPL, and
    /// one picture per set with every planner's path.
    Results {
        /// The page to write; the pictures go into `results/` beside it.
        #[arg(long, default_value = "docs/results.md")]
        out: PathBuf,
        #[command(flatten)]
        worlds: Worlds,
        /// Seeds.
        #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u64).range(1..=100))]
        seeds: u64,
        /// Planners (default: all).
        #[arg(long, value_enum, value_delimiter = ',')]
        planner: Vec<PlannerKind>,
    },
    /// Write the known-failures page: one planner on every set, each world
    /// it fails on some seed with the commands that replay it.
    Failures {
        /// The page to write.
        #[arg(long, default_value = "docs/failures.md")]
        out: PathBuf,
        #[command(flatten)]
        worlds: Worlds,
        /// Seeds.
        #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u64).range(1..=100))]
        seeds: u64,
        /// Planner.
        #[arg(long, value_enum, default_value = "eapf")]
        planner: PlannerKind,
    },
    /// Drive a rover that runs the firmware, over its serial port: set the
    /// pose, send the goal, show a status line while it drives, log the
    /// telemetry as CSV, replay it through the host's core and draw the
    /// run. Ctrl-C stops the rover.
    Drive(DriveArgs),
    /// Fit one sensor's calibration from its counts with a card at 100,
    /// 200, … 800 mm (the first five fields of the firmware's `D` lines),
    /// and print the `K` line that stores it on the board.
    Calibrate {
        /// The sensor, 0 (−40°) … 4 (+40°).
        #[arg(long, value_parser = clap::value_parser!(u8).range(0..5))]
        sensor: u8,
        /// The board's ADC.
        #[arg(long, value_enum, default_value = "avr")]
        adc: Adc,
        /// Its eight counts, nearest card first.
        #[arg(num_args = 8, required = true)]
        counts: Vec<u16>,
    },
    /// Write the faults page: one planner on every still-world set under
    /// no fault and each fault of `--fault` with its defaults, a table of
    /// fault × set.
    Faults {
        /// The page to write.
        #[arg(long, default_value = "docs/faults.md")]
        out: PathBuf,
        #[command(flatten)]
        worlds: Worlds,
        /// Seeds.
        #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..=100))]
        seeds: u64,
        /// Planner.
        #[arg(long, value_enum, default_value = "eapf")]
        planner: PlannerKind,
    },
}

/// Write `page` to `out` and say so: how many runs it took and how long.
fn publish(out: &Path, page: &str, runs: usize, started: std::time::Instant) -> Result<(), String> {
    write(out, page)?;
    say(&format!(
        "wrote {} ({runs} runs in {:.0} s)\n",
        out.display(),
        started.elapsed().as_secs_f64()
    ))
}

/// What writes a page: this command line and the commit.
fn provenance() -> results::Provenance {
    results::Provenance {
        command: std::iter::once("sim-host".to_string())
            .chain(std::env::args().skip(1))
            .collect::<Vec<_>>()
            .join(" "),
        commit: commit(),
    }
}

/// The sets of worlds the pages run over, the first seed and the workers.
#[derive(clap::Args)]
struct Worlds {
    /// The folder that holds the shared sets (`barn`, `barn-tight`,
    /// `examples`).
    #[arg(long, default_value = "../shared/scenarios")]
    shared: PathBuf,
    /// The scenario library.
    #[arg(long, default_value = "sim-host/scenarios")]
    library: PathBuf,
    /// Generated worlds of each kind.
    #[arg(long, default_value_t = 30, value_parser = clap::value_parser!(u64).range(1..=1000))]
    count: u64,
    /// First seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Worker threads (default: one per core).
    #[arg(long)]
    jobs: Option<usize>,
}

impl Worlds {
    /// The sets.
    fn sets(&self) -> Result<Vec<results::Set>, String> {
        results::sets(&self.shared, &self.library, self.count)
    }

    /// Ready to write the page `out` with `jobs` workers: the sets, and
    /// the time the runs start (a bad output is an error before they do).
    fn ready(&self, out: &Path) -> Result<(Vec<results::Set>, std::time::Instant), String> {
        workers(self.jobs)?;
        let sets = self.sets()?;
        output_ok(out, &[])?;
        Ok((sets, std::time::Instant::now()))
    }
}

fn main() -> ExitCode {
    match real_main(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("sim-host: {e}");
            ExitCode::from(2)
        }
    }
}

/// Print to stdout. A reader that has gone (`sim-host … | head`) is not
/// an error: `println!` would panic there.
fn say(text: &str) -> Result<(), String> {
    use std::io::Write;
    match std::io::stdout().lock().write_all(text.as_bytes()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(format!("stdout: {e}")),
        _ => Ok(()),
    }
}

fn sensors(perfect: bool) -> SensorMode {
    if perfect {
        SensorMode::Perfect
    } else {
        SensorMode::REALISTIC
    }
}

/// `--set-back` is for planners that sense: the ones that plan over the
/// map have no sensors to set back, and would run as without it.
fn set_back_applies(set_back: bool, planners: &[PlannerKind]) -> Result<(), String> {
    match planners.iter().find(|p| p.uses_map()) {
        Some(p) if set_back => Err(format!(
            "--set-back: planner {} plans over the map and has no sensors to set back",
            p.name()
        )),
        _ => Ok(()),
    }
}

/// What `drive` is asked.
#[derive(clap::Args)]
struct DriveArgs {
    /// The serial port (`/dev/ttyACM0`, `COM3`).
    #[arg(long)]
    port: String,
    /// Its rate.
    #[arg(long, default_value_t = 115_200)]
    baud: u32,
    /// The goal, mm.
    #[arg(long, num_args = 2, allow_negative_numbers = true, required = true)]
    goal: Vec<i16>,
    /// The rover's pose first: x mm, y mm, heading in degrees.
    #[arg(long, num_args = 3, allow_negative_numbers = true)]
    pose: Option<Vec<i16>>,
    /// Write the telemetry here as CSV.
    #[arg(long)]
    csv: Option<PathBuf>,
    /// Draw the run here.
    #[arg(long)]
    svg: Option<PathBuf>,
    /// The scenario to draw behind the run.
    #[arg(long)]
    world: Option<PathBuf>,
    /// Give up after this long without a line from the rover, s.
    #[arg(long, default_value_t = 10.0)]
    silence_s: f64,
    /// The rover's ADC, for the replay through the host's core.
    #[arg(long, value_enum, default_value = "avr")]
    adc: Adc,
    /// The firmware was built for sensors set back from the rim.
    #[arg(long)]
    set_back: bool,
}

/// A serial port as the console's line link.
struct SerialLink {
    port: Box<dyn serialport::SerialPort>,
    pending: Vec<u8>,
    silence: std::time::Duration,
}

impl sim_host::console::Link for SerialLink {
    fn send(&mut self, line: &str) -> Result<(), String> {
        use std::io::Write;
        self.port
            .write_all(format!("{line}\n").as_bytes())
            .map_err(|e| format!("serial: {e}"))
    }

    fn read_line(&mut self) -> Result<Option<String>, String> {
        use std::io::Read;
        let since = std::time::Instant::now();
        let mut buf = [0u8; 256];
        loop {
            if let Some(i) = self.pending.iter().position(|&b| b == b'\n') {
                let line: Vec<u8> = self.pending.drain(..=i).collect();
                return Ok(Some(String::from_utf8_lossy(&line).trim_end().to_string()));
            }
            if since.elapsed() > self.silence {
                return Ok(None);
            }
            match self.port.read(&mut buf) {
                Ok(n) => self.pending.extend_from_slice(&buf[..n]),
                Err(e) if e.kind() == std::io::ErrorKind::TimedOut => {}
                Err(e) => return Err(format!("serial: {e}")),
            }
        }
    }
}

/// The `drive` command.
fn drive_rover(a: DriveArgs) -> Result<(), String> {
    use sim_host::console::{self, Plan, CSV_HEADER};
    use std::sync::atomic::AtomicBool;
    use std::sync::Arc;
    // Every input and output checked before the rover moves.
    let world = a
        .world
        .as_deref()
        .map(Scenario::load)
        .transpose()
        .map_err(|e| e.to_string())?;
    let outputs: Vec<&Path> = [a.csv.as_deref(), a.svg.as_deref()]
        .into_iter()
        .flatten()
        .collect();
    let inputs: Vec<PathBuf> = a.world.iter().cloned().collect();
    for out in &outputs {
        output_ok(out, &inputs)?;
    }
    let port = serialport::new(&a.port, a.baud)
        .timeout(std::time::Duration::from_millis(50))
        .open()
        .map_err(|e| format!("{}: {e}", a.port))?;
    let mut link = SerialLink {
        port,
        pending: Vec::new(),
        silence: std::time::Duration::from_secs_f64(a.silence_s.max(0.1)),
    };
    let stop = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&stop);
    ctrlc::set_handler(move || flag.store(true, std::sync::atomic::Ordering::Relaxed))
        .map_err(|e| format!("Ctrl-C: {e}"))?;
    let status = indicatif::ProgressBar::new_spinner();
    let goal = (a.goal[0], a.goal[1]);
    let plan = Plan {
        pose: a.pose.as_ref().map(|p| (p[0], p[1], p[2])),
        goal,
    };
    let (records, end) = console::drive(&mut link, plan, &stop, |r| {
        status.set_message(r.status_line(goal));
        status.tick();
    })?;
    status.finish();
    if let Some(path) = &a.csv {
        let rows: Vec<String> = records.iter().map(console::Record::csv_row).collect();
        write(path, &format!("{CSV_HEADER}\n{}\n", rows.join("\n")))?;
    }
    // The log through the host's core, as the firmware is configured.
    let cfg = planner_core::ConfigBuilder::new(a.adc.profile())
        .sensors_set_back(a.set_back)
        .build()
        .map_err(|e| format!("configuration: {e:?}"))?;
    let replayed = console::replay(cfg, goal, &records);
    if let Some(path) = &a.svg {
        let svg = console::picture(&records, end, goal, world.as_ref(), Some(&replayed));
        write(path, &svg)?;
    }
    let differ = replayed.differ;
    say(&format!(
        "{end:?} after {} steps; replayed through the host's core: {} of them decided differently{}\n",
        records.len(),
        differ.len(),
        differ
            .first()
            .map(|i| format!(" (the first: step {i})"))
            .unwrap_or_default()
    ))
}

/// A board's ADC.
#[derive(Clone, Copy, clap::ValueEnum)]
enum Adc {
    /// ATmega328P: 10 bits, 5 V.
    Avr,
    /// STM32F4: 12 bits, 3.3 V.
    Stm32,
}

impl Adc {
    fn profile(self) -> planner_core::AdcProfile {
        match self {
            Adc::Avr => planner_core::AdcProfile::AVR_10BIT_5V,
            Adc::Stm32 => planner_core::AdcProfile::STM32_12BIT_3V3,
        }
    }
}

/// The `K` line for `sensor`'s `counts` at the card distances.
fn calibrate(sensor: u8, adc: Adc, counts: &[u16]) -> Result<String, String> {
    use planner_core::rover::calibration::{datasheet_row, fit, Row, CARD_MM};
    let adc = adc.profile();
    let row: Row = counts
        .try_into()
        .map_err(|_| format!("{} counts, not {}", counts.len(), CARD_MM.len()))?;
    let k = fit(adc, &row).map_err(|e| {
        format!(
            "sensor {sensor}: {e:?}: counts {row:?} at {CARD_MM:?} mm (the datasheet's: {:?})",
            datasheet_row(adc)
        )
    })?;
    Ok(format!(
        "{}\n",
        sim_host::console::calibration_line(sensor, k)
    ))
}

fn real_main(cli: Cli) -> Result<(), String> {
    match cli.cmd {
        Cmd::Calibrate {
            sensor,
            adc,
            counts,
        } => say(&calibrate(sensor, adc, &counts)?),
        Cmd::Drive(a) => drive_rover(a),
        Cmd::Run {
            file,
            planner,
            seed,
            svg: svg_out,
            trace,
            perfect,
            set_back,
            faults,
        } => {
            set_back_applies(set_back, &[planner])?;
            for out in svg_out.iter().chain(&trace) {
                output_ok(out, std::slice::from_ref(&file))?;
            }
            let sc = Scenario::load(&file).map_err(|e| e.to_string())?;
            let cfg = SimConfig {
                planner,
                seed,
                sensors: sensors(perfect),
                set_back,
                faults: faults.clone(),
                ..SimConfig::default()
            };
            let refp = reference::shortest_path(&sc);
            let res = sim::run(&sc, &cfg, refp.as_ref().map(|r| r.length));
            let mut report = format!(
                "scenario     {}\nplanner      {}\n",
                sc.name,
                planner.name()
            );
            if set_back {
                report += "sensors      set back from the rim by their minimum range\n";
            }
            for f in &faults {
                report += &format!("fault        {f}\n");
            }
            report += &format!(
                "outcome      {}\nsteps        {}\npath_length  {:.3} m\n",
                res.outcome.as_str(),
                res.steps,
                res.path_length
            );
            report += &match &refp {
                Some(r) => format!(
                    "reference    {:.3} m (ratio {:.3})\n",
                    r.length,
                    res.path_length / r.length
                ),
                None => "reference    none (no path on the reference grid)\n".into(),
            };
            // The planners keep their clearance beyond the disc: the
            // shortest way that leaves it, beside the disc's own, tells a
            // goal behind a gap they cannot pass from one they miss.
            let margin_mm = cfg.margin_mm()?;
            let wider = reference::with_margin(&sc, margin_mm);
            report += &match &wider {
                Some(r) => format!(
                    "with_margin  {:.3} m (the disc + {margin_mm} mm)\n",
                    r.length
                ),
                None => format!("with_margin  none (no path for the disc + {margin_mm} mm)\n"),
            };
            report += &format!(
                "min_clear    {:.3} m\nvirtual_obs  {}\n",
                res.min_clearance, res.virtual_dropped
            );
            if let Some(c) = res.contact {
                report += &format!("contact      {}\n", c.describe());
            }
            // Planner `route`: the route at the end (waypoints, then the
            // goal), or none on the graph.
            match res.route.len() {
                0 => {}
                1 => report += "route        none on the graph: for the goal directly\n",
                n => {
                    let length: f64 = res.route.windows(2).map(|w| w[0].dist(w[1])).sum();
                    report += &format!("route        {} waypoints, {length:.3} m\n", n - 1);
                }
            }
            if let Some(out) = svg_out {
                let pic = svg::render(&sc, &res, planner.name(), refp.as_ref(), wider.as_ref());
                write(&out, &pic)?;
                report += &format!("svg          {}\n", out.display());
            }
            if let Some(out) = trace {
                write(&out, &sim::trace_csv(&res.trace))?;
                report += &format!("trace        {}\n", out.display());
            }
            say(&report)
        }
        Cmd::Bench {
            paths,
            planner,
            seed,
            seeds,
            jobs,
            json,
            svg: pictures,
            summary,
            perfect,
            set_back,
            faults,
        } => {
            workers(jobs)?;
            let files = collect(&paths)?;
            if files.is_empty() {
                return Err("no scenario files found".into());
            }
            // A bad output is an error before anything runs, not after.
            if let Some(out) = &json {
                output_ok(out, &files)?;
                write(out, "")?;
            }
            // Each planner once, in the order given.
            let mut planners: Vec<PlannerKind> = Vec::new();
            for p in planner {
                if !planners.contains(&p) {
                    planners.push(p);
                }
            }
            set_back_applies(set_back, &planners)?;
            let several = planners.len() > 1;
            let mut rows = Vec::new();
            for planner in &planners {
                // Several planners: each line says whose it is.
                let who = if several {
                    format!("{} ", planner.name())
                } else {
                    String::new()
                };
                let mut theirs = Vec::new();
                for seed in seed..seed.saturating_add(seeds) {
                    let cfg = SimConfig {
                        planner: *planner,
                        seed,
                        sensors: sensors(perfect),
                        set_back,
                        faults: faults.clone(),
                        ..SimConfig::default()
                    };
                    let mut these = match &pictures {
                        Some(dir) => bench::run_all_pictured(&files, &cfg, true, dir)?,
                        None => bench::run_all(&files, &cfg, true).map_err(|e| e.to_string())?,
                    };
                    if seeds > 1 {
                        say(&format!("{who}seed {seed}: {}", bench::table(&these, true)))?;
                    }
                    theirs.append(&mut these);
                }
                if seeds > 1 {
                    say(&format!("{who}all seeds: {}", bench::table(&theirs, true)))?;
                } else {
                    let t = bench::table(&theirs, summary);
                    say(&if several && summary {
                        format!("{who}{t}")
                    } else {
                        t
                    })?;
                }
                rows.append(&mut theirs);
            }
            if several {
                say(&format!("\n{}", bench::comparison(&rows)))?;
            }
            if let Some(out) = json {
                let lines: Vec<String> = rows
                    .iter()
                    .map(|r| serde_json::to_string(r).map_err(|e| e.to_string()))
                    .collect::<Result<_, _>>()?;
                write(&out, &(lines.join("\n") + "\n"))?;
            }
            Ok(())
        }
        Cmd::Compare {
            before,
            after,
            runs,
        } => {
            let a = bench::load_rows(&before)?;
            let b = bench::load_rows(&after)?;
            say(&bench::compare(&a, &b, runs)?)
        }
        Cmd::Results {
            out,
            worlds,
            seeds,
            planner,
        } => {
            workers(worlds.jobs)?;
            let seed = worlds.seed;
            let planners = if planner.is_empty() {
                results::PLANNERS.to_vec()
            } else {
                planner
            };
            let sets = worlds.sets()?;
            // A bad output path is an error before anything runs.
            let pictures = out.with_file_name("results");
            std::fs::create_dir_all(&pictures)
                .map_err(|e| format!("{}: {e}", pictures.display()))?;
            let started = std::time::Instant::now();
            let rows = results::run(&sets, &planners, seed, seeds, true);
            let made = provenance();
            let (page, svgs) =
                results::page(&sets, &rows, &planners, seed, seeds, "results", &made);
            for (file, svg) in svgs {
                write(&pictures.join(file), &svg)?;
            }
            let runs: usize = rows.iter().map(Vec::len).sum();
            publish(&out, &page, runs, started)
        }
        Cmd::Failures {
            out,
            worlds,
            seeds,
            planner,
        } => {
            let (sets, started) = worlds.ready(&out)?;
            let seed = worlds.seed;
            let rows = results::run(&sets, &[planner], seed, seeds, true);
            let page = results::failures_page(&sets, &rows, planner, seed, seeds, &provenance());
            let runs: usize = rows.iter().map(Vec::len).sum();
            publish(&out, &page, runs, started)
        }
        Cmd::Faults {
            out,
            worlds,
            seeds,
            planner,
        } => {
            let (sets, started) = worlds.ready(&out)?;
            let seed = worlds.seed;
            let rows = results::run_faults(&sets, planner, seed, seeds, true);
            let made = provenance();
            let page = results::fault_page(&sets, &rows, planner, seed, seeds, &made);
            let runs: usize = rows.iter().flat_map(|(_, r)| r).map(Vec::len).sum();
            publish(&out, &page, runs, started)
        }
        Cmd::Gen {
            out,
            seed,
            count,
            start,
            goal,
            kind,
            force,
        } => {
            let (start, goal) = ([start[0], start[1]], [goal[0], goal[1]]);
            let fresh = |f: &Path| {
                if f.exists() && !force {
                    Err(format!("{}: exists; --force writes over it", f.display()))
                } else {
                    Ok(())
                }
            };
            let Some(count) = count else {
                let name = out
                    .file_stem()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_else(|| "random".into());
                fresh(&out)?;
                gen_world(kind, &out, &name, start, goal, seed)?;
                return say(&format!("wrote {}\n", out.display()));
            };
            let seeds = seed..seed
                .checked_add(count)
                .ok_or("--seed + --count overflows")?;
            for s in seeds.clone() {
                fresh(&out.join(format!("{}-{s}.toml", kind.prefix())))?;
            }
            for s in seeds.clone() {
                let name = format!("{}-{s}", kind.prefix());
                gen_world(
                    kind,
                    &out.join(format!("{name}.toml")),
                    &name,
                    start,
                    goal,
                    s,
                )?;
            }
            say(&format!(
                "wrote {count} worlds (seeds {} to {}) to {}\n",
                seeds.start,
                seeds.end - 1,
                out.display()
            ))
        }
    }
}

/// The worker threads: `jobs` of them (default one per core), with the
/// main thread's stack (8 MiB) rather than 2 MiB: the `route` planner's map
/// (311,312 bytes with `routemap`'s capacities) is built and moved on the
/// stack, and its searches keep their arrays there (planner-core is
/// allocation-free); a worker overflowed 2 MiB with 8,192 nodes.
fn workers(jobs: Option<usize>) -> Result<(), String> {
    let mut pool = rayon::ThreadPoolBuilder::new().stack_size(8 << 20);
    if let Some(j) = jobs {
        pool = pool.num_threads(j.max(1));
    }
    pool.build_global().map_err(|e| e.to_string())
}

/// The commit the tree is at, and whether it has changes beyond it.
fn commit() -> String {
    let git = |args: &[&str]| {
        std::process::Command::new("git")
            .args(args)
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
    match git(&["rev-parse", "--short=12", "HEAD"]) {
        Some(c) => match git(&["status", "--porcelain", "--untracked-files=no"]) {
            Some(changes) if !changes.is_empty() => format!("`{c}` with uncommitted changes"),
            _ => format!("`{c}`"),
        },
        None => "(not a git checkout)".into(),
    }
}

/// One random world of `kind` in the paper's environment 2 arena at `out`,
/// loaded back to check it.
fn gen_world(
    kind: generate::Kind,
    out: &Path,
    name: &str,
    start: [f64; 2],
    goal: [f64; 2],
    seed: u64,
) -> Result<(), String> {
    write(out, &generate::world(kind, name, start, goal, seed)?)?;
    Scenario::load(out).map(|_| ()).map_err(|e| e.to_string())
}

/// Write `text` to `path` whole or not at all: into a file beside it, then
/// renamed over it (a run stopped half-way leaves the old file).
fn write(path: &Path, text: &str) -> Result<(), String> {
    if let Some(dir) = path.parent() {
        if !dir.as_os_str().is_empty() {
            std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        }
    }
    let mut part = path.as_os_str().to_owned();
    part.push(".part");
    let part = PathBuf::from(part);
    std::fs::write(&part, text)
        .and_then(|()| std::fs::rename(&part, path))
        .map_err(|e| {
            let _ = std::fs::remove_file(&part);
            format!("{}: {e}", path.display())
        })
}

/// An output may not be one of the `inputs` (scenario files) nor a
/// scenario file by its name: the runs' figures written over a world.
fn output_ok(out: &Path, inputs: &[PathBuf]) -> Result<(), String> {
    let same = |a: &Path, b: &Path| match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    };
    if out.extension().is_some_and(|e| e == "toml") || inputs.iter().any(|i| same(out, i)) {
        return Err(format!(
            "{}: an output may not be a scenario file (.toml): it would overwrite a world",
            out.display()
        ));
    }
    Ok(())
}
