//! The 27 node indices around each node of a depth: its neighbours on its own depth, or its
//! parents one depth coarser. Read from a table where one is kept or small enough to build for a
//! solve, looked up in the node index when asked where a table would be large.

use super::*;
use crate::keys::SparseIndex;

/// Depths with at most this many nodes keep their tables in the [`DownPass`], shared by every
/// [`solve`] on the octree instead of built per solve.
pub(super) const KEEP_TABLES_BELOW: usize = 1 << 17;

/// Depths with more nodes than this build no tables: their stencils are looked up when asked.
/// A table costs 108 bytes a node (113 MB here). On the 257^3 bunny the final solve's depth 12
/// (over 2 million nodes) peaked at 2,198 MB with tables and 1,912 MB with lookups (KiB / 1024).
/// A lookup reads one brick of the index for most nodes, but from memory instead of a streamed
/// table, and the relaxation asks for every node in each sweep: that run's solves took about
/// 3.5 s more of its 90. The 129^3 bunny's finest depth (685,000 nodes) keeps its tables:
/// lookups there took the heap at the peak from 506 to 452 MB, for 0.5 to 0.9 s more.
const LOOKUP_ABOVE: usize = 1 << 20;

/// Per node of a depth, 27 node indices (`NONE` where absent) of the block around a point, in
/// [`offset`] order: around the node itself in its own depth's index (neighbours), or around
/// half its coordinates in the coarser depth's (the hats one depth coarser that overlap its own).
#[derive(Clone, Copy)]
pub(crate) enum Stencil<'a> {
    Table(&'a [u32]),
    Lookup {
        index: &'a SparseIndex,
        nodes: &'a [[u32; 3]],
        shift: u32,
    },
}

impl<'a> Stencil<'a> {
    /// The neighbours of `level`'s nodes, looked up.
    pub(crate) fn neighbours(level: &'a Level) -> Self {
        Stencil::Lookup {
            index: &level.node_index,
            nodes: &level.nodes,
            shift: 0,
        }
    }

    /// The parents of `fine`'s nodes in `coarse` (one depth coarser), looked up.
    pub(crate) fn parents(fine: &'a Level, coarse: &'a Level) -> Self {
        Stencil::Lookup {
            index: &coarse.node_index,
            nodes: &fine.nodes,
            shift: 1,
        }
    }

    /// The 27 indices of node `i`.
    #[inline]
    pub(crate) fn of(self, i: usize) -> [u32; 27] {
        match self {
            Stencil::Table(t) => {
                let mut out = [NONE; 27];
                out.copy_from_slice(&t[i * 27..i * 27 + 27]);
                out
            }
            Stencil::Lookup {
                index,
                nodes,
                shift,
            } => index.block27(ic(nodes[i].map(|v| v >> shift))),
        }
    }

    /// How many nodes the stencil serves.
    fn len(self) -> usize {
        match self {
            Stencil::Table(t) => t.len() / 27,
            Stencil::Lookup { nodes, .. } => nodes.len(),
        }
    }

    /// Every node's indices as one table (27 per node).
    pub(crate) fn table(self) -> Vec<u32> {
        (0..self.len())
            .into_par_iter()
            .with_min_len(GRAIN)
            .map(|i| self.of(i))
            .collect::<Vec<[u32; 27]>>()
            .into_flattened()
    }

    /// The stencil a solve uses: the `kept` table if there is one, else a table built into
    /// `store` on a depth of at most [`LOOKUP_ABOVE`] nodes, else this stencil as it is.
    pub(crate) fn or_table(self, kept: Option<&'a Vec<u32>>, store: &'a mut Vec<u32>) -> Self {
        match kept {
            Some(t) => Stencil::Table(t),
            None if self.len() <= LOOKUP_ABOVE => {
                *store = self.table();
                Stencil::Table(store)
            }
            None => self,
        }
    }
}
