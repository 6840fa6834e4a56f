//! Benchmarks: many scenarios in parallel, one JSON line and one table row
//! per run (and, if asked, one picture), totals at the end.

use crate::reference;
use crate::scenario::{Scenario, ScenarioError};
use crate::sim::{self, Contact, Outcome, SimConfig, Touched};
use crate::svg;
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, HashMap};
use std::fmt::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// One run's figures (also the `--json` line, which [`load_rows`] reads
/// back).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Row {
    /// Scenario name.
    pub name: String,
    /// Planner name.
    pub planner: String,
    /// Exactly one of reached, collision, unreachable, timeout.
    pub outcome: Outcome,
    /// Planner cycles.
    pub steps: usize,
    /// Driven length, m.
    pub path_length: f64,
    /// Reference shortest length, m (null when there is none).
    pub reference_length: Option<f64>,
    /// Smallest clearance, m.
    pub min_clearance: f64,
    /// Virtual obstacles dropped.
    pub virtual_obstacles: usize,
    /// Whether the file says the scenario is solvable.
    pub solvable: bool,
    /// The file.
    pub file: PathBuf,
    /// Seed of the run's sensor noise and faults.
    pub seed: u64,
    /// What the disc touched, in a collision (absent from rows written
    /// before it was recorded).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub contact: Option<Contact>,
    /// Simulated time (s, turns and stands included) over the time the
    /// reference takes at cruise speed, for reached runs with a reference
    /// (absent from rows written before it was recorded).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time_ratio: Option<f64>,
    /// The run's term of SPL ([`Row::spl_term`]); absent where SPL does
    /// not count the run (and from rows written before it was recorded,
    /// which [`load_rows`] fills in).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spl: Option<f64>,
    /// Cycles the planner stopped for a sensor fault (0 in rows written
    /// before it was recorded).
    #[serde(default)]
    pub sensor_faults: usize,
    /// The faults injected (`--fault`), as their names and parameters.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub faults: Vec<String>,
}

impl Row {
    /// `path_length / reference_length` for reached runs.
    pub fn ratio(&self) -> Option<f64> {
        match (self.outcome, self.reference_length) {
            (Outcome::Reached, Some(r)) if r > 0.0 => Some(self.path_length / r),
            _ => None,
        }
    }

    /// The run's term of SPL (success weighted by path length, Anderson et
    /// al. 2018): S·ℓ/max(p, ℓ), S = 1 if reached, ℓ the reference, p the
    /// driven length; `None` for a run SPL does not count (an unsolvable
    /// world, or one without a reference).
    pub fn spl_term(&self) -> Option<f64> {
        match (self.solvable, self.reference_length) {
            (true, Some(l)) if l > 0.0 => Some(if self.outcome == Outcome::Reached {
                l / self.path_length.max(l)
            } else {
                0.0
            }),
            _ => None,
        }
    }

    /// The row with its SPL term filled in.
    pub fn with_spl(self) -> Row {
        Row {
            spl: self.spl_term(),
            ..self
        }
    }

    /// Whether a reachable goal was reported unreachable.
    pub fn wrongly_unreachable(&self) -> bool {
        self.solvable && self.outcome == Outcome::Unreachable
    }

    /// Whether the run kept the rules whatever it reached: no collision,
    /// the disc never touched anything, an unsolvable goal not "reached".
    pub fn safe(&self) -> bool {
        self.outcome != Outcome::Collision
            && self.min_clearance > 0.0
            && (self.solvable || self.outcome != Outcome::Reached)
    }

    /// Whether the outcome is the right one: reached when solvable,
    /// unreachable when not, never a collision.
    pub fn correct(&self) -> bool {
        if self.solvable {
            self.outcome == Outcome::Reached
        } else {
            self.outcome == Outcome::Unreachable
        }
    }
}

/// Run every scenario file; a bad file is an error before anything runs.
pub fn run_all(
    files: &[PathBuf],
    cfg: &SimConfig,
    progress: bool,
) -> Result<Vec<Row>, ScenarioError> {
    let scenarios = load_all(files)?;
    Ok(run_loaded(&scenarios, cfg, progress, None).0)
}

