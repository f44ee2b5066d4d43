//! `od::entries(mode)`: the sorted entry metadata table of each mode.

use crate::Options;
use crate::modes::Modes;
use coforge_spec::model::{Device, Entry, Object, Value, in_mode};
use coforge_spec::types::{DataType, NmtState, WriteWhen};
use proc_macro2::{Ident, Span, TokenStream};
use quote::{ToTokens, quote};

/// Value limits of an entry: (low, high, allowed values).
type LimitsKey = (Option<i64>, Option<i64>, Vec<i64>);

/// The most copies one run describes: what a PDO mapping cache entry has room for
/// (`coforge_stack::pdo::mapping::MAX_COPIES`); longer series of alike objects take more runs.
const MAX_COPIES: u8 = 31;

/// One `EntryInfo`: an entry, or a run of consecutive sub-entries that describe alike, in
/// `copies + 1` consecutive objects.
#[derive(Debug, Clone, PartialEq)]
struct Run {
    index: u16,
    sub: u8,
    last_sub: u8,
    copies: u8,
    meta: Meta,
}

impl Run {
    /// Describes the same sub-entries as `other`, whatever the object.
    fn alike(&self, other: &Run) -> bool {
        (self.sub, self.last_sub, &self.meta) == (other.sub, other.last_sub, &other.meta)
    }
}

/// Everything but the sub-index; equal metadata on consecutive subs forms a run.
#[derive(Debug, Clone, PartialEq)]
struct Meta {
    data_type: DataType,
    access: String,
    host_access: String,
    host_write_before_can_enabled: bool,
    pdo_mappable: bool,
    storage: String,
    writable_in: Option<Vec<NmtState>>,
    size: u16,
    limits: Option<LimitsKey>,
}

/// Bytes an entry holds; strings and domains: their maximum.
pub(crate) fn size_of(e: &Entry) -> u16 {
    let bytes = match (e.data_type.bits(), e.length, &e.default) {
        (Some(bits), _, _) => bits.div_ceil(8),
        (None, Some(len), _) => len,
        (None, None, Some(Value::Str(s))) => u32::try_from(s.len()).unwrap_or(u32::MAX),
        // A domain without a declared length: as much as a transfer brings.
        (None, None, _) => u32::from(u16::MAX),
    };
    u16::try_from(bytes).unwrap_or(u16::MAX)
}

fn meta(e: &Entry) -> Meta {
    let int = |v: &Option<Value>| v.as_ref().and_then(|v| v.int_for(1));
    let (low, high) = (int(&e.low), int(&e.high));
    let values = e.values.clone().unwrap_or_default();
    Meta {
        data_type: e.data_type,
        access: format!("{:?}", e.access),
        host_access: format!("{:?}", e.host_access),
        host_write_before_can_enabled: e.host_write_when == WriteWhen::BeforeCanEnabled,
        pdo_mappable: e.pdo_mapping,
        storage: format!("{:?}", e.storage),
        writable_in: e.writable_in.clone(),
        size: size_of(e),
        limits: (low.is_some() || high.is_some() || !values.is_empty()).then_some((low, high, values)),
    }
}

/// The runs of one object in one mode, sorted by sub.
fn object_runs(o: &Object, mode: Option<&str>) -> Vec<Run> {
    let mut entries: Vec<&Entry> = o.entries.iter().filter(|e| in_mode(&e.modes, mode)).collect();
    entries.sort_by_key(|e| e.sub);
    let mut out: Vec<Run> = Vec::new();
    for e in entries {
        let m = meta(e);
        match out.last_mut() {
            Some(last) if u16::from(last.last_sub) + 1 == u16::from(e.sub) && last.meta == m => last.last_sub = e.sub,
            _ => out.push(Run { index: o.index, sub: e.sub, last_sub: e.sub, copies: 0, meta: m }),
        }
    }
    out
}

/// The runs of one mode, sorted by (index, sub). An app-backed object described exactly like
/// the object at the index before it is not listed again: the earlier object's runs count it
/// as a copy (the field dispatch never sees copies, app objects get the index accessed).
fn runs(d: &Device, mode: Option<&str>) -> Vec<Run> {
    let mut out: Vec<Run> = Vec::new();
    // Where the runs of the last object listed start.
    let mut last_object = 0;
    for o in d.objects.iter().filter(|o: &&Object| in_mode(&o.modes, mode)) {
        let runs = object_runs(o, mode);
        let previous = out.get_mut(last_object..).unwrap_or_default();
        let repeats = previous.first().is_some_and(|p| u32::from(p.index) + u32::from(p.copies) + 1 == u32::from(o.index) && p.copies < MAX_COPIES)
            && runs.iter().all(|r| r.meta.storage == "App")
            && previous.len() == runs.len()
            && previous.iter().zip(&runs).all(|(p, r)| p.alike(r));
        if repeats {
            previous.iter_mut().for_each(|p| p.copies += 1);
        } else {
            last_object = out.len();
            out.extend(runs);
        }
    }
    out
}

