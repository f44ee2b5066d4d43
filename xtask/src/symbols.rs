//! `cargo xtask size --symbols <device | image.elf> [count]`: where an image's flash goes, from
//! its symbol table: the largest functions and constants, and the flash per module.
//!
//! With LTO most code is inlined into few functions (a board's `main` holds most of the node),
//! so a module's figure counts only the functions that kept a symbol of their own; inlined
//! code counts in its caller.

use crate::elf::Symbol;
use crate::{Result, root};
use std::collections::BTreeMap;
use std::path::PathBuf;

/// Prints the report for the size-probe image of a device, or for an ELF file.
pub fn report(args: &[String]) -> Result {
    let Some(what) = args.first() else {
        return Err(format!("usage: cargo xtask size --symbols <{} | path/to/image.elf> [count]", crate::size::DEVICES.join(" | ")));
    };
    let count = match args.get(1) {
        Some(n) => n.parse().map_err(|_| format!("not a count: {n}"))?,
        None => 40,
    };
    let elf = if crate::size::DEVICES.contains(&what.as_str()) {
        crate::size::build_probes()?;
        crate::size::probe_elf(what)
    } else {
        let path = PathBuf::from(what);
        if path.is_absolute() { path } else { root().join(path) }
    };
    let bytes = std::fs::read(&elf).map_err(|e| format!("cannot read {}: {e}", elf.display()))?;
    let symbols = crate::elf::symbols(&bytes).map_err(|e| format!("{}: {e}", elf.display()))?;
    for line in table(&symbols, count).lines() {
        println!("xtask: {line}");
    }
    Ok(())
}

/// Whether a symbol costs flash (code or constants) rather than RAM alone.
fn in_flash(s: &Symbol) -> bool {
    !matches!(s.section.as_str(), ".bss" | ".uninit")
}

/// The `count` largest symbols, then the flash per module, as text lines.
fn table(symbols: &[Symbol], count: usize) -> String {
    let mut sorted: Vec<&Symbol> = symbols.iter().collect();
    sorted.sort_by(|a, b| b.size.cmp(&a.size).then_with(|| a.name.cmp(&b.name)));
    let flash: u64 = symbols.iter().filter(|s| in_flash(s)).map(|s| u64::from(s.size)).sum();
    let mut out = format!("the {count} largest symbols ({flash} bytes of flash in symbols):\n");
    for s in sorted.iter().take(count) {
        out.push_str(&format!("{:>7}  {:<8} {}\n", s.size, s.section, demangle(&s.name)));
    }
    let mut modules: BTreeMap<String, (u64, u64)> = BTreeMap::new();
    for s in symbols.iter().filter(|s| in_flash(s)) {
        let m = modules.entry(module(&demangle(&s.name))).or_default();
        if s.section == ".text" {
            m.0 += u64::from(s.size);
        } else {
            m.1 += u64::from(s.size);
        }
    }
    let mut modules: Vec<(String, (u64, u64))> = modules.into_iter().collect();
    modules.sort_by(|a, b| (b.1.0 + b.1.1).cmp(&(a.1.0 + a.1.1)).then_with(|| a.0.cmp(&b.0)));
    out.push_str(&format!("flash per module (code, constants; inlined code counts in its caller):\n{:>7} {:>7}  module\n", "code", "const"));
    for (name, (text, rodata)) in modules {
        out.push_str(&format!("{text:>7} {rodata:>7}  {name}\n"));
    }
    out
}

/// The module a demangled symbol belongs to: its first two path segments (of the type, for
/// `<T as Trait>::f`), without generic arguments.
fn module(name: &str) -> String {
    let path = match name.strip_prefix('<') {
        Some(rest) => rest.split(" as ").next().unwrap_or(rest).trim_start_matches(['&', '*']),
        None => name,
    };
    let plain = strip_generics(path);
    let segments: Vec<&str> = plain.split("::").filter(|s| !s.is_empty()).collect();
    match segments.as_slice() {
        [] | [_] => "(no module: runtime and C symbols)".to_string(),
        [krate, module, ..] if segments.len() > 2 => format!("{krate}::{module}"),
        [krate, ..] => (*krate).to_string(),
    }
}

fn strip_generics(path: &str) -> String {
    let mut depth = 0_u32;
    path.chars()
        .filter(|&c| {
            match c {
                '<' => depth += 1,
                '>' => depth = depth.saturating_sub(1),
                _ => return depth == 0,
            }
            false
        })
        .collect()
}

