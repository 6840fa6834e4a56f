//! The scenario parser on any text: a scenario or an error, never a panic;
//! a scenario it accepts builds a world.

#![no_main]

use libfuzzer_sys::fuzz_target;
use sim_host::scenario::Scenario;
use std::path::Path;

fuzz_target!(|text: &str| {
    if let Ok(sc) = Scenario::parse(text, Path::new("fuzz.toml")) {
        let _ = sc.world();
    }
});
