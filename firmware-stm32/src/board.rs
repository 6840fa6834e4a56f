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
use core::sync::atomic::{AtomicU32, Ordering};
use cortex_m::peripheral::{syst::SystClkSource, DWT};
use cortex_m_rt::exception;
use defmt_rtt as _;
use panic_probe as _;
use planner_core::eapf::sensors::OneShotSensors;
use planner_core::rover::app::{self, Board, Event, Rover, RoverConfig, Sweep};
use planner_core::rover::calibration::{self, STORED_BYTES};
use planner_core::rover::drive::Wheels;
use planner_core::{AdcProfile, IrSensors, Planner, Point};
use stm32f4xx_hal::adc::{config::AdcConfig, Adc};
use stm32f4xx_hal::flash::{FlashExt, LockedFlash};
use stm32f4xx_hal::pac::USART1;
use stm32f4xx_hal::qei::Qei;
use stm32f4xx_hal::serial::{Rx, Tx};
use stm32f4xx_hal::watchdog::IndependentWatchdog;
use stm32f4xx_hal::{pac, prelude::*, rcc::Config};

/// Wheel encoders: 210 counts per wheel turn with one channel; in x4 encoder
/// mode the timers count 840, so four counts make one core tick.
const COUNTS_PER_TICK: i32 = 4;

/// Milliseconds since the clock started, counted by SysTick's interrupt.
static MILLIS: AtomicU32 = AtomicU32::new(0);

#[exception]
fn SysTick() {
    MILLIS.fetch_add(1, Ordering::Relaxed);
}

/// The board's parts as the rover application sees them. The motors,
/// encoders and sensors are closures over the HAL's drivers, whose types
/// are long to name.
struct Parts<M, E, S> {
    motors: M,
    encoders: E,
    sensors: S,
    tx: Tx<USART1>,
    rx: Rx<USART1>,
    flash: LockedFlash,
    watchdog: IndependentWatchdog,
}

/// Where the sensors' calibration is kept: the start of the STM32F411xE's
/// last flash sector (sector 7, 128 KB at offset 0x6_0000), which
/// `memory.x` leaves out of the program's flash.
const CALIBRATION_OFFSET: u32 = 0x6_0000;

/// The watchdog's period, and the one it gets while a sector is erased:
/// the CPU waits for the flash meanwhile, 1 to 4 s for 128 KB (RM0383,
/// §3.5; the datasheet's t_ERASE128KB).
const WATCHDOG_MS: u32 = 500;
const ERASE_WATCHDOG_MS: u32 = 8_000;

impl<M: FnMut(Wheels), E, S> app::Motors for Parts<M, E, S> {
    fn set(&mut self, wheels: Wheels) {
        (self.motors)(wheels);
    }
}

impl<M, E: FnMut() -> (i16, i16), S> app::Encoders for Parts<M, E, S> {
    fn take(&mut self) -> (i16, i16) {
        (self.encoders)()
    }
}

impl<M, E, S: FnMut() -> Sweep> app::Sensors for Parts<M, E, S> {
    fn sweep(&mut self) -> Sweep {
        (self.sensors)()
    }
}

impl<M, E, S> app::Clock for Parts<M, E, S> {
    fn millis(&mut self) -> u32 {
        MILLIS.load(Ordering::Relaxed)
    }
    fn cycles(&mut self) -> u32 {
        DWT::cycle_count()
    }
}

impl<M, E, S> app::Serial for Parts<M, E, S> {
    fn read(&mut self) -> Option<u8> {
        self.rx.read().ok()
    }
    fn write(&mut self, b: u8) {
        let _ = self.tx.write_char(b as char);
    }
}

impl<M: FnMut(Wheels), E: FnMut() -> (i16, i16), S: FnMut() -> Sweep> Board for Parts<M, E, S> {
    fn load_calibration(&mut self, bytes: &mut [u8; STORED_BYTES]) -> bool {
        calibration::load_from_flash(&mut self.flash, CALIBRATION_OFFSET, bytes)
    }

    /// Erase the sector and write the bytes (the application stores only
    /// while the rover stands still).
    fn store_calibration(&mut self, bytes: &[u8; STORED_BYTES]) -> bool {
        self.watchdog.start(ERASE_WATCHDOG_MS.millis());
        let done =
            calibration::store_in_flash(&mut self.flash.unlocked(), CALIBRATION_OFFSET, bytes);
        self.watchdog.start(WATCHDOG_MS.millis());
        done
    }

