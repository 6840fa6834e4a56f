//! The planners the simulator can drive. All planner logic lives in
//! planner-core; this module only converts units (metres and radians to the
//! core's millimetres and binary angles) and back.

use crate::geom::V2;
use crate::routemap::{self, ROUTE_EDGES, ROUTE_NODES};
use crate::scenario::Scenario;
use crate::units::{to_angle, to_mm, to_point, to_rad, to_v2};
use planner_core::maps::route::{RouteConfig, RoutePlanner};
use planner_core::peers::apf::{ApfConfig, ApfPlanner};
use planner_core::peers::freespace::FreeSpace;
use planner_core::peers::{Bug2, TangentBug, Vfh};
use planner_core::{
    AdcProfile, ConfigBuilder, EscapeConfig, Navigator, Planner, Pose, RawCounts, Status,
};

/// Planner names for `--planner`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum PlannerKind {
    /// The product: EAPF plus virtual-obstacle escape.
    Eapf,
    /// EAPF as the paper describes it, without the escape.
    EapfPlain,
    /// Classical APF (Khatib), the baseline.
    Apf,
    /// The liquid-movement planner over the known map, offline (restart
    /// from the start after each virtual obstacle).
    Liquid,
    /// The same, online (go on from the local minimum).
    LiquidOnline,
    /// The route layer over the known map (Dijkstra's candidates, the
    /// safest within 25 % of the shortest), driven by the `eapf` planner
    /// with its sensors leg by leg.
    Route,
    /// Bug2 (Lumelsky & Stepanov 1987), a peer: the m-line, boundary
    /// following on a fixed side.
    Bug2,
    /// TangentBug (Kamon, Rivlin & Rimon 1998), a peer, on five beams with
    /// looks by turning on the spot.
    #[value(name = "tangentbug")]
    #[serde(rename = "tangentbug")]
    TangentBug,
    /// VFH+ (Ulrich & Borenstein 1998), a peer: certainty grid, polar
    /// histogram, valleys.
    Vfh,
    /// Planning with the free-space assumption over a grid the beams fill
    /// (Koenig, Tovey & Smirnov 2003).
    #[value(name = "freespace")]
    #[serde(rename = "freespace")]
    FreeSpace,
}

impl PlannerKind {
    /// Does it plan over the scenario's map instead of sensing?
    pub fn uses_map(self) -> bool {
        matches!(self, PlannerKind::Liquid | PlannerKind::LiquidOnline)
    }

    /// The `--planner` name.
    pub fn name(self) -> &'static str {
        match self {
            PlannerKind::Eapf => "eapf",
            PlannerKind::EapfPlain => "eapf-plain",
            PlannerKind::Apf => "apf",
            PlannerKind::Liquid => "liquid",
            PlannerKind::LiquidOnline => "liquid-online",
            PlannerKind::Route => "route",
            PlannerKind::Bug2 => "bug2",
            PlannerKind::TangentBug => "tangentbug",
            PlannerKind::Vfh => "vfh",
            PlannerKind::FreeSpace => "freespace",
        }
    }
}

/// A command in simulator units.
#[derive(Clone, Copy, Debug)]
pub struct SimCommand {
    /// World heading, rad.
    pub heading: f64,
    /// Step, m.
    pub step_m: f64,
    /// The core's status.
    pub status: Status,
}

/// What a run leaves to draw: remembered points, the midpoint of the
/// active ones, virtual obstacles (centre, radius), virtual obstacles dropped.
pub type Diagnostics = (Vec<V2>, Option<V2>, Vec<(V2, f64)>, usize);

/// The escape each sensing planner runs with: on (the defaults, the
/// retreat limit and boundary following included) for `eapf`, on without
/// boundary following for `route`, off otherwise.
fn escape_config(kind: PlannerKind) -> EscapeConfig {
    EscapeConfig {
        enabled: matches!(kind, PlannerKind::Eapf | PlannerKind::Route),
        // With the map, a leg given up is blocked and the route planned
        // again: a better last resort than following a boundary.
        follow: kind == PlannerKind::Eapf,
        ..EscapeConfig::default()
    }
}

/// The core planner behind a [`SimPlanner`]: the product planner and the
/// route layer (which drives one) are kept as themselves for their
/// pictures; every other through the trait alone.
enum Core {
    Eapf(Box<Planner>),
    Route(Box<RoutePlanner<ROUTE_NODES, ROUTE_EDGES>>),
    Other(Box<dyn Navigator + Send>),
}

