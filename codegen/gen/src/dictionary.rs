//! The typed dictionary: `Od<A>` with one field per RAM/persistent object (app-backed entries
//! go to `A: AppObjects`), `Od::new` with the spec's defaults (`$NODEID` resolved), and the
//! `ObjectDictionary` implementation whose dispatch is a generated `match`.

use crate::Options;
use crate::naming::{camel, ident as id};
use coforge_spec::model::{Device, Entry, Object, Value};
use coforge_spec::types::{DataType, ObjectKind, Storage};
use proc_macro2::{Ident, TokenStream};
use quote::quote;
use std::collections::BTreeMap;

/// One index, merged over every mode it exists in.
struct Slot<'a> {
    index: u16,
    object: &'a Object,
    /// sub -> the entry (first mode wins for defaults and types).
    entries: BTreeMap<u8, &'a Entry>,
}

fn slots(d: &Device) -> Vec<Slot<'_>> {
    let mut map: BTreeMap<u16, Slot<'_>> = BTreeMap::new();
    for o in &d.objects {
        let slot = map.entry(o.index).or_insert_with(|| Slot { index: o.index, object: o, entries: BTreeMap::new() });
        for e in &o.entries {
            slot.entries.entry(e.sub).or_insert(e);
        }
    }
    map.into_values().collect()
}

