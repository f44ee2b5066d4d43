//! The typed dictionary: `Od<A>` with one field per RAM/persistent object (app-backed entries
//! go to `A: AppObjects`), `Od::new` with the spec's defaults (`$NODEID` resolved), and the
//! `EntryAccess` implementation: `field` is one generated `match` on the entry's dense
//! object number, so reads and writes share one jump table and their code lives in the stack.

use crate::Options;
use crate::modes::Modes;
use crate::naming::{camel, ident as id};
use coforge_spec::model::{Device, Entry, Object, Value, in_mode};
use coforge_spec::types::{DataType, ObjectKind, Storage};
use proc_macro2::{Ident, TokenStream};
use quote::quote;
use std::collections::BTreeMap;

/// One index, merged over every mode it exists in.
struct Slot<'a> {
    index: u16,
    /// Dense object number ([`object_numbers`]).
    number: u16,
    object: &'a Object,
    /// sub -> the entry (first mode wins for types).
    entries: BTreeMap<u8, &'a Entry>,
}

/// The spec default of an entry in each mode it exists in: `(mode variant, default tokens)`.
type ModeDefaults = Vec<(Ident, TokenStream)>;

/// The default of `index`/`sub` in every mode, in the field's Rust type.
fn mode_defaults(d: &Device, modes: &Modes, index: u16, sub: u8, stack: &TokenStream) -> ModeDefaults {
    let mut out = Vec::new();
    for (variant, mode) in &modes.variants {
        let entry = d
            .objects
            .iter()
            .filter(|o| o.index == index && in_mode(&o.modes, mode.as_deref()))
            .flat_map(|o| &o.entries)
            .find(|e| e.sub == sub && in_mode(&e.modes, mode.as_deref()));
        if let Some(e) = entry {
            out.push((variant.clone(), initial(e, stack)));
        }
    }
    out
}

/// Every index of the device, in every mode, numbered densely in index order: the
/// `EntryInfo::object` the table carries and the `field` dispatch switches on.
pub(crate) fn object_numbers(d: &Device) -> BTreeMap<u16, u16> {
    let indices: std::collections::BTreeSet<u16> = d.objects.iter().map(|o| o.index).collect();
    indices.into_iter().zip(0..).collect()
}

fn slots(d: &Device) -> Vec<Slot<'_>> {
    let numbers = object_numbers(d);
    let mut map: BTreeMap<u16, Slot<'_>> = BTreeMap::new();
    for o in &d.objects {
        let number = numbers.get(&o.index).copied().unwrap_or_default();
        let slot = map.entry(o.index).or_insert_with(|| Slot { index: o.index, number, object: o, entries: BTreeMap::new() });
        for e in &o.entries {
            slot.entries.entry(e.sub).or_insert(e);
        }
    }
    map.into_values().collect()
}