/// A planner under simulation.
pub struct SimPlanner {
    core: Core,
}

impl SimPlanner {
    /// The planner `kind` for scenario `sc`, sensors on an `adc`, on the
    /// rim or `set_back` behind it, `noisy` or not
    /// ([`crate::sensor::SensorMode::noisy`]:
    /// the watch for stuck sensors is off without noise).
    pub fn new(
        kind: PlannerKind,
        sc: &Scenario,
        adc: AdcProfile,
        set_back: bool,
        noisy: bool,
    ) -> SimPlanner {
        let escape = escape_config(kind);
        let radius_mm = (sc.robot_radius * 1000.0).round().clamp(20.0, 1000.0) as u16;
        let builder = ConfigBuilder::new(adc);
        let cfg = match noisy {
            true => builder,
            false => builder.frozen_after_views(0),
        }
        .robot_radius_mm(radius_mm)
        .escape(escape)
        .sensors_set_back(set_back)
        .build()
        .expect("the default configuration with a validated scenario radius is valid");
        let goal = to_point(V2::new(sc.goal[0], sc.goal[1]));
        let core = match kind {
            PlannerKind::Apf => {
                Core::Other(Box::new(ApfPlanner::new(cfg, ApfConfig::default(), goal)))
            }
            PlannerKind::Bug2 => Core::Other(Box::new(Bug2::new(cfg, goal))),
            PlannerKind::TangentBug => Core::Other(Box::new(TangentBug::new(cfg, goal))),
            PlannerKind::Vfh => Core::Other(Box::new(Vfh::new(cfg, goal))),
            PlannerKind::FreeSpace => {
                let start = to_point(V2::new(sc.start[0], sc.start[1]));
                Core::Other(Box::new(FreeSpace::<256>::new(cfg, start, goal)))
            }
            PlannerKind::Route => {
                let keep_m = sc.robot_radius + routemap::PREFERRED_MARGIN_M;
                let route = RouteConfig {
                    preferred_clearance_mm: to_mm(keep_m),
                    ..RouteConfig::default()
                };
                let map = routemap::build(sc);
                Core::Route(Box::new(RoutePlanner::new(cfg, map, route, goal)))
            }
            _ => Core::Eapf(Box::new(Planner::new(cfg, goal))),
        };
        SimPlanner { core }
    }

    fn navigator(&mut self) -> &mut dyn Navigator {
        match &mut self.core {
            Core::Eapf(p) => p.as_mut(),
            Core::Route(p) => p.as_mut(),
            Core::Other(p) => p.as_mut(),
        }
    }

    fn config(&self) -> &planner_core::Config {
        match &self.core {
            Core::Eapf(p) => p.config(),
            Core::Route(p) => Navigator::config(p.as_ref()),
            Core::Other(p) => p.config(),
        }
    }

    /// Sensor angles, rad.
    pub fn sensor_angles_rad(&self) -> [f64; 5] {
        self.config().sensor_angles().map(to_rad)
    }

    /// How near the goal counts as there, m.
    pub fn goal_tolerance_m(&self) -> f64 {
        self.config().goal_tolerance_mm() as f64 / 1000.0
    }

    /// Sensor face offset from the centre, m.
    pub fn sensor_offset_m(&self) -> f64 {
        self.config().sensor_offset_mm() as f64 / 1000.0
    }

    /// One cycle with odometry pose (`p`, `heading`) and raw counts.
    pub fn step(&mut self, p: V2, heading: f64, raw: &RawCounts) -> SimCommand {
        let pose = Pose {
            position: to_point(p),
            heading: to_angle(heading),
        };
        let out = self.navigator().step_raw(pose, raw);
        SimCommand {
            heading: to_rad(out.command.heading),
            step_m: out.command.step_mm as f64 / 1000.0,
            status: out.status,
        }
    }

    /// The guard: may the advance go on for `remaining_m`?
    pub fn guard(&mut self, raw: &RawCounts, remaining_m: f64) -> bool {
        let mm = to_mm(remaining_m);
        self.navigator().guard_raw(raw, mm) == planner_core::Guard::Continue
    }

    /// The follower's state for `SIM_DEBUG` (planner `eapf`): off, seek or
    /// follow, where it met the last boundary, the filtered readings (mm;
    /// `-` nothing in range) and how many flank points the guard keeps.
    pub fn follow_state(&self) -> Option<String> {
        self.eapf().map(|p| {
            let f = p.follow();
            let mode = match (f.active(), f.following()) {
                (false, _) => "off",
                (true, false) => "seek",
                (true, true) => "follow",
            };
            let readings: Vec<String> = p
                .last_readings()
                .iter()
                .map(|r| r.obstacle_mm().map_or("-".into(), |d| d.to_string()))
                .collect();
            format!(
                "{mode} hit {:?} readings [{}] flank {}",
                f.hit().map(to_v2),
                readings.join(", "),
                p.flank().points().len()
            )
        })
    }

