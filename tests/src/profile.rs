//! Where the ATmega328P firmware's planner step spends its cycles
//! (`cargo xtask avr-profile`).
//!
//! Replays traces through the firmware in simavr one instruction at a
//! time and charges each instruction's cycles to its address while a
//! planner step runs (from the entry of `timed::step` until it returns),
//! and to the function the step's own code called it under (a shadow call
//! stack kept from the `call`/`rcall`/`icall`, `ret`/`reti` instructions
//! and interrupt entries). The step's own code is `timed::step` and
//! `Planner::step_raw`, which the AVR build keeps out of line.
//! Functions are named from the ELF's symbol table: the debug line tables
//! of the LTO-built AVR image name the wrong files, so a profile by source
//! line is not to be had; mark a function `#[inline(never)]` to see it.
//! avr-tester hides simavr's CPU state (the program counter), so this
//! drives simavr through `simavr-ffi` itself.

use crate::avr::{replay_answer, replay_frame, F_CPU, REPLAY_ANSWER_LEN};
use crate::{sorted, Trace};
use simavr_ffi as ffi;
use std::collections::{HashMap, VecDeque};
use std::ffi::CString;
use std::path::Path;
use std::process::Command;

/// Bytes the firmware sent on USART0.
unsafe extern "C" fn on_output(_: *mut ffi::avr_irq_t, value: u32, param: *mut std::ffi::c_void) {
    let rx = unsafe { &mut *(param as *mut VecDeque<u8>) };
    rx.push_back(value as u8);
}

/// The ATmega328P's interrupt vectors: 26 of two words each.
const VECTOR_TABLE_END: u32 = 26 * 4;

fn uart_ioctl(kind: u8) -> u32 {
    u32::from_be_bytes([b'u', b'a', kind, b'0'])
}

struct Sim {
    avr: *mut ffi::avr_t,
    /// Boxed: simavr's output hook holds its address while `Sim` moves.
    #[allow(clippy::box_collection)]
    rx: Box<VecDeque<u8>>,
    input: *mut ffi::avr_irq_t,
    /// Cycles per instruction address while a step runs.
    hist: HashMap<u32, u64>,
    step_entry: u32,
    /// Cycles of all steps by the entry address of the function the step's
    /// own code called (0: the step's own instructions): an instruction of
    /// a called function is charged to the outermost call it runs under.
    by_callee: HashMap<u32, u64>,
    /// Return addresses of the calls made inside the step, and where the
    /// outermost one went.
    shadow: Vec<u32>,
    /// How deep in the shadow stack the step's own code is: 1 inside
    /// `step_raw` (see [`Sim::own_fn`]), else 0.
    own_depth: usize,
    /// A function whose code counts as the step's own (`step_raw`), not as
    /// a callee.
    own_fn: u32,
    outer_callee: u32,
    /// The same split of this step, and of the worst step.
    this_step: HashMap<u32, u64>,
    worst_step: (u64, HashMap<u32, u64>),
    /// Each step's cycles as counted here, in order.
    counted: Vec<u64>,
    /// Stack pointer at the step's entry, while one runs.
    in_step: Option<u16>,
    steps: u64,
    /// Steps that returned with frames left on the shadow stack (calls
    /// or returns the decoder missed).
    unbalanced: u64,
    /// The entries of `__mulsi3` and `__udivmodsi4`, and what their
    /// operands were at each call inside a step (see [`Operands`]).
    arith: (u32, u32),
    operands: Operands,
}

/// The operands the step's 32-bit multiplies and divisions were called
/// with, read from the registers at the routines' entries: what their
/// shorter ways in `firmware-avr/asm/` are chosen by.
#[derive(Clone, Debug, Default)]
pub struct Operands {
    /// Multiplies whose operands were both below 2^16, both 16-bit values
    /// sign-extended (not both below 2^16), or wider.
    pub mul: [u64; 3],
    /// Divisions by the quotient's length in bytes (1 to 4, rows) and the
    /// divisor's (columns).
    pub div: [[u64; 4]; 4],
    /// Divisions by zero (the planner guards every one of its divisions).
    pub div_by_zero: u64,
}

