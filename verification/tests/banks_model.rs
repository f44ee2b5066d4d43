//! An exhaustive search of the mirrored banks' state space on a tiny geometry (2 blocks of 2
//! bytes, 12 bytes per bank): breadth-first over every sequence of operations up to a depth,
//! with visited states hashed, from blank banks (the first mount formats them) and from banks
//! whose sequence numbers are about to wrap. The operations:
//!
//! - write block i with a value from a 3-value alphabet;
//! - the same write with the power cut at any byte write, leaving the byte old, new or any
//!   value that could matter (every marker value in the banks, +1, complemented, 0x00, 0xFF);
//! - a single-byte corruption of either bank (4 values per byte, at most 2 per path), only
//!   while the other bank's copy of that block is intact (valid, holding a committed or
//!   in-flight value), also while the power is off;
//! - a read and a `check_block` of each block;
//! - a reboot, and a reboot with the power cut at any byte write of the recovery.
//!
//! After every transition: a reboot (on a copy of the devices) reads every block as its
//! committed value or the value of a write cut in flight, never a mix and never lost, and
//! leaves banks that agree and a second mount that writes nothing; a recovery cut changes
//! nothing that the next completed recovery reads; a completed write is in both banks; reads
//! return the committed values; `check_block` flags a corrupted copy; the bank sums equal a
//! recomputation whenever no corrupted data byte is waiting to be read.

use coforge_verification::banks::*;
use std::collections::HashSet;
use std::hash::{DefaultHasher, Hash, Hasher};

const N: usize = 12;
const BLOCKS: usize = 2;
const BLOCK: usize = 2;
type Tiny<'p> = Banks<'p, N, BLOCKS, BLOCK>;
type Images = [[u8; N]; 2];
type Value = [u8; BLOCK];
/// A state and the hash of its key.
type Found = (State, (u64, u64));

const VALUES: [Value; 3] = [[0x00, 0x00], [0x01, 0x80], [0xFF, 0x01]];
const CORRUPTIONS: u8 = 2;

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
enum Op {
    Write(usize, usize),
    CutWrite(usize, usize, u32, CutByte),
    Corrupt(usize, usize, u8),
    Read(usize),
    Check(usize),
    Reboot,
    RebootCut(u32, CutByte),
}

#[derive(Debug, Clone)]
struct State {
    /// Powered: the images the last mount started from (the live banks are that mount plus
    /// `since`). Off: the images now.
    images: Images,
    since: Vec<Op>,
    powered: bool,
    committed: [Value; BLOCKS],
    /// A write cut in flight, not yet settled by a completed reboot.
    pending: [Option<Value>; BLOCKS],
    corruptions: u8,
    /// A corrupted byte in the block's pair not yet repaired (both copies valid and equal).
    corrupted: [bool; BLOCKS],
    /// A corrupted data byte in `[bank][block]` that no load has seen yet.
    dirty: [[bool; BLOCKS]; 2],
    path: Vec<Op>,
}

fn devices<'p>(power: &'p Power, images: &Images) -> [CutEeprom<'p, N>; 2] {
    [CutEeprom::new(power, images[0]), CutEeprom::new(power, images[1])]
}

/// The live banks of a powered state.
fn rebuild<'p>(power: &'p Power, s: &State) -> Tiny<'p> {
    power.restore_power();
    let mut banks = Tiny::mount(devices(power, &s.images));
    for &op in &s.since {
        match op {
            Op::Write(block, v) => banks.write(block * BLOCK, &VALUES[v]).expect("replayed write"),
            Op::Corrupt(bank, pos, value) => banks.banks_mut()[bank].as_bytes_mut()[pos] = value,
            Op::Read(block) => {
                let _ = banks.read(block * BLOCK, &mut [0; BLOCK]);
            }
            Op::Check(block) => {
                let _ = banks.check_block(block);
            }
            _ => unreachable!("only powered operations are replayed"),
        }
    }
    banks.clear_status(0);
    banks.clear_status(1);
    banks
}

fn images_of(power: &Power, s: &State) -> Images {
    if s.powered { images(&rebuild(power, s)) } else { s.images }
}

fn acceptable(s: &State, block: usize, content: &Value) -> bool {
    *content == s.committed[block] || s.pending[block] == Some(*content)
}

