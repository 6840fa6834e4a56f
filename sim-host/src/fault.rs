//! Faults injected into a run: broken sensors, slipping or stalling
//! wheels, glitching encoders, late commands (`--fault NAME[:KEY=VALUE,…]`,
//! repeatable). A run without faults draws nothing from the faults' random
//! numbers, so it is the same run as before.

use crate::sensor::{counts, PHANTOM_V};
use planner_core::{AdcProfile, RawCounts, SENSOR_COUNT};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use std::fmt;
use std::str::FromStr;

/// The peak output of the sensor's curve (at about 6.5 cm), volts: what a
/// spike reads.
const PEAK_V: f64 = 3.1;

/// One fault and its parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Fault {
    /// Sensor `sensor` (0 = rightmost … 4 = leftmost) reads 0 V: unplugged.
    Dead { sensor: usize },
    /// Sensor `sensor` freezes at the value it reads `after_s` seconds in.
    Stuck { sensor: usize, after_s: f64 },
    /// Sensor `sensor` reads the "nothing in range" level (0.28 V) for
    /// ever: plausible and wrong.
    StuckClear { sensor: usize },
    /// Each reading of each sensor is, with probability `rate`, the
    /// curve's peak (3.1 V, something very near).
    Spikes { rate: f64 },
    /// Each reading of each sensor is, with probability `rate`, the
    /// "nothing in range" level.
    Dropouts { rate: f64 },
    /// Sensor `sensor`'s neighbour (the next to the left; for the leftmost,
    /// the next to the right) reads `fraction` of its voltage on top of
    /// its own.
    Crosstalk { sensor: usize, fraction: f64 },
    /// Every sensor reads `volts` more (sunlight).
    Ambient { volts: f64 },
    /// Wheel slip: each advance's true length differs from the encoders'
    /// by a Gaussian fraction of σ `sigma`, each turn's by σ `sigma` per
    /// radian.
    Slip { sigma: f64 },
    /// The wheels stop from `at_s` for `for_s` seconds: no advance moves
    /// the rover then (the encoders see it: the executor ends the step).
    Stall { at_s: f64, for_s: f64 },
    /// Each centimetre of an advance is, with probability `rate`, missed
    /// by the encoders or counted twice (odometry only).
    EncoderGlitch { rate: f64 },
    /// Every turn goes `fraction` farther than commanded (odometry does
    /// not know).
    Overshoot { fraction: f64 },
    /// The planner decides on the counts of one cycle before.
    Latency,
}

/// Every fault's name, in the order of the table.
pub const NAMES: [&str; 12] = [
    "dead",
    "stuck",
    "stuck-clear",
    "spikes",
    "dropouts",
    "crosstalk",
    "ambient",
    "slip",
    "stall",
    "encoder-glitch",
    "overshoot",
    "latency",
];

impl Fault {
    /// The fault `name` with its default parameters.
    pub fn named(name: &str) -> Option<Fault> {
        Some(match name {
            "dead" => Fault::Dead { sensor: 2 },
            "stuck" => Fault::Stuck {
                sensor: 2,
                after_s: 5.0,
            },
            "stuck-clear" => Fault::StuckClear { sensor: 2 },
            "spikes" => Fault::Spikes { rate: 0.02 },
            "dropouts" => Fault::Dropouts { rate: 0.02 },
            "crosstalk" => Fault::Crosstalk {
                sensor: 2,
                fraction: 0.3,
            },
            "ambient" => Fault::Ambient { volts: 0.3 },
            "slip" => Fault::Slip { sigma: 0.05 },
            "stall" => Fault::Stall {
                at_s: 10.0,
                for_s: 2.0,
            },
            "encoder-glitch" => Fault::EncoderGlitch { rate: 0.02 },
            "overshoot" => Fault::Overshoot { fraction: 0.1 },
            "latency" => Fault::Latency,
            _ => return None,
        })
    }