fn ident(name: &str) -> Ident {
    Ident::new(name, Span::call_site())
}

fn run_tokens(r: &Run, offset: TokenStream, stack: &TokenStream, limits: &mut Vec<LimitsKey>) -> TokenStream {
    let Run { index, sub, last_sub, copies, meta: m } = r;
    let copies = crate::dec((*copies).into());
    let index = crate::hex((*index).into(), 4);
    let (sub, last_sub) = (crate::dec((*sub).into()), crate::dec((*last_sub).into()));
    let data_type = ident(&format!("{:?}", m.data_type));
    let access = ident(&m.access);
    let host_access = ident(&m.host_access);
    let storage = ident(&m.storage);
    let (before, pdo, size) = (&m.host_write_before_can_enabled, &m.pdo_mappable, crate::dec(m.size.into()));
    // The flags spell out only what differs from `EntryFlags::new`.
    let mut flags = quote!(#stack::od::EntryFlags::new(#stack::od::HostAccess::#host_access, #stack::od::Storage::#storage));
    if *pdo {
        flags = quote!(#flags.pdo_mappable());
    }
    if *before {
        flags = quote!(#flags.host_write_before_can_enabled());
    }
    if let Some(states) = &m.writable_in {
        let states = states.iter().map(|s| ident(&format!("{s:?}")));
        flags = quote!(#flags.writable_in(#stack::od::NmtStates::NONE #(.with(#stack::od::NmtState::#states))*));
    }
    if r.copies != 0 {
        flags = quote!(#flags.copies(#copies));
    }
    // 0: none; n: entry n - 1 of `od::LIMITS`.
    let limits = match &m.limits {
        None => 0,
        Some(key) => {
            let at = limits.iter().position(|k| k == key).unwrap_or_else(|| {
                limits.push(key.clone());
                limits.len() - 1
            });
            at + 1
        }
    };
    let limits = crate::dec(limits as u64);
    quote! {
        #stack::od::EntryInfo {
            index: #index,
            offset: (#offset) as u16,
            size: #size,
            sub: #sub,
            last_sub: #last_sub,
            limits: #limits,
            kind: #stack::od::EntryKind::new(#stack::od::DataType::#data_type, #stack::od::Access::#access),
            flags: #flags,
        }
    }
}

/// `ENTRIES`, every run of every mode once, and per mode the positions of its runs
/// (`PICK_<MODE>`, shared by modes with equal tables), with the `match mode` selecting each
/// mode's `Table`. A device whose modes all have one table has no picks.
fn table(modes: &Modes, per_mode: &[Vec<TokenStream>], stack: &TokenStream) -> (Vec<TokenStream>, TokenStream) {
    let (mut all, mut keys): (Vec<&TokenStream>, Vec<String>) = (Vec::new(), Vec::new());
    let picks: Vec<Vec<usize>> = per_mode
        .iter()
        .map(|runs| {
            runs.iter()
                .map(|r| {
                    let key = r.to_string();
                    keys.iter().position(|k| *k == key).unwrap_or_else(|| {
                        keys.push(key);
                        all.push(r);
                        all.len() - 1
                    })
                })
                .collect()
        })
        .collect();
    let count = crate::dec(all.len() as u64);
    let mut statics = vec![quote!(static ENTRIES: [#stack::od::EntryInfo; #count] = [#(#all),*];)];
    if picks.iter().all(|p| p.len() == all.len()) {
        // Every mode has every run (in the one sorted order there is).
        let arms = vec![quote!(#stack::od::Table::new(&ENTRIES)); modes.variants.len()];
        return (statics, modes.select(&arms));
    }
    if all.len() > 256 {
        let error = format!("the modes' entry tables have {} distinct runs; a table of several modes holds at most 256", all.len());
        statics.push(quote!(::core::compile_error!(#error);));
    }
    let per_mode_picks: Vec<Vec<TokenStream>> = picks.iter().map(|p| p.iter().map(|&i| crate::dec(i as u64).into_token_stream()).collect()).collect();
    let (pick_statics, select) = modes.tables_as("PICK", &quote!(u8), &per_mode_picks, |pick| quote!(#stack::od::Table::picked(&ENTRIES, &#pick)));
    statics.extend(pick_statics);
    (statics, select)
}

pub fn od_module(d: &Device, modes: &Modes, options: &Options) -> TokenStream {
    let stack = &options.stack;
    let mut limits: Vec<LimitsKey> = Vec::new();
    let offsets = crate::dictionary::offsets(d, stack);
    // App-backed runs have no place in the value image: offset 0, never read.
    let offset = |r: &Run| offsets.get(&(r.index, r.sub)).cloned().filter(|_| r.meta.storage != "App").unwrap_or_else(|| quote!(0));
    let per_mode: Vec<Vec<TokenStream>> =
        modes.variants.iter().map(|(_, mode)| runs(d, mode.as_deref()).iter().map(|r| run_tokens(r, offset(r), stack, &mut limits)).collect()).collect();
    let (tables, select) = table(modes, &per_mode, stack);
    let limit_items: Vec<TokenStream> = limits
        .iter()
        .map(|(low, high, values)| {
            let opt = |v: &Option<i64>| match v {
                Some(v) => {
                    let v = proc_macro2::Literal::i64_unsuffixed(*v);
                    quote!(Some(#v))
                }
                None => quote!(None),
            };
            let values = values.iter().map(|v| proc_macro2::Literal::i64_unsuffixed(*v));
            let (low, high) = (opt(low), opt(high));
            quote!(#stack::od::Limits { low: #low, high: #high, values: &[#(#values),*] })
        })
        .collect();
    let limit_count = crate::dec(limit_items.len() as u64);
    // The SDO server buffers a download until its last segment: size the buffer for the
    // largest value the bus may write. Domains without a declared length do not count; a
    // download larger than the buffer is refused with "out of memory".
    let max_write = d.objects.iter().flat_map(|o| &o.entries).filter(|e| e.access.writable() && size_of(e) != u16::MAX).map(size_of).max().unwrap_or(4).max(4);
    let max_write = crate::dec(max_write.into());
    quote! {
        /// Object dictionary metadata, generated from the spec.
        pub mod od {
            use super::Mode;
            // The entries' offsets are places in it.
            #[allow(unused_imports)]
            use super::Values;
            /// Bytes of the largest value the bus may write (the SDO download buffer).
            pub const MAX_WRITE_SIZE: usize = #max_write;
            /// Every distinct value limit of the dictionary: an entry's `limits` n is entry n - 1.
            pub static LIMITS: [#stack::od::Limits; #limit_count] = [#(#limit_items),*];
            #(#tables)*
            /// Every entry of `mode`, sorted by index and sub-index; consecutive sub-entries that
            /// are described alike share one run (`sub..=last_sub`).
            // Every engine looks entries up: one call each, not the `match` in every caller.
            #[inline(never)]
            pub fn entries(mode: Mode) -> #stack::od::Table<'static> {
                #select
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn memory_blocks_collapse_into_two_runs_each() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../spec/co401memory1.yaml");
        let d = coforge_spec::load_file(&path).into_device().expect("spec loads");
        let runs = runs(&d, None);
        // The 64 blocks 5000..503F are alike: two objects listed, 31 and 32 copies.
        let blocks: Vec<(u16, u8, u8, u8)> =
            runs.iter().filter(|r| (0x5000..=0x503F).contains(&r.index)).map(|r| (r.index, r.sub, r.last_sub, r.copies)).collect();
        assert_eq!(blocks, [(0x5000, 0, 0, 31), (0x5000, 1, 128, 31), (0x5020, 0, 0, 31), (0x5020, 1, 128, 31)]);
        // Nothing else repeats: 5C00 follows the blocks but is not alike.
        assert!(runs.iter().filter(|r| !(0x5000..=0x503F).contains(&r.index)).all(|r| r.copies == 0));
        // Sorted, and runs never overlap.
        assert!(runs.windows(2).all(|w| (w[0].index, w[0].last_sub) < (w[1].index, w[1].sub)));
        let entries: usize = d.objects.iter().map(|o| o.entries.len()).sum();
        assert!(runs.len() * 90 < entries, "{} runs for {entries} entries", runs.len());
    }
}
