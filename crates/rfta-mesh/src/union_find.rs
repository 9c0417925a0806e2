//! Disjoint sets of indices.

/// Disjoint sets of the indices `0..n` (union-find with path halving), each named by its
/// smallest member, so that the sets and their names do not depend on the order of the unions.
///
/// ```
/// use rfta_mesh::UnionFind;
///
/// let mut sets = UnionFind::new(5);
/// sets.union(3, 1);
/// sets.union(4, 3);
/// assert_eq!([sets.find(4), sets.find(2), sets.find(0)], [1, 2, 0]);
/// ```
#[derive(Debug, Clone)]
pub struct UnionFind {
    parent: Vec<usize>,
}

impl UnionFind {
    /// `n` sets of one index each.
    pub fn new(n: usize) -> Self {
        Self {
            parent: (0..n).collect(),
        }
    }

    /// The smallest member of `x`'s set.
    pub fn find(&mut self, mut x: usize) -> usize {
        while self.parent[x] != x {
            self.parent[x] = self.parent[self.parent[x]];
            x = self.parent[x];
        }
        x
    }

    /// Joins the sets of `a` and `b`.
    pub fn union(&mut self, a: usize, b: usize) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            // Smaller index as root keeps the structure independent of edge visiting order.
            let (lo, hi) = (ra.min(rb), ra.max(rb));
            self.parent[hi] = lo;
        }
    }
}
