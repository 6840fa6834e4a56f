//! The serial text protocol both firmwares speak: one command per line (`\n` ends it), fields
//! separated by spaces (`\r` and tabs count as spaces), integers in decimal.
//!
//! A stop is never lost to noise on the line ([`LineReader`]):
//! - a pause of more than [`STALE_MS`] inside a line drops what came before
//!   it, so a fragment (line noise, a half-sent command) is not glued onto
//!   the next command;
//! - a line that is not a command stops the rover, as `S` does, and is
//!   answered `ERR`: it may have been a stop.
//!
//! A console should send each line whole (ravedude's and terminals in line
//! mode do).
//!
//! | line | meaning | reply |
//! |---|---|---|
//! | `G <x_mm> <y_mm>` | new goal; forget the map; start driving | `OK` |
//! | `P <x_mm> <y_mm> <heading_deg>` | set the odometry pose (when stopped) | `OK` |
//! | `S` | stop now (motors off) | `OK` |
//! | `M` | report memory (the AVR; the STM32 answers `ERR`) | `M stack_peak=<bytes>` |
//! | `R <x_mm> <y_mm>` | replay mode toward goal (x, y), see below (the AVR's `replay` binary, which the emulator tests run; the STM32's emulated build replays a trace built in) | `OK` |
//! | `D` | the sensors now: their raw counts, and what the planner reads from them | `D <c0> … <c4> <r0> … <r4>` |
//! | `K <sensor> <gain_q8> <offset>` | sensor `sensor` (0–4)'s correction, fitted by the console from its counts with a card at 100, 200, … 800 mm (`crate::rover::calibration`): kept, used and stored on the board | `OK`; `ERR` if refused (a correction no working sensor needs, or the rover driving: a store blocks the loop), or kept but not stored (a board without storage) |
//!
//! `D` is for bringing a rover up: the five sensors in the pin map's order
//! (−40° to +40°), first the ADC counts, then each count as the planner's
//! calibration reads it: a distance from the sensor face in mm, `-` for
//! nothing in range, `<` for nearer than the calibration trusts (an
//! obstacle at the face, for the planner), `!` for a count no working
//! sensor gives (a fault: an unplugged sensor reads `0 … !`). Hold a
//! target in front of each sensor in turn to check the wiring and the
//! calibration; the line is the same on both firmwares ([`sensor_readings`]).
//!
//! A line that is not a command gets `ERR` and stops the rover; a command
//! refused in the state the rover is in (`P` while driving) gets `ERR`
//! alone. Telemetry, one line per planner step (the STM32 also logs each
//! step over defmt):
//! `T <ms> <x_mm> <y_mm> <heading> <status> <cmd_heading> <step_mm> <cycles> <cal> <c0> … <c4>`
//! with headings in binary angle units (65,536 = 360°) and status one of
//! `M` (moving), `A` (arrived), `U` (unreachable), `F` (sensor fault);
//! `cycles` is the step as it ran, the interrupts that came during it
//! included; `cal` the sensors' calibration: `C` each sensor's own, `-`
//! the datasheet's (none stored), `!` the datasheet's because the stored
//! one is corrupt; `c0 … c4` the counts the step read. During an advance,
//! each guard look that changed what the planner keeps (its flank points)
//! is logged as `g <remaining_mm> <c0> … <c4>`: with the `T` lines, enough
//! to replay the run through the host's core, bit for bit (the console's
//! `replay`).
//!
//! Replay mode (for bit-exactness and cycle counts from a recorded trace):
//! the host sends frames of `0xA5`, the number `n` (u8, at most 8) of the
//! guard's samples during the advance before the step, `n` samples of the
//! step still to go (u16) and five raw counts (u16), then the step's x, y
//! (i16), heading (u16) and five raw counts (u16), all little-endian; the
//! firmware runs the guard on each sample, then the step, and answers with
//! 15 bytes: `0x5A`, heading (u16), step (u16), status (u8: 0 moving,
//! 1 arrived, 2 unreachable, 3 fault), step cycles (u32), the guard's
//! verdicts (u8, bit `i` set if sample `i` said stop), the cycles of its
//! costliest look (u32). A frame starting
//! with any other byte ends replay mode (`OK`). Motors, ADC sampling and the
//! control tick are off during replay, and the firmware runs each guard
//! look and step with interrupts off, so that their cycles are theirs alone.

