//! `serial::proofs` (under `cfg(kani)`): a Kani harness per command of the protocol, that
//! `decode(encode(x)) == x` for every frame of its codes and lengths, and one that the
//! protocol's decoder is total on symbolic bytes and arrival gaps. The properties themselves
//! are `coforge_link::properties`, which the verification crate's random tests run too.

use crate::naming::ident as snake;
use coforge_spec::model::{Command, Direction, FieldType, Framing, Serial};
use proc_macro2::{Ident, Span, TokenStream};
use quote::quote;

/// Data bytes a harness gives a command's variable tail: enough to show the tail is carried
/// whole, few enough that Kani finishes in minutes (framing-level harnesses cover long data).
pub const TAIL_BYTES: u32 = 4;
/// Bytes the decoder-totality harness pushes: longer than most commands' frames.
pub const TOTAL_BYTES: usize = 8;
/// As [`TOTAL_BYTES`], for a start+CRC framing: its frames carry 5 bytes of framing, and
/// with 8 bytes CBMC ran out of 24 GB on CANopenIA's (the CRC over every split of the bytes
/// into garbage and frames). 6 bytes still hold a whole frame with 2 payload bytes after
/// a byte of garbage; the framing-level harness covers the decoder itself on 8 bytes.
pub const TOTAL_BYTES_START_CRC: usize = 6;
/// Longest framing overhead: start byte, two length bytes, two CRC bytes (start+CRC).
const OVERHEAD: u32 = 5;

/// The most data bytes the harness of `c` tries.
pub fn harness_data_len(c: &Command) -> u32 {
    let tail = match c.tail().map(|t| t.ty) {
        Some(FieldType::Tail { max }) => max.min(TAIL_BYTES),
        _ => 0,
    };
    // A length code stands for the whole length: the harness tries the fixed fields only.
    (c.fixed_size() + tail).clamp(c.length.0.min(c.length.1), c.length.1)
}

/// The harness name of `c`: `round_trip_<direction>_<command>`.
pub fn harness_name(c: &Command) -> String {
    let dir = match c.direction {
        Direction::HostToDevice => "host_to_device",
        Direction::DeviceToHost => "device_to_host",
    };
    format!("round_trip_{dir}_{}", snake(&c.name))
}

fn round_trip(c: &Command) -> TokenStream {
    let name = Ident::new(&harness_name(c), Span::call_site());
    let max = harness_data_len(c);
    let min = c.length.0.min(max);
    let (max_l, min_l) = (crate::dec(max.into()), crate::dec(min.into()));
    let out = crate::dec((max + OVERHEAD).into());
    let codes: Vec<TokenStream> = c.codes().iter().map(|&x| crate::hex(x.into(), 2)).collect();
    let n_codes = crate::dec(codes.len() as u64);
    let lc = match c.length_code {
        Some(x) => {
            let x = crate::hex(x.into(), 2);
            quote!(Some(#x))
        }
        None => quote!(None),
    };
    let dir = match c.direction {
        Direction::HostToDevice => quote!(HostToDevice),
        Direction::DeviceToHost => quote!(DeviceToHost),
    };
    // Loops run over the frame's bytes and the decoder's CRC bytes.
    let unwind = crate::dec((max + OVERHEAD + 2).into());
    let doc = format!(" `{}`: decode(encode(x)) == x for each of its codes and {min}..={max} data bytes.", c.name);
    quote! {
        #[doc = #doc]
        #[kani::proof]
        #[kani::unwind(#unwind)]
        fn #name() {
            const CODES: [u8; #n_codes] = [#(#codes),*];
            let which: usize = kani::any();
            kani::assume(which < CODES.len());
            let data: [u8; #max_l] = kani::any();
            let len: usize = kani::any();
            kani::assume((#min_l..=#max_l).contains(&len));
            let mut out = [0_u8; #out];
            let mut copy = [0_u8; super::MAX_DATA];
            prop_round_trip::<super::Codec>(Direction::#dir, CODES[which], #lc, &data[..len], &mut out, &mut copy);
        }
    }
}

/// The harnesses of `serial`, or nothing for a device without a serial protocol.
pub fn proofs_module(serial: &Serial) -> TokenStream {
    let harnesses = serial.commands.iter().map(round_trip);
    // The loops run over the pushed bytes and, with a CRC, over a command's frame encoded
    // again (its data and the framing's bytes).
    let (bytes, unwind) = match serial.framing {
        Framing::StartLengthCrc { .. } => (TOTAL_BYTES_START_CRC, TOTAL_BYTES_START_CRC as u32 + OVERHEAD + 2),
        Framing::NibbleLength { .. } | Framing::LengthByte { .. } => (TOTAL_BYTES, TOTAL_BYTES as u32 + 2),
    };
    let n = crate::dec(bytes as u64);
    let unwind = crate::dec(unwind.into());
    let doc = format!(" The decoder takes any {bytes} bytes at any gaps without panicking; every frame it completes decodes and encodes again.");
    quote! {
        /// Kani harnesses over this protocol (`cargo kani`; see verification/README.md).
        #[cfg(kani)]
        mod proofs {
            use ::coforge_link::properties::{Direction, prop_decoder_total, prop_round_trip};

            #(#harnesses)*

            #[doc = #doc]
            #[kani::proof]
            #[kani::unwind(#unwind)]
            fn decoder_total() {
                let bytes: [u8; #n] = kani::any();
                let gaps: [u8; 2] = kani::any();
                let mut out = [0_u8; super::MAX_DATA + 8];
                prop_decoder_total::<super::Codec>(&bytes, &gaps, &mut out);
            }
        }
    }
}
