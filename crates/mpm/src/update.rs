//! The point update, the last stage of a load step: every point moves
//! with the converged grid displacement and commits the state its step
//! converged to (its deformation gradient, history and stress).

use nalgebra::SMatrix;
use rayon::prelude::*;

use crate::equilibrium::PointState;
use crate::grid::{Connectivity, increment};
use crate::parallel;
use crate::particles::{Dim, MaterialPoints, Space};

/// Moves each point with the grid displacement `u` and commits its state
/// from `states`; a point yields in the step if its plastic strain grew.
pub fn commit<const D: usize>(
    mp: &mut MaterialPoints<D>,
    conn: &Connectivity<D>,
    u: &[f64],
    states: &[PointState<D>],
) where
    Dim<D>: Space<D>,
{
    (
        &mut mp.position,
        &mut mp.deformation,
        &mut mp.history,
        &mut mp.stress,
        &mut mp.yielding,
    )
        .into_par_iter()
        .enumerate()
        .with_min_len(parallel::BOOKKEEPING)
        .for_each(|(p, (x, f, history, stress, yielding))| {
            let (dx, grad_u) = increment(conn.point_links(p), u);
            let df = SMatrix::<f64, D, D>::identity() + grad_u;
            for d in 0..D {
                x[d] += dx[d];
            }
            *f = df * *f;
            commit_state(&states[p], history, stress, yielding);
        });
}

/// Commits each point's state from `states` without moving it: a
/// geostatic stage's, whose displacements are not the material's motion
/// but the correction that brings its initial stresses into equilibrium.
pub fn commit_in_place<const D: usize>(mp: &mut MaterialPoints<D>, states: &[PointState<D>])
where
    Dim<D>: Space<D>,
{
    (&mut mp.history, &mut mp.stress, &mut mp.yielding)
        .into_par_iter()
        .enumerate()
        .with_min_len(parallel::BOOKKEEPING)
        .for_each(|(p, (history, stress, yielding))| {
            commit_state(&states[p], history, stress, yielding);
        });
}

/// A point's commit of `state`: it yields in the step if its plastic
/// strain grew.
fn commit_state<const D: usize>(
    state: &PointState<D>,
    history: &mut <Dim<D> as Space<D>>::History,
    stress: &mut <Dim<D> as Space<D>>::Stress,
    yielding: &mut bool,
) where
    Dim<D>: Space<D>,
{
    *yielding = Dim::<D>::plastic_strain(&state.history) > Dim::<D>::plastic_strain(history);
    *history = state.history;
    *stress = state.cauchy;
}