/// What a completed reboot of `images` reads, after checking that it is acceptable for `s`,
/// that the banks then agree and that a second mount writes nothing.
fn reboot_view(s: &State, images: &Images) -> Result<[Value; BLOCKS], String> {
    let power = Power::new();
    let mut banks = Tiny::mount(devices(&power, images));
    let mut view = [[0; BLOCK]; BLOCKS];
    for (block, c) in contents(&mut banks).into_iter().enumerate() {
        match c {
            Ok(c) if acceptable(s, block, &c) => view[block] = c,
            other => return Err(format!("a reboot reads block {block} as {other:?}, expected {:?} or {:?}", s.committed[block], s.pending[block])),
        }
    }
    if disagreeing_blocks(&banks) != 0 {
        return Err("the banks disagree after a reboot".into());
    }
    reset_counts(&mut banks);
    let again = Tiny::mount(banks.into_banks());
    if writes(&again) != 0 {
        return Err("a second mount writes".into());
    }
    Ok(view)
}

fn key(s: &State, live: Option<&Tiny<'_>>, images: &Images) -> (u64, u64) {
    let text = match live {
        Some(banks) => format!("{banks:?} {:?} {:?} {} {:?} {:?}", s.committed, s.pending, s.corruptions, s.corrupted, s.dirty),
        None => format!("off {images:?} {:?} {:?} {} {:?}", s.committed, s.pending, s.corruptions, s.corrupted),
    };
    let mut a = DefaultHasher::new();
    text.hash(&mut a);
    let mut b = DefaultHasher::new();
    (text, 0x9E37_79B9_u32).hash(&mut b);
    (a.finish(), b.finish())
}

/// Every byte value a torn byte could hold that compares equal to something that matters.
fn cut_bytes(images: &Images) -> Vec<CutByte> {
    let mut values = vec![0x00_u8, 0xFF, GARBAGE];
    for image in images {
        for block in 0..BLOCKS {
            let slot = slot::<BLOCK>(image, block);
            for &m in &[slot[BLOCK], slot[BLOCK + 3]] {
                values.extend([m, m.wrapping_add(1), !m, !m.wrapping_add(1)]);
            }
        }
    }
    values.sort_unstable();
    values.dedup();
    let mut cuts = vec![CutByte::Old, CutByte::New];
    cuts.extend(values.into_iter().map(CutByte::Garbage));
    cuts
}

struct Stats {
    transitions: u64,
    cut_writes: u64,
    recovery_cuts: u64,
    corruptions: u64,
}

/// All successors of `s`, each checked; an `Err` is a violated invariant.
fn successors(s: &State, stats: &mut Stats) -> Result<Vec<Found>, String> {
    let power = Power::new();
    let now = images_of(&power, s);
    let view_before = reboot_view(s, &now)?;
    let mut ops = Vec::new();
    let cuts = cut_bytes(&now);
    if s.powered {
        for block in 0..BLOCKS {
            for v in 0..VALUES.len() {
                ops.push(Op::Write(block, v));
                for &c in &cuts {
                    ops.push(Op::CutWrite(block, v, u32::MAX, c));
                }
            }
            ops.push(Op::Read(block));
            ops.push(Op::Check(block));
        }
    } else {
        for &c in &cuts {
            ops.push(Op::RebootCut(u32::MAX, c));
        }
    }
    ops.push(Op::Reboot);
    if s.corruptions < CORRUPTIONS {
        for bank in 0..2 {
            for pos in 0..N {
                let block = pos / slot_size(BLOCK);
                let other = slot::<BLOCK>(&now[1 - bank], block);
                let intact = copy_is_valid::<BLOCK>(&now[1 - bank], block) && acceptable(s, block, &other[..BLOCK].try_into().unwrap());
                if s.corrupted[block] || !intact {
                    continue;
                }
                let stored = now[bank][pos];
                let offset = pos % slot_size(BLOCK);
                // A data or CRC byte: one-bit flips (the CRC sees any change alike). A marker:
                // every value it could be compared with.
                let mut values = vec![stored ^ 0x01, stored ^ 0x80];
                if offset == BLOCK || offset == BLOCK + 3 {
                    values.extend([0x00, 0xFF]);
                    for image in &now {
                        let slot = slot::<BLOCK>(image, block);
                        for m in [slot[BLOCK], slot[BLOCK + 3]] {
                            values.extend([m, m.wrapping_add(1), m.wrapping_sub(1), !m]);
                        }
                    }
                }
                values.sort_unstable();
                values.dedup();
                values.retain(|&v| v != stored);
                for v in values {
                    ops.push(Op::Corrupt(bank, pos, v));
                }
            }
        }
    }
    let mut out = Vec::new();
    for op in ops {
        match op {
            // Every cut step of the operation, until one no longer fires.
            Op::CutWrite(block, v, _, c) => {
                for k in 0.. {
                    match apply(s, Op::CutWrite(block, v, k, c), &view_before)? {
                        Step::Next(next, key) => {
                            stats.cut_writes += 1;
                            out.push((next, key));
                        }
                        Step::Redundant => {}
                        Step::NoCut => break,
                    }
                }
            }
            Op::RebootCut(_, c) => {
                for k in 0.. {
                    match apply(s, Op::RebootCut(k, c), &view_before)? {
                        Step::Next(next, key) => {
                            stats.recovery_cuts += 1;
                            out.push((next, key));
                        }
                        Step::Redundant => {}
                        Step::NoCut => break,
                    }
                }
            }
            op => {
                stats.corruptions += u64::from(matches!(op, Op::Corrupt(..)));
                if let Step::Next(next, key) = apply(s, op, &view_before)? {
                    out.push((next, key));
                }
            }
        }
    }
    stats.transitions += out.len() as u64;
    Ok(out)
}