/// [`run_all`], also writing a picture of every run into the folder
/// `pictures` (made if need be) as `<file stem>-<planner>-seed<N>.svg`,
/// the same picture as `run --svg`. Two files with the same stem would
/// overwrite each other's pictures: that is an error before anything runs,
/// as a bad file is.
pub fn run_all_pictured(
    files: &[PathBuf],
    cfg: &SimConfig,
    progress: bool,
    pictures: &Path,
) -> Result<Vec<Row>, String> {
    let scenarios = load_all(files).map_err(|e| e.to_string())?;
    let mut stems: Vec<(&std::ffi::OsStr, &PathBuf)> = scenarios
        .iter()
        .map(|(f, _)| (f.file_stem().unwrap_or_default(), f))
        .collect();
    stems.sort();
    if let Some(w) = stems.windows(2).find(|w| w[0].0 == w[1].0) {
        return Err(format!(
            "{} and {}: two scenario files with one name, their pictures would overwrite each other",
            w[0].1.display(),
            w[1].1.display()
        ));
    }
    std::fs::create_dir_all(pictures).map_err(|e| format!("{}: {e}", pictures.display()))?;
    let margin_mm = cfg.margin_mm()?;
    let (rows, failed) = run_loaded(&scenarios, cfg, progress, Some((pictures, margin_mm)));
    match failed {
        Some(e) => Err(e),
        None => Ok(rows),
    }
}

fn load_all(files: &[PathBuf]) -> Result<Vec<(PathBuf, Scenario)>, ScenarioError> {
    files
        .iter()
        .map(|f| Scenario::load(f).map(|s| (f.clone(), s)))
        .collect()
}

/// The runs, sorted by file, and the first picture that could not be
/// written (pictures drawn into the folder with the way for the disc plus
/// the planners' margin, mm).
fn run_loaded(
    scenarios: &[(PathBuf, Scenario)],
    cfg: &SimConfig,
    progress: bool,
    pictures: Option<(&Path, u16)>,
) -> (Vec<Row>, Option<String>) {
    let bar = if progress {
        ProgressBar::new(scenarios.len() as u64)
    } else {
        ProgressBar::hidden()
    };
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} {elapsed_precise} {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let out = run_with(scenarios, cfg, &bar, pictures);
    bar.finish_and_clear();
    out
}

/// The runs of `scenarios` with `cfg`, sorted by file, counted on `bar`
/// (the caller's: one bar over several calls).
pub fn run_scenarios(
    scenarios: &[(PathBuf, Scenario)],
    cfg: &SimConfig,
    bar: &ProgressBar,
) -> Vec<Row> {
    run_with(scenarios, cfg, bar, None).0
}

fn run_with(
    scenarios: &[(PathBuf, Scenario)],
    cfg: &SimConfig,
    bar: &ProgressBar,
    pictures: Option<(&Path, u16)>,
) -> (Vec<Row>, Option<String>) {
    let failed: Mutex<Option<String>> = Mutex::new(None);
    let mut rows: Vec<Row> = scenarios
        .par_iter()
        .map(|(file, sc)| {
            let refp = reference::shortest_path(sc);
            let refl = refp.as_ref().map(|r| r.length);
            let res = sim::run(sc, cfg, refl);
            if let Some((dir, margin_mm)) = pictures {
                let stem = file.file_stem().unwrap_or_default().to_string_lossy();
                let out = dir.join(format!(
                    "{stem}-{}-seed{}.svg",
                    cfg.planner.name(),
                    cfg.seed
                ));
                let wider = reference::with_margin(sc, margin_mm);
                let pic = svg::render(sc, &res, cfg.planner.name(), refp.as_ref(), wider.as_ref());
                if let Err(e) = std::fs::write(&out, pic) {
                    let mut f = failed.lock().unwrap_or_else(|p| p.into_inner());
                    f.get_or_insert_with(|| format!("{}: {e}", out.display()));
                }
            }
            bar.inc(1);
            Row {
                name: sc.name.clone(),
                planner: cfg.planner.name().to_string(),
                outcome: res.outcome,
                steps: res.steps,
                path_length: res.path_length,
                reference_length: refl,
                min_clearance: res.min_clearance,
                virtual_obstacles: res.virtual_dropped,
                solvable: sc.solvable,
                file: file.clone(),
                seed: cfg.seed,
                contact: res.contact,
                time_ratio: match (res.outcome, refl) {
                    (Outcome::Reached, Some(l)) if l > 0.0 => Some(res.duration_s * cfg.speed / l),
                    _ => None,
                },
                spl: None,
                sensor_faults: res.sensor_faults,
                faults: cfg.faults.iter().map(|f| f.to_string()).collect(),
            }
            .with_spl()
        })
        .collect();
    rows.sort_by(|a, b| a.file.cmp(&b.file));
    (rows, failed.into_inner().unwrap_or_else(|p| p.into_inner()))
}