    /// Its name.
    pub fn name(&self) -> &'static str {
        match self {
            Fault::Dead { .. } => "dead",
            Fault::Stuck { .. } => "stuck",
            Fault::StuckClear { .. } => "stuck-clear",
            Fault::Spikes { .. } => "spikes",
            Fault::Dropouts { .. } => "dropouts",
            Fault::Crosstalk { .. } => "crosstalk",
            Fault::Ambient { .. } => "ambient",
            Fault::Slip { .. } => "slip",
            Fault::Stall { .. } => "stall",
            Fault::EncoderGlitch { .. } => "encoder-glitch",
            Fault::Overshoot { .. } => "overshoot",
            Fault::Latency => "latency",
        }
    }

    /// Set parameter `key` to `value`.
    fn set(&mut self, key: &str, value: &str) -> Result<(), String> {
        let name = self.name();
        let num = |lo: f64, hi: f64| -> Result<f64, String> {
            let v: f64 = value
                .parse()
                .map_err(|_| format!("fault {name}: {key}={value} is not a number"))?;
            if v.is_finite() && (lo..=hi).contains(&v) {
                Ok(v)
            } else {
                Err(format!(
                    "fault {name}: {key}={value} is outside {lo}..={hi}"
                ))
            }
        };
        let sensor = || -> Result<usize, String> {
            value
                .parse::<usize>()
                .ok()
                .filter(|&s| s < SENSOR_COUNT)
                .ok_or_else(|| format!("fault {name}: sensor={value} is not 0..=4"))
        };
        match (self, key) {
            (
                Fault::Dead { sensor: s }
                | Fault::Stuck { sensor: s, .. }
                | Fault::StuckClear { sensor: s }
                | Fault::Crosstalk { sensor: s, .. },
                "sensor",
            ) => *s = sensor()?,
            (Fault::Stuck { after_s, .. }, "after") => *after_s = num(0.0, 1e6)?,
            (
                Fault::Spikes { rate } | Fault::Dropouts { rate } | Fault::EncoderGlitch { rate },
                "rate",
            ) => *rate = num(0.0, 1.0)?,
            (Fault::Crosstalk { fraction, .. }, "fraction") => *fraction = num(0.0, 1.0)?,
            (Fault::Ambient { volts }, "volts") => *volts = num(-5.0, 5.0)?,
            (Fault::Slip { sigma }, "sigma") => *sigma = num(0.0, 0.5)?,
            (Fault::Stall { at_s, .. }, "at") => *at_s = num(0.0, 1e6)?,
            (Fault::Stall { for_s, .. }, "for") => *for_s = num(0.0, 1e6)?,
            (Fault::Overshoot { fraction }, "fraction") => *fraction = num(-0.5, 1.0)?,
            _ => return Err(format!("fault {name} has no parameter {key}")),
        }
        Ok(())
    }
}

impl FromStr for Fault {
    type Err = String;

    /// `NAME` or `NAME:KEY=VALUE,KEY=VALUE`.
    fn from_str(s: &str) -> Result<Fault, String> {
        let (name, params) = s.split_once(':').unwrap_or((s, ""));
        let mut fault = Fault::named(name)
            .ok_or_else(|| format!("unknown fault `{name}`: one of {}", NAMES.join(", ")))?;
        for kv in params.split(',').filter(|kv| !kv.is_empty()) {
            let (k, v) = kv
                .split_once('=')
                .ok_or_else(|| format!("fault {name}: `{kv}` is not KEY=VALUE"))?;
            fault.set(k.trim(), v.trim())?;
        }
        Ok(fault)
    }
}

impl fmt::Display for Fault {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Fault::Dead { sensor } | Fault::StuckClear { sensor } => {
                write!(f, "{}:sensor={sensor}", self.name())
            }
            Fault::Stuck { sensor, after_s } => write!(f, "stuck:sensor={sensor},after={after_s}"),
            Fault::Spikes { rate } | Fault::Dropouts { rate } | Fault::EncoderGlitch { rate } => {
                write!(f, "{}:rate={rate}", self.name())
            }
            Fault::Crosstalk { sensor, fraction } => {
                write!(f, "crosstalk:sensor={sensor},fraction={fraction}")
            }
            Fault::Ambient { volts } => write!(f, "ambient:volts={volts}"),
            Fault::Slip { sigma } => write!(f, "slip:sigma={sigma}"),
            Fault::Stall { at_s, for_s } => write!(f, "stall:at={at_s},for={for_s}"),
            Fault::Overshoot { fraction } => write!(f, "overshoot:fraction={fraction}"),
            Fault::Latency => write!(f, "latency"),
        }
    }
}