/// What one operation from a state led to.
enum Step {
    Next(State, (u64, u64)),
    /// A cut step past the end of the operation: it completed.
    NoCut,
    /// A cut that tore a data or CRC byte with a garbage value other than the representative
    /// one: the same as that one for every check (only the markers are compared by value).
    Redundant,
}

/// The garbage value explored in torn data and CRC bytes.
const GARBAGE: u8 = 0x5A;

fn redundant(power: &Power, c: CutByte) -> bool {
    let offset = power.torn_at().map(|at| at % slot_size(BLOCK));
    let marker = offset == Some(BLOCK) || offset == Some(BLOCK + 3);
    matches!(c, CutByte::Garbage(g) if !marker && g != GARBAGE)
}

/// One transition from `s`, checked.
fn apply(s: &State, op: Op, view_before: &[Value; BLOCKS]) -> Result<Step, String> {
    let power = Power::new();
    let mut next = s.clone();
    next.path.push(op);
    let fail = |what: String| Err(format!("{what}\n  path: {:?}", next_path(s, op)));
    // The live banks after the operation, if the power is still on.
    let live: Option<Tiny<'_>> = match op {
        Op::Write(block, v) => {
            let mut banks = rebuild(&power, s);
            if let Err(e) = banks.write(block * BLOCK, &VALUES[v]) {
                return fail(format!("write failed: {e:?}"));
            }
            let [a, b] = images(&banks);
            if !(copy_is_valid::<BLOCK>(&a, block) && slot::<BLOCK>(&a, block) == slot::<BLOCK>(&b, block)) {
                return fail("a completed write is not in both banks".into());
            }
            next.committed[block] = VALUES[v];
            next.dirty[0][block] = false;
            next.dirty[1][block] = false;
            next.since.push(op);
            Some(banks)
        }
        Op::CutWrite(block, v, k, c) => {
            let mut banks = rebuild(&power, s);
            power.arm(k, c);
            let result = banks.write(block * BLOCK, &VALUES[v]);
            if !power.is_off() {
                return Ok(Step::NoCut);
            }
            if redundant(&power, c) {
                return Ok(Step::Redundant);
            }
            // Only a write of what is stored may succeed: the cut hit the repair before it.
            if result.is_ok() && VALUES[v] != s.committed[block] {
                return fail("a cut write returned Ok".into());
            }
            if s.dirty == [[false; BLOCKS]; 2] && checksum_errors(&banks) != 0 {
                return fail("bank sums wrong right after a cut".into());
            }
            if VALUES[v] != s.committed[block] {
                next.pending[block] = Some(VALUES[v]);
            }
            next.powered = false;
            next.images = images(&banks);
            next.since.clear();
            next.dirty = [[false; BLOCKS]; 2];
            None
        }
        Op::Corrupt(bank, pos, value) => {
            next.corruptions += 1;
            next.corrupted[pos / slot_size(BLOCK)] = true;
            if pos % slot_size(BLOCK) < BLOCK && s.powered {
                next.dirty[bank][pos / slot_size(BLOCK)] = true;
            }
            if s.powered {
                let mut banks = rebuild(&power, s);
                banks.banks_mut()[bank].as_bytes_mut()[pos] = value;
                next.since.push(op);
                Some(banks)
            } else {
                next.images[bank][pos] = value;
                None
            }
        }
        Op::Read(block) => {
            let mut banks = rebuild(&power, s);
            let mut out = [0; BLOCK];
            match banks.read(block * BLOCK, &mut out) {
                Ok(()) if out == s.committed[block] => {}
                other => return fail(format!("read of block {block}: {other:?} {out:?}, committed {:?}", s.committed[block])),
            }
            next.dirty[0][block] = false;
            next.dirty[1][block] = false;
            next.since.push(op);
            Some(banks)
        }
        Op::Check(block) => {
            let mut banks = rebuild(&power, s);
            let bad = images(&banks).map(|image| !copy_is_valid::<BLOCK>(&image, block));
            if let Err(e) = banks.check_block(block) {
                return fail(format!("check_block({block}): {e:?}"));
            }
            for (bank, bad) in bad.into_iter().enumerate() {
                if bad && banks.status(bank).bits() & 0x30 == 0 {
                    return fail(format!("check_block({block}) did not flag bank {bank}"));
                }
            }
            next.dirty[0][block] = false;
            next.dirty[1][block] = false;
            next.since.push(op);
            Some(banks)
        }
        Op::Reboot => {
            let now = images_of(&power, s);
            power.restore_power();
            let mut banks = Tiny::mount(devices(&power, &now));
            for (block, c) in contents(&mut banks).into_iter().enumerate() {
                match c {
                    Ok(c) if acceptable(s, block, &c) => next.committed[block] = c,
                    other => return fail(format!("reboot reads block {block} as {other:?}")),
                }
            }
            next.pending = [None; BLOCKS];
            next.powered = true;
            next.images = now;
            next.since.clear();
            next.dirty = [[false; BLOCKS]; 2];
            // The live banks are the mount of `now`; reads after it changed nothing.
            Some(rebuild(&power, &next))
        }
        Op::RebootCut(k, c) => {
            let now = images_of(&power, s);
            power.arm(k, c);
            let banks = Tiny::mount(devices(&power, &now));
            if !power.is_off() {
                return Ok(Step::NoCut);
            }
            if redundant(&power, c) {
                return Ok(Step::Redundant);
            }
            if checksum_errors(&banks) != 0 {
                return fail("bank sums wrong after a cut mount".into());
            }
            next.powered = false;
            next.images = images(&banks);
            next.since.clear();
            next.dirty = [[false; BLOCKS]; 2];
            None
        }
    };
    if let Some(banks) = &live
        && next.dirty == [[false; BLOCKS]; 2]
        && checksum_errors(banks) != 0
    {
        return fail("bank sums differ from a recomputation".into());
    }
    let images_now = match &live {
        Some(banks) => images(banks),
        None => next.images,
    };
    for (block, corrupted) in next.corrupted.iter_mut().enumerate() {
        let [a, b] = images_now.map(|image| slot::<BLOCK>(&image, block).to_vec());
        if copy_is_valid::<BLOCK>(&images_now[0], block) && a == b {
            *corrupted = false;
        }
    }
    let view = match reboot_view(&next, &images_now) {
        Ok(v) => v,
        Err(e) => return fail(e),
    };
    if matches!(op, Op::RebootCut(..)) && view != *view_before {
        return fail(format!("a recovery cut changed what the next recovery reads: {view_before:?} -> {view:?}"));
    }
    let live = live.map(|mut b| {
        b.clear_status(0);
        b.clear_status(1);
        b
    });
    let k = key(&next, live.as_ref(), &images_now);
    Ok(Step::Next(next, k))
}