/// Demangles a Rust symbol: legacy (`_ZN...E`, what rustc emits by default) in full, v0
/// (`_R...`, the precompiled `compiler_builtins`) to its plain path; anything else is
/// returned as it is.
pub fn demangle(symbol: &str) -> String {
    let symbol = symbol.split(".llvm.").next().unwrap_or(symbol);
    if let Some(v0) = symbol.strip_prefix("_R") {
        return demangle_v0(v0).unwrap_or_else(|| symbol.to_string());
    }
    let Some(rest) = symbol.strip_prefix("_ZN") else { return symbol.to_string() };
    let (mut segments, rest) = idents(rest, false);
    if rest != "E" || segments.is_empty() {
        return symbol.to_string();
    }
    // The last segment is the hash (`h` and 16 hex digits).
    if segments.last().is_some_and(|h| h.len() == 17 && h.starts_with('h') && h[1..].chars().all(|c| c.is_ascii_hexdigit())) {
        segments.pop();
    }
    segments.iter().map(|s| unescape(s)).collect::<Vec<_>>().join("::")
}

/// The length-prefixed identifiers at the start of `s`, and what follows them; `v0`: an
/// identifier may have a `_` between its length and itself.
fn idents(mut s: &str, v0: bool) -> (Vec<&str>, &str) {
    let mut out = Vec::new();
    while let Some(digits) = s.find(|c: char| !c.is_ascii_digit()).filter(|&n| n > 0) {
        let Ok(len) = s[..digits].parse::<usize>() else { break };
        // v0 separates an identifier that starts with a digit or `_` by one `_`.
        let start = if v0 && s[digits..].starts_with('_') { digits + 1 } else { digits };
        let Some(ident) = s.get(start..start + len) else { break };
        out.push(ident);
        s = &s[start + len..];
    }
    (out, s)
}

/// The path of a v0 symbol whose tags are all nested paths (`Nv`, `Nt`...) around a crate root
/// (`C`, an optional `s<hash>_` disambiguator, the crate name): the common case of free
/// functions and statics. `None` for anything more involved.
fn demangle_v0(s: &str) -> Option<String> {
    let root = s.trim_start_matches(|c: char| c == 'N' || c.is_ascii_lowercase()).strip_prefix('C')?;
    let root = match root.strip_prefix('s') {
        Some(hashed) => &hashed[hashed.find('_')? + 1..],
        None => root,
    };
    let (segments, rest) = idents(root, true);
    (rest.is_empty() && !segments.is_empty()).then(|| segments.join("::"))
}

/// Undoes the escapes of a legacy symbol segment (`$LT$` for `<`, `..` for `::`...).
fn unescape(segment: &str) -> String {
    const ESCAPES: [(&str, &str); 11] = [
        ("$LT$", "<"),
        ("$GT$", ">"),
        ("$RF$", "&"),
        ("$BP$", "*"),
        ("$SP$", "@"),
        ("$LP$", "("),
        ("$RP$", ")"),
        ("$C$", ","),
        ("..", "::"),
        ("$u20$", " "),
        ("$u27$", "'"),
    ];
    let mut s = segment.strip_prefix("_$").map_or_else(|| segment.to_string(), |r| format!("${r}"));
    for (from, to) in ESCAPES {
        s = s.replace(from, to);
    }
    // Any other character as `$uXX$`.
    while let Some(at) = s.find("$u") {
        let Some(end) = s[at + 2..].find('$') else { break };
        let Some(c) = u32::from_str_radix(&s[at + 2..at + 2 + end], 16).ok().and_then(char::from_u32) else { break };
        s.replace_range(at..at + 3 + end, &c.to_string());
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn legacy_symbols_demangle_and_group_by_module() {
        let field = "_ZN84_$LT$co401gw1..Od$LT$A$GT$$u20$as$u20$coforge_stack..od..dictionary..EntryAccess$GT$5field17h6afde475acc12fd1E";
        assert_eq!(demangle(field), "<co401gw1::Od<A> as coforge_stack::od::dictionary::EntryAccess>::field");
        assert_eq!(module(&demangle(field)), "co401gw1");
        let table = "_ZN8co401gw12od15ENTRIES_DIGITAL17hd0aa0d74ae45eed7E";
        assert_eq!(demangle(table), "co401gw1::od::ENTRIES_DIGITAL");
        assert_eq!(module(&demangle(table)), "co401gw1::od");
        let closure = "_ZN8co401gw118__cortex_m_rt_main28_$u7b$$u7b$closure$u7d$$u7d$3VAR17hf79cc4d5444a0230E";
        assert_eq!(demangle(closure), "co401gw1::__cortex_m_rt_main::{{closure}}::VAR");
        assert_eq!(demangle("__aeabi_memcpy"), "__aeabi_memcpy");
        assert_eq!(demangle("_RNvNtCsjc7sn2q0iDy_17compiler_builtins3mem6memcpy"), "compiler_builtins::mem::memcpy");
        let div = "_RNvNtNtCsjc7sn2q0iDy_17compiler_builtins3int19specialized_div_rem11u32_div_rem.llvm.5864861550599870333";
        assert_eq!(demangle(div), "compiler_builtins::int::specialized_div_rem::u32_div_rem");
        assert_eq!(module("__aeabi_memcpy"), "(no module: runtime and C symbols)");
        assert_eq!(module("coforge_stack::node::Core<D,S,_>::send"), "coforge_stack::node");
    }
}
