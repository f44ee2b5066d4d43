//! Byte-at-a-time `memcpy`, `memmove`, `memset`, `memcmp`/`bcmp` and their ARM EABI names, in
//! place of compiler-builtins' word-at-a-time versions in coforge's Cortex-M images.
//!
//! Why: the images copy and clear only small things (CAN frames, SDO segments, dictionary
//! records, a 512-byte SD block at most), while compiler-builtins' versions, built for speed
//! and linked without LTO, take 1,586 bytes of flash in the CO401GW1 image: 5 % of the
//! STM32F042's 32 KiB. These take under 100. A byte costs about 6 cycles instead of about 2
//! for aligned words: a 512-byte block about 64 µs instead of about 21 µs at 48 MHz, and
//! nothing here copies anything in a hurry.
//!
//! How: compiler-builtins defines all of these symbols weak, so with the feature `symbols`
//! the linker takes these. Each loop stores through `write_volatile`, which keeps LLVM from
//! recognising the loop as a `memcpy`/`memset` idiom and calling the very function it is
//! compiling. The `__aeabi_*` names are what LLVM calls on ARM; the `4`/`8` forms promise
//! aligned pointers, which a byte loop does not need. `__aeabi_memset` takes (destination,
//! length, value), not C's order. They are `extern "C"`, which is the AAPCS on ARM, so the
//! host tests (`tests/mem.rs`) call exactly what the images link.
#![no_std]

use core::ptr::{read, write_volatile};

// The exported functions call these, never each other: LLVM takes a call to anything named
// `memcpy`, `memset`, `memmove`, `memcmp` or `bcmp` for the builtin, and would turn
// `__aeabi_memcpy` calling `memcpy` into `__aeabi_memcpy` calling itself.

/// Front to back; also right when `dest` lies below an overlapping `src`.
///
/// # Safety
/// Both ranges valid for `n` bytes.
#[inline(always)]
#[allow(unsafe_code)]
unsafe fn copy_up(dest: *mut u8, src: *const u8, n: usize) {
    let mut i = 0;
    while i < n {
        // SAFETY: `i < n`, and the caller promises both ranges hold `n` bytes.
        unsafe { write_volatile(dest.add(i), read(src.add(i))) };
        i += 1;
    }
}

/// Any overlap: back to front when `dest` lies above `src`.
///
/// # Safety
/// Both ranges valid for `n` bytes.
#[inline(always)]
#[allow(unsafe_code)]
unsafe fn copy_any(dest: *mut u8, src: *const u8, n: usize) {
    if (dest as usize) <= (src as usize) {
        // SAFETY: the caller's promise; front to back never overwrites a byte not yet read.
        return unsafe { copy_up(dest, src, n) };
    }
    let mut i = n;
    while i > 0 {
        i -= 1;
        // SAFETY: `i < n`; back to front never overwrites a byte not yet read.
        unsafe { write_volatile(dest.add(i), read(src.add(i))) };
    }
}

/// # Safety
/// `dest` valid for `n` bytes.
#[inline(always)]
#[allow(unsafe_code)]
unsafe fn fill(dest: *mut u8, value: u8, n: usize) {
    let mut i = 0;
    while i < n {
        // SAFETY: `i < n`, and the caller promises `dest` holds `n` bytes.
        unsafe { write_volatile(dest.add(i), value) };
        i += 1;
    }
}

/// # Safety
/// Both ranges valid for `n` bytes.
#[inline(always)]
#[allow(unsafe_code)]
unsafe fn compare(a: *const u8, b: *const u8, n: usize) -> i32 {
    let mut i = 0;
    while i < n {
        // SAFETY: `i < n`, and the caller promises both ranges hold `n` bytes. Volatile, so
        // that LLVM does not see a `bcmp` idiom in the loop either.
        let (x, y) = unsafe { (core::ptr::read_volatile(a.add(i)), core::ptr::read_volatile(b.add(i))) };
        if x != y {
            return i32::from(x) - i32::from(y);
        }
        i += 1;
    }
    0
}

