//! Probes: named reference points that move with the grid displacement,
//! reported every step.

use crate::boundary::quadrature::active_hats;
use crate::grid::{Basis, Connectivity, Grid};
use crate::report::ProbeReport;

/// Named reference points that move with the grid displacement, in `D`
/// dimensions.
#[derive(Debug, Clone)]
pub struct Probes<const D: usize = 2> {
    pub names: Vec<String>,
    pub reference: Vec<[f64; D]>,
    pub position: Vec<[f64; D]>,
}

impl<const D: usize> Default for Probes<D> {
    fn default() -> Self {
        Self {
            names: Vec::new(),
            reference: Vec::new(),
            position: Vec::new(),
        }
    }
}

impl<const D: usize> Probes<D> {
    /// Probes at their reference positions.
    pub fn new(named: impl IntoIterator<Item = (String, [f64; D])>) -> Self {
        let mut probes = Probes::default();
        for (name, at) in named {
            probes.names.push(name);
            probes.reference.push(at);
            probes.position.push(at);
        }
        probes
    }

    /// Moves each probe with the grid displacement interpolated by the
    /// boundary's shape functions (the cell's bilinear hats, or the
    /// B-splines; renormalised if some nodes are inactive; a probe away
    /// from all material stays where it is).
    pub fn advect(&mut self, grid: &Grid<D>, basis: Basis, conn: &Connectivity<D>, u: &[f64]) {
        let (mut weights, mut shares) = (Vec::new(), Vec::new());
        for x in &mut self.position {
            shares.clear();
            let sum = active_hats(basis, grid, *x, &conn.nodes, &mut weights, &mut shares);
            let mut d = [0.0; D];
            for &(a, n) in &shares {
                for c in 0..D {
                    d[c] += n * u[D * a + c];
                }
            }
            if sum > 0.0 {
                for c in 0..D {
                    x[c] += d[c] / sum;
                }
            }
        }
    }

    pub fn reports(&self) -> Vec<ProbeReport> {
        (0..self.names.len())
            .map(|i| ProbeReport {
                name: self.names[i].clone(),
                position: self.position[i].to_vec(),
                displacement: (0..D)
                    .map(|c| self.position[i][c] - self.reference[i][c])
                    .collect(),
            })
            .collect()
    }
}
