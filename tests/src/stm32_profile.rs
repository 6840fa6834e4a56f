//! Where the STM32 firmware's planner step spends its instructions
//! (`cargo xtask stm32-profile`).
//!
//! Runs the `qemu` build (the traces of `cargo xtask stm32-report`) once
//! more in QEMU, one instruction per translation block with its address
//! logged (`-singlestep -d exec,nochain`), and charges every instruction
//! of a timed span to where it is. The spans are the firmware's own: each
//! lies between the return from one call of `emulated::stamp` (SysTick's
//! count) and the entry of the next; the first two are the empty span
//! that measures the reads' overhead and the calibration loop, the rest
//! are the steps. The Cortex-M4's image keeps its debug info, so an
//! instruction inlined into the step is named by the function it was
//! written in, and by the function the step's code called it under
//! (`addr2line`'s inlined frames), not only by the symbol it lands in.

use crate::stm32::{instructions, qemu_command, qemu_elf_with, run_traces_with};
use crate::{sorted, Trace};
use addr2line::Loader;
use std::collections::HashMap;
use std::io::{BufRead, BufReader};
use std::process::Stdio;

/// What [`profile`] found.
#[derive(Debug)]
pub struct Profile {
    /// Instructions of each step as counted here (the span less the empty
    /// span's), in replay order.
    pub counted: Vec<u32>,
    /// Each step's instructions as the firmware counted them (SysTick).
    pub timed: Vec<u32>,
    /// Steps whose answer differs from the host core's.
    pub mismatches: usize,
    /// Instructions of all steps by the symbol they are in, most first.
    pub by_symbol: Vec<(String, u64)>,
    /// Instructions of all steps by what the step called them under: the
    /// function `Planner::step_raw` called (inlined or not), or the step's
    /// own code. Most first.
    pub by_callee: Vec<(String, u64)>,
    /// Instructions of all steps by the function they were written in (the
    /// innermost inlined frame).
    pub by_source: Vec<(String, u64)>,
    /// The worst step's index and its split by what the step called.
    pub worst: (usize, Vec<(String, u64)>),
    /// The worst step by what the step called and, within that, the
    /// function the code was written in (`callee > source`).
    pub worst_detail: Vec<(String, u64)>,
}

/// The step's own code, in the tables.
pub const OWN_CODE: &str = "(the step's own code: step_raw and what is inlined)";

/// One logged instruction: its address and the symbol QEMU named.
fn parse(line: &str) -> Option<(u32, &str)> {
    // `Trace 0: 0x7f… [00800408/08000400/00000110/ff020201] Reset`
    let open = line.find('[')?;
    let fields = line.get(open + 1..)?;
    let pc = fields.split('/').nth(1)?;
    let sym = line.get(line.find("] ")? + 2..)?.trim_end();
    Some((u32::from_str_radix(pc, 16).ok()?, sym))
}

/// A function name without the legacy mangling's hash (`::h0123…`).
fn strip_hash(name: &str) -> &str {
    match name.rfind("::h") {
        Some(i) if name.len() - i == 19 => &name[..i],
        _ => name,
    }
}

/// Names for addresses, each worked out once.
struct Names {
    loader: Loader,
    /// Per address: the function it was written in, and the function
    /// `step_raw` called it under (`None`: the step's own code).
    cache: HashMap<u32, (String, Option<String>)>,
}

impl Names {
    fn of(&mut self, pc: u32) -> &(String, Option<String>) {
        let loader = &self.loader;
        self.cache.entry(pc).or_insert_with(|| {
            let mut chain = Vec::new();
            if let Ok(mut frames) = loader.find_frames(pc as u64) {
                while let Ok(Some(f)) = frames.next() {
                    let name = f
                        .function
                        .and_then(|n| n.demangle().ok().map(|n| strip_hash(&n).to_string()))
                        .unwrap_or_else(|| format!("{pc:#x}"));
                    chain.push(name);
                }
            }
            let source = chain.first().cloned().unwrap_or_else(|| format!("{pc:#x}"));
            let callee = chain
                .iter()
                .position(|n| n.ends_with("Planner::step_raw"))
                .and_then(|i| i.checked_sub(1))
                .map(|i| chain[i].clone());
            (source, callee)
        })
    }
}

/// Profile the planner step over `traces` (built into the `qemu` firmware
/// and replayed once to read the firmware's own counts, then once more
/// with QEMU's instruction log).
pub fn profile(traces: &[Trace]) -> Profile {
    profile_with(traces, false)
}