/// The faults of one run and what they remember.
#[derive(Clone, Debug)]
pub struct Faults {
    faults: Vec<Fault>,
    adc: AdcProfile,
    rng: Pcg64,
    /// Each stuck sensor's frozen count, once frozen.
    frozen: [Option<u16>; SENSOR_COUNT],
    /// The counts the planner read last cycle (latency).
    previous: Option<RawCounts>,
}

impl Faults {
    /// `faults` on a board with `adc`, random numbers from `seed`.
    pub fn new(faults: &[Fault], adc: AdcProfile, seed: u64) -> Faults {
        Faults {
            faults: faults.to_vec(),
            adc,
            rng: Pcg64::seed_from_u64(seed ^ 0xfa17_fa17),
            frozen: [None; SENSOR_COUNT],
            previous: None,
        }
    }

    /// The counts the ADC reads at time `t`, from the sensors' `raw`.
    pub fn sensors(&mut self, mut raw: RawCounts, t: f64) -> RawCounts {
        let full = self.adc.full_scale();
        let volts = |v: f64| counts(self.adc, v);
        for &fault in &self.faults {
            match fault {
                Fault::Dead { sensor } => raw[sensor] = 0,
                Fault::Stuck { sensor, after_s } if t >= after_s => {
                    raw[sensor] = *self.frozen[sensor].get_or_insert(raw[sensor]);
                }
                Fault::StuckClear { sensor } => raw[sensor] = volts(PHANTOM_V),
                Fault::Spikes { rate } => {
                    for r in raw.iter_mut() {
                        if self.rng.gen_bool(rate) {
                            *r = volts(PEAK_V);
                        }
                    }
                }
                Fault::Dropouts { rate } => {
                    for r in raw.iter_mut() {
                        if self.rng.gen_bool(rate) {
                            *r = volts(PHANTOM_V);
                        }
                    }
                }
                Fault::Crosstalk { sensor, fraction } => {
                    let to = if sensor + 1 < SENSOR_COUNT {
                        sensor + 1
                    } else {
                        sensor - 1
                    };
                    let add = (raw[sensor] as f64 * fraction).round() as u16;
                    raw[to] = raw[to].saturating_add(add).min(full);
                }
                Fault::Ambient { volts: v } => {
                    let add = counts(self.adc, v.abs());
                    for r in raw.iter_mut() {
                        *r = if v >= 0.0 {
                            r.saturating_add(add).min(full)
                        } else {
                            r.saturating_sub(add)
                        };
                    }
                }
                _ => {}
            }
        }
        raw
    }

    /// The counts the planner decides on this cycle, `raw` read now: with
    /// latency, last cycle's.
    pub fn planner_counts(&mut self, raw: RawCounts) -> RawCounts {
        if self.faults.contains(&Fault::Latency) {
            self.previous.replace(raw).unwrap_or(raw)
        } else {
            raw
        }
    }

    /// The slip (distance σ as a fraction, heading σ per radian) the faults
    /// add, if any.
    pub fn slip(&self) -> Option<(f64, f64)> {
        self.faults.iter().find_map(|f| match *f {
            Fault::Slip { sigma } => Some((sigma, sigma)),
            _ => None,
        })
    }

    /// Whether the wheels are stalled at time `t`.
    pub fn stalled(&self, t: f64) -> bool {
        self.faults.iter().any(|f| match *f {
            Fault::Stall { at_s, for_s } => (at_s..at_s + for_s).contains(&t),
            _ => false,
        })
    }

    /// The turn the wheels make for a commanded `turn` (rad).
    pub fn turn(&self, turn: f64) -> f64 {
        self.faults.iter().fold(turn, |t, f| match *f {
            Fault::Overshoot { fraction } => t * (1.0 + fraction),
            _ => t,
        })
    }

