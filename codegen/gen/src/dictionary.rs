//! The typed dictionary: `Values`, one `#[repr(C)]` struct of byte-aligned little-endian
//! fields for every RAM and persistent object (app-backed entries go to `A: AppObjects`),
//! which is at the same time the value image every `EntryInfo::offset` points into; `Od<A>`
//! around it; the spec's defaults as a value image (`DEFAULT_VALUES`) with patches for what
//! depends on the node-ID or the mode; the spans that NMT resets and the 1010h store act on.
//! Reads, writes, resets, saves and loads are the stack's (`coforge_stack::od::image`), once
//! for every device: nothing here dispatches per object.

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
    object: &'a Object,
    /// sub -> the entry (first mode wins for types).
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

/// The native Rust type of an entry's value: what app-backed objects' hooks take and give.
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
        _ => bytes_type(e, stack),
    }
}

fn bytes_type(e: &Entry, stack: &TokenStream) -> TokenStream {
    let n = crate::dec(u64::from(crate::entries::size_of(e)));
    quote!(#stack::value::Bytes<#n>)
}

/// The type of an entry's field in `Values`: exactly the entry's bytes, little-endian and
/// byte-aligned, so that the struct is the value image (`BOOLEAN` one byte, 0 or 1; 24-, 40-,
/// 48- and 56-bit integers their bytes; strings and domains their length, then their bytes).
fn image_type(e: &Entry, stack: &TokenStream) -> TokenStream {
    let zc = quote!(#stack::zerocopy::little_endian);
    match e.data_type {
        DataType::Boolean | DataType::Unsigned8 => quote!(u8),
        DataType::Integer8 => quote!(i8),
        DataType::Unsigned16 => quote!(#zc::U16),
        DataType::Unsigned32 => quote!(#zc::U32),
        DataType::Unsigned64 => quote!(#zc::U64),
        DataType::Integer16 => quote!(#zc::I16),
        DataType::Integer32 => quote!(#zc::I32),
        DataType::Integer64 => quote!(#zc::I64),
        DataType::Real32 => quote!(#zc::F32),
        DataType::Real64 => quote!(#zc::F64),
        t => match t.bits() {
            Some(bits) => {
                let n = crate::dec(u64::from(bits / 8));
                quote!([u8; #n])
            }
            None => bytes_type(e, stack),
        },
    }
}

/// An entry's spec default, as the value image needs it.
#[derive(Debug, Clone, PartialEq)]
enum Init {
    Int(i64),
    /// `$NODEID + base`: the image holds `base`, a patch adds the node-ID.
    NodeId(i64),
    Real(f64),
    Str(String),
}

fn default_of(e: &Entry) -> Init {
    match (&e.default, e.data_type) {
        (Some(Value::Str(s)), _) => Init::Str(s.clone()),
        (_, t) if t.int_range().is_none() && !t.is_real() => Init::Str(String::new()),
        (Some(Value::Real(x)), _) => Init::Real(*x),
        (None, t) if t.is_real() => Init::Real(0.0),
        (None, _) => Init::Int(0),
        (Some(Value::Int(expr)), DataType::Boolean) => Init::Int(i64::from(expr.eval(&Default::default(), Some(1)).unwrap_or(0) != 0)),
        (Some(Value::Int(expr)), t) if t.is_real() => Init::Real(expr.eval(&Default::default(), Some(1)).unwrap_or(0) as f64),
        (Some(Value::Int(expr)), _) => match expr.node_id_offset() {
            Ok(Some(base)) => Init::NodeId(base),
            _ => Init::Int(expr.eval(&Default::default(), None).unwrap_or(0)),
        },
    }
}

/// The default of `index`/`sub` in every mode it exists in: `(mode variant, default)`.
fn mode_defaults(d: &Device, modes: &Modes, index: u16, sub: u8) -> Vec<(Ident, Init)> {
    let mut out = Vec::new();
    for (variant, mode) in &modes.variants {
        let entry = d
            .objects
            .iter()
            .filter(|o| o.index == index && in_mode(&o.modes, mode.as_deref()))
            .flat_map(|o| &o.entries)
            .find(|e| e.sub == sub && in_mode(&e.modes, mode.as_deref()));
        if let Some(e) = entry {
            out.push((variant.clone(), default_of(e)));
        }
    }
    out
}

/// `v` as a constant of the image type `ty` of entry `e`.
fn constant(e: &Entry, ty: &TokenStream, v: &Init, stack: &TokenStream) -> TokenStream {
    match v {
        Init::Str(s) => quote!(#stack::value::Bytes::new(#s)),
        Init::Real(x) => quote!(#ty::new(#x as _)),
        Init::Int(v) | Init::NodeId(v) => {
            let lit = literal(*v);
            match e.data_type {
                DataType::Boolean | DataType::Unsigned8 | DataType::Integer8 => lit,
                t if t.bits().is_some_and(|b| ![16, 32, 64].contains(&b)) => {
                    // 24-, 40-, 48- and 56-bit integers: their low bytes.
                    let n = crate::dec(u64::from(t.bits().unwrap_or(0) / 8));
                    quote!(#stack::value::low_bytes::<#n>(#lit as i64 as u64))
                }
                _ => quote!(#ty::new(#lit)),
            }
        }
    }
}

/// An integer literal: hex from 10 up, like the datasheets.
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

/// One stored value of the image, in layout order: an entry, or an array's items alike.
struct Leaf {
    index: u16,
    /// Its offset in `Values` and its bytes, as constant expressions.
    offset: TokenStream,
    size: TokenStream,
    persistent: bool,
}

/// A default the value image cannot hold: the node-ID's, or a mode's.
struct PatchOf {
    index: u16,
    offset: TokenStream,
    width: u8,
    value: Init,
}

/// What the struct walk gathers.
#[derive(Default)]
struct Layout {
    /// Record structs, emitted once per shape.
    structs: Vec<TokenStream>,
    /// Record types emitted so far, by shape.
    shapes: Vec<(String, Ident)>,
    fields: Vec<TokenStream>,
    /// The field initialisers of `DEFAULT_VALUES`.
    defaults: Vec<TokenStream>,
    leaves: Vec<Leaf>,
    /// `(index, sub)` -> offset: what the entry tables carry.
    offsets: BTreeMap<(u16, u8), TokenStream>,
    node_ids: Vec<PatchOf>,
    /// Per mode variant, the defaults that differ between modes.
    per_mode: BTreeMap<String, Vec<PatchOf>>,
    /// Generation errors (a default the patches cannot carry).
    errors: Vec<String>,
}

impl Layout {
    /// Notes the defaults of the entry at `offset` that the image cannot hold. Returns the
    /// default the image holds (the first mode's).
    fn defaults_of(&mut self, e: &Entry, index: u16, offset: &TokenStream, defaults: &[(Ident, Init)]) -> Init {
        let first = defaults.first().map_or(Init::Int(0), |(_, v)| v.clone());
        let varies = defaults.iter().any(|(_, v)| *v != first);
        let width = e.data_type.bits().map_or(0, |b| b / 8);
        let patch = |value: &Init| PatchOf { index, offset: offset.clone(), width: width as u8, value: value.clone() };
        if varies || matches!(first, Init::NodeId(_)) {
            let int = |v: &Init| matches!(v, Init::Int(_) | Init::NodeId(_));
            if !(1..=4).contains(&width) || !defaults.iter().all(|(_, v)| int(v)) {
                self.errors
                    .push(format!("{index:04X}h sub {}: a default that depends on the mode or the node-ID must be an integer of at most 32 bits", e.sub));
            }
        }
        if varies {
            for (variant, v) in defaults {
                self.per_mode.entry(variant.to_string()).or_default().push(patch(v));
            }
        } else if matches!(first, Init::NodeId(_)) {
            self.node_ids.push(patch(&first));
        }
        first
    }
}

fn is_stored(e: &Entry) -> bool {
    e.storage != Storage::App
}

fn slot_layout(d: &Device, modes: &Modes, slot: &Slot<'_>, stack: &TokenStream, l: &mut Layout) {
    let o = slot.object;
    let index = slot.index;
    let kept: Vec<&Entry> = slot.entries.values().copied().filter(|e| is_stored(e)).collect();
    let Some(&first) = kept.first() else { return };
    let field = id(&o.ident);
    let doc = format!(" {index:04X}h {}", o.name);
    let defaults = |sub| mode_defaults(d, modes, index, sub);
    let persistent = |e: &Entry| e.storage == Storage::Persistent;
    let items: Vec<&Entry> = kept.iter().copied().filter(|e| e.sub > 0).collect();
    match (o.kind, items.first()) {
        (ObjectKind::Array, Some(&item)) => {
            let n = items.iter().map(|e| usize::from(e.sub)).max().unwrap_or(0);
            let ty = image_type(item, stack);
            let count = crate::dec(n as u64);
            let mut init = quote!(0);
            if let Some(e) = kept.iter().find(|e| e.sub == 0) {
                let offset = quote!(::core::mem::offset_of!(Values, #field.sub0));
                let v = l.defaults_of(e, index, &offset, &defaults(0));
                init = constant(e, &quote!(u8), &v, stack);
                l.leaves.push(Leaf { index, offset: offset.clone(), size: quote!(1), persistent: persistent(e) });
                l.offsets.insert((index, 0), offset);
            }
            let mut values = Vec::new();
            for i in 1..=n {
                let k = crate::dec((i - 1) as u64);
                let offset = quote!(::core::mem::offset_of!(Values, #field.items) + #k * ::core::mem::size_of::<#ty>());
                let Some(e) = items.iter().find(|e| usize::from(e.sub) == i) else {
                    values.push(constant(item, &ty, &Init::Int(0), stack));
                    continue;
                };
                if rust_type(e, stack).to_string() != rust_type(item, stack).to_string() {
                    l.errors.push(format!("{index:04X}h sub {i}: an array's elements must have one data type"));
                }
                let v = l.defaults_of(e, index, &offset, &defaults(e.sub));
                values.push(constant(e, &ty, &v, stack));
                l.offsets.insert((index, e.sub), offset);
            }
            // The items as one leaf when they persist alike (most arrays), else one each.
            if items.iter().all(|e| persistent(e) == persistent(item)) {
                let size = quote!(#count * ::core::mem::size_of::<#ty>());
                l.leaves.push(Leaf { index, offset: quote!(::core::mem::offset_of!(Values, #field.items)), size, persistent: persistent(item) });
            } else {
                for e in &items {
                    let offset = l.offsets.get(&(index, e.sub)).cloned().unwrap_or_default();
                    l.leaves.push(Leaf { index, offset, size: quote!(::core::mem::size_of::<#ty>()), persistent: persistent(e) });
                }
            }
            l.fields.push(quote!(#[doc = #doc] pub #field: #stack::value::Array<#ty, #count>));
            l.defaults.push(quote!(#field: #stack::value::Array { sub0: #init, items: [#(#values),*] }));
        }
        (ObjectKind::Record, _) => {
            let name = camel(&o.ident);
            let (mut sub_fields, mut inits, mut shape) = (Vec::new(), Vec::new(), String::new());
            for e in &kept {
                let f = id(&e.ident);
                let ty = image_type(e, stack);
                let offset = quote!(::core::mem::offset_of!(Values, #field.#f));
                let v = l.defaults_of(e, index, &offset, &defaults(e.sub));
                let init = constant(e, &ty, &v, stack);
                inits.push(quote!(#f: #init));
                l.leaves.push(Leaf { index, offset: offset.clone(), size: quote!(::core::mem::size_of::<#ty>()), persistent: persistent(e) });
                l.offsets.insert((index, e.sub), offset);
                let sdoc = format!(" Sub {}: {}", e.sub, e.name);
                shape.push_str(&format!("{}:{f}:{ty};", e.sub));
                sub_fields.push(quote!(#[doc = #sdoc] pub #f: #ty));
            }
            // Records of one shape (the PDO parameter records) share one type; the later ones
            // are aliases of the first.
            let record_type = match l.shapes.iter().find(|(s, _)| *s == shape) {
                Some((_, first)) => {
                    let alias = format!("{doc} (the same record as [`{first}`])");
                    l.structs.push(quote!(#[doc = #alias] pub type #name = #first;));
                    first.clone()
                }
                None => {
                    l.shapes.push((shape, name.clone()));
                    let zerocopy = zerocopy_path(stack);
                    let zerocopy_crate = zerocopy_crate(stack);
                    l.structs.push(quote! {
                        #[doc = #doc]
                        #[derive(Debug, Clone, Copy, PartialEq, #zerocopy::FromBytes, #zerocopy::IntoBytes, #zerocopy::KnownLayout, #zerocopy::Immutable, #zerocopy::Unaligned)]
                        #[zerocopy(crate = #zerocopy_crate)]
                        #[repr(C)]
                        pub struct #name { #(#sub_fields),* }
                    });
                    name.clone()
                }
            };
            l.fields.push(quote!(#[doc = #doc] pub #field: #name));
            l.defaults.push(quote!(#field: #record_type { #(#inits),* }));
        }
        // A VAR, a DOMAIN, or an array or record whose only stored entry is sub 0.
        _ => {
            let ty = image_type(first, stack);
            let offset = quote!(::core::mem::offset_of!(Values, #field));
            let v = l.defaults_of(first, index, &offset, &defaults(first.sub));
            l.leaves.push(Leaf { index, offset: offset.clone(), size: quote!(::core::mem::size_of::<#ty>()), persistent: persistent(first) });
            l.offsets.insert((index, first.sub), offset);
            l.fields.push(quote!(#[doc = #doc] pub #field: #ty));
            let init = constant(first, &ty, &v, stack);
            l.defaults.push(quote!(#field: #init));
        }
    }
}

fn zerocopy_path(stack: &TokenStream) -> TokenStream {
    quote!(#stack::zerocopy)
}

/// The path the zerocopy derives name their crate by, as the string their attribute takes.
fn zerocopy_crate(stack: &TokenStream) -> String {
    format!("{stack}::zerocopy").replace(' ', "")
}

fn layout(d: &Device, modes: &Modes, stack: &TokenStream) -> Layout {
    let mut l = Layout::default();
    for slot in slots(d) {
        slot_layout(d, modes, &slot, stack, &mut l);
    }
    l
}

/// `(index, sub)` -> the offset in the value image of every stored entry: the entry tables'
/// `offset`.
pub(crate) fn offsets(d: &Device, stack: &TokenStream) -> BTreeMap<(u16, u8), TokenStream> {
    layout(d, &Modes::of(d), stack).offsets
}

/// The class of an index: a span never holds two, since every `Area` is a union of whole
/// classes.
fn area_class(index: u16) -> u8 {
    match index {
        0x0000..=0x0FFF => 0,
        0x1000..=0x1FFF => 1,
        0x2000..=0x5FFF => 2,
        0x6000..=0x9FFF => 3,
        _ => 4,
    }
}

/// Consecutive leaves that `take` selects, of one index class, as one span each (the leaves
/// are in layout order, so consecutive ones are adjacent bytes).
fn spans(leaves: &[Leaf], take: impl Fn(&Leaf) -> bool, stack: &TokenStream) -> Vec<TokenStream> {
    let mut groups: Vec<Vec<&Leaf>> = Vec::new();
    let mut open = false;
    for leaf in leaves {
        match groups.last_mut() {
            Some(g) if open && take(leaf) && g.first().is_some_and(|f| area_class(f.index) == area_class(leaf.index)) => g.push(leaf),
            _ if take(leaf) => groups.push(vec![leaf]),
            _ => {}
        }
        open = take(leaf);
    }
    groups
        .iter()
        .filter_map(|g| {
            let (first, last) = (g.first()?, g.last()?);
            let index = crate::hex(first.index.into(), 4);
            let (start, end) = (&first.offset, &last.offset);
            let size = &last.size;
            Some(quote!(#stack::od::image::Span { index: #index, start: (#start) as u16, len: (#end + #size - (#start)) as u16 }))
        })
        .collect()
}

fn patch_tokens(p: &PatchOf, stack: &TokenStream) -> TokenStream {
    let index = crate::hex(p.index.into(), 4);
    let offset = &p.offset;
    let width = crate::dec(p.width.into());
    let (plus_node_id, value) = match p.value {
        Init::NodeId(v) => (true, v),
        Init::Int(v) => (false, v),
        _ => (false, 0),
    };
    let value = crate::hex(value as u32 as u64, 1);
    quote!(#stack::od::image::Patch::new(#index, (#offset) as u16, #width, #plus_node_id, #value))
}

pub fn dictionary(d: &Device, modes: &Modes, options: &Options) -> TokenStream {
    let stack = &options.stack;
    let block_transfer = d.identity.sdo_block_transfer;
    let has = |index: u16| d.objects.iter().any(|o| o.index == index);
    let (history, sync_cycle, consumer) = (has(0x1003), has(0x1006), has(0x1016));
    let l = layout(d, modes, stack);
    let errors = l.errors.iter().map(|e| quote!(::core::compile_error!(#e);));
    let stored = spans(&l.leaves, |_| true, stack);
    let persistent = spans(&l.leaves, |leaf| leaf.persistent, stack);
    let (stored_n, persistent_n) = (crate::dec(stored.len() as u64), crate::dec(persistent.len() as u64));
    let node_ids: Vec<TokenStream> = l.node_ids.iter().map(|p| patch_tokens(p, stack)).collect();
    let node_id_n = crate::dec(node_ids.len() as u64);
    let per_mode: Vec<Vec<TokenStream>> = modes
        .variants
        .iter()
        .map(|(v, _)| l.per_mode.get(&v.to_string()).map_or(Vec::new(), |ps| ps.iter().map(|p| patch_tokens(p, stack)).collect()))
        .collect();
    let (mode_tables, mode_select) = modes.tables("MODE_DEFAULTS", &quote!(#stack::od::image::Patch), &per_mode);
    let Layout { structs, fields, defaults, .. } = l;
    let zerocopy = zerocopy_path(stack);
    let zerocopy_crate = zerocopy_crate(stack);
    let node_config = node_config(d, stack);
    quote! {
        #(#errors)*
        #(#structs)*

        /// The values of every RAM and persistent entry, in index order: typed fields for the
        /// device's code, and, byte for byte, the value image the entry table's offsets point
        /// into (`coforge_stack::od::image`).
        // `Copy`: a copy of the defaults is one copy of their image, not one per field.
        #[derive(Debug, Clone, Copy, #zerocopy::FromBytes, #zerocopy::IntoBytes, #zerocopy::KnownLayout, #zerocopy::Immutable, #zerocopy::Unaligned)]
        #[zerocopy(crate = #zerocopy_crate)]
        #[repr(C)]
        pub struct Values {
            #(#fields),*
        }

        /// The spec's defaults (the first mode's where the modes differ; `$NODEID` ones
        /// without the node-ID, which `NODE_ID_DEFAULTS` adds).
        pub const DEFAULT_VALUES: Values = Values { #(#defaults),* };

        /// [`DEFAULT_VALUES`] as bytes, and in the sparse form kept in flash (most defaults
        /// are 0).
        const DEFAULT_IMAGE: [u8; ::core::mem::size_of::<Values>()] = #zerocopy::transmute!(DEFAULT_VALUES);
        static DEFAULTS: [u8; #stack::od::image::sparse_len(&DEFAULT_IMAGE)] = #stack::od::image::sparse(&DEFAULT_IMAGE);

        /// The spans NMT resets set back to the defaults.
        static STORED: [#stack::od::image::Span; #stored_n] = [#(#stored),*];

        /// The persistent block 1010h saves: the persistent spans one after the other.
        static PERSISTENT: [#stack::od::image::Span; #persistent_n] = [#(#persistent),*];

        /// The defaults `$NODEID + n` of every mode.
        static NODE_ID_DEFAULTS: [#stack::od::image::Patch; #node_id_n] = [#(#node_ids),*];

        #(#mode_tables)*

        /// The defaults of `mode` that differ between the modes.
        fn mode_defaults(mode: Mode) -> &'static [#stack::od::image::Patch] {
            #mode_select
        }

        /// The device's object dictionary: the values of what lives in RAM (`values`, also
        /// reached through `Deref`), `app` for what the device keeps elsewhere.
        #[derive(Debug, Clone)]
        pub struct Od<A> {
            mode: Mode,
            /// Reads and writes of app-backed objects go here.
            pub app: A,
            pub values: Values,
        }

        impl<A> ::core::ops::Deref for Od<A> {
            type Target = Values;
            fn deref(&self) -> &Values {
                &self.values
            }
        }

        impl<A> ::core::ops::DerefMut for Od<A> {
            fn deref_mut(&mut self) -> &mut Values {
                &mut self.values
            }
        }

        impl<A: #stack::od::AppObjects> Od<A> {
            /// The dictionary with the spec's defaults of `mode`, `$NODEID` resolved for
            /// `node_id`.
            pub fn new(mode: Mode, node_id: u8, app: A) -> Self {
                use #stack::od::NodeDictionary as _;
                let mut od = Od { mode, app, values: #zerocopy::FromZeros::new_zeroed() };
                od.reset_area(#stack::od::Area::ALL, node_id);
                od
            }

            pub fn mode(&self) -> Mode {
                self.mode
            }
        }

        /// The node settings of the spec's `node:` section, for `node_id`.
        pub const fn node_config(node_id: u8) -> #stack::config::NodeConfig {
            #node_config
        }

        impl<A: #stack::od::AppObjects> #stack::od::NodeDictionary for Od<A> {
            type Mode = Mode;
            const MODES: &'static [Mode] = &Mode::ALL;
            const PERSISTENT_SIZE: usize = #stack::od::image::block_len(&PERSISTENT);
            const SDO_BLOCK_TRANSFER: bool = #block_transfer;
            const COMM: #stack::od::CommObjects =
                #stack::od::CommObjects { error_history: #history, sync_cycle: #sync_cycle, heartbeat_consumer: #consumer };

            fn persistent() -> &'static [#stack::od::image::Span] {
                &PERSISTENT
            }

            fn stored() -> &'static [#stack::od::image::Span] {
                &STORED
            }

            fn node_id_defaults() -> &'static [#stack::od::image::Patch] {
                &NODE_ID_DEFAULTS
            }

            fn defaults() -> &'static [u8] {
                &DEFAULTS
            }

            fn mode_defaults(&self) -> &'static [#stack::od::image::Patch] {
                mode_defaults(self.mode)
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

            fn set_mode(&mut self, mode: Mode, node_id: u8) {
                self.mode = mode;
                #stack::od::image::patch(#zerocopy::IntoBytes::as_mut_bytes(&mut self.values), mode_defaults(mode), #stack::od::Area::ALL, node_id);
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

            fn entries(&self) -> #stack::od::Table<'static> {
                od::entries(self.mode)
            }

            fn limits(&self) -> &'static [#stack::od::Limits] {
                &od::LIMITS
            }

            fn image(&self) -> &[u8] {
                #zerocopy::IntoBytes::as_bytes(&self.values)
            }

            fn image_mut(&mut self) -> &mut [u8] {
                #zerocopy::IntoBytes::as_mut_bytes(&mut self.values)
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
