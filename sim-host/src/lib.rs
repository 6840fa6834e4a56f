//! # sim-host
//!
//! Worlds, virtual Sharp IR sensors and a simulated rover that run the
//! identical planner-core: a front end, like the firmware crates, with no
//! planner logic of its own. Modules: [`scenario`] (format 1 files),
//! [`geom`] and [`world`] (exact ray casting and swept collision),
//! [`sensor`] (the IR curve, noise, 38 ms updates), [`sim`] (rover, guard,
//! odometry, outcomes), [`reference`](mod@reference) (shortest paths), [`planners`] (unit
//! conversion to the core), [`routemap`] (the `route` planner's waypoint graph), [`bench`](mod@bench), [`svg`], [`generate`].
//!
//! Crates: `serde` + `toml` for scenario files (typed, unknown keys refused),
//! `clap` for the CLI, `rayon` and `indicatif` for parallel benches with a
//! progress bar, `rand_pcg` for seeded, portable random numbers.

pub mod bench;
pub mod console;
pub mod fault;
pub mod generate;
pub mod geom;
pub mod planners;
pub mod reference;
pub mod results;
pub mod routemap;
pub mod scenario;
pub mod sensor;
pub mod sim;
pub mod svg;
pub mod units;
pub mod world;
