//! What the planner step's parts cost on the ATmega328P: the `costs` bench
//! (firmware-avr/src/bin/costs.rs) times each primitive on fixed inputs in
//! simavr; this test checks every result against the host core's (the same
//! code, so they must be equal) and prints the cycles, the figures behind
//! the README's account of where the AVR step's time goes:
//! `cargo test --release -p rover-tests --test avr_costs -- --nocapture`.

// The inputs the bench does not print, from the bench's own file.
#[path = "../../firmware-avr/src/bench_inputs.rs"]
mod bench_inputs;

use planner_core::eapf::command::free_distance_mm;
use planner_core::eapf::escape::Escape;
use planner_core::fixed::{hypot, inverse_square_force, isqrt};
use planner_core::{AdcProfile, Angle, ConfigBuilder, Reading};
use rover_tests::avr::{costs_elf, Avr};
use std::collections::BTreeMap;

/// The host's answer for a bench line's name and inputs.
fn host(name: &str, a: i32, b: i32) -> (i32, i32) {
    let cfg = ConfigBuilder::new(AdcProfile::AVR_10BIT_5V)
        .build()
        .unwrap();
    match name {
        "nothing" => (a, 0),
        "div_u32" => ((a as u32 / b as u32) as i32, 0),
        "div_sweep" => {
            let (q, r) = bench_inputs::div_sweep(|n, d| (n / d, n % d));
            (q as i32, r as i32)
        }
        "mul_i32" => (a.wrapping_mul(b), 0),
        "mul_sweep" => (bench_inputs::mul_sweep(|a, b| a.wrapping_mul(b)) as i32, 0),
        "isqrt" => (isqrt(a as u32) as i32, 0),
        // 68 equal roots XORed: an even count cancels.
        "long_span" => (0, 0),
        // Whether a span of `a` roots laps Timer1's period.
        "lap" => (i32::from(a > 75), 0),
        "hypot" => (hypot(a, b) as i32, 0),
        "atan2" => (Angle::atan2(a, b).0 as i32, 0),
        "sin" => (Angle::from_deg(a as i16).sin(), 0),
        "inverse_square" => (inverse_square_force(a as u16), 0),
        "free_clear" | "free_near" => {
            let readings = if name == "free_clear" {
                [Reading::Clear; 5]
            } else {
                bench_inputs::NEAR
            };
            let rel = Angle::from_deg(a as i16);
            (free_distance_mm(&cfg, &readings, rel) as i32, 0)
        }
        "vo_force" => {
            // The bench's drop sequence (bounded as there), up to `a`
            // obstacles held.
            let esc = bench_inputs::CREEP_ESCAPE;
            let mut escape = Escape::new();
            for k in 0..bench_inputs::CREEP_CYCLES {
                if escape.len() >= a as usize {
                    break;
                }
                bench_inputs::creep(&mut escape, &esc, k);
            }
            assert_eq!(escape.len(), a as usize, "the drop sequence holds {a}");
            let f = escape.force(bench_inputs::VO_PROBE, Angle::ZERO);
            (f.x, f.y)
        }
        other => panic!("unknown bench line {other}"),
    }
}

#[test]
fn the_step_parts_compute_the_host_results_and_print_their_cycles() {
    let mut avr = Avr::boot_elf(&costs_elf());
    let mut cycles: BTreeMap<String, Vec<(i32, u32)>> = BTreeMap::new();
    let mut lines = 0;
    loop {
        let line = avr.read_line(2_000).expect("a bench line within 2 s");
        if line == "END" {
            break;
        }
        let f: Vec<&str> = line.split(' ').collect();
        assert_eq!((f.len(), f[0]), (7, "C"), "bench line {line:?}");
        let num = |i: usize| f[i].parse::<i64>().expect("a number");
        let (a, b) = (num(2) as i32, num(3) as i32);
        let got = (num(4) as i32, num(5) as i32);
        assert_eq!(got, host(f[1], a, b), "{line}");
        cycles
            .entry(f[1].to_string())
            .or_default()
            .push((a, num(6) as u32));
        lines += 1;
    }
    assert!(lines >= 25, "only {lines} bench lines");
    for (name, runs) in &cycles {
        let list: Vec<String> = runs.iter().map(|(a, c)| format!("{a}:{c}")).collect();
        println!("avr cycles {name}: {}", list.join(" "));
    }
    // The measurement subtracts its own cost: timing nothing gives ~0.
    for &(_, c) in &cycles["nothing"] {
        assert!(
            c <= 40 || c >= u32::MAX - 40,
            "timing nothing took {c} cycles"
        );
    }
    // The same span from sixteen points of Timer1's period, interrupts
    // off: the clock reads it the same each time (`clock::Stamp::cycles`).
    let long = &cycles["long_span"];
    assert_eq!(long.len(), 16, "sixteen long spans");
    assert!(
        long.iter().all(|&(_, c)| c == long[0].1) && long[0].1 > 32_768,
        "the long span read differently: {long:?}"
    );
    assert_eq!(
        cycles["vo_force"].len(),
        planner_core::eapf::escape::VIRTUAL_CAPACITY,
        "one timing per obstacle added, up to the capacity"
    );
}
