//! The real board (STM32F411, 84 MHz from the internal oscillator).
//!
//! | pin | use |
//! |---|---|
//! | PA0, PA1, PA4, PB0, PB1 | IR sensors at −40°, −20°, 0°, +20°, +40° (ADC1 IN0, IN1, IN4, IN8, IN9; 3.3 V reference) |
//! | PA6, PA7 | left, right motor PWM (TIM3 CH1, CH2, 20 kHz) → TB6612FNG PWMA, PWMB |
//! | PB12, PB13 | left motor direction → AIN1, AIN2 |
//! | PB14, PB15 | right motor direction → BIN1, BIN2 |
//! | PB6, PB7 | left wheel encoder A, B (TIM4 encoder mode) |
//! | PA15, PB3 | right wheel encoder A, B (TIM2 encoder mode) |
//! | PA9, PA10 | USART1 TX, RX: 115,200 8N1, the command lines of `planner_core::rover::protocol` |
//! | SWDIO, SWCLK | probe-rs: flashing and defmt logs over RTT |
//!
//! The GP2Y0A21 outputs up to 3.1 V: within the 3.3 V ADC range, no divider.
//! Not PA2/PA3: on a Nucleo-64 they are wired to the ST-LINK's virtual COM
//! port (solder bridges SB13/SB14, closed as shipped), whose TX would drive
//! a sensor's input. On the Nucleo, PA0, PA1, PA4 and PB0 are the Arduino
//! header's A0–A3 (the Uno's sensor pins) and PB1 is on CN10; on the Black
//! Pill all five are on its pin headers.

use core::fmt::Write as _;
use cortex_m::peripheral::syst::SystClkSource;
use defmt_rtt as _;
use micromath::F32Ext;
use panic_probe as _;
use planner_core::eapf::sensors::{OneShotSensors, SENSOR_WARMUP_MS};
use planner_core::rover::drive::{Body, Executor, ExecutorConfig, Odometry, Wheels};
use planner_core::rover::protocol::{self, Request};
use planner_core::{Angle, IrSensors, Planner, Point, Pose, Status};
use stm32f4xx_hal::adc::{config::AdcConfig, Adc};
use stm32f4xx_hal::qei::Qei;
use stm32f4xx_hal::watchdog::IndependentWatchdog;
use stm32f4xx_hal::{pac, prelude::*, rcc::Config};

/// Wheel encoders: 210 counts per wheel turn with one channel; in x4 encoder
/// mode the timers count 840, so four counts make one core tick.
const COUNTS_PER_TICK: i32 = 4;