/// Totals over rows.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Totals {
    /// Runs.
    pub runs: usize,
    /// Solvable scenarios.
    pub solvable: usize,
    /// Reached.
    pub reached: usize,
    /// Collisions.
    pub collisions: usize,
    /// Of the collisions, those with a moving circle: within 45° of the
    /// heading, and at the disc's side or back (where no beam looks).
    pub movers: (usize, usize),
    /// Reported unreachable.
    pub unreachable: usize,
    /// Unsolvable scenarios reported unreachable.
    pub unreachable_correct: usize,
    /// Timeouts.
    pub timeouts: usize,
    /// Stops as arrived away from the goal (odometry astray).
    pub astray: usize,
    /// Runs in which the planner flagged a sensor fault.
    pub flagged: usize,
    /// Mean path ratio over reached runs with a reference.
    pub mean_ratio: Option<f64>,
    /// Reached runs within 1.25× the reference.
    pub within_125: usize,
    /// Reachable goals reported unreachable.
    pub wrongly_unreachable: usize,
    /// SPL over the runs it counts ([`Row::spl_term`]).
    pub spl: Option<f64>,
    /// Mean time ratio over reached runs with a reference.
    pub time_ratio: Option<f64>,
}

/// Sum up.
pub fn totals(rows: &[Row]) -> Totals {
    let ratios: Vec<f64> = rows.iter().filter_map(Row::ratio).collect();
    Totals {
        runs: rows.len(),
        solvable: rows.iter().filter(|r| r.solvable).count(),
        reached: rows
            .iter()
            .filter(|r| r.outcome == Outcome::Reached)
            .count(),
        collisions: rows
            .iter()
            .filter(|r| r.outcome == Outcome::Collision)
            .count(),
        movers: (
            rows.iter()
                .filter(|r| r.contact.is_some_and(|c| c.with == Touched::MoverAhead))
                .count(),
            rows.iter()
                .filter(|r| r.contact.is_some_and(|c| c.with == Touched::MoverBeside))
                .count(),
        ),
        unreachable: rows
            .iter()
            .filter(|r| r.outcome == Outcome::Unreachable)
            .count(),
        unreachable_correct: rows
            .iter()
            .filter(|r| !r.solvable && r.outcome == Outcome::Unreachable)
            .count(),
        timeouts: rows
            .iter()
            .filter(|r| r.outcome == Outcome::Timeout)
            .count(),
        astray: rows.iter().filter(|r| r.outcome == Outcome::Astray).count(),
        flagged: rows.iter().filter(|r| r.sensor_faults > 0).count(),
        mean_ratio: (!ratios.is_empty()).then(|| ratios.iter().sum::<f64>() / ratios.len() as f64),
        within_125: ratios.iter().filter(|&&r| r <= 1.25).count(),
        wrongly_unreachable: rows.iter().filter(|r| r.wrongly_unreachable()).count(),
        spl: mean(rows.iter().filter_map(|r| r.spl)),
        time_ratio: mean(rows.iter().filter_map(|r| r.time_ratio)),
    }
}

