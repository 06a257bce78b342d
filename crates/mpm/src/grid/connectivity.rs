//! The grid reset of a load step: every point's shape functions at its
//! position, and the nodes they touch, which become the step's active nodes
//! (numbered `0..n` in key order). Every Newton iteration of the step reuses
//! it.

use nalgebra::SMatrix;
use rayon::prelude::*;

use super::{Basis, Grid, LatticeIndex, NodeKey, NodeWeight, Support, lattice_coordinates};

/// A point's view of one active node.
#[derive(Debug, Clone, Copy)]
pub struct Link<const D: usize = 2> {
    /// Active node index.
    pub node: u32,
    /// Shape function value.
    pub n: f64,
    /// Shape function gradient in the step's start configuration.
    pub grad: [f64; D],
}

/// Shape functions of every point on the active nodes of one load step;
/// node `a`'s degrees of freedom are `D a .. D a + D`.
#[derive(Debug, Clone)]
pub struct Connectivity<const D: usize = 2> {
    /// Active node keys, sorted.
    pub nodes: Vec<NodeKey>,
    /// `links[offsets[p]..offsets[p + 1]]` are point `p`'s nodes.
    pub offsets: Vec<usize>,
    pub links: Vec<Link<D>>,
}

impl<const D: usize> Default for Connectivity<D> {
    fn default() -> Self {
        Self {
            nodes: Vec::new(),
            offsets: Vec::new(),
            links: Vec::new(),
        }
    }
}

const CHUNK: usize = 4096;

impl<const D: usize> Connectivity<D> {
    /// Evaluates the shape functions of every point, at `positions` with
    /// the domains `support` gives, keeping the nodes for which `in_grid`
    /// holds: the grid ends there, as a finite mesh would.
    pub fn build(
        grid: &Grid<D>,
        basis: Basis,
        positions: &[[f64; D]],
        support: impl Fn(usize) -> Support<D> + Sync,
        in_grid: impl Fn(NodeKey) -> bool + Sync,
    ) -> Self {
        let n = positions.len();
        let chunks: Vec<(Vec<usize>, Vec<NodeWeight<D>>)> = (0..n)
            .into_par_iter()
            .chunks(CHUNK)
            .map(|idx| {
                let mut counts = Vec::with_capacity(idx.len());
                let mut weights = Vec::with_capacity(idx.len() * 9);
                for p in idx {
                    let before = weights.len();
                    basis.eval(grid, positions[p], support(p), &mut weights);
                    let mut k = before;
                    for i in before..weights.len() {
                        if in_grid(weights[i].node) {
                            weights[k] = weights[i];
                            k += 1;
                        }
                    }
                    weights.truncate(k);
                    counts.push(weights.len() - before);
                }
                (counts, weights)
            })
            .collect();
        let mut offsets = Vec::with_capacity(n + 1);
        offsets.push(0);
        for (counts, _) in &chunks {
            for c in counts {
                offsets.push(offsets.last().unwrap() + c);
            }
        }
        // The active nodes: each chunk's, then all, sorted and deduplicated
        // (a chunk's points share most of their nodes).
        let mut nodes: Vec<NodeKey> = chunks
            .par_iter()
            .flat_map_iter(|(_, weights)| {
                let mut keys: Vec<NodeKey> = weights.iter().map(|w| w.node).collect();
                keys.sort_unstable();
                keys.dedup();
                keys
            })
            .collect();
        nodes.par_sort_unstable();
        nodes.dedup();
        let coordinates: Vec<[i64; D]> = nodes.iter().map(|&k| lattice_coordinates(k)).collect();
        let place = LatticeIndex::new(&coordinates);
        let mut links = Vec::with_capacity(offsets[n]);
        links.par_extend(chunks.par_iter().flat_map_iter(|(_, weights)| {
            weights.iter().map(|w| Link {
                node: place
                    .get(lattice_coordinates(w.node))
                    .expect("every linked node is active") as u32,
                n: w.n,
                grad: w.grad,
            })
        }));
        Self {
            nodes,
            offsets,
            links,
        }
    }

    /// Bytes of the links, offsets and node keys on the heap.
    pub fn heap_bytes(&self) -> usize {
        use std::mem::size_of_val;
        size_of_val(self.nodes.as_slice())
            + size_of_val(self.offsets.as_slice())
            + size_of_val(self.links.as_slice())
    }

    pub fn n_nodes(&self) -> usize {
        self.nodes.len()
    }

    pub fn n_dofs(&self) -> usize {
        D * self.nodes.len()
    }

    #[inline]
    pub fn point_links(&self, p: usize) -> &[Link<D>] {
        &self.links[self.offsets[p]..self.offsets[p + 1]]
    }

    pub fn n_points(&self) -> usize {
        self.offsets.len() - 1
    }
}
/// Displacement `sum_a N_a u_a` and displacement gradient
/// `grad_u = sum_a u_a (x) g_a` of a point (`dF = I + grad_u`).
#[inline]
pub fn increment<const D: usize>(links: &[Link<D>], u: &[f64]) -> ([f64; D], SMatrix<f64, D, D>) {
    let mut dx = [0.0; D];
    let mut df = SMatrix::zeros();
    for l in links {
        let ua: [f64; D] = std::array::from_fn(|i| u[D * l.node as usize + i]);
        for i in 0..D {
            dx[i] += l.n * ua[i];
            for j in 0..D {
                df[(i, j)] += ua[i] * l.grad[j];
            }
        }
    }
    (dx, df)
}