use crate::eapf::config::Config;
use crate::eapf::sensors::{RawCounts, Reading};
use crate::rover::calibration::Correction;

/// One parsed command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Request {
    /// `G x y`: new goal, mm.
    Goal(i16, i16),
    /// `P x y deg`: set the pose, mm and whole degrees.
    Pose(i16, i16, i16),
    /// `S`: stop.
    Stop,
    /// `M`: memory report.
    Memory,
    /// `R x y`: replay mode toward (x, y) mm.
    Replay(i16, i16),
    /// `D`: the sensors' counts and readings now.
    Sensors,
    /// `K sensor gain_q8 offset`: sensor `sensor`'s correction, to keep
    /// and store ([`crate::rover::calibration`]).
    Calibrate(u8, Correction),
}

fn parse_i16(field: &[u8]) -> Option<i16> {
    let (neg, digits) = match field.split_first() {
        Some((b'-', rest)) => (true, rest),
        _ => (false, field),
    };
    if digits.is_empty() || digits.len() > 5 {
        return None;
    }
    let mut v: i32 = 0;
    for &d in digits {
        if !d.is_ascii_digit() {
            return None;
        }
        v = v * 10 + (d - b'0') as i32;
    }
    let v = if neg { -v } else { v };
    i16::try_from(v).ok()
}

/// Parse one line (without its `\n`).
pub fn parse(line: &[u8]) -> Option<Request> {
    let mut f = line
        .split(|&b| matches!(b, b' ' | b'\r' | b'\t'))
        .filter(|s| !s.is_empty());
    let cmd = f.next()?;
    let mut num = || f.next().and_then(parse_i16);
    let req = match cmd {
        b"G" => Request::Goal(num()?, num()?),
        b"P" => Request::Pose(num()?, num()?, num()?),
        b"S" => Request::Stop,
        b"M" => Request::Memory,
        b"R" => Request::Replay(num()?, num()?),
        b"D" => Request::Sensors,
        b"K" => Request::Calibrate(
            u8::try_from(num()?).ok()?,
            Correction {
                gain_q8: u16::try_from(num()?).ok()?,
                offset: num()?,
            },
        ),
        _ => return None,
    };
    match f.next() {
        None => Some(req),
        Some(_) => None, // trailing fields
    }
}

/// Longest command line, bytes.
pub const LINE_CAPACITY: usize = 32;

/// What the reply to `D` says of one sensor's count, after the counts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SensorField {
    /// A distance from the sensor face, mm.
    Number(u16),
    /// A reading that is no distance: `-`, `<` or `!` (see the table above).
    Sign(u8),
}

/// What the calibration reads from each of the counts `raw`, as the reply
/// to `D` says it (see the table above).
pub fn sensor_readings<'a>(
    cfg: &'a Config,
    raw: &'a RawCounts,
) -> impl Iterator<Item = SensorField> + 'a {
    raw.iter().map(|&c| match cfg.calibration.reading(c) {
        Reading::Range(mm) => SensorField::Number(mm),
        Reading::Clear => SensorField::Sign(b'-'),
        Reading::TooClose => SensorField::Sign(b'<'),
        Reading::Implausible => SensorField::Sign(b'!'),
    })
}

/// The whole reply to `D`, `\n` ended, a byte at a time to `out`: the
/// counts `raw`, then what the planner reads from `read` (the counts
/// through the sensors' own calibration, [`crate::rover::calibration`];
/// `raw` itself without one).
pub fn write_sensor_line(cfg: &Config, raw: &RawCounts, read: &RawCounts, out: &mut dyn FnMut(u8)) {
    out(b'D');
    write_counts(out, raw);
    for f in sensor_readings(cfg, read) {
        out(b' ');
        match f {
            SensorField::Number(n) => write_number(n.into(), out),
            SensorField::Sign(c) => out(c),
        }
    }
    out(b'\n');
}

