//! Where the AVR image's flash goes (`cargo xtask avr-size`): the image's
//! code symbols ([`crate::profile::text_symbols`]) summed by part, so that
//! the flash budget's miss can be read by what fills the image: the
//! planner's own functions and its step (inlined into the firmware's timed
//! span) against the firmware's drivers, formatting and runtime.

/// The parts, in the order [`parts`] gives them.
pub const PARTS: [&str; 9] = [
    "planner-core's functions",
    "the planner step, inlined into firmware_avr::timed::step",
    "the firmware's main loop (executor, odometry, protocol, telemetry inlined)",
    "the configuration, in program memory",
    "the firmware's drivers",
    "ufmt (telemetry text)",
    "interrupt handlers",
    "libgcc, avr-libc and the firmware's assembly (multiply, division, start-up)",
    "core and heapless",
];

/// The part a code symbol (demangled, generic arguments kept) belongs to:
/// one of [`PARTS`]. A generic function of `core` or `heapless` made for
/// the planner's types counts as the planner's (it is there because of it).
pub fn part_of(name: &str) -> &'static str {
    let i = if name == "firmware_avr::timed::step" {
        1
    } else if name.starts_with("firmware_avr::__avr_device_rt_main") {
        2
    } else if name.contains("progmem::CONFIG") {
        3
    } else if name.starts_with("__vector") {
        6
    } else if name.contains("planner_core") {
        0
    } else if name.contains("ufmt") {
        5
    } else if name.contains("firmware_avr") {
        4
    } else if name.starts_with("__") || name.starts_with("mem") {
        7
    } else {
        8
    };
    PARTS[i]
}

/// Bytes per part of `symbols` ((address, size, name) as
/// [`crate::profile::text_symbols`] gives them), in [`PARTS`] order.
pub fn parts(symbols: &[(u32, u32, String)]) -> Vec<(&'static str, u32)> {
    PARTS
        .iter()
        .map(|&p| {
            let bytes = symbols
                .iter()
                .filter(|(_, _, name)| part_of(name) == p)
                .map(|&(_, size, _)| size)
                .sum();
            (p, bytes)
        })
        .collect()
}

/// The module of planner-core a symbol of its part is in: the path segment
/// after the first `planner_core::` in its name, or within a layer's folder
/// the one after that (`escape` for `planner_core::eapf::escape::…`,
/// `Planner` for the product planner's own methods).
pub fn planner_module(name: &str) -> Option<&str> {
    let segment = |rest: &str| {
        let end = rest
            .find(|c: char| !(c.is_alphanumeric() || c == '_'))
            .unwrap_or(rest.len());
        (end, rest.len() > end + 1 && rest[end..].starts_with("::"))
    };
    let rest = &name[name.find("planner_core::")? + "planner_core::".len()..];
    let (end, more) = segment(rest);
    // A layer's folder (`eapf::escape`): the module within it.
    if more && ["eapf", "maps", "peers", "rover"].contains(&&rest[..end]) {
        let inner = &rest[end + 2..];
        return Some(&inner[..segment(inner).0]);
    }
    Some(&rest[..end])
}

/// Bytes of planner-core's functions (the first of [`PARTS`]) per module,
/// largest first.
pub fn planner_modules(symbols: &[(u32, u32, String)]) -> Vec<(String, u32)> {
    let mut by: Vec<(String, u32)> = Vec::new();
    for (_, size, name) in symbols {
        if part_of(name) != PARTS[0] {
            continue;
        }
        let m = planner_module(name).unwrap_or("?");
        match by.iter_mut().find(|(k, _)| k == m) {
            Some((_, b)) => *b += size,
            None => by.push((m.to_string(), *size)),
        }
    }
    by.sort_by(|a, b| b.1.cmp(&a.1).then_with(|| a.0.cmp(&b.0)));
    by
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn symbols_go_to_their_parts() {
        let cases = [
            ("firmware_avr::timed::step", 1),
            ("firmware_avr::__avr_device_rt_main", 2),
            ("firmware_avr::progmem::CONFIG::VALUE", 3),
            ("__vector_21", 6),
            ("<planner_core::eapf::escape::Escape>::force", 0),
            (
                "<core::array::iter::IntoIter<&planner_core::eapf::sensors::Reading, 3> as core::iter::traits::iterator::Iterator>::position::<planner_core::eapf::follow::side_of::{closure#0}>",
                0,
            ),
            (
                "<i32 as ufmt::uDebug>::fmt::<firmware_avr::serial::Serial>",
                5,
            ),
            ("firmware_avr::motors::set", 4),
            ("__mulsi3", 7),
            ("memcpy", 7),
            ("<core::ops::index_range::IndexRange as core::iter::traits::iterator::Iterator>::next", 8),
        ];
        for (name, part) in cases {
            assert_eq!(part_of(name), PARTS[part], "{name}");
        }
        let syms = vec![
            (0, 10, "__mulsi3".to_string()),
            (10, 30, "planner_core::fixed::isqrt".to_string()),
            (40, 5, "__divmodhi4".to_string()),
        ];
        let got = parts(&syms);
        assert_eq!(got[0], (PARTS[0], 30));
        assert_eq!(got[7], (PARTS[7], 15));
        assert_eq!(got.iter().map(|p| p.1).sum::<u32>(), 45);
    }

    #[test]
    fn planner_symbols_go_to_their_modules() {
        assert_eq!(
            planner_module("<planner_core::eapf::escape::Escape>::force"),
            Some("escape")
        );
        assert_eq!(planner_module("planner_core::fixed::isqrt"), Some("fixed"));
        assert_eq!(
            planner_module("<planner_core::eapf::Planner>::set_goal"),
            Some("Planner")
        );
        assert_eq!(planner_module("planner_core::eapf"), Some("eapf"));
        assert_eq!(
            planner_module(
                "<core::array::iter::IntoIter<&planner_core::eapf::sensors::Reading, 3>>::next"
            ),
            Some("sensors")
        );
        assert_eq!(planner_module("__mulsi3"), None);
        let syms: Vec<(u32, u32, String)> = [
            (4, "<planner_core::eapf::escape::Escape>::force"),
            (9, "planner_core::fixed::isqrt"),
            (3, "planner_core::eapf::escape::reach_mm"),
            (50, "firmware_avr::timed::step"),
        ]
        .iter()
        .map(|&(size, name)| (0, size, name.to_string()))
        .collect();
        assert_eq!(
            planner_modules(&syms),
            [("fixed".to_string(), 9), ("escape".to_string(), 7)]
        );
    }
}