impl Operands {
    fn multiply(&mut self, a: u32, b: u32) {
        let short = |x: u32| x < 1 << 16;
        let signed = |x: u32| (x as i32) >= -(1 << 15) && (x as i32) < 1 << 15;
        let class = if short(a) && short(b) {
            0
        } else if signed(a) && signed(b) {
            1
        } else {
            2
        };
        self.mul[class] += 1;
    }

    fn divide(&mut self, n: u32, d: u32) {
        let bytes = |x: u32| ((32 - x.leading_zeros()).max(1) as usize).div_ceil(8) - 1;
        match n.checked_div(d) {
            Some(q) => self.div[bytes(q)][bytes(d)] += 1,
            None => self.div_by_zero += 1,
        }
    }
}

impl Sim {
    fn new(elf: &std::path::Path, step_entry: u32, own_fn: u32, arith: (u32, u32)) -> Sim {
        let mcu = CString::new("atmega328p").unwrap();
        let path = CString::new(elf.to_str().unwrap()).unwrap();
        unsafe {
            let avr = ffi::avr_make_mcu_by_name(mcu.as_ptr());
            assert!(!avr.is_null(), "simavr knows the atmega328p");
            ffi::avr_init(avr);
            let fw: *mut ffi::elf_firmware_t = Box::into_raw(Box::new(std::mem::zeroed()));
            assert_eq!(ffi::elf_read_firmware(path.as_ptr(), fw), 0, "read {elf:?}");
            (*fw).frequency = F_CPU;
            ffi::avr_load_firmware(avr, fw);
            (*avr).frequency = F_CPU;
            let mut flags: u32 = 0;
            ffi::avr_ioctl(avr, uart_ioctl(b'g'), &mut flags as *mut u32 as *mut _);
            flags &= !ffi::AVR_UART_FLAG_STDIO;
            ffi::avr_ioctl(avr, uart_ioctl(b's'), &mut flags as *mut u32 as *mut _);
            let mut rx = Box::new(VecDeque::new());
            let out = ffi::avr_io_getirq(avr, uart_ioctl(b'r'), ffi::UART_IRQ_OUTPUT as i32);
            ffi::avr_irq_register_notify(
                out,
                Some(on_output),
                &mut *rx as *mut VecDeque<u8> as *mut _,
            );
            let input = ffi::avr_io_getirq(avr, uart_ioctl(b'r'), ffi::UART_IRQ_INPUT as i32);
            Sim {
                avr,
                rx,
                input,
                hist: HashMap::new(),
                by_callee: HashMap::new(),
                shadow: Vec::new(),
                own_depth: 0,
                own_fn,
                outer_callee: 0,
                this_step: HashMap::new(),
                worst_step: (0, HashMap::new()),
                counted: Vec::new(),
                step_entry,
                in_step: None,
                steps: 0,
                unbalanced: 0,
                arith,
                operands: Operands::default(),
            }
        }
    }

    /// The instruction at byte address `pc`, and if it is a call, its
    /// return address and target (byte addresses).
    fn decode(&self, pc: u32) -> (u16, Option<(u32, u32)>) {
        let (op, k16) = self.opcode(pc);
        let call = if op & 0xfe0e == 0x940e {
            // call k: 22-bit word address over two words.
            let k = ((op as u32 >> 4) & 0x1f) << 17 | (op as u32 & 1) << 16 | k16 as u32;
            Some((pc + 4, 2 * k))
        } else if op & 0xf000 == 0xd000 {
            // rcall k: 12-bit signed word offset.
            let k = ((op as i32) << 20) >> 20;
            Some((pc + 2, (pc as i32 + 2 + 2 * k) as u32))
        } else if op == 0x9509 {
            // icall: to the word address in Z (r31:r30).
            let z = unsafe {
                let d = (*self.avr).data;
                u16::from_le_bytes([*d.add(30), *d.add(31)])
            };
            Some((pc + 2, 2 * z as u32))
        } else {
            None
        };
        (op, call)
    }