/// `v` in decimal, a byte at a time to `out`: the firmwares' one integer
/// formatter (`core::fmt`'s costs kilobytes of flash). The largest power of
/// ten not above `v` first, then a digit per power: no buffer, no index, no
/// recursion (the stack bound needs none). `dyn`, so that an image holds one
/// copy whatever it writes to.
#[inline(never)]
pub fn write_number(v: u32, out: &mut dyn FnMut(u8)) {
    let mut p: u32 = 1;
    while p <= v / 10 {
        p *= 10;
    }
    let mut rest = v;
    loop {
        // `p` is never 0 (a power of ten at most `v`); `checked_` keeps
        // the image free of a panic path the compiler cannot rule out.
        out(b'0' + rest.checked_div(p).unwrap_or(0) as u8);
        rest = rest.checked_rem(p).unwrap_or(0);
        if p == 1 {
            break;
        }
        p /= 10;
    }
}

/// A space, then `v` in decimal: one field of a line.
pub fn write_field(out: &mut dyn FnMut(u8), v: u32) {
    out(b' ');
    write_number(v, out);
}

/// Five counts, each a field ([`write_field`]).
#[inline(never)]
pub fn write_counts(out: &mut dyn FnMut(u8), counts: &RawCounts) {
    for &c in counts {
        write_field(out, c.into());
    }
}

/// `v` in decimal, `-` first if negative.
pub fn write_signed(v: i16, out: &mut dyn FnMut(u8)) {
    if v < 0 {
        out(b'-');
    }
    write_number(v.unsigned_abs().into(), out);
}

/// A pause inside a line longer than this, ms, drops the bytes before it.
pub const STALE_MS: u32 = 1_000;

/// Gathers received bytes into lines and parses each.
#[derive(Clone, Debug, Default)]
pub struct LineReader {
    line: heapless::Vec<u8, LINE_CAPACITY>,
    overlong: bool,
    /// When the last byte came, ms.
    last_ms: u32,
}

impl LineReader {
    /// An empty reader.
    #[cfg_attr(target_arch = "avr", inline(never))]
    pub fn new() -> Self {
        LineReader::default()
    }

