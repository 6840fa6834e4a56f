//! The serial line reader on any bytes with any pauses between them: no
//! panic, one answer per `\n` and none otherwise.

#![no_main]

use libfuzzer_sys::fuzz_target;
use planner_core::rover::protocol::LineReader;

fuzz_target!(|bytes: Vec<(u8, u16)>| {
    let mut reader = LineReader::new();
    let mut now: u32 = 0;
    for &(b, pause) in &bytes {
        now = now.wrapping_add(pause as u32);
        let answered = reader.feed(b, now).is_some();
        assert_eq!(answered, b == b'\n', "byte {b}");
    }
});
