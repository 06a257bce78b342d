//! The grid reset of a load step: every point's shape functions at its
//! position, and the nodes they touch, which become the step's active nodes
//! (numbered `0..n` in key order). Every Newton iteration of the step reuses
//! it.

use nalgebra::Matrix2;
use rayon::prelude::*;

use super::{Basis, Grid, LatticeIndex, NodeKey, NodeWeight, Support, node_indices};

/// A point's view of one active node.
#[derive(Debug, Clone, Copy)]
pub struct Link {
    /// Active node index.
    pub node: u32,
    /// Shape function value.
    pub n: f64,
    /// Shape function gradient in the step's start configuration.
    pub grad: [f64; 2],
}

/// Shape functions of every point on the active nodes of one load step.
#[derive(Debug, Clone, Default)]
pub struct Connectivity {
    /// Active node keys, sorted.
    pub nodes: Vec<NodeKey>,
    /// `links[offsets[p]..offsets[p + 1]]` are point `p`'s nodes.
    pub offsets: Vec<usize>,
    pub links: Vec<Link>,
}

const CHUNK: usize = 4096;

impl Connectivity {
    /// Evaluates the shape functions of every point, at `positions` with
    /// the domains `support` gives, keeping the nodes for which `in_grid`
    /// holds: the grid ends there, as a finite mesh would.
    pub fn build(
        grid: &Grid,
        basis: Basis,
        positions: &[[f64; 2]],
        support: impl Fn(usize) -> Support + Sync,
        in_grid: impl Fn(NodeKey) -> bool + Sync,
    ) -> Self {
        let n = positions.len();
        let chunks: Vec<(Vec<usize>, Vec<NodeWeight>)> = (0..n)
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
        let coordinates: Vec<(i64, i64)> = nodes.iter().map(|&k| node_indices(k)).collect();
        let place = LatticeIndex::new(&coordinates);
        let mut links = Vec::with_capacity(offsets[n]);
        links.par_extend(chunks.par_iter().flat_map_iter(|(_, weights)| {
            weights.iter().map(|w| {
                let (i, j) = node_indices(w.node);
                Link {
                    node: place.get(i, j).expect("every linked node is active") as u32,
                    n: w.n,
                    grad: w.grad,
                }
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
        2 * self.nodes.len()
    }

    #[inline]
    pub fn point_links(&self, p: usize) -> &[Link] {
        &self.links[self.offsets[p]..self.offsets[p + 1]]
    }

    pub fn n_points(&self) -> usize {
        self.offsets.len() - 1
    }
}
/// Displacement `sum_a N_a u_a` and displacement gradient
/// `grad_u = sum_a u_a (x) g_a` of a point (`dF = I + grad_u`).
#[inline]
pub fn increment(links: &[Link], u: &[f64]) -> ([f64; 2], Matrix2<f64>) {
    let mut dx = [0.0; 2];
    let mut df = Matrix2::zeros();
    for l in links {
        let ua = [u[2 * l.node as usize], u[2 * l.node as usize + 1]];
        for i in 0..2 {
            dx[i] += l.n * ua[i];
            for j in 0..2 {
                df[(i, j)] += ua[i] * l.grad[j];
            }
        }
    }
    (dx, df)
}