/// [`profile`] of the firmware built with the sensors on the rim, or
/// `set_back` behind it (its `set-back` feature; `traces` recorded alike).
pub fn profile_with(traces: &[Trace], set_back: bool) -> Profile {
    let run = run_traces_with(traces, set_back);
    let mismatches = run.mismatches(traces);
    let elf = qemu_elf_with(set_back);
    let log = elf.with_file_name("qemu-exec.log");
    // One instruction per translation block: `-singlestep` up to QEMU 8,
    // `one-insn-per-tb` from 8.1 on (where `-singlestep` went away).
    let logged = |one_per_tb: &[&str]| {
        qemu_command(&elf)
            .args(one_per_tb)
            .args(["-d", "exec,nochain", "-D"])
            .arg(&log)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status()
            .expect("qemu-system-arm")
            .success()
    };
    let ok = logged(&["-singlestep"]) || logged(&["-accel", "tcg,one-insn-per-tb=on"]);
    assert!(ok, "qemu with the instruction log failed");
    let mut names = Names {
        loader: Loader::new(&elf).expect("the qemu build's debug info"),
        cache: HashMap::new(),
    };

    // Each span as (address, symbol index, call site) per instruction: the
    // call site is the last address in the step's own function (`run`,
    // where the step is inlined) before a call out of it.
    let mut symbols: Vec<String> = Vec::new();
    let mut symbol_ids: HashMap<String, usize> = HashMap::new();
    let mut spans: Vec<Vec<(u32, usize, u32)>> = Vec::new();
    let (mut in_stamp, mut stamps) = (false, 0usize);
    let mut span: Option<Vec<(u32, usize, u32)>> = None;
    let mut site = 0u32;
    let reader = BufReader::new(std::fs::File::open(&log).expect("the instruction log"));
    for line in reader.lines() {
        let line = line.expect("read the instruction log");
        let Some((pc, sym)) = parse(&line) else {
            continue;
        };
        let stamp = sym.contains("emulated5stamp");
        if stamp && !in_stamp {
            // Entering: an odd entry closes its span.
            if stamps % 2 == 1 {
                spans.extend(span.take());
            }
            stamps += 1;
        } else if !stamp && in_stamp && stamps % 2 == 1 {
            // Returned from an even entry (counted from 0): a span opens.
            span = Some(Vec::new());
        }
        in_stamp = stamp;
        if let Some(s) = span.as_mut() {
            let id = match symbol_ids.get(sym) {
                Some(&id) => id,
                None => {
                    symbols.push(sym.to_string());
                    symbol_ids.insert(sym.to_string(), symbols.len() - 1);
                    symbols.len() - 1
                }
            };
            if sym.contains("emulated3run") {
                site = pc;
            }
            s.push((pc, id, site));
        }
    }
    let _ = std::fs::remove_file(&log);
    assert!(
        spans.len() >= 2,
        "the log holds the overhead and calibration spans"
    );
    let empty = spans[0].len() as u32;
    let steps = &spans[2..];

    let mut by_symbol = HashMap::new();
    let mut by_callee = HashMap::new();
    let mut by_source = HashMap::new();
    let mut counted = Vec::new();
    let mut worst = (0, HashMap::new(), HashMap::new());
    let mut worst_count = 0;
    for (i, s) in steps.iter().enumerate() {
        let mut here: HashMap<(u32, usize, u32), u64> = HashMap::new();
        for &k in s {
            *here.entry(k).or_insert(0) += 1;
        }
        let (mut this, mut detail) = (HashMap::new(), HashMap::new());
        for ((pc, id, site), count) in here {
            let sym = &symbols[id];
            let d = format!("{:#}", rustc_demangle::demangle(sym));
            let (source, callee) = names.of(pc).clone();
            let key = if sym.contains("emulated3run") {
                callee.unwrap_or_else(|| OWN_CODE.to_string())
            } else {
                // Out of line: charged to what the call site's code was
                // part of, or to the function called if the step's own
                // code called it.
                let site_callee = names.of(site).1.clone();
                site_callee.unwrap_or_else(|| strip_hash(&d).to_string())
            };
            *by_symbol.entry(strip_hash(&d).to_string()).or_insert(0u64) += count;
            *detail.entry(format!("{key} > {source}")).or_insert(0u64) += count;
            *by_source.entry(source).or_insert(0u64) += count;
            *this.entry(key).or_insert(0u64) += count;
        }
        let n = (s.len() as u32).saturating_sub(empty);
        counted.push(n);
        for (k, v) in &this {
            *by_callee.entry(k.clone()).or_insert(0u64) += v;
        }
        if n > worst_count {
            worst_count = n;
            worst = (i, this, detail);
        }
    }
    Profile {
        counted,
        timed: run.steps.iter().map(|&(_, t)| instructions(t)).collect(),
        mismatches,
        by_symbol: sorted(by_symbol),
        by_callee: sorted(by_callee),
        by_source: sorted(by_source),
        worst: (worst.0, sorted(worst.1)),
        worst_detail: sorted(worst.2),
    }
}