    /// Each step and fault, over defmt.
    fn log(&mut self, event: Event) {
        match event {
            Event::Stepped(s) => defmt::info!(
                "t={=u32}ms pose=({=i16},{=i16})mm heading={=f32}deg -> {} step={=u16}mm cycles={=u32}",
                s.ms,
                s.pose.position.x,
                s.pose.position.y,
                s.pose.heading.signed() as f32 * (360.0 / 65_536.0),
                s.output.status,
                s.output.command.step_mm,
                s.cycles
            ),
            Event::SensorFailed => defmt::error!("adc error: stopped"),
        }
    }
}

pub fn run() -> ! {
    let (Some(dp), Some(mut cp)) = (pac::Peripherals::take(), cortex_m::Peripherals::take()) else {
        defmt::panic!("peripherals taken twice")
    };
    let mut rcc = dp.RCC.freeze(Config::hsi().sysclk(84.MHz()));
    let gpioa = dp.GPIOA.split(&mut rcc);
    let gpiob = dp.GPIOB.split(&mut rcc);

    let adc = Adc::new(dp.ADC1, true, AdcConfig::default(), &mut rcc);
    let mut ir = OneShotSensors::new(
        adc,
        (
            gpioa.pa0.into_analog(),
            gpioa.pa1.into_analog(),
            gpioa.pa4.into_analog(),
            gpiob.pb0.into_analog(),
            gpiob.pb1.into_analog(),
        ),
    );
    // A one-shot sweep of the five channels each control tick.
    let sensors = move || match ir.read_raw() {
        Ok(raw) => Sweep::New(raw),
        Err(_) => Sweep::Failed,
    };

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
    let mut motors = move |w: Wheels| {
        left_pwm.set_duty((w.left.unsigned_abs() as i32 * max_duty / 255) as u16);
        right_pwm.set_duty((w.right.unsigned_abs() as i32 * max_duty / 255) as u16);
        ain1.set_state((w.left > 0).into());
        ain2.set_state((w.left < 0).into());
        bin1.set_state((w.right > 0).into());
        bin2.set_state((w.right < 0).into());
    };
    motors(Wheels::STOP);

    let left_enc = Qei::new(dp.TIM4, (gpiob.pb6, gpiob.pb7), &mut rcc);
    // PA15 and PB3 leave their JTAG function (SWD keeps PA13/PA14).
    let (pa15, pb3) = (gpioa.pa15.into_input(), gpiob.pb3.into_input());
    let right_enc = Qei::new(dp.TIM2, (pa15, pb3), &mut rcc);
    let (mut last_l, mut last_r) = (left_enc.count(), right_enc.count() as u16);
    let encoders = move || {
        let (l, r) = (left_enc.count(), right_enc.count() as u16);
        let dl = l.wrapping_sub(last_l) as i16 as i32 / COUNTS_PER_TICK;
        let dr = r.wrapping_sub(last_r) as i16 as i32 / COUNTS_PER_TICK;
        // Keep the remainders for the next tick.
        last_l = last_l.wrapping_add((dl * COUNTS_PER_TICK) as u16);
        last_r = last_r.wrapping_add((dr * COUNTS_PER_TICK) as u16);
        (dl as i16, dr as i16)
    };

    let Ok(serial) = dp
        .USART1
        .serial((gpioa.pa9, gpioa.pa10), 115_200.bps(), &mut rcc)
    else {
        defmt::panic!("serial set-up")
    };
    let (mut tx, rx) = serial.split();

    let mut watchdog = IndependentWatchdog::new(dp.IWDG);
    watchdog.start(WATCHDOG_MS.millis());

    // The cycle counter for the telemetry's step cycles.
    cp.DCB.enable_trace();
    cp.DWT.enable_cycle_counter();
    // The 1 kHz control clock: SysTick's interrupt.
    let mut syst = cp.SYST;
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(rcc.clocks.sysclk().raw() / 1_000 - 1);
    syst.clear_current();
    syst.enable_interrupt();
    syst.enable_counter();

    let mut planner = Planner::new(crate::CONFIG, Point::new(0, 0));
    let mut rover = Rover::new(
        &mut planner,
        RoverConfig::reference(AdcProfile::STM32_12BIT_3V3),
    );
    defmt::info!("ready");
    let _ = tx.write_str("READY\n");
    let mut parts = Parts {
        motors,
        encoders,
        sensors,
        tx,
        rx,
        flash: LockedFlash::new(dp.FLASH),
        watchdog,
    };
    rover.load_calibration(&mut parts);
    loop {
        parts.watchdog.feed();
        rover.poll(&mut parts);
    }
}