    /// Collision points of the last cycle, m.
    pub fn last_collision_points(&self) -> Vec<V2> {
        match self.eapf() {
            Some(p) => p
                .last_collision_points()
                .iter()
                .map(|&q| to_v2(q))
                .collect(),
            None => Vec::new(),
        }
    }

    /// The route over the known map (planner `route`), waypoints then the
    /// goal, m; empty for the others.
    pub fn route(&self) -> Vec<V2> {
        match &self.core {
            Core::Route(p) => p.route().map(to_v2).collect(),
            _ => Vec::new(),
        }
    }

    /// The EAPF planner, if this one is or drives one.
    fn eapf(&self) -> Option<&Planner> {
        match &self.core {
            Core::Eapf(p) => Some(p),
            Core::Route(p) => Some(p.planner()),
            Core::Other(_) => None,
        }
    }

    /// (remembered points, midpoint of the active ones with the robot at
    /// `robot`, virtual obstacles, virtual obstacles dropped in all).
    pub fn diagnostics(&self, robot: V2) -> Diagnostics {
        match self.eapf() {
            Some(core) => eapf_diagnostics(core, robot),
            None => (Vec::new(), None, Vec::new(), 0),
        }
    }
}

/// [`SimPlanner::diagnostics`] of the product planner `core`.
pub fn eapf_diagnostics(core: &Planner, robot: V2) -> Diagnostics {
    let rem = core.memory().iter().map(|r| to_v2(r.point)).collect();
    let mid = core
        .memory()
        .midpoint(to_point(robot), core.goal())
        .map(to_v2);
    let vr = core.config().escape().radius_mm as f64 / 1000.0;
    let vos = core
        .escape()
        .obstacles()
        .map(|v| (to_v2(v.centre), vr))
        .collect();
    (rem, mid, vos, core.escape().dropped() as usize)
}

#[cfg(test)]
mod tests {
    use super::*;
    use planner_core::eapf::escape;

    #[test]
    fn each_sensing_planner_gets_its_escape() {
        let eapf = escape_config(PlannerKind::Eapf);
        assert!(eapf.enabled && eapf.is_valid());
        assert_eq!(eapf, EscapeConfig::default());
        assert_eq!(
            (eapf.retreat_mm, eapf.retreat_per_drop_mm),
            (escape::RETREAT_MM, escape::RETREAT_PER_DROP_MM)
        );
        // The route layer's last resort is its own (block the leg, plan
        // again), not boundary following.
        let route = escape_config(PlannerKind::Route);
        assert_eq!(
            route,
            EscapeConfig {
                follow: false,
                ..eapf
            }
        );
        assert!(!escape_config(PlannerKind::EapfPlain).enabled);
        assert!(!escape_config(PlannerKind::Apf).enabled);
    }

    /// `SimPlanner::new` expects the configuration to build: it must for
    /// every radius a scenario may give (`(0, 1)` m, clamped to the core's
    /// 20 ..= 1,000 mm), on both ADCs, for each sensing planner.
    #[test]
    fn every_scenario_radius_builds_a_planner() {
        let mut sc = crate::scenario::Scenario::parse(
            "format = 1\nname = \"r\"\nbounds = [0.0, 0.0, 6.0, 5.0]\nstart = [3.0, 2.5]\ngoal = [4.0, 2.5]\n",
            std::path::Path::new("r.toml"),
        )
        .unwrap();
        for mm in 1..1_000 {
            sc.robot_radius = mm as f64 / 1000.0;
            for adc in [AdcProfile::AVR_10BIT_5V, AdcProfile::STM32_12BIT_3V3] {
                for kind in [
                    PlannerKind::Eapf,
                    PlannerKind::EapfPlain,
                    PlannerKind::Apf,
                    PlannerKind::Bug2,
                ] {
                    for set_back in [false, true] {
                        let p = SimPlanner::new(kind, &sc, adc, set_back, true);
                        let want = mm.clamp(20, 1_000) as u16;
                        assert_eq!(p.config().robot_radius_mm(), want, "{mm} mm");
                    }
                }
            }
        }
    }
}