    /// The instruction word at byte address `pc` (and the next).
    fn opcode(&self, pc: u32) -> (u16, u16) {
        unsafe {
            let f = (*self.avr).flash;
            let w = |a: u32| u16::from_le_bytes([*f.add(a as usize), *f.add(a as usize + 1)]);
            (w(pc), w(pc + 2))
        }
    }

    fn sp(&self) -> u16 {
        unsafe {
            let d = (*self.avr).data;
            u16::from_le_bytes([*d.add(0x5d), *d.add(0x5e)])
        }
    }

    /// One instruction; its cycles charged to its address inside a step.
    fn one(&mut self) {
        let pc = unsafe { (*self.avr).pc };
        if pc == self.step_entry && self.in_step.is_none() {
            self.in_step = Some(self.sp());
            self.steps += 1;
        }
        let (op, call) = self.decode(pc);
        if self.in_step.is_some() && (pc == self.arith.0 || pc == self.arith.1) {
            // avr-gcc's convention: the first operand in r22..r25, the
            // second in r18..r21.
            let reg = |i: usize| unsafe { *(*self.avr).data.add(i) };
            let word = |i: usize| u32::from_le_bytes([reg(i), reg(i + 1), reg(i + 2), reg(i + 3)]);
            let (a, b) = (word(22), word(18));
            if pc == self.arith.0 {
                self.operands.multiply(a, b);
            } else {
                self.operands.divide(a, b);
            }
        }
        let before = unsafe { (*self.avr).cycle };
        let state = unsafe { ffi::avr_run(self.avr) };
        assert!(
            state != ffi::cpu_Crashed as i32 && state != ffi::cpu_Done as i32,
            "the firmware stopped (state {state})"
        );
        let spent = unsafe { (*self.avr).cycle } - before;
        if let Some(sp) = self.in_step {
            *self.hist.entry(pc).or_default() += spent;
            let callee = if self.shadow.len() <= self.own_depth {
                0
            } else {
                self.outer_callee
            };
            *self.this_step.entry(callee).or_default() += spent;
            let next = unsafe { (*self.avr).pc };
            // The instruction's own effect on the call stack first: an
            // interrupt may have been taken right after it.
            if let Some((ret, target)) = call {
                if self.shadow.len() == self.own_depth {
                    if target == self.own_fn {
                        self.own_depth += 1;
                    } else {
                        self.outer_callee = target;
                    }
                }
                self.shadow.push(ret);
            } else if matches!(op, 0x9508 | 0x9518) {
                // ret, reti.
                self.shadow.pop();
                self.own_depth = self.own_depth.min(self.shadow.len());
            }
            // An interrupt: simavr went to the vector table. Its `reti`
            // pops this frame (a Timer1 overflow, say, in a step).
            if next < VECTOR_TABLE_END && call.is_none() {
                if self.shadow.len() == self.own_depth {
                    self.outer_callee = next;
                }
                self.shadow.push(0);
            }
            // `ret` from the step pops the return address above the entry
            // SP. (Only a `ret`: an epilogue that writes SP a byte at a time
            // can leave it above the entry SP for one instruction.)
            if op == 0x9508 && self.sp() > sp {
                self.in_step = None;
                self.unbalanced += u64::from(!self.shadow.is_empty());
                self.shadow.clear();
                self.own_depth = 0;
                let step = std::mem::take(&mut self.this_step);
                for (callee, c) in &step {
                    *self.by_callee.entry(*callee).or_default() += c;
                }
                let cycles = step.values().sum();
                self.counted.push(cycles);
                if cycles > self.worst_step.0 {
                    self.worst_step = (cycles, step);
                }
            }
        }
    }

