//! Every function against the standard library, exhaustively over a 24-byte buffer: every
//! destination, source and length that fit, overlaps in both directions included.
// Raw pointers into the test's own buffers, always in range: the functions' contract.
#![allow(unsafe_code)]

use coforge_board_mem as mem;

const LEN: usize = 24;

/// A buffer whose bytes differ from each other and from any fill value the tests use.
fn pattern() -> [u8; LEN] {
    core::array::from_fn(|i| 0x40 + i as u8)
}

/// Every (destination, source, length) that fits the buffer.
fn moves() -> impl Iterator<Item = (usize, usize, usize)> {
    (0..LEN).flat_map(|d| (0..LEN).flat_map(move |s| (0..=LEN - d.max(s)).map(move |n| (d, s, n))))
}

type Copy = unsafe extern "C" fn(*mut u8, *const u8, usize);

fn copy_fns() -> [(&'static str, Copy); 3] {
    [("__aeabi_memcpy", mem::__aeabi_memcpy), ("__aeabi_memcpy4", mem::__aeabi_memcpy4), ("__aeabi_memcpy8", mem::__aeabi_memcpy8)]
}

fn move_fns() -> [(&'static str, Copy); 3] {
    [("__aeabi_memmove", mem::__aeabi_memmove), ("__aeabi_memmove4", mem::__aeabi_memmove4), ("__aeabi_memmove8", mem::__aeabi_memmove8)]
}

#[test]
fn memcpy_copies_between_buffers_and_returns_dest() {
    let mut cases = 0;
    for (d, s, n) in moves() {
        let src = pattern();
        let mut dest = [0u8; LEN];
        let mut want = dest;
        want[d..d + n].copy_from_slice(&src[s..s + n]);
        let ret = unsafe { mem::memcpy(dest.as_mut_ptr().add(d), src.as_ptr().add(s), n) };
        assert_eq!(ret, dest.as_mut_ptr().wrapping_add(d), "memcpy returns dest ({d}, {s}, {n})");
        assert_eq!(dest, want, "memcpy({d}, {s}, {n})");
        for (name, f) in copy_fns() {
            let mut dest = [0u8; LEN];
            unsafe { f(dest.as_mut_ptr().add(d), src.as_ptr().add(s), n) };
            assert_eq!(dest, want, "{name}({d}, {s}, {n})");
        }
        cases += 1;
    }
    assert_eq!(cases, 5_476);
}

#[test]
fn memmove_handles_overlap_in_both_directions() {
    let mut overlapping = (0, 0);
    for (d, s, n) in moves() {
        let mut want = pattern();
        want.copy_within(s..s + n, d);
        let mut buf = pattern();
        let p = buf.as_mut_ptr();
        let ret = unsafe { mem::memmove(p.add(d), p.add(s), n) };
        assert_eq!(ret, p.wrapping_add(d), "memmove returns dest ({d}, {s}, {n})");
        assert_eq!(buf, want, "memmove({d}, {s}, {n})");
        for (name, f) in move_fns() {
            let mut buf = pattern();
            let p = buf.as_mut_ptr();
            unsafe { f(p.add(d), p.add(s), n) };
            assert_eq!(buf, want, "{name}({d}, {s}, {n})");
        }
        if n > 0 && d.abs_diff(s) < n {
            if d < s {
                overlapping.0 += 1
            } else if d > s {
                overlapping.1 += 1
            }
        }
    }
    // Both directions of overlap were exercised, not only disjoint moves.
    assert!(overlapping.0 > 1_000 && overlapping.1 > 1_000, "{overlapping:?}");
}

#[test]
fn memset_and_memclr_fill_exactly_their_range() {
    for d in 0..LEN {
        for n in 0..=LEN - d {
            // 0x1AB: only the low byte counts, as in C.
            for c in [0x00, 0x5A, 0xFF, 0x1AB] {
                let mut want = pattern();
                want[d..d + n].fill(c as u8);
                let mut buf = pattern();
                let ret = unsafe { mem::memset(buf.as_mut_ptr().add(d), c, n) };
                assert_eq!(ret, buf.as_mut_ptr().wrapping_add(d));
                assert_eq!(buf, want, "memset({d}, {c:#x}, {n})");
                type Set = unsafe extern "C" fn(*mut u8, usize, i32);
                let sets: [(&str, Set); 3] =
                    [("__aeabi_memset", mem::__aeabi_memset), ("__aeabi_memset4", mem::__aeabi_memset4), ("__aeabi_memset8", mem::__aeabi_memset8)];
                for (name, f) in sets {
                    let mut buf = pattern();
                    // The EABI order: destination, length, value.
                    unsafe { f(buf.as_mut_ptr().add(d), n, c) };
                    assert_eq!(buf, want, "{name}({d}, {n}, {c:#x})");
                }
            }
            let mut want = pattern();
            want[d..d + n].fill(0);
            type Clr = unsafe extern "C" fn(*mut u8, usize);
            let clears: [(&str, Clr); 3] =
                [("__aeabi_memclr", mem::__aeabi_memclr), ("__aeabi_memclr4", mem::__aeabi_memclr4), ("__aeabi_memclr8", mem::__aeabi_memclr8)];
            for (name, f) in clears {
                let mut buf = pattern();
                unsafe { f(buf.as_mut_ptr().add(d), n) };
                assert_eq!(buf, want, "{name}({d}, {n})");
            }
        }
    }
}

#[test]
fn memcmp_and_bcmp_order_by_the_first_differing_byte() {
    let a = pattern();
    for n in 0..=LEN {
        assert_eq!(unsafe { mem::memcmp(a.as_ptr(), a.as_ptr(), n) }, 0);
        for at in 0..n {
            for (x, y) in [(0x00u8, 0xFFu8), (0xFF, 0x00), (0x7F, 0x80), (0x80, 0x7F)] {
                let (mut l, mut r) = (a, a);
                l[at] = x;
                r[at] = y;
                // A later difference must not count.
                if at + 1 < n {
                    l[at + 1] = y;
                    r[at + 1] = x;
                }
                let got = unsafe { mem::memcmp(l.as_ptr(), r.as_ptr(), n) };
                assert_eq!(got.signum(), i32::from(x).cmp(&i32::from(y)) as i32, "memcmp at {at} of {n}: {x:#x} vs {y:#x}");
                assert_eq!(got, l[..n].cmp(&r[..n]) as i32 * got.abs(), "memcmp agrees with slice order");
                assert_ne!(unsafe { mem::bcmp(l.as_ptr(), r.as_ptr(), n) }, 0);
            }
        }
        // A difference past `n` is not looked at.
        if n < LEN {
            let mut r = a;
            r[n] ^= 0xFF;
            assert_eq!(unsafe { mem::memcmp(a.as_ptr(), r.as_ptr(), n) }, 0);
            assert_eq!(unsafe { mem::bcmp(a.as_ptr(), r.as_ptr(), n) }, 0);
        }
    }
}