/// The Rust type of an entry's field.
pub(crate) fn rust_type(e: &Entry, stack: &TokenStream) -> TokenStream {
    match e.data_type {
        DataType::Boolean => quote!(bool),
        DataType::Unsigned8 => quote!(u8),
        DataType::Unsigned16 => quote!(u16),
        DataType::Unsigned24 | DataType::Unsigned32 => quote!(u32),
        DataType::Unsigned40 | DataType::Unsigned48 | DataType::Unsigned56 | DataType::Unsigned64 => quote!(u64),
        DataType::Integer8 => quote!(i8),
        DataType::Integer16 => quote!(i16),
        DataType::Integer24 | DataType::Integer32 => quote!(i32),
        DataType::Integer40 | DataType::Integer48 | DataType::Integer56 | DataType::Integer64 => quote!(i64),
        DataType::Real32 => quote!(f32),
        DataType::Real64 => quote!(f64),
        DataType::VisibleString | DataType::OctetString | DataType::UnicodeString | DataType::Domain | DataType::TimeOfDay | DataType::TimeDifference => {
            let n = crate::dec(u64::from(crate::entries::size_of(e)));
            quote!(#stack::value::Bytes<#n>)
        }
    }
}

/// The spec default of an entry's field; `node_id` is in scope in `reset_area`.
fn initial(e: &Entry, stack: &TokenStream) -> TokenStream {
    let ty = rust_type(e, stack);
    match (&e.default, e.data_type) {
        // Evaluated at compile time: a copy from flash, not a call that fills the text in.
        (Some(Value::Str(s)), _) => quote!(const { #stack::value::Bytes::new(#s) }),
        (_, t) if t.int_range().is_none() && !t.is_real() => quote!(const { #stack::value::Bytes::new("") }),
        (Some(Value::Real(x)), _) => quote!(#x as #ty),
        (None, DataType::Boolean) => quote!(false),
        (Some(Value::Int(expr)), DataType::Boolean) => {
            let b = expr.eval(&Default::default(), Some(1)).unwrap_or(0) != 0;
            quote!(#b)
        }
        (None, t) if t.is_real() => quote!(0.0),
        (None, _) => quote!(0),
        (Some(Value::Int(expr)), t) if t.is_real() => {
            let v = expr.eval(&Default::default(), Some(1)).unwrap_or(0) as f64;
            quote!(#v as #ty)
        }
        (Some(Value::Int(expr)), _) => match expr.node_id_offset() {
            Ok(Some(base)) => {
                let base = literal(base);
                quote!((node_id as #ty).wrapping_add(#base))
            }
            _ => literal(expr.eval(&Default::default(), None).unwrap_or(0)),
        },
    }
}

/// An integer literal the field's type is inferred for: hex from 10 up, like the datasheets.
fn literal(v: i64) -> TokenStream {
    match v {
        10.. => crate::hex(v.unsigned_abs(), 1),
        0..10 => {
            let l = proc_macro2::Literal::i64_unsuffixed(v);
            quote!(#l)
        }
        _ => {
            let l = proc_macro2::Literal::u64_unsuffixed(v.unsigned_abs());
            quote!(-#l)
        }
    }
}

fn stored(e: &Entry) -> bool {
    e.storage != Storage::App
}

/// Per index: field declarations, record structs, field names, dispatch arms and defaults.
struct Parts {
    structs: Vec<TokenStream>,
    fields: Vec<TokenStream>,
    /// The field names, for `Od::new`.
    names: Vec<Ident>,
    /// `(object number, sub) => &mut field` arms of `field`.
    field_arms: Vec<TokenStream>,
    /// The persistent block, saved by 1010h: its units in block (index) order.
    persist: Vec<Unit>,
    /// Record types that implement `Persistent` (emitted once per type).
    persistent_records: Vec<Ident>,
    /// Every stored entry (RAM and persistent): what an NMT reset sets back to its default.
    resets: Vec<Place>,
    /// Record types emitted so far, by shape (sub, field, type of each entry).
    shapes: Vec<(String, Ident)>,
}

/// One stored value: its index, where it lives in `Od`, its type and its default.
#[derive(Clone)]
struct Place {
    /// The object index, as a number and as the literal generated code uses.
    number: u16,
    index: TokenStream,
    place: TokenStream,
    ty: TokenStream,
    /// The default: one expression, or a `match self.mode` where the modes differ.
    default: TokenStream,
    /// Whether the default differs between the modes the entry exists in.
    per_mode: bool,
}

/// One unit of the persistent block: a field, an array's items, a whole array or a whole
/// record, whose entries' images follow each other in the block.
struct Unit {
    /// The object index (every entry of a unit has the same).
    index: TokenStream,
    /// Where it lives in `Od`.
    place: TokenStream,
    /// Bytes of its image.
    size: TokenStream,
}

/// The image size of one entry's field.
fn image_size(ty: &TokenStream, stack: &TokenStream) -> TokenStream {
    quote!(<#ty as #stack::value::Persist>::SIZE)
}

impl Place {
    fn new(number: u16, place: TokenStream, ty: TokenStream, default: TokenStream, per_mode: bool) -> Place {
        Place { number, index: crate::hex(number.into(), 4), place, ty, default, per_mode }
    }
}

impl Parts {
    /// A stored entry: reset by NMT resets, and a unit of the persistent block of its own
    /// unless `grouped` (the caller saves it with others as one unit).
    #[allow(clippy::too_many_arguments)]
    fn place(&mut self, e: &Entry, number: u16, place: TokenStream, ty: TokenStream, defaults: ModeDefaults, grouped: bool, stack: &TokenStream) {
        let distinct: std::collections::BTreeSet<String> = defaults.iter().map(|(_, t)| t.to_string()).collect();
        let per_mode = distinct.len() > 1;
        let default = match defaults.as_slice() {
            [(_, only), ..] if !per_mode => only.clone(),
            _ => {
                // Modes the entry does not exist in keep the first mode's value: no table
                // lists the entry there, so nothing reads it.
                let arms = defaults.iter().map(|(v, t)| quote!(Mode::#v => #t));
                quote!(match self.mode { #(#arms,)* #[allow(unreachable_patterns)] _ => Default::default() })
            }
        };
        let p = Place::new(number, place, ty, default, per_mode);
        if persistent(e) && !grouped {
            self.persist.push(Unit { index: p.index.clone(), place: p.place.clone(), size: image_size(&p.ty, stack) });
        }
        self.resets.push(p);
    }
}

fn persistent(e: &Entry) -> bool {
    e.storage == Storage::Persistent
}

/// The defaults of one entry of the slot being generated, per mode.
type DefaultsOf<'a> = &'a dyn Fn(u8) -> ModeDefaults;

fn slot_parts(slot: &Slot<'_>, stack: &TokenStream, parts: &mut Parts, defaults: DefaultsOf<'_>) {
    let number = crate::dec(slot.number.into());
    let o = slot.object;
    // App-backed entries never reach `field`: the stack routes them by their storage class.
    let kept: Vec<&Entry> = slot.entries.values().copied().filter(|e| stored(e)).collect();
    if kept.is_empty() {
        return;
    }
    let field = id(&o.ident);
    let doc = format!(" {:04X}h {}", slot.index, o.name);
    match o.kind {
        ObjectKind::Var | ObjectKind::Domain => plain_field(kept[0], &field, &doc, slot.index, &number, stack, parts, defaults),
        ObjectKind::Array => {
            let items: Vec<&Entry> = kept.iter().copied().filter(|e| e.sub > 0).collect();
            let n = items.iter().map(|e| usize::from(e.sub)).max().unwrap_or(0);
            let Some(first) = items.first() else {
                // Only sub 0 is stored (the elements are app-backed): a plain field.
                return plain_field(kept[0], &field, &doc, slot.index, &number, stack, parts, defaults);
            };
            let ty = rust_type(first, stack);
            let count = crate::dec(n as u64);
            let sub0 = kept.iter().find(|e| e.sub == 0);
            // Every item 1..=N persistent: the items are one unit, with sub 0 if it is
            // persistent too (the same images at the same offsets as entry by entry).
            let items_unit = items.len() == n && items.iter().all(|e| persistent(e));
            let whole_unit = items_unit && sub0.is_some_and(|e| persistent(e));
            if let Some(e) = sub0 {
                parts.place(e, slot.index, quote!(self.#field.sub0), quote!(u8), defaults(e.sub), whole_unit, stack);
            }
            if items_unit {
                let index = crate::hex(slot.index.into(), 4);
                let item_size = image_size(&ty, stack);
                parts.persist.push(if whole_unit {
                    Unit { index, place: quote!(self.#field), size: quote!(1 + #item_size * #count) }
                } else {
                    Unit { index, place: quote!(self.#field.items), size: quote!(#item_size * #count) }
                });
            }
            let item_defaults: Vec<ModeDefaults> = items.iter().map(|e| defaults(e.sub)).collect();
            let texts: std::collections::BTreeSet<String> = item_defaults.iter().flatten().map(|(_, t)| t.to_string()).collect();
            match item_defaults.first().and_then(|d| d.first()) {
                // Every item has one default in every mode: one array store resets them all
                // (a fill, not one store per item); the store still saves item by item.
                Some((_, default)) if texts.len() == 1 && items.len() == n => {
                    for e in items.iter().filter(|e| persistent(e) && !items_unit) {
                        let i = crate::dec(u64::from(e.sub) - 1);
                        let index = crate::hex(slot.index.into(), 4);
                        parts.persist.push(Unit { index, place: quote!(self.#field.items[#i]), size: image_size(&ty, stack) });
                    }
                    parts.resets.push(Place::new(slot.index, quote!(self.#field.items), quote!([#ty; #count]), quote!([#default; #count]), false));
                }
                _ => {
                    for (e, d) in items.iter().zip(item_defaults) {
                        let i = crate::dec(u64::from(e.sub) - 1);
                        parts.place(e, slot.index, quote!(self.#field.items[#i]), ty.clone(), d, items_unit, stack);
                    }
                }
            }
            parts.fields.push(quote!(#[doc = #doc] pub #field: #stack::value::Array<#ty, #count>));
            parts.names.push(field.clone());
            parts.field_arms.push(quote!((#number, s) => self.#field.sub(s)));
        }
        ObjectKind::Record => {
            let name = camel(&o.ident);
            let mut sub_fields = Vec::new();
            let mut sub_arms = Vec::new();
            let mut shape = String::new();
            // Every stored entry persistent: the record is one unit of the block.
            let record_unit = kept.iter().all(|e| persistent(e));
            let mut unit_fields = Vec::new();
            let first_reset = parts.resets.len();
            for e in &kept {
                let f = id(&e.ident);
                let sub = crate::dec(e.sub.into());
                let ty = rust_type(e, stack);
                parts.place(e, slot.index, quote!(self.#field.#f), ty.clone(), defaults(e.sub), record_unit, stack);
                unit_fields.push((f.clone(), image_size(&ty, stack)));
                let sdoc = format!(" Sub {}: {}", e.sub, e.name);
                shape.push_str(&format!("{}:{f}:{ty};", e.sub));
                sub_fields.push(quote!(#[doc = #sdoc] pub #f: #ty));
                sub_arms.push(quote!(#sub => &mut self.#f));
            }
            // One store of a constant record (a copy from flash) resets the record, not one
            // store per entry; defaults that depend on the mode or the node-ID (integers,
            // 0 in the constant) are stored after it. Only for more than four constant
            // entries: fewer are smaller as stores (measured on thumbv6m).
            let record_resets = parts.resets.split_off(first_reset);
            let varies = |p: &Place| p.per_mode || p.default.to_string().contains("node_id");
            let integer = |p: &Place| ["u8", "u16", "u32", "u64", "i8", "i16", "i32", "i64"].contains(&p.ty.to_string().as_str());
            if record_resets.iter().all(|p| !varies(p) || integer(p)) && record_resets.iter().filter(|p| !varies(p)).count() > 4 {
                let names = kept.iter().map(|e| id(&e.ident));
                let values = record_resets.iter().map(|p| if varies(p) { quote!(0) } else { p.default.clone() });
                parts.resets.push(Place::new(
                    slot.index,
                    quote!(self.#field),
                    quote!(#name),
                    quote!({ const DEFAULT: #name = #name { #(#names: #values),* }; DEFAULT }),
                    false,
                ));
                parts.resets.extend(record_resets.into_iter().filter(varies));
            } else {
                parts.resets.extend(record_resets);
            }
            // Records of one shape (the PDO parameter records) share one type and one
            // sub-index dispatch; the later ones are aliases of the first.
            let record_type = parts.shapes.iter().find(|(s, _)| *s == shape).map_or(name.clone(), |(_, first)| first.clone());
            if record_unit {
                let index = crate::hex(slot.index.into(), 4);
                let sizes = unit_fields.iter().map(|(_, size)| size);
                parts.persist.push(Unit { index, place: quote!(self.#field), size: quote!(0 #(+ #sizes)*) });
                if !parts.persistent_records.contains(&record_type) {
                    parts.persistent_records.push(record_type.clone());
                    let (names, sizes): (Vec<&Ident>, Vec<&TokenStream>) = unit_fields.iter().map(|(f, size)| (f, size)).unzip();
                    parts.structs.push(quote! {
                        /// The record's entries, one after the other in the persistent block.
                        impl #stack::value::Persistent for #record_type {
                            fn save_to(&self, at: usize, sink: &mut dyn FnMut(usize, &[u8]) -> bool) -> bool {
                                #stack::value::save_fields(&[#((&self.#names, #sizes)),*], at, sink)
                            }
                            fn load_from(&mut self, at: usize, source: &mut dyn FnMut(usize, &mut [u8]) -> bool) -> bool {
                                #stack::value::load_fields(&mut [#((&mut self.#names, #sizes)),*], at, source)
                            }
                        }
                    });
                }
            }
            match parts.shapes.iter().find(|(s, _)| *s == shape) {
                Some((_, first)) => {
                    let alias = format!("{doc} (the same record as [`{first}`])");
                    parts.structs.push(quote!(#[doc = #alias] pub type #name = #first;));
                }
                None => {
                    parts.shapes.push((shape, name.clone()));
                    parts.structs.push(quote! {
                        #[doc = #doc]
                        #[derive(Debug, Clone, PartialEq, Default)]
                        pub struct #name { #(#sub_fields),* }

                        impl #name {
                            /// The field of sub-index `sub`.
                            #[inline]
                            pub fn sub(&mut self, sub: u8) -> Option<&mut dyn #stack::value::OdValue> {
                                Some(match sub {
                                    #(#sub_arms,)*
                                    _ => return None,
                                })
                            }
                        }
                    });
                }
            }
            parts.field_arms.push(quote!((#number, s) => self.#field.sub(s)));
            parts.fields.push(quote!(#[doc = #doc] pub #field: #name));
            parts.names.push(field.clone());
        }
    }
}

/// A single stored entry (a VAR, or sub 0 alone) as one field.
#[allow(clippy::too_many_arguments)]
fn plain_field(
    e: &Entry,
    field: &Ident,
    doc: &str,
    index: u16,
    number: &proc_macro2::Literal,
    stack: &TokenStream,
    parts: &mut Parts,
    defaults: DefaultsOf<'_>,
) {
    let ty = rust_type(e, stack);
    parts.place(e, index, quote!(self.#field), ty.clone(), defaults(e.sub), false, stack);
    parts.fields.push(quote!(#[doc = #doc] pub #field: #ty));
    parts.names.push(field.clone());
    // The caller has found `sub` in this entry's run, so a single field needs no sub test.
    parts.field_arms.push(quote!((#number, _) => Some(&mut self.#field)));
}

/// The class of an index: resets test one index per run of places in the same class, since
/// every [`Area`](https://docs.rs/coforge-stack) is a union of whole classes.
fn area_class(index: u16) -> u8 {
    match index {
        0x0000..=0x0FFF => 0,
        0x1000..=0x1FFF => 1,
        0x2000..=0x5FFF => 2,
        0x6000..=0x9FFF => 3,
        _ => 4,
    }
}

/// `reset_area`'s body: one `if` per run of places in the same index class.
fn reset_groups(resets: &[Place]) -> Vec<TokenStream> {
    let mut groups: Vec<(u16, Vec<&Place>)> = Vec::new();
    for p in resets {
        match groups.last_mut() {
            Some((first, places)) if area_class(*first) == area_class(p.number) => places.push(p),
            _ => groups.push((p.number, vec![p])),
        }
    }
    groups
        .into_iter()
        .map(|(_, places)| {
            let index = &places[0].index;
            let (targets, defaults): (Vec<&TokenStream>, Vec<&TokenStream>) = places.iter().map(|p| (&p.place, &p.default)).unzip();
            quote!(if area.contains(#index) { #(#targets = #defaults;)* })
        })
        .collect()
}

pub fn dictionary(d: &Device, modes: &Modes, options: &Options) -> TokenStream {
    let stack = &options.stack;
    let block_transfer = d.identity.sdo_block_transfer;
    let has = |index: u16| d.objects.iter().any(|o| o.index == index);
    let (history, sync_cycle, consumer) = (has(0x1003), has(0x1006), has(0x1016));
    let mut parts = Parts {
        structs: Vec::new(),
        fields: Vec::new(),
        names: Vec::new(),
        field_arms: Vec::new(),
        persist: Vec::new(),
        persistent_records: Vec::new(),
        resets: Vec::new(),
        shapes: Vec::new(),
    };
    for slot in slots(d) {
        let defaults = |sub| mode_defaults(d, modes, slot.index, sub, stack);
        slot_parts(&slot, stack, &mut parts, &defaults);
    }
    let Parts { structs, fields, names, field_arms, persist, resets, .. } = parts;
    let p_index: Vec<&TokenStream> = persist.iter().map(|u| &u.index).collect();
    let places: Vec<&TokenStream> = persist.iter().map(|u| &u.place).collect();
    let sizes: Vec<&TokenStream> = persist.iter().map(|u| &u.size).collect();
    let unit_numbers: Vec<proc_macro2::Literal> = (0..persist.len()).map(|n| crate::dec(n as u64)).collect();
    let unit_count = crate::dec(persist.len() as u64);
    // The entries whose default differs between modes are reset by one function, which
    // `set_mode` calls too.
    let (mode_resets, resets): (Vec<Place>, Vec<Place>) = resets.into_iter().partition(|p| p.per_mode);
    let mode_groups = reset_groups(&mode_resets);
    let reset_groups = reset_groups(&resets);
    let node_config = node_config(d, stack);
    quote! {
        #(#structs)*

        /// The device's object dictionary: typed fields for what lives in RAM, `app` for
        /// what the device keeps elsewhere.
        #[derive(Debug, Clone)]
        pub struct Od<A> {
            mode: Mode,
            /// Reads and writes of app-backed objects go here.
            pub app: A,
            #(#fields),*
        }

        impl<A: #stack::od::AppObjects> Od<A> {
            /// The dictionary with the spec's defaults of `mode`, `$NODEID` resolved for
            /// `node_id`: all zero first, then the one place that knows the defaults,
            /// `reset_area`.
            pub fn new(mode: Mode, node_id: u8, app: A) -> Self {
                use #stack::od::NodeDictionary as _;
                let mut od = Od { mode, app, #(#names: Default::default()),* };
                od.reset_area(#stack::od::Area::ALL, node_id);
                od
            }

            pub fn mode(&self) -> Mode {
                self.mode
            }

            /// The defaults that differ between modes, in `area`: what `set_mode` sets (in
            /// every area) and `reset_area` (after the others).
            #[allow(unused_variables)]
            fn reset_mode_defaults(&mut self, area: #stack::od::Area, node_id: u8) {
                #(#mode_groups)*
            }

            /// Unit `n` of the persistent block ([`PERSISTENT_UNITS`]).
            #[allow(unreachable_code)]
            fn persistent_unit(&self, n: usize) -> Option<&dyn #stack::value::Persistent> {
                Some(match n {
                    #(#unit_numbers => &#places,)*
                    _ => return None,
                })
            }

            /// Unit `n` of the persistent block, to load it.
            #[allow(unreachable_code)]
            fn persistent_unit_mut(&mut self, n: usize) -> Option<&mut dyn #stack::value::Persistent> {
                Some(match n {
                    #(#unit_numbers => &mut #places,)*
                    _ => return None,
                })
            }
        }

        /// The units of the persistent block (every `storage: persistent` entry, index order):
        /// each one's index and image size. The store code walks this table once for every
        /// unit instead of a copy of it per entry.
        const PERSISTENT_UNITS: [(u16, u16); #unit_count] = [#((#p_index, (#sizes) as u16)),*];

        /// The node settings of the spec's `node:` section, for `node_id`.
        pub const fn node_config(node_id: u8) -> #stack::config::NodeConfig {
            #node_config
        }

        impl<A: #stack::od::AppObjects> #stack::od::NodeDictionary for Od<A> {
            type Mode = Mode;
            const MODES: &'static [Mode] = &Mode::ALL;
            const PERSISTENT_SIZE: usize = 0 #(+ #sizes)*;
            const SDO_BLOCK_TRANSFER: bool = #block_transfer;
            const COMM: #stack::od::CommObjects =
                #stack::od::CommObjects { error_history: #history, sync_cycle: #sync_cycle, heartbeat_consumer: #consumer };

            fn save_area(&self, area: #stack::od::Area, sink: &mut dyn FnMut(usize, &[u8]) -> bool) -> bool {
                let (mut at, mut ok) = (0, true);
                for (n, &(index, size)) in PERSISTENT_UNITS.iter().enumerate() {
                    if area.contains(index) {
                        ok &= self.persistent_unit(n).is_some_and(|unit| unit.save_to(at, sink));
                    }
                    at += usize::from(size);
                }
                ok
            }

            fn load_area(&mut self, area: #stack::od::Area, source: &mut dyn FnMut(usize, &mut [u8]) -> bool) -> bool {
                let (mut at, mut ok) = (0, true);
                for (n, &(index, size)) in PERSISTENT_UNITS.iter().enumerate() {
                    if area.contains(index) {
                        ok &= self.persistent_unit_mut(n).is_some_and(|unit| unit.load_from(at, source));
                    }
                    at += usize::from(size);
                }
                ok
            }

            #[allow(unused_variables)]
            fn reset_area(&mut self, area: #stack::od::Area, node_id: u8) {
                #(#reset_groups)*
                self.reset_mode_defaults(area, node_id);
            }

            fn emergencies(&self) -> &'static [#stack::emcy::EmcyDefault] {
                emcy::emergencies(self.mode)
            }

            fn emergency_named(&self, name: &str) -> Option<#stack::emcy::EmcyDefault> {
                emcy::by_name(self.mode, name)
            }

            fn new(mode: Mode, node_id: u8, app: A) -> Self {
                Od::new(mode, node_id, app)
            }

            fn mode(&self) -> Mode {
                self.mode
            }

            #[allow(unused_variables)]
            fn set_mode(&mut self, mode: Mode, node_id: u8) {
                self.mode = mode;
                self.reset_mode_defaults(#stack::od::Area::ALL, node_id);
            }

            fn mode_name(mode: Mode) -> &'static str {
                mode.name()
            }

            fn node_config(node_id: u8) -> #stack::config::NodeConfig {
                node_config(node_id)
            }
        }

        impl<A: #stack::od::AppObjects> #stack::od::EntryAccess for Od<A> {
            type App = A;

            fn entries(&self) -> &'static [#stack::od::EntryInfo] {
                od::entries(self.mode)
            }

            fn limits(&self) -> &'static [#stack::od::Limits] {
                &od::LIMITS
            }

            #[allow(unreachable_patterns)]
            fn field(&mut self, info: &#stack::od::EntryInfo, sub: u8) -> Option<&mut dyn #stack::value::OdValue> {
                match (info.object, sub) {
                    #(#field_arms,)*
                    _ => None,
                }
            }

            fn app(&mut self) -> &mut A {
                &mut self.app
            }
        }
    }
}

/// `NodeConfig` from the spec's `node:` section: only what differs from plain CiA 301.
fn node_config(d: &Device, stack: &TokenStream) -> TokenStream {
    let n = &d.node;
    let object = |o: Option<u16>| match o {
        Some(i) => {
            let i = crate::hex(i.into(), 4);
            quote!(Some(#i))
        }
        None => quote!(None),
    };
    let (restart, bootup, startup) = (object(n.restart_time_object), object(n.bootup_object), object(n.startup_object));
    let remapping = object(n.remapping_object);
    let (deadlines, combine, auto_save) = (n.rpdo_deadline_monitoring, n.combine_emcy_codes, n.auto_save);
    let (listed_only, tpdo_on_write) = (n.listed_emergencies_only, n.tpdo_on_write);
    quote! {
        #stack::config::NodeConfig {
            restart_time_object: #restart,
            bootup_object: #bootup,
            startup_object: #startup,
            remapping_object: #remapping,
            rpdo_deadlines: #deadlines,
            combine_emcy_codes: #combine,
            auto_save: #auto_save,
            listed_emergencies_only: #listed_only,
            tpdo_on_write: #tpdo_on_write,
            ..#stack::config::NodeConfig::new(node_id)
        }
    }
}
