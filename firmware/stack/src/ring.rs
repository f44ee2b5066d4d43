//! A fixed-capacity FIFO of `Copy` values with byte-sized positions: the node's transmit
//! queue, its event queue and the EMCY producer's queue. heapless's `Deque` keeps two `usize`
//! positions and a flag (24 bytes with padding on a 64-bit host, 12 on Cortex-M) where two
//! bytes do for at most 255 values, and every byte of a node counts against its 2 KiB.

/// A FIFO of at most `N` (1..=255) values of `T`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Ring<T: Copy, const N: usize> {
    /// Slots; those outside `head..head + len` (modulo `N`) hold stale values.
    buf: [T; N],
    /// The oldest value's slot.
    head: u8,
    len: u8,
}

impl<T: Copy, const N: usize> Ring<T, N> {
    const CAPACITY_FITS: () = assert!(N > 0 && N <= 255, "a ring holds 1..=255 values");

    /// An empty ring; `fill` only initialises the slots and is never read back.
    pub(crate) const fn new(fill: T) -> Self {
        let () = Self::CAPACITY_FITS;
        Ring { buf: [fill; N], head: 0, len: 0 }
    }

    pub(crate) const fn is_full(&self) -> bool {
        self.len as usize == N
    }

    /// Appends `value`; gives it back if the ring is full.
    pub(crate) fn push_back(&mut self, value: T) -> Result<(), T> {
        if self.is_full() {
            return Err(value);
        }
        match self.buf.get_mut(Self::wrap(usize::from(self.head) + usize::from(self.len))) {
            Some(slot) => *slot = value,
            None => return Err(value),
        }
        self.len += 1;
        Ok(())
    }

    /// Removes and returns the oldest value.
    pub(crate) fn pop_front(&mut self) -> Option<T> {
        if self.len == 0 {
            return None;
        }
        let at = usize::from(self.head);
        self.head = Self::wrap(at + 1) as u8;
        self.len -= 1;
        // Read last, straight into the caller's slot: no copy held across the stores above
        // (with one, the compiler calls `memcpy` for a 12-byte frame).
        self.buf.get(at).copied()
    }

    /// Appends `value`, dropping the oldest value if the ring is full: for queues whose reader
    /// may never come, where the newest matter most. Whether one was dropped.
    pub(crate) fn push_back_evicting(&mut self, value: T) -> bool {
        let evicted = self.is_full() && self.pop_front().is_some();
        let _ = self.push_back(value);
        evicted
    }

    pub(crate) fn clear(&mut self) {
        self.head = 0;
        self.len = 0;
    }

    /// A position below `2 * N` brought into `0..N`: a compare, not a division (Cortex-M0
    /// has no divide instruction).
    const fn wrap(at: usize) -> usize {
        if at >= N { at - N } else { at }
    }
}

#[cfg(test)]
mod tests {
    use super::Ring;

    #[test]
    fn values_come_out_in_order_across_the_wrap() {
        let mut r: Ring<u16, 3> = Ring::new(0);
        assert_eq!(r.pop_front(), None);
        for round in 0..5_u16 {
            assert_eq!(r.push_back(round * 10), Ok(()));
            assert_eq!(r.push_back(round * 10 + 1), Ok(()));
            assert_eq!(r.pop_front(), Some(round * 10));
            assert_eq!(r.pop_front(), Some(round * 10 + 1));
            assert_eq!(r.pop_front(), None, "round {round}");
        }
    }

    #[test]
    fn a_full_ring_refuses_and_clear_empties_it() {
        let mut r: Ring<u8, 2> = Ring::new(0);
        assert_eq!(r.push_back(1), Ok(()));
        assert_eq!(r.push_back(2), Ok(()));
        assert!(r.is_full());
        assert_eq!(r.push_back(3), Err(3));
        assert_eq!(r.pop_front(), Some(1));
        assert_eq!(r.push_back(3), Ok(()));
        assert!(r.is_full());
        r.clear();
        assert!(!r.is_full());
        assert_eq!(r.pop_front(), None);
        assert_eq!(r.push_back(4), Ok(()));
        assert_eq!(r.pop_front(), Some(4));
    }

    #[test]
    fn a_full_ring_keeps_the_newest_when_asked() {
        let mut r: Ring<u8, 2> = Ring::new(0);
        assert!(!r.push_back_evicting(1));
        assert!(!r.push_back_evicting(2));
        assert!(r.push_back_evicting(3), "1 dropped");
        assert_eq!((r.pop_front(), r.pop_front(), r.pop_front()), (Some(2), Some(3), None));
    }

    #[test]
    fn the_positions_take_two_bytes() {
        assert_eq!(core::mem::size_of::<Ring<[u8; 8], 6>>(), 6 * 8 + 2);
    }
}
