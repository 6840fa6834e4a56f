//! The AVR firmware's worst stack depth, worked out from its image: every
//! function's own use (its pushes and the frame its prologue allocates) and
//! the calls between them, read from `avr-objdump -d`.
//!
//! Stack painting (`firmware-avr/src/stack.rs`) measures the deepest point
//! the runs reached; this bounds what any run can reach. It holds because
//! the image has no indirect call or jump (LLVM's AVR code has none unless
//! the source uses function pointers or trait objects) and no recursion:
//! both are refused, as then the graph would not show every path. An
//! interrupt adds its handler's worst depth on top of the deepest point of
//! `main` once: on the AVR an interrupt clears the I flag and the handlers
//! never set it again (a handler that does is refused too).

use std::collections::HashMap;
use std::path::Path;
use std::process::Command as Cmd;

/// Bytes a `call`, `rcall` or interrupt pushes on the ATmega328P (a 16-bit
/// program counter).
const RETURN_ADDRESS: u32 = 2;

/// A function of the image: where it starts and its instructions
/// (address, mnemonic, operands).
struct Function {
    name: String,
    start: u32,
    code: Vec<(u32, String, String)>,
}

/// The worst stack depth: bytes, and the deepest chain of calls from
/// `main` and the interrupt handler whose depth is added to it.
#[derive(Debug)]
pub struct StackBound {
    /// The bound, bytes below the top of RAM.
    pub bytes: u32,
    /// The deepest chain from `main` (demangled names).
    pub path: Vec<String>,
    /// The deepest interrupt handler, and its depth with its callees.
    pub interrupt: (String, u32),
}

/// The stack bound of the AVR image `elf`, or why the call graph cannot
/// give one.
pub fn stack_bound(elf: &Path) -> Result<StackBound, String> {
    let out = Cmd::new("avr-objdump")
        .args(["-d", "--no-show-raw-insn"])
        .arg(elf)
        .output()
        .expect("avr-objdump (Debian binutils-avr)");
    assert!(out.status.success(), "avr-objdump failed on {elf:?}");
    Graph::parse(&String::from_utf8_lossy(&out.stdout)).bound()
}

struct Graph {
    functions: Vec<Function>,
    by_name: HashMap<String, usize>,
}

/// `0x1f` or `31` as a number.
fn number(s: &str) -> Option<u32> {
    let s = s.split(';').next()?.trim();
    match s.strip_prefix("0x") {
        Some(hex) => u32::from_str_radix(hex, 16).ok(),
        None => s.parse().ok(),
    }
}

impl Graph {
    fn parse(listing: &str) -> Graph {
        let mut functions: Vec<Function> = Vec::new();
        for line in listing.lines() {
            // `000021ac <name>:` opens a function.
            if let Some((addr, rest)) = line.split_once(" <") {
                if let (Ok(start), Some(name)) =
                    (u32::from_str_radix(addr, 16), rest.strip_suffix(">:"))
                {
                    functions.push(Function {
                        name: name.to_string(),
                        start,
                        code: Vec::new(),
                    });
                    continue;
                }
            }
            // `    21ac:\tpush\tr2` is an instruction of the last one.
            let Some((addr, rest)) = line.trim_start().split_once(":\t") else {
                continue;
            };
            let (Ok(addr), Some(f)) = (u32::from_str_radix(addr, 16), functions.last_mut()) else {
                continue;
            };
            let mut parts = rest.splitn(2, '\t');
            let op = parts.next().unwrap_or("").trim().to_string();
            let args = parts.next().unwrap_or("").trim().to_string();
            f.code.push((addr, op, args));
        }
        functions.sort_by_key(|f| f.start);
        let by_name = functions
            .iter()
            .enumerate()
            .map(|(i, f)| (f.name.clone(), i))
            .collect();
        Graph { functions, by_name }
    }

    /// The function whose code holds `addr`.
    fn containing(&self, addr: u32) -> Option<usize> {
        let i = self.functions.partition_point(|f| f.start <= addr);
        i.checked_sub(1)
    }

