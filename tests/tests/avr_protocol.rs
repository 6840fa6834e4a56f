//! The ATmega328P firmware's serial protocol (`planner_core::rover::protocol`) as
//! a user meets it in simavr: bad lines get `ERR`, never a reset; a goal
//! starts the drive and its telemetry; the pose cannot be set while
//! driving; `S` stops the motors; `D` reports the sensors as the host's
//! core reads them.

use planner_core::rover::protocol::write_sensor_line;
use planner_core::{AdcProfile, ConfigBuilder, RawCounts};
use rover_tests::avr::{wheels_for_1ms, Avr};

/// The `D` line the host's core writes for `raw` with the AVR's default
/// configuration, without its `\n`.
fn host_sensor_line(raw: &RawCounts) -> String {
    let cfg = ConfigBuilder::new(AdcProfile::AVR_10BIT_5V)
        .build()
        .unwrap();
    let mut line = Vec::new();
    write_sensor_line(&cfg, raw, raw, &mut |b| line.push(b));
    String::from_utf8(line).unwrap().trim_end().to_string()
}

/// The counts of a `D` line.
fn counts(line: &str) -> RawCounts {
    let f: Vec<u16> = line
        .split_whitespace()
        .skip(1)
        .take(5)
        .map(|c| c.parse().unwrap())
        .collect();
    f.try_into().unwrap()
}

/// The reply to `line`, past the telemetry lines (`T …`) of a drive.
fn reply(a: &mut Avr, line: &str) -> Option<String> {
    a.send(format!("{line}\n").as_bytes());
    loop {
        let l = a.read_line(100)?;
        if !l.starts_with("T ") {
            return Some(l);
        }
    }
}

#[test]
fn the_serial_protocol_as_a_user_meets_it() {
    let mut a = Avr::boot();
    let overlong = format!("G {}", "1".repeat(40));
    for bad in [
        "X",
        "G 1",
        "G 1 2 3",
        "G 40000 0",
        "G 1x 2",
        "P 1 2",
        &overlong,
    ] {
        assert_eq!(reply(&mut a, bad).as_deref(), Some("ERR"), "{bad:?}");
    }
    // Nothing on the sensor pins yet: five faults.
    assert_eq!(reply(&mut a, "D").as_deref(), Some("D 0 0 0 0 0 ! ! ! ! !"));
    // Each sensor at its phantom level, nothing in range (0.28 V of 5 V:
    // simavr's ADC reference is 3.3 V, hence the scaling), but the middle
    // one at 1.0 V, an obstacle about 30 cm from its face.
    let scaled = |mv: u32| mv * 3_300 / 5_000;
    {
        let mut pins = a.avr.pins();
        pins.adc0().set_mv(scaled(280));
        pins.adc1().set_mv(scaled(280));
        pins.adc2().set_mv(scaled(1_000));
        pins.adc3().set_mv(scaled(280));
        pins.adc4().set_mv(scaled(280));
    }
    a.run_us(5_000);
    let d = reply(&mut a, "D").unwrap();
    assert_eq!(d, host_sensor_line(&counts(&d)), "as the host reads them");
    let f: Vec<&str> = d.split_whitespace().collect();
    assert_eq!((f[6], f[7], f[9], f[10]), ("-", "-", "-", "-"), "{d}");
    let mm: u16 = f[8].parse().unwrap_or_else(|_| panic!("a distance: {d}"));
    assert!((220..=320).contains(&mm), "{d}");
    {
        let mut pins = a.avr.pins();
        pins.adc2().set_mv(scaled(280));
    }
    a.run_us(5_000);
    assert_eq!(reply(&mut a, "P 100 200 0").as_deref(), Some("OK"));
    assert_eq!(reply(&mut a, "G 3000 200").as_deref(), Some("OK"));
    // The first step's telemetry: moving, straight on (heading 0), a step.
    let t = a.read_line(300).expect("telemetry");
    let f: Vec<&str> = t.split_whitespace().collect();
    assert_eq!((f[0], f[2], f[3], f[5]), ("T", "100", "200", "M"), "{t}");
    assert!(f[7].parse::<u32>().unwrap() > 0, "a step: {t}");
    // The rover drives: the PWM pins pulse.
    let pulses: u32 = (0..200).map(|_| wheels_for_1ms(&mut a).2).sum();
    assert!(pulses > 0, "the motors run while driving");
    assert_eq!(
        reply(&mut a, "P 0 0 0").as_deref(),
        Some("ERR"),
        "no pose while driving"
    );
    assert_eq!(reply(&mut a, "S").as_deref(), Some("OK"));
    let pulses: u32 = (0..100).map(|_| wheels_for_1ms(&mut a).2).sum();
    assert_eq!(pulses, 0, "the motors are off after S");
    let m = reply(&mut a, "M").unwrap();
    assert!(m.starts_with("M stack_peak="), "{m}");
    // Stopped, the pose may be set again; the firmware never reset.
    assert_eq!(reply(&mut a, "P 0 0 0").as_deref(), Some("OK"));
    assert_eq!(a.read_line(50), None, "no READY again: no reset");
}

/// A stop is never lost to a fragment on the line: after a pause the
/// fragment is dropped and `S` stops the rover; glued onto `S` without a
/// pause, the line is refused and stops the rover all the same. A space
/// before the `\r` is a space.
#[test]
fn a_stop_is_never_lost() {
    let mut a = Avr::boot();
    {
        let mut pins = a.avr.pins();
        {
            let mv = 280 * 3_300 / 5_000;
            pins.adc0().set_mv(mv);
            pins.adc1().set_mv(mv);
            pins.adc2().set_mv(mv);
            pins.adc3().set_mv(mv);
            pins.adc4().set_mv(mv);
        }
    }
    a.run_us(5_000);
    let driving = |a: &mut Avr| (0..200).map(|_| wheels_for_1ms(a).2).sum::<u32>() > 0;
    let start = |a: &mut Avr| {
        assert_eq!(reply(a, "G 3000 200 \r").as_deref(), Some("OK"));
        assert!(driving(a), "the motors run after G");
    };

    start(&mut a);
    a.send(b"G 10");
    a.run_us(1_200_000);
    assert!(driving(&mut a), "a fragment alone changes nothing");
    assert_eq!(reply(&mut a, "S").as_deref(), Some("OK"), "after a pause");
    assert!(!driving(&mut a), "stopped");

    start(&mut a);
    a.send(b"G 10");
    assert_eq!(reply(&mut a, "S").as_deref(), Some("ERR"), "glued on");
    assert!(!driving(&mut a), "stopped all the same");

    start(&mut a);
    a.send(b"\x00\xff#");
    assert_eq!(reply(&mut a, "").as_deref(), Some("ERR"), "noise");
    assert!(!driving(&mut a), "noise stops the rover");
}