    fn send(&mut self, bytes: &[u8]) {
        for &b in bytes {
            unsafe { ffi::avr_raise_irq(self.input, b as u32) };
            // Let the firmware take the byte before the next (simavr's
            // input FIFO is small).
            for _ in 0..2_000 {
                self.one();
            }
        }
    }

    fn take(&mut self, n: usize) -> Vec<u8> {
        let mut budget: u64 = 400_000_000;
        while self.rx.len() < n {
            self.one();
            budget -= 1;
            assert!(budget > 0, "no answer from the firmware");
        }
        self.rx.drain(..n).collect()
    }

    fn line(&mut self) -> String {
        let mut s = Vec::new();
        loop {
            let b = self.take(1)[0];
            if b == b'\n' {
                return String::from_utf8_lossy(&s).trim_end().to_string();
            }
            s.push(b);
        }
    }
}

/// The serial rate the firmware `elf` sets up, baud: booted in simavr until
/// its first line, USART0's rate read from its registers (UBRR0, and U2X0
/// in UCSR0A, which halves the divider).
pub fn usart_baud(elf: &Path) -> f64 {
    let mut sim = Sim::new(elf, u32::MAX, u32::MAX, (u32::MAX, u32::MAX));
    sim.line();
    let reg = |a: usize| unsafe { *(*sim.avr).data.add(a) };
    let ubrr = u16::from_le_bytes([reg(0xc4), reg(0xc5)]);
    let per_bit = if reg(0xc0) & 0b10 != 0 { 8.0 } else { 16.0 };
    F_CPU as f64 / (per_bit * (f64::from(ubrr) + 1.0))
}

/// A function's name without generic arguments: `<Force>::along` stays
/// `Force::along`, `Deque<Point, 16>::push_back` becomes `Deque::push_back`.
fn short(name: &str) -> String {
    let mut s = String::new();
    // Per open `<`: whether it opens generic arguments (dropped).
    let mut open: Vec<bool> = Vec::new();
    let mut prev = ' ';
    for c in name.chars() {
        match c {
            '<' => open.push(prev.is_alphanumeric() || prev == '_'),
            '>' => {
                open.pop();
            }
            _ if open.iter().any(|&g| g) => {}
            _ => s.push(c),
        }
        prev = c;
    }
    s
}

/// A profile of the planner steps of some replayed traces.
pub struct Profile {
    /// Planner steps run.
    pub steps: u64,
    /// Cycles inside the steps, as the profiler counted them.
    pub cycles: u64,
    /// Each step's cycles as the firmware timed them itself (Timer1), in
    /// replay order.
    pub step_cycles: Vec<u32>,
    /// Each step's cycles as the profiler counted them (the whole call of
    /// `timed::step`), in replay order.
    pub step_counted: Vec<u64>,
    /// Cycles by function the instructions are in.
    pub by_function: Vec<(String, u64)>,
    /// Cycles by instruction address (byte address) and its function,
    /// costliest first: to read beside `avr-objdump -d` of the ELF.
    pub by_address: Vec<(u32, String, u64)>,
    /// Cycles by what the step's own code called (callees included);
    /// [`OWN_CODE`] for the step's own instructions.
    pub by_callee: Vec<(String, u64)>,
    /// The costliest step: its cycles and the same split.
    pub worst: (u64, Vec<(String, u64)>),
    /// Steps whose command differs from the host core's (none: the
    /// profiled run is the bit-exact one).
    pub mismatches: usize,
    /// Steps whose calls and returns did not pair up (none, or the split
    /// by callee is wrong).
    pub unbalanced: u64,
    /// The operands of the steps' 32-bit multiplies and divisions.
    pub operands: Operands,
}

impl Profile {
    /// Cycles of all the steps as the firmware timed them.
    pub fn timed(&self) -> u64 {
        self.step_cycles.iter().map(|&c| u64::from(c)).sum()
    }
}

/// [`Profile::by_callee`]'s name for the step's own code (`step_raw` and
/// what is inlined into it).
pub const OWN_CODE: &str = "(the step's own code: step_raw and what is inlined)";