    /// A function's own stack: its pushes (all of them, wherever they
    /// are) and the frame its prologue takes from the stack pointer
    /// (`in r28, 0x3d; in r29, 0x3e;` then `sbiw r28, n` or `subi r28,
    /// lo; sbci r29, hi`).
    fn own(&self, i: usize) -> u32 {
        let code = &self.functions[i].code;
        let pushes = code.iter().filter(|(_, op, _)| op == "push").count() as u32;
        let arg = |k: usize, op: &str, reg: &str| {
            code.get(k)
                .filter(|(_, o, a)| o == op && a.starts_with(reg))
                .and_then(|(_, _, a)| number(a.split_once(',')?.1))
        };
        let frame = code
            .iter()
            .position(|(_, op, a)| op == "in" && a.starts_with("r28, 0x3d"))
            .map_or(0, |k| {
                arg(k + 2, "sbiw", "r28")
                    .or_else(|| {
                        let lo = arg(k + 2, "subi", "r28")?;
                        Some(lo + 256 * arg(k + 3, "sbci", "r29").unwrap_or(0))
                    })
                    .unwrap_or(0)
            });
        pushes + frame
    }

    /// The functions `i` calls (true) or jumps into (false).
    fn callees(&self, i: usize) -> Result<Vec<(usize, bool)>, String> {
        let f = &self.functions[i];
        let mut out = Vec::new();
        for (addr, op, args) in &f.code {
            if matches!(op.as_str(), "icall" | "ijmp" | "eicall" | "eijmp") {
                return Err(format!("{op} at {addr:#x} in {}", f.name));
            }
            let call = matches!(op.as_str(), "call" | "rcall");
            if !call && !matches!(op.as_str(), "jmp" | "rjmp") {
                continue;
            }
            // The target is the address after `;`: `rcall .+12 ; 0x2b8 <f>`.
            let Some(target) = args
                .split_once(';')
                .and_then(|(_, t)| t.split_whitespace().next())
                .and_then(number)
            else {
                continue;
            };
            match self.containing(target) {
                Some(t) if t != i => out.push((t, call)),
                Some(_) if call => return Err(format!("{} calls itself", f.name)),
                _ => {}
            }
        }
        Ok(out)
    }

    /// The deepest stack from entering `i`: its own and its deepest callee
    /// (plus the return address of a call), with the chain.
    fn worst(
        &self,
        i: usize,
        on_path: &mut Vec<usize>,
        memo: &mut HashMap<usize, (u32, Vec<usize>)>,
    ) -> Result<(u32, Vec<usize>), String> {
        if let Some(w) = memo.get(&i) {
            return Ok(w.clone());
        }
        if on_path.contains(&i) {
            return Err(format!("recursion through {}", self.functions[i].name));
        }
        on_path.push(i);
        let mut deepest = (0, Vec::new());
        for (c, call) in self.callees(i)? {
            let (d, chain) = self.worst(c, on_path, memo)?;
            let d = d + if call { RETURN_ADDRESS } else { 0 };
            if d > deepest.0 {
                deepest = (d, chain);
            }
        }
        on_path.pop();
        let mut chain = vec![i];
        chain.extend(deepest.1);
        let w = (self.own(i) + deepest.0, chain);
        memo.insert(i, w.clone());
        Ok(w)
    }

    /// Every function `i` may run, itself included.
    fn reachable(&self, i: usize) -> Result<Vec<usize>, String> {
        let (mut seen, mut todo) = (vec![i], vec![i]);
        while let Some(f) = todo.pop() {
            for (c, _) in self.callees(f)? {
                if !seen.contains(&c) {
                    seen.push(c);
                    todo.push(c);
                }
            }
        }
        Ok(seen)
    }