/// The Rust type of an entry's field.
fn rust_type(e: &Entry, stack: &TokenStream) -> TokenStream {
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

/// The initial value of an entry's field; `node_id` is in scope in `Od::new`.
fn initial(e: &Entry, stack: &TokenStream) -> TokenStream {
    let ty = rust_type(e, stack);
    match (&e.default, e.data_type) {
        (Some(Value::Str(s)), _) => quote!(#stack::value::Bytes::new(#s)),
        (_, t) if t.int_range().is_none() && !t.is_real() => quote!(#stack::value::Bytes::new("")),
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

/// Per index: field declarations, record structs, initialisers, and dispatch arms.
struct Parts {
    structs: Vec<TokenStream>,
    fields: Vec<TokenStream>,
    inits: Vec<TokenStream>,
    read_arms: Vec<TokenStream>,
    write_arms: Vec<TokenStream>,
    /// Persistent entries, saved by 1010h.
    persist: Vec<Place>,
    /// Every stored entry (RAM and persistent): what an NMT reset sets back to its default.
    resets: Vec<Place>,
}

/// One stored value: its index, where it lives in `Od`, its type and its default.
#[derive(Clone)]
struct Place {
    index: TokenStream,
    place: TokenStream,
    ty: TokenStream,
    default: TokenStream,
}

impl Parts {
    fn place(&mut self, e: &Entry, index: &TokenStream, place: TokenStream, ty: TokenStream, default: TokenStream) {
        let p = Place { index: index.clone(), place, ty, default };
        if persistent(e) {
            self.persist.push(p.clone());
        }
        self.resets.push(p);
    }
}

fn persistent(e: &Entry) -> bool {
    e.storage == Storage::Persistent
}

fn slot_parts(slot: &Slot<'_>, stack: &TokenStream, parts: &mut Parts) {
    let index = crate::hex(slot.index.into(), 4);
    let o = slot.object;
    // App-backed entries: routed by sub-index runs.
    let app: Vec<u8> = slot.entries.values().filter(|e| !stored(e)).map(|e| e.sub).collect();
    for (lo, hi) in ranges(&app) {
        let (lo, hi) = (crate::dec(lo.into()), crate::dec(hi.into()));
        parts.read_arms.push(quote!((#index, #lo..=#hi) => self.app.read(info, sub, offset, buf)));
        parts.write_arms.push(quote!((#index, #lo..=#hi) => self.app.write(info, sub, data)));
    }
    let kept: Vec<&Entry> = slot.entries.values().copied().filter(|e| stored(e)).collect();
    if kept.is_empty() {
        return;
    }
    let field = id(&o.ident);
    let doc = format!(" {:04X}h {}", slot.index, o.name);
    match o.kind {
        ObjectKind::Var | ObjectKind::Domain => plain_field(kept[0], &field, &doc, &index, stack, parts),
        ObjectKind::Array => {
            let items: Vec<&Entry> = kept.iter().copied().filter(|e| e.sub > 0).collect();
            let n = items.iter().map(|e| usize::from(e.sub)).max().unwrap_or(0);
            let Some(first) = items.first() else {
                // Only sub 0 is stored (the elements are app-backed): a plain field.
                return plain_field(kept[0], &field, &doc, &index, stack, parts);
            };
            let ty = rust_type(first, stack);
            let zero = initial(&Entry { default: None, ..(*first).clone() }, stack);
            let item_inits: Vec<TokenStream> =
                (1..=n).map(|s| items.iter().find(|e| usize::from(e.sub) == s).map_or(zero.clone(), |e| initial(e, stack))).collect();
            let sub0 = kept.iter().find(|e| e.sub == 0).map_or(quote!(0), |e| initial(e, stack));
            if let Some(e) = kept.iter().find(|e| e.sub == 0) {
                parts.place(e, &index, quote!(self.#field.sub0), quote!(u8), initial(e, stack));
            }
            for e in &items {
                let i = crate::dec(u64::from(e.sub) - 1);
                parts.place(e, &index, quote!(self.#field.items[#i]), ty.clone(), initial(e, stack));
            }
            let count = crate::dec(n as u64);
            parts.fields.push(quote!(#[doc = #doc] pub #field: #stack::value::Array<#ty, #count>));
            parts.inits.push(quote!(#field: #stack::value::Array { sub0: #sub0, items: [#(#item_inits),*] }));
            parts.read_arms.push(quote!((#index, 0) => self.#field.sub0.read(info, offset, buf)));
            parts.write_arms.push(quote!((#index, 0) => self.#field.sub0.write(info, data)));
            let last = crate::dec(n as u64);
            parts.read_arms.push(
                quote!((#index, s @ 1..=#last) => self.#field.items.get(usize::from(s) - 1).ok_or(#stack::od::SdoAbort::NoSubIndex)?.read(info, offset, buf)),
            );
            parts.write_arms.push(
                quote!((#index, s @ 1..=#last) => self.#field.items.get_mut(usize::from(s) - 1).ok_or(#stack::od::SdoAbort::NoSubIndex)?.write(info, data)),
            );
        }
        ObjectKind::Record => {
            let name = camel(&o.ident);
            let mut sub_fields = Vec::new();
            let mut sub_inits = Vec::new();
            for e in &kept {
                let f = id(&e.ident);
                let sub = crate::dec(e.sub.into());
                let (ty, init) = (rust_type(e, stack), initial(e, stack));
                parts.place(e, &index, quote!(self.#field.#f), ty.clone(), init.clone());
                let sdoc = format!(" Sub {}: {}", e.sub, e.name);
                sub_fields.push(quote!(#[doc = #sdoc] pub #f: #ty));
                sub_inits.push(quote!(#f: #init));
                parts.read_arms.push(quote!((#index, #sub) => self.#field.#f.read(info, offset, buf)));
                parts.write_arms.push(quote!((#index, #sub) => self.#field.#f.write(info, data)));
            }
            parts.structs.push(quote! {
                #[doc = #doc]
                #[derive(Debug, Clone, PartialEq)]
                pub struct #name { #(#sub_fields),* }
            });
            parts.fields.push(quote!(#[doc = #doc] pub #field: #name));
            parts.inits.push(quote!(#field: #name { #(#sub_inits),* }));
        }
    }
}

/// A single stored entry (a VAR, or sub 0 alone) as one field.
fn plain_field(e: &Entry, field: &Ident, doc: &str, index: &TokenStream, stack: &TokenStream, parts: &mut Parts) {
    let (ty, init) = (rust_type(e, stack), initial(e, stack));
    parts.place(e, index, quote!(self.#field), ty.clone(), init.clone());
    parts.fields.push(quote!(#[doc = #doc] pub #field: #ty));
    parts.inits.push(quote!(#field: #init));
    parts.read_arms.push(quote!((#index, 0) => self.#field.read(info, offset, buf)));
    parts.write_arms.push(quote!((#index, 0) => self.#field.write(info, data)));
}

/// Consecutive runs of sub-indices.
fn ranges(subs: &[u8]) -> Vec<(u8, u8)> {
    let mut out: Vec<(u8, u8)> = Vec::new();
    for &s in subs {
        match out.last_mut() {
            Some((_, hi)) if u16::from(*hi) + 1 == u16::from(s) => *hi = s,
            _ => out.push((s, s)),
        }
    }
    out
}

pub fn dictionary(d: &Device, options: &Options) -> TokenStream {
    let stack = &options.stack;
    let mut parts = Parts {
        structs: Vec::new(),
        fields: Vec::new(),
        inits: Vec::new(),
        read_arms: Vec::new(),
        write_arms: Vec::new(),
        persist: Vec::new(),
        resets: Vec::new(),
    };
    for slot in slots(d) {
        slot_parts(&slot, stack, &mut parts);
    }
    let Parts { structs, fields, inits, read_arms, write_arms, persist, resets } = parts;
    let (p_index, places): (Vec<&TokenStream>, Vec<&TokenStream>) = persist.iter().map(|p| (&p.index, &p.place)).unzip();
    let types: Vec<&TokenStream> = persist.iter().map(|p| &p.ty).collect();
    let (r_index, r_places): (Vec<&TokenStream>, Vec<&TokenStream>) = resets.iter().map(|p| (&p.index, &p.place)).unzip();
    let r_defaults: Vec<&TokenStream> = resets.iter().map(|p| &p.default).collect();
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
            /// The dictionary with the spec's defaults, `$NODEID` resolved for `node_id`.
            pub fn new(mode: Mode, node_id: u8, app: A) -> Self {
                Od { mode, app, #(#inits),* }
            }

            pub fn mode(&self) -> Mode {
                self.mode
            }
        }

        impl<A: #stack::od::AppObjects> #stack::od::Dictionary for Od<A> {
            const PERSISTENT_SIZE: usize = 0 #(+ <#types as #stack::value::Persist>::SIZE)*;

            #[allow(unused_mut, unused_variables)]
            fn save_area(&self, area: #stack::od::Area, sink: &mut dyn FnMut(usize, &[u8]) -> bool) -> bool {
                use #stack::value::Persist as _;
                let (mut at, mut ok) = (0, true);
                #(
                    if area.contains(#p_index) {
                        let mut image = [0_u8; <#types as #stack::value::Persist>::SIZE];
                        #places.save(&mut image);
                        ok &= sink(at, &image);
                    }
                    at += <#types as #stack::value::Persist>::SIZE;
                )*
                ok
            }

            #[allow(unused_mut, unused_variables)]
            fn load_area(&mut self, area: #stack::od::Area, source: &mut dyn FnMut(usize, &mut [u8]) -> bool) -> bool {
                use #stack::value::Persist as _;
                let (mut at, mut ok) = (0, true);
                #(
                    if area.contains(#p_index) {
                        let mut image = [0_u8; <#types as #stack::value::Persist>::SIZE];
                        if source(at, &mut image) {
                            #places.load(&image);
                        } else {
                            ok = false;
                        }
                    }
                    at += <#types as #stack::value::Persist>::SIZE;
                )*
                ok
            }

            #[allow(unused_variables)]
            fn reset_area(&mut self, area: #stack::od::Area, node_id: u8) {
                #( if area.contains(#r_index) { #r_places = #r_defaults; } )*
            }

            fn emergencies(&self) -> &'static [#stack::emcy::EmcyDefault] {
                emcy::emergencies(self.mode)
            }
        }

        impl<A: #stack::od::AppObjects> #stack::od::ObjectDictionary for Od<A> {
            fn entries(&self) -> &'static [#stack::od::EntryInfo] {
                od::entries(self.mode)
            }

            fn read_entry(&mut self, info: &#stack::od::EntryInfo, sub: u8, offset: usize, buf: &mut [u8]) -> Result<#stack::od::ReadLen, #stack::od::SdoAbort> {
                use #stack::value::OdValue as _;
                match (info.index, sub) {
                    #(#read_arms,)*
                    _ => Err(#stack::od::SdoAbort::NoObject),
                }
            }

            fn write_entry(&mut self, info: &#stack::od::EntryInfo, sub: u8, data: &[u8]) -> Result<(), #stack::od::SdoAbort> {
                use #stack::value::OdValue as _;
                info.check_data(data)?;
                match (info.index, sub) {
                    #(#write_arms,)*
                    _ => Err(#stack::od::SdoAbort::NoObject),
                }
            }
        }
    }
}