fn next_path(s: &State, op: Op) -> Vec<Op> {
    let mut p = s.path.clone();
    p.push(op);
    p
}

/// Breadth-first from `start` to `depth` operations; returns (states, transitions, stats).
fn search(start: State, depth: usize) -> (usize, Stats, Vec<usize>) {
    let mut stats = Stats { transitions: 0, cut_writes: 0, recovery_cuts: 0, corruptions: 0 };
    let power = Power::new();
    let live = start.powered.then(|| rebuild(&power, &start));
    let mut visited: HashSet<(u64, u64)> = HashSet::new();
    visited.insert(key(&start, live.as_ref(), &start.images));
    let mut frontier = vec![start];
    let mut per_depth = vec![1];
    for _ in 0..depth {
        // Two workers, one per core.
        let chunks: Vec<&[State]> = frontier.chunks(frontier.len().div_ceil(2).max(1)).collect();
        let results: Vec<(Vec<Found>, Stats)> = std::thread::scope(|scope| {
            let handles: Vec<_> = chunks
                .iter()
                .map(|chunk| {
                    scope.spawn(move || {
                        let mut st = Stats { transitions: 0, cut_writes: 0, recovery_cuts: 0, corruptions: 0 };
                        let mut out = Vec::new();
                        for s in chunk.iter() {
                            match successors(s, &mut st) {
                                Ok(next) => out.extend(next),
                                Err(e) => panic!("invariant violated: {e}"),
                            }
                        }
                        (out, st)
                    })
                })
                .collect();
            handles.into_iter().map(|h| h.join().expect("worker")).collect()
        });
        let mut next_frontier = Vec::new();
        for (out, st) in results {
            stats.transitions += st.transitions;
            stats.cut_writes += st.cut_writes;
            stats.recovery_cuts += st.recovery_cuts;
            stats.corruptions += st.corruptions;
            for (state, k) in out {
                if visited.insert(k) {
                    next_frontier.push(state);
                }
            }
        }
        per_depth.push(next_frontier.len());
        frontier = next_frontier;
        if frontier.is_empty() {
            break;
        }
    }
    (visited.len(), stats, per_depth)
}