/// The mean of `values`; `None` when there are none.
fn mean(values: impl Iterator<Item = f64>) -> Option<f64> {
    let (sum, n) = values.fold((0.0, 0usize), |(s, n), v| (s + v, n + 1));
    (n > 0).then(|| sum / n as f64)
}

/// A figure with three decimals, or "–" where there is none.
fn fig(v: Option<f64>) -> String {
    v.map_or_else(|| "–".into(), |v| format!("{v:.3}"))
}

/// The table: one row per scenario (unless `summary_only`), then totals.
pub fn table(rows: &[Row], summary_only: bool) -> String {
    let mut s = String::new();
    if !summary_only {
        let _ = writeln!(
            s,
            "| scenario | planner | outcome | steps | path m | ref m | ratio | min clear m | VOs |"
        );
        let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|");
        for r in rows {
            let _ = writeln!(
                s,
                "| {} | {} | {}{} | {} | {:.2} | {} | {} | {:.3} | {} |",
                r.name,
                r.planner,
                r.outcome.as_str(),
                if r.correct() { "" } else { " ✗" },
                r.steps,
                r.path_length,
                r.reference_length
                    .map(|l| format!("{l:.2}"))
                    .unwrap_or_else(|| "–".into()),
                r.ratio()
                    .map(|l| format!("{l:.2}"))
                    .unwrap_or_else(|| "–".into()),
                r.min_clearance,
                r.virtual_obstacles
            );
        }
        s.push('\n');
    }
    let t = totals(rows);
    let pct = |n: usize, d: usize| {
        if d == 0 {
            0.0
        } else {
            100.0 * n as f64 / d as f64
        }
    };
    // The split on the totals line, so that one line per seed still holds it.
    let split = escape_split(rows).map_or_else(String::new, |x| format!(" | {x}"));
    // Only where moving circles were met, so that the line of a static set
    // is as it was.
    let movers = match t.movers {
        (0, 0) => String::new(),
        (ahead, beside) => format!(" ({ahead} with a mover ahead, {beside} beside or behind)"),
    };
    // Only where faults showed, as for the movers.
    let mut timeouts = t.timeouts.to_string();
    if t.astray > 0 {
        timeouts += &format!(" | astray {}", t.astray);
    }
    if t.flagged > 0 {
        timeouts += &format!(" | sensor fault flagged in {}", t.flagged);
    }
    let _ = writeln!(
        s,
        "runs {} | reached {}/{} solvable ({:.1}%) | collisions {}{movers} | unreachable {} ({} of {} unsolvable) | timeouts {timeouts} | mean path ratio {} | within 1.25x {}/{} | SPL {} | time ratio {}{split}",
        t.runs,
        t.reached,
        t.solvable,
        pct(t.reached, t.solvable),
        t.collisions,
        t.unreachable,
        t.unreachable_correct,
        t.runs - t.solvable,
        t.mean_ratio.map(|r| format!("{r:.3}")).unwrap_or_else(|| "–".into()),
        t.within_125,
        t.reached,
        fig(t.spl),
        fig(t.time_ratio)
    );
    s
}

/// The mean path ratio split by whether the run dropped virtual obstacles:
/// the field's own paths against those with an escape's detours, which is
/// where a planner's mean ratio is lost or won (the commit history, "Where the
/// path ratio goes"). `None` where no reached run dropped any (a planner
/// without the escape; the line's ratio is already the field's own).
pub fn escape_split(rows: &[Row]) -> Option<String> {
    let part = |escaped: bool| {
        let these: Vec<Row> = rows
            .iter()
            .filter(|r| (r.virtual_obstacles > 0) == escaped)
            .cloned()
            .collect();
        totals(&these)
    };
    let (with, without) = (part(true), part(false));
    let with_ratio = with.mean_ratio?;
    let without_ratio = without
        .mean_ratio
        .map_or_else(|| "–".into(), |r| format!("{r:.3}"));
    Some(format!(
        "ratio without virtual obstacles {without_ratio} ({}/{} within 1.25x), with them {with_ratio:.3} ({}/{})",
        without.within_125, without.reached, with.within_125, with.reached
    ))
}

