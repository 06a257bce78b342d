//! How a point's deformation enters its stress in a step's point loop
//! when it is averaged over the point's cell against volumetric locking:
//! F-bar ([`super::fbar`]) or the cell-mean strain ([`super::cell_mean`]).
//! Without one, each point answers its own displacement gradient
//! (`crate::equilibrium`'s plain loop).
//!
//! The equilibrium of a step asks an averaging the same questions, whichever
//! it is: the nodes its cells couple, the internal force at a trial
//! increment (keeping what the tangent and the commit need of it), a
//! point's response there, the points' stiffness, and what the next step
//! carries across the grid's reset. Both are one code for either
//! dimension ([`CellAverages`]; in 3D their cells have eight corners).

use nalgebra::SMatrix;
use rayon::prelude::*;

use super::cell_mean::{CellMean, CellTrial};
use super::fbar::{self, FbarCells, FbarTrial};
use super::{Pattern, internal_force};
use crate::grid::Connectivity;
use crate::parallel;
use crate::particles::admissible::InadmissiblePoint;
use crate::particles::{Dim, MaterialPoints, Space};

type Response<const D: usize> = <Dim<D> as Space<D>>::Response;
type Tangent<const D: usize> = <Dim<D> as Space<D>>::Tangent;

/// A way of averaging the points' deformation over their cells.
pub trait Averaging<const D: usize>: Send + Sync
where
    Dim<D>: Space<D>,
{
    /// What a trial increment leaves for the tangent and the commit.
    type Trial: Send + Sync;
    /// What the next step carries of a converged one.
    type Carried;

    /// The node groups the cells join (for the stiffness pattern).
    fn coupling_groups(&self) -> Vec<Vec<u32>>;

    /// The internal force at the trial increment `u`, and the trial state
    /// it leaves; or the first point `u` makes inadmissible.
    fn internal_force(
        &self,
        conn: &Connectivity<D>,
        mp: &MaterialPoints<D>,
        u: &[f64],
    ) -> Result<(Vec<f64>, Self::Trial), InadmissiblePoint>;

    /// Point `p`'s response at the trial `trial` of increment `u`, or the
    /// point if it is not admissible there.
    fn response(
        &self,
        trial: &Self::Trial,
        conn: &Connectivity<D>,
        mp: &MaterialPoints<D>,
        u: &[f64],
        p: usize,
        want_tangent: bool,
    ) -> Result<Response<D>, InadmissiblePoint>;

    /// The tangent point `p`'s own gradient enters the stiffness with,
    /// when the averaging sets it; `None` for its response's.
    fn own_tangent(&self, mp: &MaterialPoints<D>, p: usize) -> Option<Tangent<D>>;

    /// Adds the cells' coupling stiffness at `trial` to tangent values in
    /// `pattern`'s layout (which must hold [`Averaging::coupling_groups`]).
    fn add_couplings(
        &self,
        trial: &Self::Trial,
        conn: &Connectivity<D>,
        mp: &MaterialPoints<D>,
        pattern: &Pattern,
        values: &mut [f64],
    );

    /// What the next step carries of the converged `trial`.
    fn carried(&self, trial: &Self::Trial, mp: &MaterialPoints<D>) -> Self::Carried;

    /// Bytes a trial state holds on the heap.
    fn trial_bytes(trial: &Self::Trial) -> usize;
}

/// The averagings, in either dimension.
pub enum CellAverages<const D: usize = 2> {
    Fbar(FbarCells<D>),
    CellMean(CellMean<D>),
}

/// A trial state of [`CellAverages`].
pub enum AveragedTrial<const D: usize = 2> {
    Fbar(FbarTrial<D>),
    CellMean(CellTrial<D>),
}

/// What a step carries of the last one's averaging: F-bar's pressures
/// ([`FbarCells::carried`]) or the cell mean's stresses
/// ([`CellMean::carried`]).
pub enum Carried<const D: usize = 2> {
    FbarPressure(Vec<f64>),
    CellMeanStress(Vec<SMatrix<f64, D, D>>),
}

