//! A bucket queue: items filed by the leading bits of their non-negative cost, taken from the
//! lowest non-empty bucket, last in first out within one.
//!
//! Pushing and taking cost O(1) and touch the ends of a few vectors, where a binary heap of a
//! million edges misses the cache on every pop (at 129^3 the heap's pops, mostly of stale
//! entries, were as long as all the collapses' tests). Costs within a sixteenth of an octave
//! share a bucket, so the order is the cost's to about 4%: the greedy order of quadric error
//! simplification is a heuristic at that grain anyway. The order is a function of the pushes'
//! order, so a deterministic caller gets a deterministic queue.

/// The cost's bits kept: sign, exponent and four bits of mantissa.
const SHIFT: u32 = 48;

/// Items by cost bucket.
pub(crate) struct Buckets<T> {
    buckets: Vec<Vec<T>>,
    /// No bucket below this one holds an item.
    lowest: usize,
    len: usize,
}

impl<T> Buckets<T> {
    pub(crate) fn new() -> Self {
        Self {
            buckets: (0..1usize << (64 - SHIFT)).map(|_| Vec::new()).collect(),
            lowest: usize::MAX,
            len: 0,
        }
    }

    /// Files `item` by `cost` (NaN and negative costs as 0).
    pub(crate) fn push(&mut self, cost: f64, item: T) {
        let cost = if cost > 0.0 { cost } else { 0.0 };
        let b = (cost.to_bits() >> SHIFT) as usize;
        self.buckets[b].push(item);
        self.lowest = self.lowest.min(b);
        self.len += 1;
    }

    /// The last item filed in the lowest bucket.
    pub(crate) fn pop(&mut self) -> Option<T> {
        while self.lowest < self.buckets.len() {
            if let Some(item) = self.buckets[self.lowest].pop() {
                self.len -= 1;
                return Some(item);
            }
            self.lowest += 1;
        }
        None
    }

    pub(crate) fn len(&self) -> usize {
        self.len
    }

    /// Keeps only the items `keep` accepts, in their order.
    pub(crate) fn retain(&mut self, mut keep: impl FnMut(&T) -> bool) {
        for b in &mut self.buckets {
            b.retain(&mut keep);
        }
        self.len = self.buckets.iter().map(Vec::len).sum();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn items_come_out_by_cost_bucket() {
        let mut q = Buckets::new();
        for (cost, item) in [(3.0, 'c'), (0.5, 'a'), (100.0, 'd'), (1.0, 'b'), (0.0, 'z')] {
            q.push(cost, item);
        }
        q.push(f64::NAN, 'n');
        let order: Vec<char> = std::iter::from_fn(|| q.pop()).collect();
        assert_eq!(order, ['n', 'z', 'a', 'b', 'c', 'd']);
        assert_eq!(q.len(), 0);
    }

    #[test]
    fn a_lower_cost_pushed_later_comes_first() {
        let mut q = Buckets::new();
        q.push(8.0, 1);
        q.push(9.0, 2);
        assert_eq!(q.pop(), Some(1));
        q.push(0.1, 3);
        q.retain(|&x| x != 2);
        assert_eq!((q.pop(), q.pop(), q.len()), (Some(3), None, 0));
    }
}