/// Replay `traces` through the firmware `elf` and profile its steps.
pub fn profile(elf: &Path, traces: &[Trace]) -> Profile {
    let syms = Symbols::of(elf);
    let entry = syms
        .entry_of("replay::timed::step")
        .unwrap_or_else(|| panic!("no timed::step in {elf:?}"));
    // Out of line on the AVR, inlined elsewhere: absent is fine.
    let own_fn = syms
        .entry_of("planner_core::eapf::Planner::step_raw")
        .unwrap_or(u32::MAX);
    let arith = ["__mulsi3", "__udivmodsi4"].map(|f| {
        syms.entry_of(f)
            .unwrap_or_else(|| panic!("no {f} in {elf:?}"))
    });
    let mut sim = Sim::new(elf, entry, own_fn, (arith[0], arith[1]));
    assert_eq!(sim.line(), "READY", "boot line");
    let mut step_cycles = Vec::new();
    let mut mismatches = 0;
    for t in traces {
        sim.send(format!("R {} {}\n", t.goal.x, t.goal.y).as_bytes());
        assert_eq!(sim.line(), "OK", "enter replay");
        for (f, want) in t.frames.iter().zip(&t.outputs) {
            sim.send(&replay_frame(f));
            let r = sim.take(REPLAY_ANSWER_LEN);
            let got = replay_answer(&r).expect("replay answer");
            mismatches += usize::from(got.answer != *want);
            step_cycles.push(got.cycles);
        }
        sim.send(&[0x00]);
        assert_eq!(sim.line(), "OK", "leave replay");
    }
    let mut inner: HashMap<String, u64> = HashMap::new();
    for (a, c) in &sim.hist {
        *inner.entry(syms.name(*a)).or_default() += c;
    }
    let by_callee = |m: &HashMap<u32, u64>| -> Vec<(String, u64)> {
        let mut out: HashMap<String, u64> = HashMap::new();
        for (a, c) in m {
            let name = if *a == 0 {
                OWN_CODE.to_string()
            } else {
                syms.name(*a)
            };
            *out.entry(name).or_default() += c;
        }
        sorted(out)
    };
    Profile {
        steps: sim.steps,
        cycles: sim.hist.values().sum(),
        step_cycles,
        step_counted: sim.counted,
        by_function: sorted(inner),
        by_address: {
            let mut v: Vec<(u32, String, u64)> = sim
                .hist
                .iter()
                .map(|(a, c)| (*a, syms.name(*a), *c))
                .collect();
            v.sort_by(|a, b| b.2.cmp(&a.2).then(a.0.cmp(&b.0)));
            v
        },
        by_callee: by_callee(&sim.by_callee),
        worst: (sim.worst_step.0, by_callee(&sim.worst_step.1)),
        mismatches,
        unbalanced: sim.unbalanced,
        operands: sim.operands,
    }
}

/// The ELF's function symbols, demangled, by address.
struct Symbols(Vec<(u32, u32, String)>);

/// The code symbols (`t`, `T`) of an AVR ELF: (address, size, demangled
/// name without its hash), sorted by address, from `avr-nm`.
pub fn text_symbols(elf: &std::path::Path) -> Vec<(u32, u32, String)> {
    let out = Command::new("avr-nm")
        .args(["-S", "--defined-only"])
        .arg(elf)
        .output()
        .expect("avr-nm (Debian binutils-avr)");
    let mut v: Vec<(u32, u32, String)> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter_map(|l| {
            let mut f = l.splitn(4, ' ');
            let a = u32::from_str_radix(f.next()?, 16).ok()?;
            let size = u32::from_str_radix(f.next()?, 16).ok()?;
            let kind = f.next()?;
            let name = format!("{:#}", rustc_demangle::demangle(f.next()?));
            (kind == "t" || kind == "T").then_some((a, size, name))
        })
        .collect();
    v.sort();
    v
}