    /// What the encoders count for a true advance `piece` (m).
    pub fn odometry(&mut self, piece: f64) -> f64 {
        let mut counted = piece;
        for &fault in &self.faults {
            if let Fault::EncoderGlitch { rate } = fault {
                if self.rng.gen_bool(rate) {
                    counted = if self.rng.gen_bool(0.5) {
                        0.0
                    } else {
                        2.0 * piece
                    };
                }
            }
        }
        counted
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_name_parses_to_its_defaults_and_prints_back() {
        for name in NAMES {
            let f: Fault = name.parse().unwrap();
            assert_eq!(f.name(), name);
            assert_eq!(f.to_string().parse::<Fault>().unwrap(), f);
        }
        let f: Fault = "stuck:sensor=0,after=2.5".parse().unwrap();
        assert_eq!(
            f,
            Fault::Stuck {
                sensor: 0,
                after_s: 2.5
            }
        );
    }

    #[test]
    fn bad_faults_are_refused_with_the_reason() {
        for (bad, says) in [
            ("sunburn", "unknown fault `sunburn`"),
            ("dead:sensor=5", "sensor=5 is not 0..=4"),
            ("spikes:rate=2", "outside"),
            ("spikes:rate=nan", "outside"),
            ("slip:rate=0.1", "has no parameter rate"),
            ("stall:at", "is not KEY=VALUE"),
            ("ambient:volts=x", "is not a number"),
        ] {
            let e = bad.parse::<Fault>().unwrap_err();
            assert!(e.contains(says), "{bad}: {e}");
        }
    }

    const ADC: AdcProfile = AdcProfile::AVR_10BIT_5V;
    const RAW: RawCounts = [100, 200, 300, 400, 500];

    fn with(fault: &str) -> Faults {
        Faults::new(&[fault.parse().unwrap()], ADC, 1)
    }

    #[test]
    fn sensor_faults_change_the_counts_as_named() {
        assert_eq!(with("dead").sensors(RAW, 0.0), [100, 200, 0, 400, 500]);
        let mut stuck = with("stuck:after=1");
        assert_eq!(stuck.sensors(RAW, 0.5), RAW);
        assert_eq!(stuck.sensors(RAW, 1.0), RAW);
        assert_eq!(stuck.sensors([9; 5], 2.0), [9, 9, 300, 9, 9]);
        // Two stuck sensors keep a value each.
        let two: Vec<Fault> = ["stuck:sensor=0,after=0", "stuck:sensor=4,after=0"]
            .iter()
            .map(|f| f.parse().unwrap())
            .collect();
        let mut both = Faults::new(&two, ADC, 1);
        assert_eq!(both.sensors(RAW, 0.0), RAW);
        assert_eq!(both.sensors([9; 5], 1.0), [100, 9, 9, 9, 500]);
        let phantom = counts(ADC, PHANTOM_V);
        assert_eq!(with("stuck-clear").sensors(RAW, 0.0)[2], phantom);
        assert_eq!(
            with("crosstalk:fraction=0.5").sensors(RAW, 0.0),
            [100, 200, 300, 550, 500]
        );
        // The leftmost's neighbour is the one to its right.
        assert_eq!(
            with("crosstalk:sensor=4,fraction=0.5").sensors(RAW, 0.0),
            [100, 200, 300, 650, 500]
        );
        let sun = counts(ADC, 0.3);
        assert_eq!(with("ambient").sensors(RAW, 0.0), RAW.map(|r| r + sun));
        let mut spikes = with("spikes:rate=1");
        assert_eq!(spikes.sensors(RAW, 0.0), [counts(ADC, PEAK_V); 5]);
        assert_eq!(with("dropouts:rate=1").sensors(RAW, 0.0), [phantom; 5]);
        // Rare ones are rare.
        let mut rare = with("spikes:rate=0.02");
        let hit = (0..1_000).filter(|_| rare.sensors(RAW, 0.0) != RAW).count();
        assert!((40..200).contains(&hit), "{hit}");
    }

    #[test]
    fn motion_faults_change_the_motion_as_named() {
        let mut late = with("latency");
        assert_eq!(late.planner_counts(RAW), RAW);
        assert_eq!(late.planner_counts([1; 5]), RAW);
        assert_eq!(late.planner_counts([2; 5]), [1; 5]);
        assert_eq!(with("slip:sigma=0.1").slip(), Some((0.1, 0.1)));
        assert_eq!(with("dead").slip(), None);
        let stall = with("stall:at=1,for=2");
        assert!(!stall.stalled(0.9) && stall.stalled(1.0) && stall.stalled(2.9));
        assert!(!stall.stalled(3.0));
        assert!((with("overshoot").turn(1.0) - 1.1).abs() < 1e-12);
        let mut glitch = with("encoder-glitch:rate=1");
        let counted: Vec<f64> = (0..100).map(|_| glitch.odometry(0.01)).collect();
        assert!(counted.contains(&0.0) && counted.contains(&0.02));
        assert_eq!(with("dead").odometry(0.01), 0.01);
    }
}
