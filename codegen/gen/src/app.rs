//! `app::Hooks`: one typed hook per app-backed object or group of repeated objects, and
//! `app::Typed<H>`, the `AppObjects` that routes the dictionary's app reads and writes to
//! them. The owner of an object handles its reads and writes; the device names objects by
//! hook, never by number. `Hooks` also carries the provided `AppObjects` hooks (write
//! indications, streamed SDO downloads) by index, which `Typed` forwards.
//!
//! A group is the objects one `repeat` template made (they share its span), in index order:
//! CO401Memory1's 64 memory blocks are one hook taking the block number `n`, CR3101's
//! "Designation file f" objects (3000h, 3100h, ..) one taking the file.

use crate::Options;
use crate::dictionary::rust_type;
use coforge_spec::model::{Device, Entry, Object};
use coforge_spec::types::{ObjectKind, Storage};
use proc_macro2::TokenStream;
use quote::{format_ident, quote};
use std::collections::BTreeMap;

/// Objects of one template with app-backed entries.
struct Group<'a> {
    /// Hook name: the objects' common identifier.
    name: String,
    objects: Vec<&'a Object>,
}

fn app_entries(o: &Object) -> impl Iterator<Item = &Entry> {
    o.entries.iter().filter(|e| e.storage == Storage::App)
}

/// Every index once (its first definition over the modes), in index order.
fn objects(d: &Device) -> Vec<&Object> {
    let mut by_index: BTreeMap<u16, &Object> = BTreeMap::new();
    for o in &d.objects {
        by_index.entry(o.index).or_insert(o);
    }
    by_index.into_values().collect()
}

/// The identifier tokens the objects of a group have in common (`memory_block_0_byte_access`
/// and `memory_block_1_byte_access` give `memory_block_byte_access`).
fn common_name(objects: &[&Object]) -> String {
    let [first, rest @ ..] = objects else { return String::new() };
    let Some(second) = rest.first() else { return first.ident.clone() };
    let (a, b): (Vec<&str>, Vec<&str>) = (first.ident.split('_').collect(), second.ident.split('_').collect());
    if a.len() != b.len() {
        return first.ident.clone();
    }
    a.iter().zip(&b).filter(|(x, y)| x == y).map(|(x, _)| *x).collect::<Vec<_>>().join("_")
}

fn groups(d: &Device) -> Vec<Group<'_>> {
    let mut out: Vec<Group<'_>> = Vec::new();
    for o in objects(d).into_iter().filter(|o| app_entries(o).next().is_some()) {
        let same_template = |g: &&mut Group<'_>| g.objects.first().is_some_and(|f| f.span == o.span && f.kind == o.kind);
        match out.iter_mut().find(same_template) {
            Some(g) => g.objects.push(o),
            None => out.push(Group { name: String::new(), objects: vec![o] }),
        }
    }
    for g in &mut out {
        g.name = common_name(&g.objects);
    }
    out
}

