//! Virtual Sharp GP2Y0A21YK0F-like IR sensors: true distance → output
//! voltage → ADC counts, as the core sees them on the real rover.
//!
//! The voltage curve interpolates the datasheet points (`GP2Y0A21_MV_MM`,
//! docs/algorithms.md §5) linearly in 1/distance (the sensor's output is close to linear in
//! 1/distance), folds back below 10 cm (peak 3.1 V near 6.5 cm, then falling,
//! so a very near object reads as farther), continues the 70–80 cm slope
//! beyond 80 cm and floors at a 0.28 V phantom level when nothing is in range.
//! Realistic mode adds a per-unit gain spread, seeded Gaussian voltage noise
//! and a new value only every 28.7–47.9 ms, held in between. Perfect mode
//! has none of that and no fold-back: for algorithm studies.

use crate::geom::V2;
use crate::world::World;
use planner_core::eapf::sensors::GP2Y0A21_MV_MM;
use planner_core::{AdcProfile, RawCounts, SENSOR_COUNT};
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, Normal};
use rand_pcg::Pcg64;

/// Phantom output with nothing in range, volts.
pub const PHANTOM_V: f64 = 0.28;

/// How the sensors behave.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SensorMode {
    /// Datasheet curve with fold-back, unit spread, noise, 38 ms updates.
    Realistic {
        /// Voltage noise, standard deviation in volts.
        noise_v: f64,
        /// Unit-to-unit gain spread: each unit's gain is uniform in 1 ± this.
        spread: f64,
    },
    /// Exact, instant, no fold-back.
    Perfect,
}

impl SensorMode {
    /// Whether a reading carries noise: a noise-free sensor's count is the
    /// same whenever its distance is, which the planner's watch for stuck
    /// sensors must not take for a fault.
    pub fn noisy(&self) -> bool {
        matches!(self, SensorMode::Realistic { noise_v, .. } if *noise_v > 0.0)
    }

    /// The default realistic model: 10 mV noise, ±5 % unit spread.
    pub const REALISTIC: SensorMode = SensorMode::Realistic {
        noise_v: 0.010,
        spread: 0.05,
    };
}

/// Output voltage for an object `d` metres from the sensor face (None:
/// nothing within reach).
pub fn voltage(d: Option<f64>, fold_back: bool) -> f64 {
    let Some(d) = d else { return PHANTOM_V };
    let pts: Vec<(f64, f64)> = GP2Y0A21_MV_MM
        .iter()
        .map(|&(mv, mm)| (mm as f64 / 1000.0, mv as f64 / 1000.0))
        .collect();
    let (d_near, v_near) = pts[0];
    if d < d_near {
        if !fold_back {
            // Perfect mode: keep rising as 1/d.
            return v_near * d_near / d.max(1e-3);
        }
        // Fold-back: 2.6 V at 10 cm, peak 3.1 V at 6.5 cm, 1.0 V at contact.
        let fold = [(0.0, 1.0), (0.03, 2.2), (0.065, 3.1), (0.10, 2.6)];
        for w in fold.windows(2) {
            if d <= w[1].0 {
                let f = (d - w[0].0) / (w[1].0 - w[0].0);
                return w[0].1 + f * (w[1].1 - w[0].1);
            }
        }
    }
    // Linear in 1/d between datasheet points; the last segment extends.
    let k = pts
        .windows(2)
        .position(|w| d <= w[1].0)
        .unwrap_or(pts.len() - 2);
    let (d0, v0) = pts[k];
    let (d1, v1) = pts[k + 1];
    let f = (1.0 / d - 1.0 / d0) / (1.0 / d1 - 1.0 / d0);
    (v0 + f * (v1 - v0)).max(PHANTOM_V)
}

/// Volts to counts on an ADC (rounded, clamped to full scale).
pub fn counts(adc: AdcProfile, v: f64) -> u16 {
    let fs = adc.full_scale() as f64;
    (v / (adc.vref_mv as f64 / 1000.0) * fs)
        .round()
        .clamp(0.0, fs) as u16
}

/// The five sensors of one rover.
#[derive(Clone, Debug)]
pub struct VirtualSensors {
    adc: AdcProfile,
    mode: SensorMode,
    angles: [f64; SENSOR_COUNT],
    offset_m: f64,
    /// How far a sensor can see anything at all, m.
    reach_m: f64,
    gain: [f64; SENSOR_COUNT],
    held: [u16; SENSOR_COUNT],
    held_v: [f64; SENSOR_COUNT],
    next_update: [f64; SENSOR_COUNT],
    rng: Pcg64,
}

impl VirtualSensors {
    /// Sensors at `angles_rad` (robot frame), faces `offset_m` from the centre.
    pub fn new(
        adc: AdcProfile,
        mode: SensorMode,
        angles_rad: [f64; SENSOR_COUNT],
        offset_m: f64,
        seed: u64,
    ) -> Self {
        let mut rng = Pcg64::seed_from_u64(seed);
        let mut gain = [1.0; SENSOR_COUNT];
        if let SensorMode::Realistic { spread, .. } = mode {
            for g in gain.iter_mut() {
                *g = 1.0 + rng.gen_range(-spread..=spread);
            }
        }
        VirtualSensors {
            adc,
            mode,
            angles: angles_rad,
            offset_m,
            reach_m: 1.5,
            gain,
            held: [0; SENSOR_COUNT],
            held_v: [0.0; SENSOR_COUNT],
            next_update: [f64::NEG_INFINITY; SENSOR_COUNT],
            rng,
        }
    }

