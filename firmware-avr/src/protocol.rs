//! The serial text protocol: one command per line (`\n` ends it, `\r` is
//! ignored), fields separated by spaces, integers in decimal.
//!
//! | line | meaning | reply |
//! |---|---|---|
//! | `G <x_mm> <y_mm>` | new goal; forget the map; start driving | `OK` |
//! | `P <x_mm> <y_mm> <heading_deg>` | set the odometry pose (when stopped) | `OK` |
//! | `S` | stop now (motors off) | `OK` |
//! | `M` | report memory | `M stack_peak=<bytes>` |
//! | `R <x_mm> <y_mm>` | replay mode toward goal (x, y), see below | `OK` |
//!
//! Anything else gets `ERR`. Telemetry, one line per planner step:
//! `T <ms> <x_mm> <y_mm> <heading> <status> <cmd_heading> <step_mm> <cycles>`
//! with headings in binary angle units (65,536 = 360°) and status one of
//! `M` (moving), `A` (arrived), `U` (unreachable), `F` (sensor fault).
//!
//! Replay mode (for bit-exactness and cycle counts from a recorded trace):
//! the host sends frames of 17 bytes, `0xA5`, then x, y (i16), heading (u16),
//! five raw counts (u16), all little-endian; the firmware answers each with
//! 10 bytes: `0x5A`, heading (u16), step (u16), status (u8: 0 moving,
//! 1 arrived, 2 unreachable, 3 fault), step cycles (u32). A frame starting
//! with any other byte ends replay mode (`OK`). Motors, ADC sampling and the
//! control tick are off during replay so that nothing interrupts the step.

/// One parsed command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Request {
    Goal(i16, i16),
    Pose(i16, i16, i16),
    Stop,
    Memory,
    Replay(i16, i16),
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
        .split(|&b| b == b' ')
        .filter(|s| !s.is_empty())
        .map(|s| s.strip_suffix(b"\r").unwrap_or(s));
    let cmd = f.next()?;
    let mut num = || f.next().and_then(parse_i16);
    let req = match cmd {
        b"G" => Request::Goal(num()?, num()?),
        b"P" => Request::Pose(num()?, num()?, num()?),
        b"S" => Request::Stop,
        b"M" => Request::Memory,
        b"R" => Request::Replay(num()?, num()?),
        _ => return None,
    };
    match f.next() {
        None => Some(req),
        Some(_) => None, // trailing fields
    }
}
