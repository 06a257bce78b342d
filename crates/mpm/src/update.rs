//! The point update, the last stage of a load step: every point moves
//! with the converged grid displacement and commits the state its step
//! converged to (its deformation gradient, history and stress).

use nalgebra::Matrix2;
use rayon::prelude::*;

use crate::equilibrium::PointState;
use crate::grid::{Connectivity, increment};
use crate::parallel;
use crate::particles::MaterialPoints;

/// Moves each point with the grid displacement `u` and commits its state
/// from `states`; a point yields in the step if its plastic strain grew.
pub fn commit(mp: &mut MaterialPoints, conn: &Connectivity, u: &[f64], states: &[PointState]) {
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
            let df = Matrix2::identity() + grad_u;
            x[0] += dx[0];
            x[1] += dx[1];
            *f = df * *f;
            *yielding = states[p].history.plastic_strain > history.plastic_strain;
            *history = states[p].history;
            *stress = states[p].cauchy;
        });
}

/// Commits each point's state from `states` without moving it: a
/// geostatic stage's, whose displacements are not the material's motion
/// but the correction that brings its initial stresses into equilibrium.
pub fn commit_in_place(mp: &mut MaterialPoints, states: &[PointState]) {
    (&mut mp.history, &mut mp.stress, &mut mp.yielding)
        .into_par_iter()
        .enumerate()
        .with_min_len(parallel::BOOKKEEPING)
        .for_each(|(p, (history, stress, yielding))| {
            *yielding = states[p].history.plastic_strain > history.plastic_strain;
            *history = states[p].history;
            *stress = states[p].cauchy;
        });
}