/// The planners side by side: one row of [`totals`] per planner, in the
/// order they first appear in `rows`, and the mean path ratio over the runs
/// (scenario and seed) that every planner reached, a fair comparison where
/// they reach different runs (a planner that reaches only easy goals has a
/// low ratio over its own).
pub fn comparison(rows: &[Row]) -> String {
    let mut planners: Vec<&str> = Vec::new();
    for r in rows {
        if !planners.contains(&r.planner.as_str()) {
            planners.push(&r.planner);
        }
    }
    // How many planners reached each run (file and seed).
    let mut reached: HashMap<(&Path, u64), usize> = HashMap::new();
    for r in rows.iter().filter(|r| r.ratio().is_some()) {
        *reached.entry((r.file.as_path(), r.seed)).or_default() += 1;
    }
    let common = |r: &Row| reached.get(&(r.file.as_path(), r.seed)) == Some(&planners.len());
    let mut s = String::new();
    let _ = writeln!(
        s,
        "| planner | runs | reached | collisions | unreachable (of unsolvable) | wrongly unreachable | timeouts | SPL | mean path ratio | time ratio | within 1.25x | ratio where all reached |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|---|---|");
    for p in planners.iter().copied() {
        let theirs: Vec<Row> = rows.iter().filter(|r| r.planner == p).cloned().collect();
        let t = totals(&theirs);
        let shared: Vec<f64> = theirs
            .iter()
            .filter(|r| common(r))
            .filter_map(Row::ratio)
            .collect();
        let _ = writeln!(
            s,
            "| {p} | {} | {}/{} | {} | {} ({}/{}) | {} | {} | {} | {} | {} | {}/{} | {} ({} runs) |",
            t.runs,
            t.reached,
            t.solvable,
            t.collisions,
            t.unreachable,
            t.unreachable_correct,
            t.runs - t.solvable,
            t.wrongly_unreachable,
            t.timeouts,
            fig(t.spl),
            fig(t.mean_ratio),
            fig(t.time_ratio),
            t.within_125,
            t.reached,
            if shared.is_empty() {
                "–".to_string()
            } else {
                format!("{:.3}", shared.iter().sum::<f64>() / shared.len() as f64)
            },
            shared.len()
        );
    }
    s
}

/// Read a `bench --json` file back: one [`Row`] per line (blank lines
/// skipped). A line that is not a run is an error naming the file and line.
pub fn load_rows(path: &Path) -> Result<Vec<Row>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    text.lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(i, l)| {
            serde_json::from_str::<Row>(l)
                .map(Row::with_spl)
                .map_err(|e| format!("{}:{}: not a bench run: {e}", path.display(), i + 1))
        })
        .collect()
}