    /// Take one byte, received at `now_ms` (a millisecond clock that may
    /// wrap). At the end of a line (`\n`): `Some` of what it says,
    /// `Some(None)` for a line that is not a command (too long included),
    /// on which the firmware stops. Bytes before a pause of more than
    /// [`STALE_MS`] are dropped first.
    pub fn feed(&mut self, b: u8, now_ms: u32) -> Option<Option<Request>> {
        if now_ms.wrapping_sub(self.last_ms) > STALE_MS {
            self.line.clear();
            self.overlong = false;
        }
        self.last_ms = now_ms;
        if b != b'\n' {
            if self.line.push(b).is_err() {
                self.overlong = true;
            }
            return None;
        }
        let req = if self.overlong {
            None
        } else {
            parse(&self.line)
        };
        self.line.clear();
        self.overlong = false;
        Some(req)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_parse_to_requests() {
        assert_eq!(parse(b"G 1200 -350"), Some(Request::Goal(1200, -350)));
        assert_eq!(parse(b"P 0 0 90\r"), Some(Request::Pose(0, 0, 90)));
        assert_eq!(parse(b"G 1 2 \r"), Some(Request::Goal(1, 2)));
        assert_eq!(parse(b"\tS\t\r"), Some(Request::Stop));
        assert_eq!(parse(b"S"), Some(Request::Stop));
        assert_eq!(parse(b"M"), Some(Request::Memory));
        assert_eq!(parse(b"R  10   20"), Some(Request::Replay(10, 20)));
        assert_eq!(parse(b"D"), Some(Request::Sensors));
    }

    /// `D`'s line: the counts in order, then each reading's token, from
    /// the calibration of each sensor.
    #[test]
    fn the_sensor_line_says_counts_then_readings() {
        use crate::eapf::config::ConfigBuilder;
        use crate::eapf::sensors::AdcProfile;
        let adc = AdcProfile::AVR_10BIT_5V;
        let cfg = ConfigBuilder::new(adc).build().unwrap();
        let cal = cfg.calibration();
        let (far, near) = cal.window();
        let mid = (far + near) / 2;
        let Reading::Range(mm) = cal.reading(mid) else {
            panic!("{mid} is in the window ({far}, {near})")
        };
        assert!((100..=800).contains(&mm), "{mm} mm at count {mid}");
        let raw = [0, far - 1, mid, near + 1, adc.full_scale() + 1];
        let want = format!(
            "D 0 {} {mid} {} {} ! - {mm} < !\n",
            far - 1,
            near + 1,
            adc.full_scale() + 1
        );
        assert_eq!(line(&cfg, &raw), want);
        assert_eq!(
            line(&cfg, &[u16::MAX; 5]),
            "D 65535 65535 65535 65535 65535 ! ! ! ! !\n"
        );
    }

    #[test]
    fn numbers_are_written_in_decimal() {
        for v in [
            0u32,
            1,
            9,
            10,
            99,
            100,
            101,
            1_023,
            9_999,
            10_000,
            60_001,
            u16::MAX.into(),
            1_000_000_007,
            u32::MAX,
        ] {
            let mut got = std::vec::Vec::new();
            write_number(v, &mut |b| got.push(b));
            assert_eq!(got, v.to_string().into_bytes());
        }
        for v in [i16::MIN, -32_767, -1_000, -1, 0, 7, i16::MAX] {
            let mut got = std::vec::Vec::new();
            write_signed(v, &mut |b| got.push(b));
            assert_eq!(got, v.to_string().into_bytes());
        }
    }

    /// The line as the STM32 writes it.
    fn line(cfg: &Config, raw: &RawCounts) -> std::string::String {
        let mut got = std::vec::Vec::new();
        write_sensor_line(cfg, raw, raw, &mut |b| got.push(b));
        std::string::String::from_utf8(got).unwrap()
    }

    #[test]
    fn the_reader_parses_line_by_line_and_refuses_overlong_ones() {
        let mut r = LineReader::new();
        let mut got = heapless::Vec::<Option<Request>, 4>::new();
        let long = [b'7'; 40];
        for &b in b"G 10 20\nS\n"
            .iter()
            .chain(long.iter())
            .chain(b"\nM\n".iter())
        {
            if let Some(req) = r.feed(b, 0) {
                got.push(req).unwrap();
            }
        }
        assert_eq!(
            got.as_slice(),
            &[
                Some(Request::Goal(10, 20)),
                Some(Request::Stop),
                None,
                Some(Request::Memory)
            ]
        );
    }

    /// A fragment then, after a pause, a stop: the fragment is dropped and
    /// the stop stands. Without the pause the glued line is refused (and
    /// the firmware stops on it all the same).
    #[test]
    fn a_stale_fragment_is_not_glued_onto_the_next_line() {
        let feed = |r: &mut LineReader, bytes: &[u8], ms: u32| {
            bytes.iter().filter_map(|&b| r.feed(b, ms)).last()
        };
        let mut r = LineReader::new();
        assert_eq!(feed(&mut r, b"G 10", 5), None);
        assert_eq!(
            feed(&mut r, b"S\n", 5 + STALE_MS + 1),
            Some(Some(Request::Stop))
        );
        assert_eq!(feed(&mut r, b"G 10", 4_000), None);
        assert_eq!(feed(&mut r, b"S\n", 4_000 + STALE_MS), Some(None));
        // Across the clock's wrap.
        assert_eq!(feed(&mut r, b"xx", u32::MAX - 10), None);
        assert_eq!(feed(&mut r, b"S\n", STALE_MS), Some(Some(Request::Stop)));
        // An overlong fragment is dropped too.
        assert_eq!(feed(&mut r, &[b'7'; 40], 9_000), None);
        assert_eq!(
            feed(&mut r, b"M\n", 9_000 + STALE_MS + 1),
            Some(Some(Request::Memory))
        );
    }

    #[test]
    fn bad_lines_are_refused() {
        for bad in [
            &b""[..],
            b"G 1",
            b"G 1 2 3",
            b"G 40000 0",
            b"G 1x 2",
            b"X",
            b"G - 2",
            b"P 1 2",
            b"D 1",
        ] {
            assert_eq!(parse(bad), None, "{:?}", core::str::from_utf8(bad));
        }
    }
}
