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
//! carries across the grid's reset. The averagings exist in plane strain;
//! in 3D the step has none yet ([`Unaveraged`]).

use nalgebra::Matrix2;
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

/// The plane-strain averagings.
pub enum CellAverages {
    Fbar(FbarCells),
    CellMean(CellMean),
}

/// A trial state of [`CellAverages`].
pub enum AveragedTrial {
    Fbar(FbarTrial),
    CellMean(CellTrial),
}

/// What a step carries of the last one's averaging: F-bar's pressures
/// ([`FbarCells::carried`]) or the cell mean's stresses
/// ([`CellMean::carried`]).
pub enum Carried {
    FbarPressure(Vec<f64>),
    CellMeanStress(Vec<Matrix2<f64>>),
}

impl Averaging<2> for CellAverages {
    type Trial = AveragedTrial;
    type Carried = Carried;

    fn coupling_groups(&self) -> Vec<Vec<u32>> {
        match self {
            CellAverages::Fbar(fbar) => fbar.coupling_groups(),
            CellAverages::CellMean(cells) => cells.coupling_groups(),
        }
    }

    fn internal_force(
        &self,
        conn: &Connectivity,
        mp: &MaterialPoints,
        u: &[f64],
    ) -> Result<(Vec<f64>, AveragedTrial), InadmissiblePoint> {
        match self {
            CellAverages::CellMean(cells) => {
                let trial = cells.trial(conn, mp, u)?;
                let f_int = internal_force(conn, mp, |p| cells.stress(&trial, mp, p));
                Ok((f_int, AveragedTrial::CellMean(trial)))
            }
            CellAverages::Fbar(fbar) => {
                let averages = fbar::trial_averages(fbar, conn, mp, u);
                let (local, parts): (Vec<Matrix2<f64>>, Vec<_>) = (0..mp.len())
                    .into_par_iter()
                    .with_min_len(parallel::POINT_RESPONSES)
                    .map(|p| {
                        fbar::point_response(fbar, (&averages, None), conn, mp, u, p)
                            .map(|(response, part)| (response.p, part))
                    })
                    .collect::<Result<Vec<_>, _>>()?
                    .into_iter()
                    .unzip();
                let trial = FbarTrial::new(fbar, averages, parts);
                let f_int = internal_force(conn, mp, |p| trial.stress(fbar, p, &local[p]));
                Ok((f_int, AveragedTrial::Fbar(trial)))
            }
        }
    }

    fn response(
        &self,
        trial: &AveragedTrial,
        conn: &Connectivity,
        mp: &MaterialPoints,
        u: &[f64],
        p: usize,
        want_tangent: bool,
    ) -> Result<Response<2>, InadmissiblePoint> {
        match (self, trial) {
            (CellAverages::CellMean(cells), AveragedTrial::CellMean(trial)) => {
                cells.response(trial, mp, p, want_tangent)
            }
            (CellAverages::Fbar(fbar), AveragedTrial::Fbar(trial)) => {
                let cells = (trial.averages.as_slice(), Some(trial.means.as_slice()));
                fbar::point_response(fbar, cells, conn, mp, u, p).map(|(response, _)| response)
            }
            _ => unreachable!("a trial state of another averaging"),
        }
    }

    fn own_tangent(&self, mp: &MaterialPoints, p: usize) -> Option<Tangent<2>> {
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
        trial: &AveragedTrial,
        conn: &Connectivity,
        mp: &MaterialPoints,
        pattern: &Pattern,
        values: &mut [f64],
    ) {
        match (self, trial) {
            (CellAverages::CellMean(cells), AveragedTrial::CellMean(trial)) => {
                cells.add_to(conn, mp, trial, pattern, values);
            }
            (CellAverages::Fbar(fbar), AveragedTrial::Fbar(trial)) => {
                fbar.add_to(conn, mp, trial, pattern, values);
            }
            _ => unreachable!("a trial state of another averaging"),
        }
    }

    fn carried(&self, trial: &AveragedTrial, mp: &MaterialPoints) -> Carried {
        match (self, trial) {
            (CellAverages::CellMean(cells), AveragedTrial::CellMean(trial)) => {
                Carried::CellMeanStress(cells.carried(trial, mp))
            }
            (CellAverages::Fbar(fbar), AveragedTrial::Fbar(trial)) => {
                Carried::FbarPressure(fbar.carried(trial))
            }
            _ => unreachable!("a trial state of another averaging"),
        }
    }

    fn trial_bytes(trial: &AveragedTrial) -> usize {
        match trial {
            AveragedTrial::Fbar(trial) => trial.heap_bytes(),
            AveragedTrial::CellMean(trial) => trial.heap_bytes(),
        }
    }
}

/// No averaging: in 3D, until F-bar and the cell mean are made for cells
/// of eight corners. The type has no values, so a 3D step's averaging is
/// always `None`, and the methods below cannot be called.
pub enum Unaveraged {}

impl Averaging<3> for Unaveraged {
    type Trial = Unaveraged;
    type Carried = Unaveraged;

    fn coupling_groups(&self) -> Vec<Vec<u32>> {
        match *self {}
    }

    fn internal_force(
        &self,
        _: &Connectivity<3>,
        _: &MaterialPoints<3>,
        _: &[f64],
    ) -> Result<(Vec<f64>, Unaveraged), InadmissiblePoint> {
        match *self {}
    }

    fn response(
        &self,
        _: &Unaveraged,
        _: &Connectivity<3>,
        _: &MaterialPoints<3>,
        _: &[f64],
        _: usize,
        _: bool,
    ) -> Result<Response<3>, InadmissiblePoint> {
        match *self {}
    }

    fn own_tangent(&self, _: &MaterialPoints<3>, _: usize) -> Option<Tangent<3>> {
        match *self {}
    }

    fn add_couplings(
        &self,
        _: &Unaveraged,
        _: &Connectivity<3>,
        _: &MaterialPoints<3>,
        _: &Pattern,
        _: &mut [f64],
    ) {
        match *self {}
    }

    fn carried(&self, _: &Unaveraged, _: &MaterialPoints<3>) -> Unaveraged {
        match *self {}
    }

    fn trial_bytes(trial: &Unaveraged) -> usize {
        match *trial {}
    }
}