pub fn run() -> ! {
    let (Some(dp), Some(cp)) = (pac::Peripherals::take(), cortex_m::Peripherals::take()) else {
        defmt::panic!("peripherals taken twice")
    };
    let mut rcc = dp.RCC.freeze(Config::hsi().sysclk(84.MHz()));
    let gpioa = dp.GPIOA.split(&mut rcc);
    let gpiob = dp.GPIOB.split(&mut rcc);

    let adc = Adc::new(dp.ADC1, true, AdcConfig::default(), &mut rcc);
    let mut sensors = OneShotSensors::new(
        adc,
        (
            gpioa.pa0.into_analog(),
            gpioa.pa1.into_analog(),
            gpioa.pa4.into_analog(),
            gpiob.pb0.into_analog(),
            gpiob.pb1.into_analog(),
        ),
    );

    let (_, (ch1, ch2, ..)) = dp.TIM3.pwm_hz(20.kHz(), &mut rcc);
    let mut left_pwm = ch1.with(gpioa.pa6);
    let mut right_pwm = ch2.with(gpioa.pa7);
    left_pwm.enable();
    right_pwm.enable();
    let max_duty = left_pwm.get_max_duty() as i32;
    let mut ain1 = gpiob.pb12.into_push_pull_output();
    let mut ain2 = gpiob.pb13.into_push_pull_output();
    let mut bin1 = gpiob.pb14.into_push_pull_output();
    let mut bin2 = gpiob.pb15.into_push_pull_output();
    let mut drive = |w: Wheels| {
        left_pwm.set_duty((w.left.unsigned_abs() as i32 * max_duty / 255) as u16);
        right_pwm.set_duty((w.right.unsigned_abs() as i32 * max_duty / 255) as u16);
        ain1.set_state((w.left > 0).into());
        ain2.set_state((w.left < 0).into());
        bin1.set_state((w.right > 0).into());
        bin2.set_state((w.right < 0).into());
    };
    drive(Wheels::STOP);

    let left_enc = Qei::new(dp.TIM4, (gpiob.pb6, gpiob.pb7), &mut rcc);
    // PA15 and PB3 leave their JTAG function (SWD keeps PA13/PA14).
    let (pa15, pb3) = (gpioa.pa15.into_input(), gpiob.pb3.into_input());
    let right_enc = Qei::new(dp.TIM2, (pa15, pb3), &mut rcc);
    let (mut last_l, mut last_r) = (left_enc.count(), right_enc.count() as u16);

    let Ok(serial) = dp
        .USART1
        .serial((gpioa.pa9, gpioa.pa10), 115_200.bps(), &mut rcc)
    else {
        defmt::panic!("serial set-up")
    };
    let (mut tx, mut rx) = serial.split();

    let mut watchdog = IndependentWatchdog::new(dp.IWDG);
    watchdog.start(500.millis());

    // 1 kHz control tick from SysTick (polled).
    let mut syst = cp.SYST;
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(rcc.clocks.sysclk().raw() / 1_000 - 1);
    syst.clear_current();
    syst.enable_counter();

    let mut planner = Planner::new(crate::CONFIG, Point::new(0, 0));
    let mut odometry = Odometry::new(Body::REFERENCE, Pose::default());
    let mut executor = Executor::new(ExecutorConfig::default());
    let mut driving = false;
    let mut lines = protocol::LineReader::new();
    let mut ms: u32 = 0;
    let mut warm = false;
    // The counts of the last tick (`None` after an ADC error), for `D`.
    let mut last_raw = None;
    defmt::info!("ready");
    let _ = tx.write_str("READY\n");

    loop {
        watchdog.feed();
        while let Ok(b) = rx.read() {
            let Some(req) = lines.feed(b, ms) else {
                continue;
            };
            let reply = match req {
                Some(Request::Goal(x, y)) => {
                    planner.set_goal(Point::new(x, y));
                    executor.halt();
                    driving = true;
                    "OK\n"
                }
                Some(Request::Pose(x, y, deg)) if !driving => {
                    odometry.set_pose(Pose {
                        position: Point::new(x, y),
                        heading: Angle::from_deg(deg),
                    });
                    "OK\n"
                }
                Some(Request::Stop) => {
                    executor.halt();
                    driving = false;
                    "OK\n"
                }
                // Not a command: it may have been a stop (`protocol`).
                None => {
                    executor.halt();
                    driving = false;
                    "ERR\n"
                }
                // The counts, then what the planner reads from each.
                Some(Request::Sensors) => match last_raw {
                    Some(raw) => {
                        protocol::write_sensor_line(planner.config(), &raw, |b| {
                            let _ = tx.write_char(b as char);
                        });
                        ""
                    }
                    None => "ERR\n",
                },
                _ => "ERR\n",
            };
            let _ = tx.write_str(reply);
        }

        if !syst.has_wrapped() {
            continue;
        }
        ms = ms.wrapping_add(1);
        let (l, r) = (left_enc.count(), right_enc.count() as u16);
        let dl = l.wrapping_sub(last_l) as i16 as i32 / COUNTS_PER_TICK;
        let dr = r.wrapping_sub(last_r) as i16 as i32 / COUNTS_PER_TICK;
        // Keep the remainders for the next tick.
        last_l = last_l.wrapping_add((dl * COUNTS_PER_TICK) as u16);
        last_r = last_r.wrapping_add((dr * COUNTS_PER_TICK) as u16);
        odometry.update(dl as i16, dr as i16);
        // No step before the sensors' first output (kept once past: `ms`
        // wraps after 49 days).
        warm = warm || ms >= SENSOR_WARMUP_MS;
        // Every tick, driving or not: `D` prints the last counts.
        let read = sensors.read_raw();
        last_raw = read.as_ref().ok().copied();
        if !driving || !warm {
            drive(Wheels::STOP);
            continue;
        }
        let pose = odometry.pose();
        let Ok(raw) = read else {
            // An ADC error is a sensor fault: stop.
            driving = false;
            drive(Wheels::STOP);
            defmt::error!("adc error: stopped");
            continue;
        };
        if executor.is_idle() {
            let out = planner.step_raw(pose, &raw);
            let (dx, dy) = pose.position.to(planner.goal());
            let to_goal_m = ((dx * dx + dy * dy) as f32).sqrt() / 1000.0;
            defmt::info!(
                "t={=u32}ms pose=({=i16},{=i16})mm heading={=f32}deg to_goal={=f32}m -> {} step={=u16}mm",
                ms,
                pose.position.x,
                pose.position.y,
                pose.heading.signed() as f32 * (360.0 / 65_536.0),
                to_goal_m,
                out.status,
                out.command.step_mm
            );
            if out.status != Status::Moving {
                driving = false;
                drive(Wheels::STOP);
                continue;
            }
            executor.start(out.command);
        }
        let wheels = executor.tick(pose, odometry.travelled_mm(), |remaining| {
            planner.guard_raw(&raw, remaining)
        });
        drive(wheels);
    }
}