    fn bound(&self) -> Result<StackBound, String> {
        let entry = *self.by_name.get("main").ok_or("no `main` in the image")?;
        let mut memo = HashMap::new();
        let (main, chain) = self.worst(entry, &mut Vec::new(), &mut memo)?;
        let mut interrupt = (String::new(), 0);
        for (i, f) in self.functions.iter().enumerate() {
            if !f.name.starts_with("__vector_") {
                continue;
            }
            let (d, _) = self.worst(i, &mut Vec::new(), &mut memo)?;
            if let Some(s) = self
                .reachable(i)?
                .into_iter()
                .find(|&c| self.functions[c].code.iter().any(|(_, op, _)| op == "sei"))
            {
                return Err(format!(
                    "{} enables interrupts in {}: they may nest",
                    f.name, self.functions[s].name
                ));
            }
            if d > interrupt.1 {
                interrupt = (f.name.clone(), d);
            }
        }
        let name = |i: &usize| format!("{:#}", rustc_demangle::demangle(&self.functions[*i].name));
        Ok(StackBound {
            // The start-up code calls `main`; an interrupt pushes its
            // return address, then its handler's own.
            bytes: RETURN_ADDRESS + main + RETURN_ADDRESS + interrupt.1,
            path: chain.iter().map(name).collect(),
            interrupt,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A made-up listing: `main` calls `a` (6 pushes, a frame of 0x20)
    /// and jumps to `b` (2 pushes); `a` calls `c` (a leaf); one interrupt
    /// handler of 3 pushes.
    const LISTING: &str = "\
00000100 <main>:
     100:\tcall\t0x200\t; 0x200 <a>
     104:\tjmp\t0x300\t; 0x300 <b>

00000200 <a>:
     200:\tpush\tr16
     202:\tpush\tr17
     204:\tpush\tr28
     206:\tpush\tr29
     208:\tpush\tr14
     20a:\tpush\tr15
     20c:\tin\tr28, 0x3d\t; 61
     20e:\tin\tr29, 0x3e\t; 62
     210:\tsbiw\tr28, 0x20\t; 32
     212:\trcall\t.+92     \t; 0x270 <c>
     214:\tbrne\t.-4     \t; 0x212 <a+0x12>
     216:\tret

00000270 <c>:
     270:\tret

00000300 <b>:
     300:\tpush\tr2
     302:\tpush\tr3
     304:\tret

00000400 <__vector_1>:
     400:\tpush\tr0
     402:\tpush\tr1
     404:\tpush\tr24
     406:\treti
";

    #[test]
    fn the_bound_of_a_listing_by_hand() {
        let b = Graph::parse(LISTING).bound().unwrap();
        // Start-up's call 2, main's call 2, a's 6 + 32, c's call 2, then
        // an interrupt's 2 and its handler's 3.
        assert_eq!(b.bytes, 2 + 2 + 38 + 2 + 2 + 3);
        assert_eq!(b.path, ["main", "a", "c"]);
        assert_eq!(b.interrupt, ("__vector_1".to_string(), 3));
    }

    #[test]
    fn a_large_frame_counts_both_bytes() {
        let listing = LISTING.replace(
            "     210:\tsbiw\tr28, 0x20\t; 32\n",
            "     210:\tsubi\tr28, 0x99\t; 153\n     211:\tsbci\tr29, 0x04\t; 4\n",
        );
        let b = Graph::parse(&listing).bound().unwrap();
        assert_eq!(b.bytes, 2 + 2 + 6 + 0x499 + 2 + 2 + 3);
    }

    #[test]
    fn what_the_graph_cannot_bound_is_refused() {
        let indirect = LISTING.replace("     270:\tret", "     270:\ticall");
        assert!(Graph::parse(&indirect).bound().is_err());
        let recursive = LISTING.replace("0x270 <c>", "0x200 <a>");
        assert!(Graph::parse(&recursive).bound().is_err());
        let nesting = LISTING.replace("     404:\tpush\tr24", "     404:\tsei");
        assert!(Graph::parse(&nesting).bound().is_err());
        // The handler calls `a` (its deepest chain) and a shallow function
        // that enables interrupts, off that chain.
        let nesting_below = LISTING.replace(
            "     406:\treti",
            "     406:\tcall\t0x200\t; 0x200 <a>\n     40a:\tcall\t0x500\t; 0x500 <e>\n     40e:\treti\n\n00000500 <e>:\n     500:\tsei\n     502:\tret",
        );
        assert!(Graph::parse(&nesting_below).bound().is_err());
    }
}
