//! Random circle worlds with the EAPF paper's parameters (environment 2:
//! 80 circles, radii 0.12–0.9 m, 17.15 m × 14.7 m), written as format 1.

use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use std::fmt::Write;

/// Parameters of a random circle world.
#[derive(Clone, Debug)]
pub struct RandomWorld {
    /// Scenario name.
    pub name: String,
    /// Width and height, m.
    pub size: [f64; 2],
    /// Number of circles.
    pub circles: usize,
    /// Radius range, m.
    pub radii: [f64; 2],
    /// Start and goal, m.
    pub start: [f64; 2],
    /// Goal, m.
    pub goal: [f64; 2],
    /// Robot radius, m.
    pub robot_radius: f64,
    /// Seed.
    pub seed: u64,
}

impl RandomWorld {
    /// The paper's environment 2 parameters with a given start and goal.
    pub fn paper_env2(name: &str, start: [f64; 2], goal: [f64; 2], seed: u64) -> Self {
        RandomWorld {
            name: name.to_string(),
            size: [17.15, 14.7],
            circles: 80,
            radii: [0.12, 0.9],
            start,
            goal,
            robot_radius: 0.10,
            seed,
        }
    }

    /// The scenario file text. Circles that would come within
    /// `robot_radius + 0.15` m of the start or goal are drawn again.
    pub fn to_toml(&self, description: &str) -> String {
        let mut rng = Pcg64::seed_from_u64(self.seed);
        let mut s = String::new();
        let _ = writeln!(s, "format = 1");
        let _ = writeln!(s, "name = \"{}\"", self.name);
        let _ = writeln!(s, "description = \"{description}\"");
        let _ = writeln!(s, "bounds = [0.0, 0.0, {}, {}]", self.size[0], self.size[1]);
        let _ = writeln!(s, "start = [{}, {}]", self.start[0], self.start[1]);
        let _ = writeln!(s, "goal = [{}, {}]", self.goal[0], self.goal[1]);
        let _ = writeln!(s, "robot_radius = {}", self.robot_radius);
        let _ = writeln!(
            s,
            "# generated: seed {}, {} circles, radii {}..{} m",
            self.seed, self.circles, self.radii[0], self.radii[1]
        );
        let keep = self.robot_radius + 0.15;
        let mut n = 0;
        while n < self.circles {
            let r = rng.gen_range(self.radii[0]..=self.radii[1]);
            let x = rng.gen_range(0.0..self.size[0]);
            let y = rng.gen_range(0.0..self.size[1]);
            let far = |p: [f64; 2]| (p[0] - x).hypot(p[1] - y) > r + keep;
            if !(far(self.start) && far(self.goal)) {
                continue;
            }
            let _ = writeln!(
                s,
                "\n[[circle]]\ncenter = [{x:.3}, {y:.3}]\nradius = {r:.3}"
            );
            n += 1;
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn generated_worlds_are_valid_and_seeded() {
        let w = RandomWorld::paper_env2("g", [6.0, 7.3], [12.7, 9.75], 3);
        let a = w.to_toml("test");
        assert_eq!(a, w.to_toml("test"));
        let sc = crate::scenario::Scenario::parse(&a, std::path::Path::new("g")).unwrap();
        assert_eq!(sc.circle.len(), 80);
        assert!(sc.circle.iter().all(|c| (0.12..=0.9).contains(&c.radius)));
    }
}