    /// The true distance sensor `i` sees from pose (`p`, `heading`) at time `t`.
    pub fn true_distance(
        &self,
        world: &World,
        p: V2,
        heading: f64,
        i: usize,
        t: f64,
    ) -> Option<f64> {
        let a = heading + self.angles[i];
        let face = p + V2::from_angle(a) * self.offset_m;
        world.ray(face, a, self.reach_m, t)
    }

    /// The raw counts the ADC reads at time `t` with the rover at `p`, `heading`.
    pub fn read(&mut self, world: &World, p: V2, heading: f64, t: f64) -> RawCounts {
        for i in 0..SENSOR_COUNT {
            match self.mode {
                SensorMode::Perfect => {
                    let d = self.true_distance(world, p, heading, i, t);
                    self.held_v[i] = voltage(d, false);
                    self.held[i] = counts(self.adc, self.held_v[i]);
                }
                SensorMode::Realistic { noise_v, .. } => {
                    if t < self.next_update[i] {
                        continue;
                    }
                    let d = self.true_distance(world, p, heading, i, t);
                    let noise = Normal::new(0.0, noise_v)
                        .map(|n| n.sample(&mut self.rng))
                        .unwrap_or(0.0);
                    let v = voltage(d, true) * self.gain[i] + noise;
                    self.held_v[i] = v.max(0.0);
                    self.held[i] = counts(self.adc, v);
                    // The next value comes 28.7–47.9 ms later (datasheet).
                    let period = self.rng.gen_range(0.0287..=0.0479);
                    let base = if self.next_update[i].is_finite() {
                        self.next_update[i]
                    } else {
                        t - self.rng.gen_range(0.0..period)
                    };
                    self.next_update[i] = (base + period).max(t + 1e-6);
                }
            }
        }
        self.held
    }

    /// The output voltages behind the last [`VirtualSensors::read`], volts
    /// (what an emulated ADC pin is driven with).
    pub fn volts(&self) -> [f64; SENSOR_COUNT] {
        self.held_v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn curve_passes_the_datasheet_points() {
        for &(mv, mm) in GP2Y0A21_MV_MM.iter() {
            let v = voltage(Some(mm as f64 / 1000.0), true);
            assert!((v - mv as f64 / 1000.0).abs() < 1e-9, "{mm} mm: {v}");
        }
        // Between points: 15 cm lies between 2.6 V and 1.39 V, nearer 1.39 in 1/d terms.
        let v = voltage(Some(0.15), true);
        assert!(v > 1.39 && v < 2.6);
        assert!((v - (2.6 + (1.0 / 0.15 - 10.0) / (5.0 - 10.0) * (1.39 - 2.6))).abs() < 1e-12);
    }

    #[test]
    fn fold_back_and_phantom() {
        // 5 cm reads like something farther than 10 cm would not: but 2 cm
        // reads below the 10 cm voltage — it looks farther (fold-back).
        assert!(voltage(Some(0.02), true) < voltage(Some(0.10), true));
        assert!(voltage(Some(0.065), true) > 3.0);
        // Perfect mode has no fold-back.
        assert!(voltage(Some(0.02), false) > voltage(Some(0.10), false));
        // Nothing in range: the phantom level, below the 80 cm voltage, so
        // the core reads it as clear.
        assert_eq!(voltage(None, true), PHANTOM_V);
        assert!(voltage(Some(1.2), true) < 0.42);
        let cal = planner_core::Calibration::gp2y0a21(AdcProfile::AVR_10BIT_5V).unwrap();
        assert_eq!(
            cal.reading(counts(AdcProfile::AVR_10BIT_5V, PHANTOM_V)),
            planner_core::Reading::Clear
        );
    }

    #[test]
    fn counts_round_and_clamp() {
        assert_eq!(counts(AdcProfile::AVR_10BIT_5V, 2.6), 532);
        assert_eq!(counts(AdcProfile::AVR_10BIT_5V, 9.0), 1023);
        assert_eq!(counts(AdcProfile::STM32_12BIT_3V3, 0.42), 521);
    }

    #[test]
    fn realistic_values_are_held_between_updates_and_seeded() {
        let text = "format = 1\nname = \"w\"\nbounds = [0.0, 0.0, 4.0, 4.0]\nstart = [1.0, 2.0]\ngoal = [3.0, 3.5]\n[[circle]]\ncenter = [1.6, 2.0]\nradius = 0.1\n";
        let sc = crate::scenario::Scenario::parse(text, std::path::Path::new("w")).unwrap();
        let w = sc.world();
        let angles = [-0.698, -0.349, 0.0, 0.349, 0.698];
        let mk = |seed| {
            VirtualSensors::new(
                AdcProfile::AVR_10BIT_5V,
                SensorMode::REALISTIC,
                angles,
                0.1,
                seed,
            )
        };
        let (mut a, mut b) = (mk(7), mk(7));
        let p = V2::new(1.0, 2.0);
        let ra = a.read(&w, p, 0.0, 0.0);
        assert_eq!(ra, b.read(&w, p, 0.0, 0.0));
        // 1 ms later nothing has updated: the same values are held.
        assert_eq!(a.read(&w, p, 0.0, 0.001), ra);
        // The front sensor sees the circle 0.4 m away: about 0.75 V, ~153 counts.
        assert!((ra[2] as i32 - 153).abs() < 20, "{ra:?}");
        // 60 ms later every sensor has a new (noisy) value.
        let later: Vec<RawCounts> = (1..20)
            .map(|k| a.read(&w, p, 0.0, 0.06 * k as f64))
            .collect();
        assert!(later.iter().any(|r| r[2] != ra[2]));
    }
}
