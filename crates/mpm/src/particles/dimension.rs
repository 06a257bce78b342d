//! What a material point holds that differs between plane strain and 3D
//! by more than its size: the types `MaterialPoints<D>` keeps per point,
//! and its model's response to a trial increment. The rest of a point's
//! state is `[f64; D]` or a `D x D` matrix.

use std::fmt::Debug;
use std::ops::{Add, AddAssign, Index, Mul, Sub};

use nalgebra::{Matrix2, Matrix3, Matrix4, SMatrix};

use super::MaterialPoints;
use super::admissible::TrialResponse;
use super::seeding::Domain;
use crate::grid::Support;
use crate::material::{CauchyStress, History, History3, Material, Response, Response3, Tangent3};

/// The dimension `D` as a type, to hang [`Space`] on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Dim<const D: usize>;

/// The per-point types of a dimension.
pub trait Space<const D: usize> {
    /// What the constitutive model carries (plane strain: the in-plane
    /// `b - I`, `b_zz - 1` and `alpha`).
    type History: Copy + Debug + PartialEq + Send + Sync;
    /// The Cauchy stress a point reports (plane strain: `[xx, yy, xy]` and
    /// `zz`; 3D: the symmetric tensor).
    type Stress: Copy + Debug + Default + PartialEq + Send + Sync;
    /// The point's cell in the reference configuration (plane strain: a
    /// bilinear image of a square; 3D: a box's half-widths).
    type Domain: Copy + Debug + Default + PartialEq + Send + Sync;
    /// The stress's slopes across the domain of a point seeded one a cell
    /// (plane strain: six; 3D: none yet).
    type Slopes: Copy + Debug + Default + PartialEq + Send + Sync;
    /// The model's tangent `dP / d(dF)`, `D^2 x D^2`, entry `(D i + I, D j
    /// + J)` for `dP_iI / d(dF)_jJ`.
    type Tangent: TangentMatrix + Debug + Send + Sync;
    /// A model's response to a trial increment ([`Material::respond`],
    /// [`Material::respond_3d`]).
    type Response: TrialResponse + Send;

    /// The response of `material` from `history` to the step's
    /// displacement gradient `grad_u`, `j_start` the volume ratio at the
    /// step's start; without `want_tangent` the tangent may be left zero.
    fn respond(
        material: &Material,
        history: &Self::History,
        grad_u: &SMatrix<f64, D, D>,
        j_start: f64,
        want_tangent: bool,
    ) -> Self::Response;
    /// The stress a response pairs with `dF` per unit reference volume.
    fn stress_of(response: &Self::Response) -> SMatrix<f64, D, D>;
    fn tangent_of(response: &Self::Response) -> Self::Tangent;
    /// The stress and the tangent of a response, for an averaging to
    /// rewrite (F-bar's, `crate::assembly::fbar`).
    fn stress_and_tangent(
        response: &mut Self::Response,
    ) -> (&mut SMatrix<f64, D, D>, &mut Self::Tangent);
    /// What a point commits of a response: its history and Cauchy stress.
    fn state_of(response: &Self::Response) -> (Self::History, Self::Stress);
    /// The equivalent plastic strain a history holds.
    fn plastic_strain(history: &Self::History) -> f64;
    fn determinant(m: &SMatrix<f64, D, D>) -> f64;
    /// Point `p`'s domain now, for the basis ([`MaterialPoints::support`]).
    fn support(points: &MaterialPoints<D>, p: usize) -> Support<D>
    where
        Dim<D>: Space<D>;
    /// The first point whose position, deformation or stress is not a
    /// finite number ([`MaterialPoints::first_non_finite`]).
    fn first_non_finite(points: &MaterialPoints<D>) -> Option<usize>
    where
        Dim<D>: Space<D>;
}

/// What the averagings (F-bar, the cell mean) do with a model's `D^2 x D^2` tangent: sums, scaling, and
/// products of `D x D` tensors flattened row by row.
pub trait TangentMatrix:
    Copy
    + Index<(usize, usize), Output = f64>
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<f64, Output = Self>
    + AddAssign
{
    fn from_fn(f: impl FnMut(usize, usize) -> f64) -> Self;
    fn identity() -> Self {
        Self::from_fn(|r, c| if r == c { 1.0 } else { 0.0 })
    }
}

impl TangentMatrix for Matrix4<f64> {
    fn from_fn(f: impl FnMut(usize, usize) -> f64) -> Self {
        Matrix4::from_fn(f)
    }
}

impl TangentMatrix for Tangent3 {
    fn from_fn(f: impl FnMut(usize, usize) -> f64) -> Self {
        Tangent3::from_fn(f)
    }
}

impl Space<2> for Dim<2> {
    type History = History;
    type Stress = CauchyStress;
    type Domain = Domain;
    type Slopes = [f64; 6];
    type Tangent = Matrix4<f64>;
    type Response = Response;

    fn respond(
        material: &Material,
        history: &History,
        grad_u: &Matrix2<f64>,
        j_start: f64,
        want_tangent: bool,
    ) -> Response {
        if want_tangent {
            material.respond(history, grad_u, j_start)
        } else {
            material.respond_without_tangent(history, grad_u, j_start)
        }
    }

    fn stress_of(response: &Response) -> Matrix2<f64> {
        response.p
    }

    fn tangent_of(response: &Response) -> Matrix4<f64> {
        response.tangent
    }

    fn stress_and_tangent(response: &mut Response) -> (&mut Matrix2<f64>, &mut Matrix4<f64>) {
        (&mut response.p, &mut response.tangent)
    }

    fn state_of(response: &Response) -> (History, CauchyStress) {
        (response.history, response.cauchy)
    }

    fn plastic_strain(history: &History) -> f64 {
        history.plastic_strain
    }

    fn determinant(m: &Matrix2<f64>) -> f64 {
        m.determinant()
    }

    fn support(points: &MaterialPoints, p: usize) -> Support {
        points.support(p)
    }

    fn first_non_finite(points: &MaterialPoints) -> Option<usize> {
        points.first_non_finite()
    }
}

impl Space<3> for Dim<3> {
    type History = History3;
    type Stress = Matrix3<f64>;
    type Domain = [f64; 3];
    type Slopes = ();
    type Tangent = Tangent3;
    type Response = Response3;

    /// The 3D models make their tangent whether wanted or not.
    fn respond(
        material: &Material,
        history: &History3,
        grad_u: &Matrix3<f64>,
        j_start: f64,
        _want_tangent: bool,
    ) -> Response3 {
        material.respond_3d(history, grad_u, j_start)
    }

    fn stress_of(response: &Response3) -> Matrix3<f64> {
        response.p
    }

    fn tangent_of(response: &Response3) -> Tangent3 {
        response.tangent
    }

    fn stress_and_tangent(response: &mut Response3) -> (&mut Matrix3<f64>, &mut Tangent3) {
        (&mut response.p, &mut response.tangent)
    }

    fn state_of(response: &Response3) -> (History3, Matrix3<f64>) {
        (response.history, response.cauchy)
    }

    fn plastic_strain(history: &History3) -> f64 {
        history.plastic_strain
    }

    fn determinant(m: &Matrix3<f64>) -> f64 {
        m.determinant()
    }

    fn support(points: &MaterialPoints<3>, p: usize) -> Support<3> {
        points.support(p)
    }

    fn first_non_finite(points: &MaterialPoints<3>) -> Option<usize> {
        points.first_non_finite()
    }
}
