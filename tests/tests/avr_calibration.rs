//! Each sensor's calibration on the ATmega328P (`K`,
//! `planner_core::rover::calibration`): kept in EEPROM, used over a power
//! cycle, and a corrupt copy falls back to the datasheet's curve, flagged in
//! the telemetry. The firmware runs in simavr, reset as a power cycle
//! resets it (its EEPROM kept).

use planner_core::rover::calibration::{datasheet_row, fit, Source, STORED_BYTES};
use planner_core::AdcProfile;
use rover_tests::avr::firmware_elf;
use rover_tests::profile::Bare;
use sim_host::console::{calibration_line, Record};

const ADC: AdcProfile = AdcProfile::AVR_10BIT_5V;

/// The readings of a `D` line (its last five fields).
fn readings(d: &str) -> Vec<String> {
    let f: Vec<&str> = d.split_whitespace().collect();
    assert_eq!(f.len(), 11, "{d}");
    f[6..].iter().map(|s| s.to_string()).collect()
}

/// The calibration of the next telemetry line after `G`, as it says.
fn telemetry_flag(avr: &mut Bare) -> Source {
    assert_eq!(avr.request("G 3000 0"), "OK");
    let t = loop {
        if let Some(t) = Record::parse(&avr.line()) {
            break t;
        }
    };
    assert_eq!(avr.request("S"), "OK");
    t.cal
}

/// Every sensor sees a card at 200 mm, and sensor 2 reads 20 % high there
/// (its unit's spread).
fn card_at_200_mm(avr: &mut Bare) {
    let mv = 1_390; // the datasheet's output at 200 mm
    for ch in 0..5 {
        avr.set_adc_mv(ch, if ch == 2 { mv * 120 / 100 } else { mv });
    }
    avr.run_us(5_000);
}

#[test]
fn a_calibration_is_stored_and_survives_a_power_cycle() {
    let (mut avr, first) = Bare::boot(&firmware_elf());
    assert_eq!(first, "READY");
    assert!(avr.eeprom(0, STORED_BYTES, None).iter().all(|&b| b == 0xff));
    card_at_200_mm(&mut avr);
    let before = readings(&avr.request("D"));
    let mm = |r: &[String], i: usize| r[i].parse::<u16>().unwrap();
    assert!(
        mm(&before, 2) < 180,
        "sensor 2 reads high, so near: {before:?}"
    );
    assert_eq!(
        telemetry_flag(&mut avr),
        Source::Datasheet,
        "none stored: the datasheet's"
    );

    // Its correction, as the console fits it from the card's counts.
    let row = datasheet_row(ADC).map(|c| (u32::from(c) * 120 / 100) as u16);
    let k = fit(ADC, &row).unwrap();
    assert_eq!(avr.request(&calibration_line(2, k)), "OK");
    assert_eq!(avr.request("K 2 900 0"), "ERR", "no sensor needs that gain");
    let after = readings(&avr.request("D"));
    assert!(mm(&after, 2).abs_diff(200) <= 10, "{after:?}");
    assert_eq!(
        [&after[..2], &after[3..]].concat(),
        [&before[..2], &before[3..]].concat(),
        "the others as they were"
    );
    let stored = avr.eeprom(0, STORED_BYTES, None);
    assert!(stored.iter().any(|&b| b != 0xff), "written to EEPROM");

    // Power cycle: read back and used.
    assert_eq!(avr.reset(), "READY");
    card_at_200_mm(&mut avr);
    assert_eq!(readings(&avr.request("D")), after);
    assert_eq!(telemetry_flag(&mut avr), Source::Stored);

    // A corrupt copy: the datasheet's curve, flagged.
    let mut bad = stored.clone();
    bad[3] ^= 0x04;
    avr.eeprom(0, STORED_BYTES, Some(&bad));
    assert_eq!(avr.reset(), "READY");
    card_at_200_mm(&mut avr);
    assert_eq!(readings(&avr.request("D")), before);
    assert_eq!(telemetry_flag(&mut avr), Source::Corrupt);
}
