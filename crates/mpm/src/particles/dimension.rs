//! What a material point holds that differs between plane strain and 3D
//! by more than its size: the types `MaterialPoints<D>` keeps per point.
//! The rest of a point's state is `[f64; D]` or a `D x D` matrix.

use std::fmt::Debug;
use std::ops::Index;

use nalgebra::{Matrix3, Matrix4};

use super::seeding::Domain;
use crate::material::{CauchyStress, History, History3, Tangent3};

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
    type Tangent: Copy + Debug + Send + Sync + Index<(usize, usize), Output = f64>;
}

impl Space<2> for Dim<2> {
    type History = History;
    type Stress = CauchyStress;
    type Domain = Domain;
    type Slopes = [f64; 6];
    type Tangent = Matrix4<f64>;
}

impl Space<3> for Dim<3> {
    type History = History3;
    type Stress = Matrix3<f64>;
    type Domain = [f64; 3];
    type Slopes = ();
    type Tangent = Tangent3;
}
