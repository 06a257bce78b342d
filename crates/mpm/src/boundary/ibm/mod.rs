//! Dirichlet conditions on the boundary curve by the implicit boundary
//! method (Burla & Kumar 2008; Kumar et al. 2008; in MPM, Cortis et al.
//! 2018).
//!
//! The trial displacement is `u = D u_h + u_a`: `u_h` the grid
//! interpolation, `u_a` the prescribed values, `D` a D-function of the
//! distance `phi` from the boundary, `D = 1 - (1 - phi/delta)^2` across a
//! band of width `delta` inside the material and 1 beyond. Integrated across
//! the band, the strain energy of `D u_h` has the leading part
//! `1/2 int_Gamma (4 / (3 delta)) (u_h - u_a) . A_nn (u_h - u_a) dGamma`, since
//! `int_0^delta D'(phi)^2 dphi = 4 / (3 delta)`, with `A_nn` the acoustic
//! tensor `A_iKjL n_K n_L` of the material next to the boundary. The band is
//! far thinner than a point spacing, so no point lies in it and the points
//! keep their ordinary integration; the band adds that boundary term,
//! integrated by Gauss quadrature along the B-spline (split at grid lines,
//! as tractions are). A fixed condition holds both components, a roller the
//! normal one (`P = n n` in `P A_nn P`), so inclined and curved rollers are
//! the same code.
//!
//! The band width `delta` trades two errors: the penalty holds the
//! condition to a gap of about `(3/4) delta` times the boundary strain, and
//! a boundary at an angle to the grid locks as `delta` shrinks (the bilinear
//! field cannot meet a stiff constraint at every quadrature point). The
//! default, a hundredth of a cell, keeps both at or below the
//! discretisation error; `docs/ibm.md` has the measurements.
//!
//! Updated-Lagrangian steps reset the grid, so a step's band term sees only
//! that step's increment, while a support must hold the boundary's total
//! displacement. The band's quadrature points are therefore [`Anchor`]s:
//! fixed on the reference curve (Gauss points of its segments, split at
//! the grid lines of the first step) and carried by the grid's own
//! displacement at the end of every step, so that each one knows how far it
//! has moved; the step's target is the prescribed displacement minus that.
//!
//! A support that ends inside the body's boundary (a rigid footing) can
//! be held on average over pieces of about two cells instead
//! (`"constraint": "averaged"`): held at every point, the stiff penalty
//! makes the field constant across the cell that holds the edge, and the
//! footing acts up to a cell wider (`docs/ibm.md`, The rigid footing's
//! edge).
//!
//! Nodes just beyond a supported boundary, which GIMP domains reach as the
//! body deforms, get a tiny stiffness but a force proportional to the
//! point's stress; their equilibrium would ask that stress to vanish, which
//! at a support it cannot. They get a ghost tie ([`ghost_ties`]), which makes
//! them follow the linear continuation of the field inside. Only beyond
//! pointwise supports: under an averaged one (a rigid footing) the soil
//! flows past the footing's edge, and ties would resist that flow
//! (`docs/ibm.md`, Why the ghost ties); a node also beyond a pointwise
//! support is tied by that one.
//!
//! The stages: [`anchors()`] once per run ([`anchors`]), then every load
//! step [`BandTerms`] ([`band`]) with the ghost ties ([`ghost_ties`]). In
//! 3D the anchors lie on the surface patches ([`surface_anchors`]) and
//! the band's terms are the same.

pub mod anchors;
pub mod band;
pub mod ghost_ties;
pub mod surface_anchors;

pub use anchors::{AVERAGED_PIECE_CELLS, Anchor, IbmMotion, IbmSupport, anchors, enter_stage};
pub use band::{BandTerms, DEFAULT_BAND_WIDTH};
pub use surface_anchors::{SurfaceAnchor, SurfaceSupport, surface_anchors};