/// How an accessed index selects the group and the object in it: `(pattern, n expression)`.
fn select(g: &Group<'_>) -> (TokenStream, Option<TokenStream>) {
    let indices: Vec<u16> = g.objects.iter().map(|o| o.index).collect();
    let first = indices.first().copied().unwrap_or_default();
    let last = indices.last().copied().unwrap_or_default();
    let (lo, hi) = (crate::hex(first.into(), 4), crate::hex(last.into(), 4));
    if indices.len() == 1 {
        return (quote!(#lo), None);
    }
    let stride = indices.get(1).map_or(1, |s| s - first);
    let progression = indices.iter().enumerate().all(|(i, &x)| u32::from(x) == u32::from(first) + u32::from(stride) * i as u32);
    if progression && stride == 1 {
        (quote!(#lo..=#hi), Some(quote!(index - #lo)))
    } else if progression {
        let stride = crate::hex(stride.into(), 1);
        (quote!(i @ #lo..=#hi if (i - #lo) % #stride == 0), Some(quote!((index - #lo) / #stride)))
    } else {
        let pats = indices.iter().map(|&i| crate::hex(i.into(), 4));
        let arms = indices.iter().enumerate().map(|(n, &i)| {
            let (i, n) = (crate::hex(i.into(), 4), crate::dec(n as u64));
            quote!(#i => #n)
        });
        (quote!(#(#pats)|*), Some(quote!(match index { #(#arms,)* _ => 0 })))
    }
}

/// `1..=128` or `0, 2, 4..=5`: the sub-indices a hook answers.
fn sub_ranges(entries: &[&Entry]) -> String {
    let mut runs: Vec<(u8, u8)> = Vec::new();
    for e in entries {
        match runs.last_mut() {
            Some((_, last)) if u16::from(*last) + 1 == u16::from(e.sub) => *last = e.sub,
            _ => runs.push((e.sub, e.sub)),
        }
    }
    let text: Vec<String> = runs.iter().map(|&(a, b)| if a == b { a.to_string() } else { format!("{a}..={b}") }).collect();
    text.join(", ")
}

pub fn app_module(d: &Device, options: &Options) -> TokenStream {
    let stack = &options.stack;
    let groups = groups(d);
    if groups.is_empty() {
        return TokenStream::new();
    }
    let mut hooks = Vec::new();
    let mut read_arms = Vec::new();
    let mut write_arms = Vec::new();
    for g in &groups {
        let Some(first) = g.objects.first() else { continue };
        let entries: Vec<&Entry> = app_entries(first).collect();
        let types: std::collections::BTreeSet<String> = entries.iter().map(|e| rust_type(e, stack).to_string()).collect();
        let typed = types.len() == 1 && entries.iter().all(|e| e.data_type.bits().is_some_and(|b| b <= 64) && !e.data_type.is_real());
        let writable = g.objects.iter().flat_map(|o| app_entries(o)).any(|e| e.access.writable() || e.host_access.writable());
        let (pattern, n) = select(g);
        let with_sub = first.kind != ObjectKind::Var;
        let (read, write) = (format_ident!("read_{}", g.name), format_ident!("write_{}", g.name));
        let indices = match (g.objects.first(), g.objects.last()) {
            (Some(a), Some(b)) if g.objects.len() > 1 => format!("{:04X}h..{:04X}h ({} objects)", a.index, b.index, g.objects.len()),
            _ => format!("{:04X}h", first.index),
        };
        let doc = format!(" {indices} {}: sub-index {}.", first.name, sub_ranges(&entries));
        let n_param = n.as_ref().map(|_| quote!(n: u16,));
        let n_arg = n.as_ref().map(|n| quote!(#n,));
        let sub_param = with_sub.then(|| quote!(sub: u8,));
        let sub_arg = with_sub.then(|| quote!(sub,));
        let ty = entries.first().map(|e| rust_type(e, stack)).unwrap_or_else(|| quote!(u8));
        if typed {
            hooks.push(quote! {
                #[doc = #doc]
                fn #read(&mut self, #n_param #sub_param) -> Result<#ty, #stack::od::SdoAbort>;
            });
            // A value as wide as its Rust type (all but BOOLEAN and the 24/40/48/56-bit
            // types) is its little-endian bytes: no generic conversion on the RPDO, TPDO and
            // serial paths.
            let exact = entries
                .iter()
                .all(|e| e.data_type.bits().is_some_and(|b| matches!(b, 8 | 16 | 32 | 64)) && e.data_type != coforge_spec::types::DataType::Boolean);
            let (to_bytes, from_bytes) = if exact {
                (
                    quote!(#stack::od::read_slice(&value.to_le_bytes(), offset, buf)),
                    quote!(let value = #ty::from_le_bytes(data.try_into().map_err(|_| #stack::od::SdoAbort::LengthMismatch)?);),
                )
            } else {
                (
                    quote!(#stack::value::OdValue::read(&value, entry, offset, buf)),
                    quote! {
                        let mut value: #ty = Default::default();
                        #stack::value::OdValue::write(&mut value, entry, data)?;
                    },
                )
            };
            read_arms.push(quote! {
                #pattern => {
                    let value = self.0.#read(#n_arg #sub_arg)?;
                    #to_bytes
                }
            });
            if writable {
                hooks.push(quote! {
                    #[doc = #doc]
                    fn #write(&mut self, #n_param #sub_param value: #ty) -> Result<(), #stack::od::SdoAbort>;
                });
                write_arms.push(quote! {
                    #pattern => {
                        #from_bytes
                        self.0.#write(#n_arg #sub_arg value)
                    }
                });
            }
        } else {
            hooks.push(quote! {
                #[doc = #doc]
                fn #read(&mut self, #n_param #sub_param offset: usize, buf: &mut [u8]) -> Result<#stack::od::ReadLen, #stack::od::SdoAbort>;
            });
            read_arms.push(quote!(#pattern => self.0.#read(#n_arg #sub_arg offset, buf)));
            if writable {
                hooks.push(quote! {
                    #[doc = #doc]
                    fn #write(&mut self, #n_param #sub_param data: &[u8]) -> Result<(), #stack::od::SdoAbort>;
                });
                write_arms.push(quote!(#pattern => self.0.#write(#n_arg #sub_arg data)));
            }
        }
    }
    quote! {
        /// The device's app-backed objects as typed hooks (see `Hooks`).
        pub mod app {
            /// One hook per app-backed object or group of repeated objects: the device owns
            /// their data and answers their reads and writes. The dictionary has made the
            /// access, length and value checks before a hook runs; `n` is the object's place
            /// in its group, `sub` the sub-index accessed.
            ///
            /// The provided hooks are the `AppObjects` ones of the same names (write
            /// indications, streamed SDO downloads): empty unless the device overrides them.
            pub trait Hooks {
                #(#hooks)*

                /// A write of a local entry took effect (`AppObjects::written`).
                fn written(&mut self, _index: u16, _sub: u8, _data: &[u8], _by: #stack::od::WriteSource) {}

                /// Whether any object streams its SDO downloads (`AppObjects::STREAMING`).
                const STREAMING: bool = false;

                /// Whether an SDO download of this app-backed entry streams (`AppObjects::streams`).
                fn streams(&mut self, _index: u16, _sub: u8) -> bool {
                    false
                }

                /// The next part of a streamed download (`AppObjects::write_part`).
                fn write_part(&mut self, _index: u16, _sub: u8, _offset: usize, _data: &[u8], _last: bool) -> Result<(), #stack::od::SdoAbort> {
                    Err(#stack::od::SdoAbort::UnsupportedAccess)
                }

                /// A streamed download failed (`AppObjects::abort_stream`).
                fn abort_stream(&mut self, _index: u16, _sub: u8) {}
            }

            /// The dictionary's `AppObjects`: routes each app-backed access to its hook.
            #[derive(Debug, Clone, Default)]
            pub struct Typed<H>(pub H);

            impl<H> core::ops::Deref for Typed<H> {
                type Target = H;
                fn deref(&self) -> &H {
                    &self.0
                }
            }

            impl<H> core::ops::DerefMut for Typed<H> {
                fn deref_mut(&mut self) -> &mut H {
                    &mut self.0
                }
            }

            impl<H: Hooks> #stack::od::AppObjects for Typed<H> {
                #[allow(unused_variables, clippy::identity_op)]
                fn read(&mut self, entry: &#stack::od::EntryInfo, index: u16, sub: u8, offset: usize, buf: &mut [u8]) -> Result<#stack::od::ReadLen, #stack::od::SdoAbort> {
                    match index {
                        #(#read_arms,)*
                        _ => Err(#stack::od::SdoAbort::NoObject),
                    }
                }

                #[allow(unused_variables, unreachable_patterns, clippy::identity_op)]
                fn write(&mut self, entry: &#stack::od::EntryInfo, index: u16, sub: u8, data: &[u8]) -> Result<(), #stack::od::SdoAbort> {
                    match index {
                        #(#write_arms,)*
                        // Read-only app objects: only the device itself could try.
                        _ => Err(#stack::od::SdoAbort::ReadOnly),
                    }
                }

                fn written(&mut self, index: u16, sub: u8, data: &[u8], by: #stack::od::WriteSource) {
                    self.0.written(index, sub, data, by)
                }

                const STREAMING: bool = H::STREAMING;

                fn streams(&mut self, _: &#stack::od::EntryInfo, index: u16, sub: u8) -> bool {
                    self.0.streams(index, sub)
                }

                fn write_part(&mut self, _: &#stack::od::EntryInfo, index: u16, sub: u8, offset: usize, data: &[u8], last: bool) -> Result<(), #stack::od::SdoAbort> {
                    self.0.write_part(index, sub, offset, data, last)
                }

                fn abort_stream(&mut self, _: &#stack::od::EntryInfo, index: u16, sub: u8) {
                    self.0.abort_stream(index, sub)
                }
            }
        }
    }
}
