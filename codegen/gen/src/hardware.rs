//! `hardware`: decoders for the spec's configuration pins (node-ID, bit rates, configuration
//! inputs), so a board passes raw pin levels and gets the datasheet's meaning back.
//!
//! `levels` bit n is the level of the selector's n-th pin (1 = high). Pins read through an
//! inverter (`inverted: true`) count a low level as a 1 bit, as the datasheet's tables do.

use coforge_spec::model::{Device, Selector, SelectorSource};
use proc_macro2::TokenStream;
use quote::{format_ident, quote};

/// `(pins, inverted)` of a pin-selected selector.
fn pins(s: &Selector) -> Option<(&[String], bool)> {
    match &s.source {
        SelectorSource::Pins { pins, inverted } => Some((pins, *inverted)),
        _ => None,
    }
}

/// The code the pins form: masked to the pin count, inverted where the spec says so.
fn code_expr(count: usize, inverted: bool) -> TokenStream {
    let mask = crate::hex((1_u64 << count) - 1, 2);
    if inverted { quote!(!levels & #mask) } else { quote!(levels & #mask) }
}

/// `fn name(levels) -> Option<u32>`: the code's value, `None` for reserved or unlisted codes.
fn selector_fn(name: &str, s: &Selector) -> Option<TokenStream> {
    let (pins, inverted) = pins(s)?;
    let ident = format_ident!("{name}");
    let code = code_expr(pins.len(), inverted);
    let doc = format!(" Pins {} ({}): {}", pins.join(", "), if inverted { "active low" } else { "active high" }, s.description);
    let value = if s.codes.iter().any(|c| c.value.is_some()) {
        let arms = s.codes.iter().filter(|c| !c.reserved).filter_map(|c| {
            let (code, value) = (crate::dec(u64::try_from(c.code).ok()?), crate::dec(u64::try_from(c.value?).ok()?));
            Some(quote!(#code => Some(#value),))
        });
        quote!(match code { #(#arms)* _ => None })
    } else {
        // The code is the value itself (a node-ID), within the range and not reserved.
        let reserved = s.codes.iter().filter(|c| c.reserved).filter_map(|c| u64::try_from(c.code).ok()).map(crate::dec);
        let (low, high) = s.range.unwrap_or((0, i64::from(u16::MAX)));
        let (low, high) = (crate::dec(u64::try_from(low).unwrap_or(0)), crate::dec(u64::try_from(high).unwrap_or(0)));
        quote!(match code { #(#reserved)|* => None, c if c >= #low && c <= #high => Some(c as u32), _ => None })
    };
    let value =
        if s.codes.iter().any(|c| c.reserved) || s.codes.iter().any(|c| c.value.is_some()) || s.range.is_some() { value } else { quote!(Some(code as u32)) };
    Some(quote! {
        #[doc = #doc]
        #[allow(clippy::match_single_binding, clippy::manual_range_contains, clippy::absurd_extreme_comparisons, unused_comparisons, unreachable_patterns)]
        pub const fn #ident(levels: u16) -> Option<u32> {
            let code = #code;
            #value
        }
    })
}

pub fn hardware_module(d: &Device) -> TokenStream {
    let h = &d.hardware;
    let selectors = [("node_id", &h.node_id), ("can_bitrate", &h.can_bitrate), ("serial_bitrate", &h.serial_bitrate)];
    let fns: Vec<TokenStream> = selectors.iter().filter_map(|(name, s)| selector_fn(name, s.as_ref()?)).collect();
    let config = h.config_pins.as_ref().map(|c| {
        let code = code_expr(c.pins.len(), c.inverted);
        let doc = format!(" Configuration pins {}: the value a system configuration object shows. {}", c.pins.join(", "), c.description);
        quote! {
            #[doc = #doc]
            pub const fn config(levels: u16) -> u32 {
                (#code) as u32
            }
        }
    });
    quote! {
        /// The configuration pins of the datasheet. `levels` bit n is the level of the n-th
        /// pin listed (1 = high).
        pub mod hardware {
            #(#fns)*
            #config
        }
    }
}