impl Symbols {
    fn of(elf: &std::path::Path) -> Symbols {
        let v = text_symbols(elf)
            .into_iter()
            .map(|(a, size, name)| (a, size, short(&name)))
            .collect();
        Symbols(v)
    }

    /// The address of the function named `name`.
    fn entry_of(&self, name: &str) -> Option<u32> {
        self.0.iter().find(|s| s.2 == name).map(|s| s.0)
    }

    fn name(&self, a: u32) -> String {
        let i = self.0.partition_point(|s| s.0 <= a);
        match i.checked_sub(1).map(|i| &self.0[i]) {
            Some((start, size, name)) if a < start + size.max(&2) => name.clone(),
            _ => format!("0x{a:x}"),
        }
    }
}

/// The firmware in simavr driven directly, for what avr-tester does not
/// give: a reset (the power cycle of a board that keeps its EEPROM) and the
/// EEPROM's bytes.
pub struct Bare(Sim);

impl Bare {
    /// Boot `elf` until its first line; its ADC's AVCC at 5 V.
    pub fn boot(elf: &Path) -> (Bare, String) {
        let mut sim = Sim::new(elf, u32::MAX, u32::MAX, (u32::MAX, u32::MAX));
        unsafe { (*sim.avr).avcc = 5_000 };
        let first = sim.line();
        (Bare(sim), first)
    }

    /// Reset the MCU (RAM and registers, not flash or EEPROM), as a power
    /// cycle does; its first line.
    pub fn reset(&mut self) -> String {
        unsafe { ffi::avr_reset(self.0.avr) };
        self.0.rx.clear();
        self.0.line()
    }

    /// Send `line` (and `\n`); the reply line, past telemetry (`T …`).
    pub fn request(&mut self, line: &str) -> String {
        self.0.send(format!("{line}\n").as_bytes());
        loop {
            let l = self.0.line();
            if !l.starts_with("T ") {
                return l;
            }
        }
    }

    /// The next line the firmware sends.
    pub fn line(&mut self) -> String {
        self.0.line()
    }

    /// Put `mv` millivolts on analog input `channel`.
    pub fn set_adc_mv(&mut self, channel: u32, mv: u32) {
        let adc = u32::from_be_bytes([b'a', b'd', b'c', b'0']);
        unsafe {
            let irq = ffi::avr_io_getirq(self.0.avr, adc, (ffi::ADC_IRQ_ADC0 + channel) as i32);
            ffi::avr_raise_irq(irq, mv);
        }
    }

    /// Run for `us` microseconds of the firmware's time.
    pub fn run_us(&mut self, us: u64) {
        let until = unsafe { (*self.0.avr).cycle } + us * (F_CPU as u64 / 1_000_000);
        while unsafe { (*self.0.avr).cycle } < until {
            self.0.one();
        }
    }

    /// The EEPROM's bytes from `at`, `len` of them, or put `bytes` there.
    pub fn eeprom(&mut self, at: u16, len: usize, put: Option<&[u8]>) -> Vec<u8> {
        let get = u32::from_be_bytes([b'e', b'e', b'g', b'p']);
        let set = u32::from_be_bytes([b'e', b'e', b's', b'p']);
        let mut out = vec![0u8; len];
        unsafe {
            if let Some(bytes) = put {
                let mut d = ffi::avr_eeprom_desc_t {
                    ee: bytes.as_ptr() as *mut u8,
                    offset: at,
                    size: bytes.len() as u32,
                };
                ffi::avr_ioctl(self.0.avr, set, &mut d as *mut _ as *mut _);
            }
            let mut d = ffi::avr_eeprom_desc_t {
                ee: std::ptr::null_mut(),
                offset: at,
                size: len as u32,
            };
            ffi::avr_ioctl(self.0.avr, get, &mut d as *mut _ as *mut _);
            if !d.ee.is_null() {
                std::ptr::copy_nonoverlapping(d.ee, out.as_mut_ptr(), len);
            }
        }
        out
    }
}
