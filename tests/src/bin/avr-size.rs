//! `cargo xtask avr-size [--set-back]`: where the ATmega328P image's flash
//! goes, by part (`rover_tests::flash`), from the ELF built now.

use rover_tests::avr::{elf_size, firmware_elf, set_back_firmware_elf};
use rover_tests::flash::{parts, planner_modules};
use rover_tests::profile::text_symbols;

fn main() {
    let set_back = std::env::args().any(|a| a == "--set-back");
    let elf = if set_back {
        set_back_firmware_elf()
    } else {
        firmware_elf()
    };
    let (text, data, _) = elf_size(&elf);
    let symbols = text_symbols(&elf);
    let parts = parts(&symbols);
    let counted: u32 = parts.iter().map(|p| p.1).sum();
    let build = if set_back { " (set-back)" } else { "" };
    println!("avr flash{build}: text={text} data={data}, by part:");
    for (part, bytes) in &parts {
        println!("{bytes:>7}  {part}");
    }
    println!(
        "{:>7}  in no symbol (the vector table, alignment)",
        text.saturating_sub(counted)
    );
    println!(
        "{:>7}  the planner in all (its functions and its inlined step)",
        parts[0].1 + parts[1].1
    );
    println!("planner-core's functions by module (its inlined step not included):");
    for (module, bytes) in planner_modules(&symbols) {
        println!("{bytes:>7}  {module}");
    }
}
