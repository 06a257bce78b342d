//! The run's settings and their defaults: Newton's controls (with the
//! stabilisation of the tangent), and how a failing load step is cut. The
//! case format reads its defaults from here, and from no solver module.

/// Newton controls; the defaults are the case format's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NewtonSettings {
    /// Relative out-of-balance force at which a step has converged (1e-9).
    pub tolerance: f64,
    /// Linear solves allowed per load step (30).
    pub max_iterations: usize,
    /// A relative residual above this (or not finite) is divergence (1e8).
    pub divergence_limit: f64,
    /// Soft-background stiffness, relative to the stiffest material: the
    /// fallback stabilisation, off by default (0); see
    /// [`crate::assembly::SoftCells`].
    pub tangent_regularisation: f64,
    /// Search along each Newton direction (true); see [`crate::newton::solve`].
    pub line_search: bool,
    /// Start each increment of a load-factor step from the last one's,
    /// scaled to its change of load factor (true); see
    /// [`crate::newton::solve_from`].
    pub predictor: bool,
    /// Ghost penalty on the faces of the cells at the material's edge,
    /// relative to twice the largest shear modulus (1e-3; 0: none); see
    /// [`crate::assembly::GhostFaces`].
    pub ghost_penalty: f64,
    /// The cell-mean strain's hourglass stiffness, relative to twice the
    /// material's shear modulus (1e-2); see [`crate::assembly::cell_mean`].
    pub hourglass: f64,
    /// Stiffen the bending of points seeded one a cell or fewer with their
    /// material's moduli (true); see [`crate::assembly::lone_points`].
    pub lone_points: bool,
    /// How far a free full step of the line search may raise the
    /// out-of-balance force, against the larger of the step's lowest and
    /// its starting force scale (10; the model sets ten times the stiffest
    /// material's P-wave to shear modulus ratio, and at least 1e3 for a
    /// slender body's first step); see `newton::Search`.
    pub free_step_growth: f64,
    /// End a try that has stopped converging far from equilibrium before
    /// its iteration limit (`newton::stuck`; false). Not a case setting:
    /// the stepper turns it on for the try of a load-factor increment it
    /// can still cut, never for a strength-reduction trial (whose failure
    /// is a verdict) nor an arc.
    pub give_up_when_stuck: bool,
}

impl Default for NewtonSettings {
    fn default() -> Self {
        Self {
            tolerance: 1e-9,
            max_iterations: 30,
            divergence_limit: 1e8,
            tangent_regularisation: 0.0,
            line_search: true,
            predictor: true,
            ghost_penalty: 1e-3,
            hourglass: 1e-2,
            lone_points: true,
            free_step_growth: 10.0,
            give_up_when_stuck: false,
        }
    }
}

/// Cutting a load step's increment when it fails.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Substepping {
    /// The smallest sub-increment tried, as a fraction of the step's
    /// (1/1024); 1 turns cutting off.
    pub min_fraction: f64,
    /// Failed tries allowed in one load step (40).
    pub max_cutbacks: usize,
}

impl Default for Substepping {
    fn default() -> Self {
        Self {
            min_fraction: 1.0 / 1024.0,
            max_cutbacks: 40,
        }
    }
}
