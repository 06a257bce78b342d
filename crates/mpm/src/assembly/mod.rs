//! Assembly of a load step's forces and tangent stiffness on its active
//! nodes. The sparsity pattern is built once per step, at the grid reset;
//! every Newton iteration reuses it and only the values change.
//!
//! The matrix is stored in compressed sparse columns with a full (both
//! triangles) pattern. Degree of freedom `2a + c` is component `c` of active
//! node `a`. The rows of column `2b + c` are the DOFs of the nodes adjacent to
//! `b` (sharing a point), in node order, both components per node, so the
//! entry `(2a + r, 2b + c)` sits at `col_ptr[2b + c] + 2k + r` where `k` is
//! the position of `a` in `b`'s neighbour list.

pub mod averaging;
pub mod cell_mean;
pub mod fbar;
pub mod forces;
pub mod ghost_faces;
pub mod lone_points;
pub mod pattern;
pub mod soft_cells;
pub mod solid_ghost_faces;
pub mod stiffness;
pub mod term;

pub use fbar::{FbarCells, FbarTrial};
pub use forces::{PointLoad, body_force, external_force, external_force_rate, internal_force};
pub use ghost_faces::GhostFaces;
pub use lone_points::LonePoints;
pub use pattern::{NodeAdjacency, Pattern, constrain};
pub use soft_cells::SoftCells;
pub use stiffness::stiffness;
pub use term::{Side, StepTerm};

use rayon::prelude::*;

use crate::parallel;

/// Sums per-point contributions into a vector of length `len`, in parallel:
/// one accumulator per worker thread (at least
/// [`parallel::POINT_RESPONSES`] points each), added at the end.
pub(crate) fn scatter_sum(
    n_points: usize,
    len: usize,
    add: impl Fn(usize, &mut [f64]) + Sync,
) -> Vec<f64> {
    let threads = rayon::current_num_threads().max(1);
    let per = n_points.div_ceil(threads).max(parallel::POINT_RESPONSES);
    let parts: Vec<Vec<f64>> = (0..n_points.div_ceil(per))
        .into_par_iter()
        .map(|c| {
            let mut acc = vec![0.0; len];
            for p in c * per..((c + 1) * per).min(n_points) {
                add(p, &mut acc);
            }
            acc
        })
        .collect();
    let mut parts = parts.into_iter();
    let mut total = parts.next().unwrap_or_else(|| vec![0.0; len]);
    for part in parts {
        total
            .par_iter_mut()
            .zip(part.par_iter())
            .with_min_len(parallel::BOOKKEEPING)
            .for_each(|(t, v)| *t += v);
    }
    total
}