/// Two benches of the same runs side by side, run by run: `before` and
/// `after` are their rows (two builds of a planner, or two settings), paired
/// by planner, scenario name and seed (not by path, so that two checkouts'
/// runs pair). Prints both totals over the paired runs, the mean path ratio
/// over the runs both reached, how many outcomes changed and which way,
/// and with `list_runs` each changed run.
///
/// Why: a change's totals hide runs that moved both ways (13 reached runs
/// becoming timeouts behind 10 timeouts becoming reached), and a few runs
/// moving is within what another seed would move (the commit history, "The
/// flank margin and the stuck window, swept").
pub fn compare(before: &[Row], after: &[Row], list_runs: bool) -> Result<String, String> {
    type Key<'a> = (&'a str, &'a str, u64);
    fn index<'a>(rows: &'a [Row], which: &str) -> Result<BTreeMap<Key<'a>, &'a Row>, String> {
        let mut map = BTreeMap::new();
        for r in rows {
            if map
                .insert((r.planner.as_str(), r.name.as_str(), r.seed), r)
                .is_some()
            {
                return Err(format!(
                    "{which}: {} with seed {} ({}) appears twice; compare benches of one set each",
                    r.name, r.seed, r.planner
                ));
            }
        }
        Ok(map)
    }
    let a = index(before, "before")?;
    let b = index(after, "after")?;
    let paired: Vec<(&Row, &Row)> = a
        .iter()
        .filter_map(|(k, ra)| b.get(k).map(|rb| (*ra, *rb)))
        .collect();
    if paired.is_empty() {
        return Err("no run (planner, scenario, seed) is in both files".into());
    }
    let (pa, pb): (Vec<Row>, Vec<Row>) = paired
        .iter()
        .map(|(x, y)| ((*x).clone(), (*y).clone()))
        .unzip();
    let mut s = String::new();
    let _ = write!(s, "before: {}", table(&pa, true));
    let _ = write!(s, "after:  {}", table(&pb, true));
    // The runs both reached, each side's mean ratio over them by `totals`.
    let (ba, bb): (Vec<Row>, Vec<Row>) = pa
        .iter()
        .zip(&pb)
        .filter(|(x, y)| x.ratio().is_some() && y.ratio().is_some())
        .map(|(x, y)| (x.clone(), y.clone()))
        .unzip();
    if let (Some(ra), Some(rb)) = (totals(&ba).mean_ratio, totals(&bb).mean_ratio) {
        let _ = writeln!(
            s,
            "mean path ratio where both reached ({} runs): {ra:.3} -> {rb:.3}",
            ba.len()
        );
    }
    let changed: Vec<&(&Row, &Row)> = paired
        .iter()
        .filter(|(x, y)| x.outcome != y.outcome)
        .collect();
    let _ = writeln!(
        s,
        "outcomes changed: {} of {} runs",
        changed.len(),
        paired.len()
    );
    let mut moves: BTreeMap<(Outcome, Outcome), usize> = BTreeMap::new();
    for (x, y) in &changed {
        *moves.entry((x.outcome, y.outcome)).or_default() += 1;
    }
    let mut moves: Vec<_> = moves.into_iter().collect();
    moves.sort_by(|p, q| q.1.cmp(&p.1).then(p.0.cmp(&q.0)));
    for ((from, to), n) in moves {
        let _ = writeln!(s, "  {} -> {}: {n}", from.as_str(), to.as_str());
    }
    if list_runs {
        for (x, y) in &changed {
            let _ = writeln!(
                s,
                "  {} seed {} ({}): {} ({:.1} m) -> {} ({:.1} m)",
                x.name,
                x.seed,
                x.planner,
                x.outcome.as_str(),
                x.path_length,
                y.outcome.as_str(),
                y.path_length
            );
        }
    }
    let (only_a, only_b) = (a.len() - paired.len(), b.len() - paired.len());
    if only_a + only_b > 0 {
        let _ = writeln!(
            s,
            "not compared: {only_a} runs only before, {only_b} only after"
        );
    }
    Ok(s)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    pub(crate) fn row(
        planner: &str,
        file: &str,
        seed: u64,
        outcome: Outcome,
        path_length: f64,
    ) -> Row {
        Row {
            name: file.into(),
            planner: planner.into(),
            outcome,
            steps: 10,
            path_length,
            reference_length: Some(1.0),
            min_clearance: 0.1,
            virtual_obstacles: 0,
            solvable: true,
            file: file.into(),
            seed,
            contact: None,
            time_ratio: None,
            spl: None,
            sensor_faults: 0,
            faults: Vec::new(),
        }
        .with_spl()
    }

    /// The last column compares the planners on the runs all of them
    /// reached: `b` reached only the easy run, so its own mean is low, but
    /// on the shared run `a` is the shorter.
    #[test]
    fn the_comparison_ratio_is_over_the_runs_every_planner_reached() {
        let rows = [
            row("a", "easy", 1, Outcome::Reached, 1.1),
            row("a", "hard", 1, Outcome::Reached, 3.0),
            row("b", "easy", 1, Outcome::Reached, 1.2),
            row("b", "hard", 1, Outcome::Timeout, 9.0),
            row("a", "easy", 2, Outcome::Reached, 1.3),
            row("b", "easy", 2, Outcome::Reached, 1.5),
        ];
        let table = comparison(&rows);
        let lines: Vec<&str> = table.lines().collect();
        // SPL: a (1/1.1 + 1/3 + 1/1.3) / 3 = 0.671; b (1/1.2 + 0 + 1/1.5)
        // / 3 = 0.500.
        assert_eq!(lines.len(), 4, "{table}");
        assert_eq!(
            lines[2],
            "| a | 3 | 3/3 | 0 | 0 (0/0) | 0 | 0 | 0.671 | 1.800 | – | 1/3 | 1.200 (2 runs) |"
        );
        assert_eq!(
            lines[3],
            "| b | 3 | 2/3 | 0 | 0 (0/0) | 0 | 1 | 0.500 | 1.350 | – | 1/2 | 1.350 (2 runs) |"
        );
    }

    /// The totals line splits the ratio by the escape where some reached
    /// run dropped virtual obstacles (not the timeout's), and leaves it
    /// out where none did.
    #[test]
    fn the_totals_split_the_ratio_by_the_escape() {
        let mut rows = vec![
            row("a", "w1", 1, Outcome::Reached, 1.0),
            row("a", "w2", 1, Outcome::Reached, 1.4),
            row("a", "w3", 1, Outcome::Reached, 2.0),
            row("a", "w4", 1, Outcome::Timeout, 9.0),
        ];
        assert!(!table(&rows, true).contains("virtual obstacles"));
        // SPL (1 + 1/1.4 + 1/2 + 0) / 4 = 0.554.
        rows[2].virtual_obstacles = 3;
        rows[3].virtual_obstacles = 5;
        assert_eq!(
            table(&rows, true),
            "runs 4 | reached 3/4 solvable (75.0%) | collisions 0 | unreachable 0 (0 of 0 unsolvable) \
             | timeouts 1 | mean path ratio 1.467 | within 1.25x 1/3 | SPL 0.554 | time ratio – | ratio without virtual obstacles \
             1.200 (1/2 within 1.25x), with them 2.000 (0/1)\n"
        );
    }

    /// The collisions count is split by what reached the rover only where
    /// a moving circle did; a still world's collision adds nothing to the
    /// line, and a row written before contacts were recorded reads back
    /// without one.
    #[test]
    fn the_totals_name_the_movers_that_reached_the_rover() {
        let struck = |with, standing| Some(Contact { with, standing });
        let mut rows = vec![
            row("a", "w1", 1, Outcome::Collision, 1.0),
            row("a", "w2", 1, Outcome::Collision, 1.0),
            row("a", "w3", 1, Outcome::Collision, 1.0),
            row("a", "w4", 1, Outcome::Reached, 1.0),
        ];
        rows[0].contact = struck(Touched::Static, false);
        assert!(table(&rows, true).contains("| collisions 3 | unreachable"));
        rows[1].contact = struck(Touched::MoverAhead, true);
        rows[2].contact = struck(Touched::MoverBeside, false);
        assert!(table(&rows, true)
            .contains("| collisions 3 (1 with a mover ahead, 1 beside or behind) | unreachable"));
        let old = r#"{"name":"w","planner":"a","outcome":"reached","steps":1,"path_length":1.0,"reference_length":1.0,"min_clearance":0.1,"virtual_obstacles":0,"solvable":true,"file":"w.toml","seed":1}"#;
        let back: Row = serde_json::from_str(old).unwrap();
        assert_eq!(back.contact, None);
        let line = serde_json::to_string(&rows[2]).unwrap();
        assert!(
            line.contains(r#""contact":{"with":"mover-beside","standing":false}"#),
            "{line}"
        );
    }

    /// Runs pair by planner, scenario and seed, not by path (two
    /// checkouts' files); the moves are counted each way, the runs only one
    /// side has are left out of both totals, and the ratio where both
    /// reached is over the same runs.
    #[test]
    fn compare_pairs_runs_and_counts_each_move() {
        let mut before = vec![
            row("a", "w1", 1, Outcome::Reached, 1.5),
            row("a", "w1", 2, Outcome::Reached, 2.0),
            row("a", "w2", 1, Outcome::Timeout, 9.0),
            row("a", "w3", 1, Outcome::Reached, 1.0),
            row("a", "only-before", 1, Outcome::Reached, 1.0),
        ];
        for r in &mut before {
            r.file = format!("/one/checkout/{}.toml", r.name).into();
        }
        let after = vec![
            row("a", "w1", 1, Outcome::Reached, 1.1),
            row("a", "w1", 2, Outcome::Timeout, 9.0),
            row("a", "w2", 1, Outcome::Reached, 3.0),
            row("a", "w3", 1, Outcome::Collision, 0.5),
        ];
        let text = compare(&before, &after, true).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert!(
            lines[0].starts_with("before: runs 4 | reached 3/4"),
            "{text}"
        );
        assert!(
            lines[1].starts_with("after:  runs 4 | reached 2/4"),
            "{text}"
        );
        assert_eq!(
            lines[2],
            "mean path ratio where both reached (1 runs): 1.500 -> 1.100"
        );
        assert_eq!(lines[3], "outcomes changed: 3 of 4 runs");
        // Each move once: in the order of the outcomes (reached first).
        assert_eq!(lines[4], "  reached -> collision: 1");
        assert_eq!(lines[5], "  reached -> timeout: 1");
        assert_eq!(lines[6], "  timeout -> reached: 1");
        assert_eq!(
            lines[7],
            "  w1 seed 2 (a): reached (2.0 m) -> timeout (9.0 m)"
        );
        assert_eq!(lines[10], "not compared: 1 runs only before, 0 only after");
        assert_eq!(lines.len(), 11, "{text}");
        // Without the list, the same totals and moves.
        let short = compare(&before, &after, false).unwrap();
        assert_eq!(short.lines().count(), 8, "{short}");
    }

    #[test]
    fn compare_refuses_what_it_cannot_pair() {
        let one = [row("a", "w1", 1, Outcome::Reached, 1.0)];
        let other = [row("b", "w1", 1, Outcome::Reached, 1.0)];
        let e = compare(&one, &other, false).unwrap_err();
        assert!(e.contains("no run"), "{e}");
        let twice = [one[0].clone(), one[0].clone()];
        let e = compare(&twice, &one, false).unwrap_err();
        assert!(
            e.contains("before: w1 with seed 1 (a) appears twice"),
            "{e}"
        );
    }

    /// What `bench --json` writes, `load_rows` reads back as the same rows.
    #[test]
    fn bench_json_lines_load_back() {
        let rows = [
            row("eapf", "w1", 3, Outcome::Unreachable, 4.25),
            Row {
                reference_length: None,
                ..row("route", "w2", 1, Outcome::Timeout, 7.0)
            }
            .with_spl(),
        ];
        // A reachable goal not reached counts 0 in SPL; without a
        // reference the run does not count.
        let line = serde_json::to_string(&rows[0]).unwrap();
        assert!(line.contains(r#""spl":0.0"#), "{line}");
        assert_eq!(rows[1].spl, None);
        let dir = std::env::temp_dir().join(format!("sim-host-load-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("runs.jsonl");
        let text: Vec<String> = rows
            .iter()
            .map(|r| serde_json::to_string(r).unwrap())
            .collect();
        std::fs::write(&file, text.join("\n") + "\n\n").unwrap();
        let back = load_rows(&file).unwrap();
        assert_eq!(back.len(), 2);
        for (a, b) in rows.iter().zip(&back) {
            assert_eq!(
                serde_json::to_string(a).unwrap(),
                serde_json::to_string(b).unwrap()
            );
        }
        std::fs::write(&file, "{\"name\": \"w1\"}\n").unwrap();
        let e = load_rows(&file).unwrap_err();
        assert!(e.contains("runs.jsonl:1: not a bench run"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
