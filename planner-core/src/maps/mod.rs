//! Planners over a known map: [`liquid`] (the liquid-movement planner) and
//! [`route`] (the Dijkstra + potential-field route layer over a waypoint
//! graph, which drives the product planner leg by leg).

pub mod liquid;
pub mod route;