/// Copies `n` bytes from `src` to `dest`.
///
/// # Safety
/// As C's `memcpy`: both ranges valid for `n` bytes.
#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
#[allow(unsafe_code)]
pub unsafe extern "C" fn memcpy(dest: *mut u8, src: *const u8, n: usize) -> *mut u8 {
    // SAFETY: the caller's promise, passed on.
    unsafe { copy_up(dest, src, n) };
    dest
}

/// Copies `n` bytes from `src` to `dest`; the ranges may overlap.
///
/// # Safety
/// As C's `memmove`: both ranges valid for `n` bytes.
#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
#[allow(unsafe_code)]
pub unsafe extern "C" fn memmove(dest: *mut u8, src: *const u8, n: usize) -> *mut u8 {
    // SAFETY: the caller's promise, passed on.
    unsafe { copy_any(dest, src, n) };
    dest
}

/// Sets `n` bytes at `dest` to the low byte of `c`.
///
/// # Safety
/// As C's `memset`: `dest` valid for `n` bytes.
#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
#[allow(unsafe_code)]
pub unsafe extern "C" fn memset(dest: *mut u8, c: i32, n: usize) -> *mut u8 {
    // SAFETY: the caller's promise, passed on.
    unsafe { fill(dest, c as u8, n) };
    dest
}

/// Compares `n` bytes: negative, zero or positive as the first differing byte of `a` is
/// below, equal to or above that of `b`.
///
/// # Safety
/// As C's `memcmp`: both ranges valid for `n` bytes.
#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
#[allow(unsafe_code)]
pub unsafe extern "C" fn memcmp(a: *const u8, b: *const u8, n: usize) -> i32 {
    // SAFETY: the caller's promise, passed on.
    unsafe { compare(a, b, n) }
}

/// Zero if the `n` bytes are equal, as [`memcmp`] answers.
///
/// # Safety
/// As [`memcmp`].
#[cfg_attr(feature = "symbols", unsafe(no_mangle))]
#[allow(unsafe_code)]
pub unsafe extern "C" fn bcmp(a: *const u8, b: *const u8, n: usize) -> i32 {
    // SAFETY: the caller's promise, passed on.
    unsafe { compare(a, b, n) }
}

/// The ARM EABI names, each passing on to one of the loops above.
macro_rules! aeabi {
    ($($name:ident($($arg:ident: $ty:ty),*) => $body:expr;)*) => {$(
        /// An ARM EABI memory function.
        ///
        /// # Safety
        /// As the C function of the same name.
        #[cfg_attr(feature = "symbols", unsafe(no_mangle))]
        #[allow(unsafe_code)]
        pub unsafe extern "C" fn $name($($arg: $ty),*) {
            // SAFETY: the caller's promise, passed on.
            unsafe { $body };
        }
    )*};
}

aeabi! {
    __aeabi_memcpy(dest: *mut u8, src: *const u8, n: usize) => copy_up(dest, src, n);
    __aeabi_memcpy4(dest: *mut u8, src: *const u8, n: usize) => copy_up(dest, src, n);
    __aeabi_memcpy8(dest: *mut u8, src: *const u8, n: usize) => copy_up(dest, src, n);
    __aeabi_memmove(dest: *mut u8, src: *const u8, n: usize) => copy_any(dest, src, n);
    __aeabi_memmove4(dest: *mut u8, src: *const u8, n: usize) => copy_any(dest, src, n);
    __aeabi_memmove8(dest: *mut u8, src: *const u8, n: usize) => copy_any(dest, src, n);
    __aeabi_memset(dest: *mut u8, n: usize, c: i32) => fill(dest, c as u8, n);
    __aeabi_memset4(dest: *mut u8, n: usize, c: i32) => fill(dest, c as u8, n);
    __aeabi_memset8(dest: *mut u8, n: usize, c: i32) => fill(dest, c as u8, n);
    __aeabi_memclr(dest: *mut u8, n: usize) => fill(dest, 0, n);
    __aeabi_memclr4(dest: *mut u8, n: usize) => fill(dest, 0, n);
    __aeabi_memclr8(dest: *mut u8, n: usize) => fill(dest, 0, n);
}