impl<const D: usize> Averaging<D> for CellAverages<D>
where
    Dim<D>: Space<D>,
{
    type Trial = AveragedTrial<D>;
    type Carried = Carried<D>;

    fn coupling_groups(&self) -> Vec<Vec<u32>> {
        match self {
            CellAverages::Fbar(fbar) => fbar.coupling_groups(),
            CellAverages::CellMean(cells) => cells.coupling_groups(),
        }
    }

    fn internal_force(
        &self,
        conn: &Connectivity<D>,
        mp: &MaterialPoints<D>,
        u: &[f64],
    ) -> Result<(Vec<f64>, AveragedTrial<D>), InadmissiblePoint> {
        match self {
            CellAverages::CellMean(cells) => {
                let trial = cells.trial(conn, mp, u)?;
                let f_int = internal_force(conn, mp, |p| cells.stress(&trial, mp, p));
                Ok((f_int, AveragedTrial::CellMean(trial)))
            }
            CellAverages::Fbar(fbar) => {
                let (f_int, trial) = fbar.internal_force(conn, mp, u)?;
                Ok((f_int, AveragedTrial::Fbar(trial)))
            }
        }
    }

    fn response(
        &self,
        trial: &AveragedTrial<D>,
        conn: &Connectivity<D>,
        mp: &MaterialPoints<D>,
        u: &[f64],
        p: usize,
        want_tangent: bool,
    ) -> Result<Response<D>, InadmissiblePoint> {
        match (self, trial) {
            (CellAverages::CellMean(cells), AveragedTrial::CellMean(trial)) => {
                cells.response(trial, mp, p, want_tangent)
            }
            (CellAverages::Fbar(fbar), AveragedTrial::Fbar(trial)) => {
                fbar.response(trial, conn, mp, u, p, want_tangent)
            }
            _ => unreachable!("a trial state of another averaging"),
        }
    }

    fn own_tangent(&self, mp: &MaterialPoints<D>, p: usize) -> Option<Tangent<D>> {
        match self {
            // The points' own stiffness is the hourglass term's; the
            // models' tangents enter through the cells' blocks.
            CellAverages::CellMean(cells) => Some(cells.local_tangent(mp, p)),
            // F-bar's points answer to a modified gradient.
            CellAverages::Fbar(_) => None,
        }
    }

    fn add_couplings(
        &self,
        trial: &AveragedTrial<D>,
        conn: &Connectivity<D>,
        mp: &MaterialPoints<D>,
        pattern: &Pattern,
        values: &mut [f64],
    ) {
        match (self, trial) {
            (CellAverages::CellMean(cells), AveragedTrial::CellMean(trial)) => {
                cells.add_to(conn, mp, trial, pattern, values);
            }
            (CellAverages::Fbar(fbar), AveragedTrial::Fbar(trial)) => {
                fbar.add_couplings(trial, conn, mp, pattern, values);
            }
            _ => unreachable!("a trial state of another averaging"),
        }
    }

    fn carried(&self, trial: &AveragedTrial<D>, mp: &MaterialPoints<D>) -> Carried<D> {
        match (self, trial) {
            (CellAverages::CellMean(cells), AveragedTrial::CellMean(trial)) => {
                Carried::CellMeanStress(cells.carried(trial, mp))
            }
            (CellAverages::Fbar(fbar), AveragedTrial::Fbar(trial)) => {
                Carried::FbarPressure(Averaging::carried(fbar, trial, mp))
            }
            _ => unreachable!("a trial state of another averaging"),
        }
    }

    fn trial_bytes(trial: &AveragedTrial<D>) -> usize {
        match trial {
            AveragedTrial::Fbar(trial) => trial.heap_bytes(),
            AveragedTrial::CellMean(trial) => trial.heap_bytes(),
        }
    }
}

/// F-bar on its own, as [`CellAverages::Fbar`] asks it.
impl<const D: usize> Averaging<D> for FbarCells<D>
where
    Dim<D>: Space<D>,
{
    type Trial = FbarTrial<D>;
    /// Each point's pressure ([`FbarCells::carried`]).
    type Carried = Vec<f64>;

    fn coupling_groups(&self) -> Vec<Vec<u32>> {
        FbarCells::coupling_groups(self)
    }

    fn internal_force(
        &self,
        conn: &Connectivity<D>,
        mp: &MaterialPoints<D>,
        u: &[f64],
    ) -> Result<(Vec<f64>, FbarTrial<D>), InadmissiblePoint> {
        let averages = fbar::trial_averages(self, conn, mp, u);
        let (local, parts): (Vec<SMatrix<f64, D, D>>, Vec<_>) = (0..mp.len())
            .into_par_iter()
            .with_min_len(parallel::POINT_RESPONSES)
            .map(|p| {
                fbar::point_response(self, (&averages, None), conn, mp, u, p)
                    .map(|(response, part)| (<Dim<D> as Space<D>>::stress_of(&response), part))
            })
            .collect::<Result<Vec<_>, _>>()?
            .into_iter()
            .unzip();
        let trial = FbarTrial::new(self, averages, parts);
        let f_int = internal_force(conn, mp, |p| trial.stress(self, p, &local[p]));
        Ok((f_int, trial))
    }

    /// The response always has its tangent: F-bar's stress is made from it.
    fn response(
        &self,
        trial: &FbarTrial<D>,
        conn: &Connectivity<D>,
        mp: &MaterialPoints<D>,
        u: &[f64],
        p: usize,
        _want_tangent: bool,
    ) -> Result<Response<D>, InadmissiblePoint> {
        let cells = (trial.averages.as_slice(), Some(trial.means.as_slice()));
        fbar::point_response(self, cells, conn, mp, u, p).map(|(response, _)| response)
    }

    /// F-bar's points answer to a modified gradient.
    fn own_tangent(&self, _: &MaterialPoints<D>, _: usize) -> Option<Tangent<D>> {
        None
    }

    fn add_couplings(
        &self,
        trial: &FbarTrial<D>,
        conn: &Connectivity<D>,
        mp: &MaterialPoints<D>,
        pattern: &Pattern,
        values: &mut [f64],
    ) {
        self.add_to(conn, mp, trial, pattern, values);
    }

    fn carried(&self, trial: &FbarTrial<D>, _: &MaterialPoints<D>) -> Vec<f64> {
        FbarCells::carried(self, trial)
    }

    fn trial_bytes(trial: &FbarTrial<D>) -> usize {
        trial.heap_bytes()
    }
}
