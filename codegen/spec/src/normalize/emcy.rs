//! `emergencies:`.

use super::{Cx, hex_bytes, scalar_kind, span};
use crate::expr::Vars;
use crate::model::{Emergency, NmtEffect, OutputEffect};
use crate::raw::{self, S, Scalar};
use crate::types::EmcyEvent;

pub(super) fn emergency(cx: &mut Cx<'_>, e: &S<raw::Emergency>) -> Option<Emergency> {
    let none = Vars::new();
    let v = &e.value;
    let code = cx.int_in(&v.code, &none, "emergency code", 0, 0xFFFF)?;
    let error_register = cx.int_in(&v.error_register, &none, "error register", 0, 0xFF)?;
    let manufacturer = match &v.manufacturer.value {
        Scalar::Str(s) => match hex_bytes(s, true) {
            Ok(b) if b.len() == 5 => [b[0], b[1], b[2], b[3], b[4]],
            Ok(b) => {
                cx.err("spec-value", span(&v.manufacturer), format!("`manufacturer` has {} bytes; an EMCY frame carries exactly 5 (bytes 3..7)", b.len()));
                return None;
            }
            Err(m) => {
                cx.err("spec-value", span(&v.manufacturer), m);
                return None;
            }
        },
        other => {
            cx.err("spec-value", span(&v.manufacturer), format!("`manufacturer` must be 5 hex bytes such as `00 00 00 00 80`, found {}", scalar_kind(other)));
            return None;
        }
    };
    let example = match &v.example {
        Some(x) => match &x.value {
            Scalar::Str(s) => match hex_bytes(s, false) {
                Ok(b) => Some(b.into_iter().flatten().collect()),
                Err(m) => {
                    cx.err("spec-value", span(x), m);
                    return None;
                }
            },
            other => {
                cx.err("spec-value", span(x), format!("`example` must be hex bytes, found {}", scalar_kind(other)));
                return None;
            }
        },
        None => None,
    };
    let nmt = match &v.nmt {
        Some(n) => cx.keyword(
            n,
            "NMT effect",
            |s| match s {
                "none" => Some(NmtEffect::None),
                "error_behavior" => Some(NmtEffect::ErrorBehavior),
                "preoperational" => Some(NmtEffect::PreOperational),
                "stopped" => Some(NmtEffect::Stopped),
                _ => None,
            },
            "none, error_behavior, preoperational, stopped",
        )?,
        None => NmtEffect::None,
    };
    let outputs = match &v.outputs {
        Some(n) => cx.keyword(
            n,
            "output effect",
            |s| match s {
                "unchanged" => Some(OutputEffect::Unchanged),
                "error_state" => Some(OutputEffect::ErrorState),
                _ => None,
            },
            "unchanged, error_state",
        )?,
        None => OutputEffect::Unchanged,
    };
    let event = match &v.event {
        Some(n) => Some(cx.keyword(n, "stack event", EmcyEvent::parse, &EmcyEvent::ALL.map(EmcyEvent::name).join(", "))?),
        None => None,
    };
    Some(Emergency {
        name: v.name.value.clone(),
        event,
        code,
        error_register,
        manufacturer,
        description: v.description.clone().unwrap_or_default(),
        trigger: v.trigger.clone().unwrap_or_default(),
        nmt,
        outputs,
        reset: v.reset.clone().unwrap_or_default(),
        enabled_by: match &v.enabled_by {
            Some(n) => Some(cx.int_in(n, &none, "enabled_by", 1, 0xFFFF)?),
            None => None,
        },
        example_span: v.example.as_ref().map_or(span(e), span),
        example,
        modes: cx.modes(v.modes.as_ref(), &None),
        span: span(e),
    })
}