/// The search depth (`BANKS_MODEL_DEPTH` overrides it, for deeper runs by hand).
fn depth(default: usize) -> usize {
    std::env::var("BANKS_MODEL_DEPTH").ok().and_then(|d| d.parse().ok()).unwrap_or(default)
}

fn start(images: Images, powered: bool, committed: [Value; BLOCKS]) -> State {
    State {
        images,
        since: Vec::new(),
        powered,
        committed,
        pending: [None; BLOCKS],
        corruptions: 0,
        corrupted: [false; BLOCKS],
        dirty: [[false; BLOCKS]; 2],
        path: Vec::new(),
    }
}

#[test]
fn every_reachable_state_from_blank_banks_keeps_the_invariants() {
    // Blank EEPROMs, power off: the first operation is the reboot that formats them (or a
    // cut of that format).
    let depth = depth(4);
    let (states, stats, per_depth) = search(start([[0xFF; N]; 2], false, [[0; BLOCK]; BLOCKS]), depth);
    println!(
        "model from blank banks, depth {depth}: {states} states, {} transitions ({} cut writes, {} recovery cuts, {} corruptions); new states per depth {per_depth:?}",
        stats.transitions, stats.cut_writes, stats.recovery_cuts, stats.corruptions
    );
    assert!(states > 10_000, "the search reaches the states it is meant to");
    assert!(stats.cut_writes > 0 && stats.recovery_cuts > 0 && stats.corruptions > 0);
}

#[test]
fn every_reachable_state_across_the_sequence_wrap_keeps_the_invariants() {
    // Committed banks at sequence numbers 254 and 255: the writes of the search wrap them.
    let committed = [VALUES[1], VALUES[2]];
    let image = committed_image::<N, BLOCKS, BLOCK>(&committed, &[254, 255]);
    let depth = depth(3);
    let (states, stats, per_depth) = search(start([image; 2], true, committed), depth);
    println!(
        "model across the sequence wrap, depth {depth}: {states} states, {} transitions ({} cut writes, {} recovery cuts, {} corruptions); new states per depth {per_depth:?}",
        stats.transitions, stats.cut_writes, stats.recovery_cuts, stats.corruptions
    );
    assert!(states > 10_000);
    assert!(stats.cut_writes > 0 && stats.recovery_cuts > 0 && stats.corruptions > 0);
}
