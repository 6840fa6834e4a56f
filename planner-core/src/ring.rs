//! A bounded store that forgets its oldest entry when full.
//!
//! The planner keeps remembered collision points and virtual obstacles this
//! way. Their every-cycle scans (merging, sums of forces) do not care about
//! age, so the entries stay one contiguous slice in slot order: each scan is
//! one tight loop (a wrapping `heapless::Deque` makes it two chained ones).
//! Age order is still available for reports and for the rare searches where
//! it decides the outcome.

use heapless::Vec;

/// At most `N` entries; once full, a push overwrites the oldest.
#[derive(Clone, Debug)]
pub struct Ring<T, const N: usize> {
    slots: Vec<T, N>,
    oldest: usize,
}

impl<T, const N: usize> Default for Ring<T, N> {
    fn default() -> Self {
        Ring::new()
    }
}

impl<T, const N: usize> Ring<T, N> {
    /// Empty.
    pub const fn new() -> Self {
        Ring {
            slots: Vec::new(),
            oldest: 0,
        }
    }

    /// Keep `item`; when full, in place of the oldest entry, which is
    /// returned.
    pub fn push(&mut self, item: T) -> Option<T> {
        let item = match self.slots.push(item) {
            Ok(()) => return None,
            Err(item) => item,
        };
        let slot = self.oldest;
        self.oldest = (slot + 1) % N;
        self.slots
            .get_mut(slot)
            .map(|old| core::mem::replace(old, item))
    }

    /// The entries in slot order (not age order).
    pub fn as_slice(&self) -> &[T] {
        &self.slots
    }

    /// The entries, oldest first.
    pub fn iter(&self) -> impl Iterator<Item = &T> {
        let (newer, older) = self.slots.split_at_checked(self.oldest).unwrap_or_default();
        older.iter().chain(newer)
    }

    /// The entries, oldest first, mutable.
    pub fn iter_mut(&mut self) -> impl Iterator<Item = &mut T> {
        let (newer, older) = self
            .slots
            .split_at_mut_checked(self.oldest)
            .unwrap_or_default();
        older.iter_mut().chain(newer)
    }

    /// Number of entries.
    pub fn len(&self) -> usize {
        self.slots.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.slots.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    proptest::proptest! {
        /// Behaves as a queue that drops its front when full.
        #[test]
        fn matches_a_bounded_queue(items in proptest::collection::vec(0u8..255, 0..40)) {
            let mut ring = Ring::<u8, 5>::new();
            let mut model = std::collections::VecDeque::new();
            for &x in &items {
                let evicted = if model.len() == 5 { model.pop_front() } else { None };
                model.push_back(x);
                proptest::prop_assert_eq!(ring.push(x), evicted);
                let want: std::vec::Vec<u8> = model.iter().copied().collect();
                let oldest_first: std::vec::Vec<u8> = ring.iter().copied().collect();
                let oldest_first_mut: std::vec::Vec<u8> = ring.iter_mut().map(|v| *v).collect();
                proptest::prop_assert_eq!(&oldest_first, &want);
                proptest::prop_assert_eq!(&oldest_first_mut, &want);
                let mut slots = ring.as_slice().to_vec();
                slots.sort();
                let mut sorted = want;
                sorted.sort();
                proptest::prop_assert_eq!(slots, sorted);
            }
        }
    }
}
