//! Probes: named reference points that move with the grid displacement,
//! reported every step.

use crate::boundary::quadrature::active_hats;
use crate::grid::{Basis, Connectivity, Grid};
use crate::report::ProbeReport;

/// Named reference points that move with the grid displacement.
#[derive(Debug, Clone, Default)]
pub struct Probes {
    pub names: Vec<String>,
    pub reference: Vec<[f64; 2]>,
    pub position: Vec<[f64; 2]>,
}

impl Probes {
    /// Probes at their reference positions.
    pub fn new(named: impl IntoIterator<Item = (String, [f64; 2])>) -> Self {
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
    pub fn advect(&mut self, grid: &Grid, basis: Basis, conn: &Connectivity, u: &[f64]) {
        let (mut weights, mut shares) = (Vec::new(), Vec::new());
        for x in &mut self.position {
            shares.clear();
            let sum = active_hats(basis, grid, *x, &conn.nodes, &mut weights, &mut shares);
            let mut d = [0.0; 2];
            for &(a, n) in &shares {
                d[0] += n * u[2 * a];
                d[1] += n * u[2 * a + 1];
            }
            if sum > 0.0 {
                x[0] += d[0] / sum;
                x[1] += d[1] / sum;
            }
        }
    }

    pub fn reports(&self) -> Vec<ProbeReport> {
        (0..self.names.len())
            .map(|i| ProbeReport {
                name: self.names[i].clone(),
                position: self.position[i],
                displacement: [
                    self.position[i][0] - self.reference[i][0],
                    self.position[i][1] - self.reference[i][1],
                ],
            })
            .collect()
    }
}
