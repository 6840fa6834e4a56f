//! Cross-crate tests: the simulator and the core together, and (as the
//! firmware issues land) the emulated firmware against the host core.
