//! What a submission must be to be queued: JSON, a valid case, and within
//! the service's limits. Each check names the field that fails it.

use mpm::case::solid::{SolidCase, is_solid};
use mpm::{Case, CaseError, CaseErrorKind, Simulation};

use crate::config::Limits;

/// Why a submission is refused.
#[derive(Debug, Clone, PartialEq)]
pub enum Rejection {
    /// The body is not JSON at all.
    MalformedJson(String),
    /// JSON, but not a valid case; `path` names the field.
    InvalidCase { path: String, message: String },
    /// A valid case that exceeds a configured limit.
    LimitExceeded { path: String, message: String },
}

/// A submitted case: plane strain, or 3D (`analysis.type: "3d"`).
#[derive(Debug, Clone, PartialEq)]
pub enum Submitted {
    Plane(Case),
    Solid(SolidCase),
}

impl Submitted {
    pub fn title(&self) -> Option<&str> {
        match self {
            Submitted::Plane(case) => case.title.as_deref(),
            Submitted::Solid(case) => case.title.as_deref(),
        }
    }

    /// Load steps over all stages.
    pub fn load_steps(&self) -> u64 {
        match self {
            Submitted::Plane(case) => Steps::load_steps(case),
            Submitted::Solid(case) => case.load_steps(),
        }
    }
}

/// A case that may be queued, and the material points it makes.
#[derive(Debug)]
pub struct Admitted {
    pub case: Submitted,
    pub points: usize,
}

/// Reads a body as a case: the text and the case it holds, 3D when its
/// `analysis.type` is `"3d"`. A body that is not JSON (text after the case
/// included) is `MalformedJson`; JSON that is not a valid case is
/// `InvalidCase` with the field path.
pub fn read(body: &[u8]) -> Result<(&str, Submitted), Rejection> {
    let text = std::str::from_utf8(body).map_err(|e| Rejection::MalformedJson(e.to_string()))?;
    let refused = |e: CaseError| match e.kind {
        // The JSON parser's own word on where the text stops being JSON
        // (a case error may come first in the text).
        CaseErrorKind::Syntax => Rejection::MalformedJson(
            serde_json::from_str::<serde_json::Value>(text)
                .err()
                .map_or(e.message, |e| e.to_string()),
        ),
        CaseErrorKind::Invalid => Rejection::InvalidCase {
            path: e.path,
            message: e.message,
        },
    };
    let case = if is_solid(text) {
        Submitted::Solid(SolidCase::from_json(text).map_err(refused)?)
    } else {
        Submitted::Plane(Case::from_json(text).map_err(refused)?)
    };
    Ok((text, case))
}

/// Checks a case against the limits and builds what a worker builds first
/// (CPU work: call it off the async threads), so that a case is refused
/// here, naming its field, rather than failing on the worker: a boundary
/// load or support that selects nothing, a grid-node support that holds no
/// node, a probe outside every body. The checks that cost microseconds
/// come first: the counts of every body's lattice, and the stored size
/// they imply (a lower bound, without the boundary curves).
pub fn admit(case: Submitted, limits: &Limits) -> Result<Admitted, Rejection> {
    match case {
        Submitted::Plane(case) => admit_plane(case, limits),
        Submitted::Solid(case) => admit_solid(case, limits),
    }
}

fn admit_plane(case: Case, limits: &Limits) -> Result<Admitted, Rejection> {
    check_load_steps(&case, limits)?;
    let point_limit = PointLimit::service(limits.max_points);
    if let Some(points) = check_fill_sizes(&case, point_limit)? {
        let at_least = Footprint {
            points: points as usize,
            boundary_points: 0,
            loops: 0,
        };
        check_stored_bytes(
            stored_bytes(&case, at_least),
            &case,
            at_least.points,
            limits,
        )?;
    }
    let sim = Simulation::new(&case).map_err(|e| Rejection::InvalidCase {
        path: e.path,
        message: e.message,
    })?;
    let points = sim.points.len();
    check_points(points, point_limit)?;
    let footprint = Footprint {
        points,
        boundary_points: sim.loops.iter().map(|l| l.points.len()).sum(),
        loops: sim.loops.len(),
    };
    check_stored_bytes(stored_bytes(&case, footprint), &case, points, limits)?;
    Ok(Admitted {
        case: Submitted::Plane(case),
        points,
    })
}

/// [`admit`] for a 3D case: the load steps, the points' bound from the
/// bodies' boxes (the lattice sites seeding scans), the points seeding
/// makes, and what the job would store.
fn admit_solid(case: SolidCase, limits: &Limits) -> Result<Admitted, Rejection> {
    let steps = case.load_steps();
    if steps > limits.max_load_steps as u64 {
        return Err(Rejection::LimitExceeded {
            path: "analysis.load_steps".into(),
            message: format!(
                "{steps} load steps exceed this service's limit of {}",
                limits.max_load_steps
            ),
        });
    }
    let limit = PointLimit::service(limits.max_points);
    let sites = case.points_bound();
    if sites > SITES_PER_POINT * limit.max as f64 {
        return Err(Rejection::LimitExceeded {
            path: "bodies".into(),
            message: format!(
                "seeding the bodies scans {sites:.3e} lattice sites (their bounding boxes at \
                 their spacings), over the limit of {:.3e} ({SITES_PER_POINT} per point of {})",
                SITES_PER_POINT * limit.max as f64,
                limit.name
            ),
        });
    }
    let sim = Simulation::from_solid_case(&case).map_err(|e| Rejection::InvalidCase {
        path: e.path,
        message: e.message,
    })?;
    let points = sim.points.len();
    check_points(points, limit)?;
    let cells: Vec<[usize; 2]> = sim.faces.iter().map(|f| f.data_grid_cells()).collect();
    let bytes = solid_stored_bytes(&case, points, &cells);
    check_stored_bytes(bytes, &case, points, limits)?;
    Ok(Admitted {
        case: Submitted::Solid(case),
        points,
    })
}

/// Where a case gives its load steps: `analysis.load_steps`, or its stages.
fn load_steps_field(case: &Case) -> &'static str {
    if case.stages.is_empty() {
        "analysis.load_steps"
    } else {
        "stages"
    }
}

/// A case's load steps, and the field that gives them.
trait Steps {
    fn load_steps(&self) -> u64;
    fn load_steps_field(&self) -> &'static str;
}

impl Steps for Case {
    fn load_steps(&self) -> u64 {
        self.total_load_steps()
    }

    fn load_steps_field(&self) -> &'static str {
        load_steps_field(self)
    }
}

impl Steps for SolidCase {
    fn load_steps(&self) -> u64 {
        u64::from(self.analysis.load_steps)
    }

    fn load_steps_field(&self) -> &'static str {
        "analysis.load_steps"
    }
}

fn check_load_steps(case: &Case, limits: &Limits) -> Result<(), Rejection> {
    let steps = case.total_load_steps();
    if steps > limits.max_load_steps as u64 {
        return Err(Rejection::LimitExceeded {
            path: load_steps_field(case).into(),
            message: format!(
                "{steps} load steps exceed this service's limit of {}",
                limits.max_load_steps
            ),
        });
    }
    Ok(())
}

/// Lattice sites a body's seeding may scan, per point of the point limit:
/// a shape other than a rectangle or an annulus sector scans the lattice
/// over its bounding box (a circle keeps pi/4 of it).
const SITES_PER_POINT: f64 = 4.0;

/// Refuses a case over the point limit before seeding anything, from the
/// per-direction counts of every body's lattice: exact for rectangles,
/// quadrilaterals and annulus sectors, and for other shapes the sites their seeding would
/// scan. Microseconds, whatever the case asks for. Returns the number of
/// points when every body's count is exact.
pub fn check_fill_sizes(case: &Case, limit: PointLimit) -> Result<Option<f64>, Rejection> {
    let max = limit.max as f64;
    let mut points = 0.0;
    let mut exact = true;
    for (i, body) in case.bodies.iter().enumerate() {
        let size = mpm::model::fill_size(body, &case.grid);
        exact &= size.exact;
        if size.exact {
            points += size.sites;
        } else if size.sites > SITES_PER_POINT * max {
            return Err(Rejection::LimitExceeded {
                path: format!("bodies[{i}].points"),
                message: format!(
                    "seeding this body scans {:.3e} lattice sites (its bounding box at this spacing), \
                     over the limit of {:.3e} ({SITES_PER_POINT} per point of {})",
                    size.sites,
                    SITES_PER_POINT * max,
                    limit.name
                ),
            });
        }
    }
    if points > max {
        return Err(Rejection::LimitExceeded {
            path: "bodies".into(),
            message: format!(
                "the bodies make {points:.0} material points, over {} of {}",
                limit.name, limit.max
            ),
        });
    }
    Ok(exact.then_some(points))
}

/// A limit on a case's material points, and how a refusal names it.
#[derive(Debug, Clone, Copy)]
pub struct PointLimit {
    pub max: usize,
    /// e.g. "this service's point limit".
    pub name: &'static str,
}

impl PointLimit {
    pub fn service(max: usize) -> Self {
        PointLimit {
            max,
            name: "this service's point limit",
        }
    }
}

/// The number of points the case made: within the limit, and some.
pub fn check_points(points: usize, limit: PointLimit) -> Result<(), Rejection> {
    if points > limit.max {
        return Err(Rejection::LimitExceeded {
            path: "bodies".into(),
            message: format!(
                "the bodies make {points} material points, over {} of {}",
                limit.name, limit.max
            ),
        });
    }
    if points == 0 {
        return Err(Rejection::InvalidCase {
            path: "bodies".into(),
            message:
                "the bodies contain no material points (geometry smaller than the point spacing?)"
                    .into(),
        });
    }
    Ok(())
}

/// Bytes one material point takes in a stored step, at most: its columns
/// (`mpm::report::PointColumns`) are eleven numbers of at most 24
/// characters (`-1.2345678901234567e-100`), the commas and brackets around
/// them, a body index and a yield flag (a test serialises the worst case).
pub const STORED_BYTES_PER_POINT: f64 = 305.0;
/// Bytes one point of a 3D run takes in a stored step, at most
/// (`mpm::report::SolidPointColumns`: fifteen numbers, a body index and a
/// yield flag, as [`STORED_BYTES_PER_POINT`]).
pub const STORED_BYTES_PER_SOLID_POINT: f64 = 420.0;
/// Bytes one control point of a stored 3D surface takes, at most: three
/// numbers of at most 24 characters, their commas and brackets.
pub const STORED_BYTES_PER_CONTROL_POINT: f64 = 78.0;
/// Bytes of a stored 3D surface patch besides its control points: its
/// body, cells and flags (128), and its knots, integers to 12 characters.
fn surface_patch_bytes(cells: [usize; 2]) -> f64 {
    let [u, v] = cells.map(|c| c as f64);
    (3.0 * u + 1.0) * (3.0 * v + 1.0) * STORED_BYTES_PER_CONTROL_POINT
        + 128.0
        + 12.0 * (3.0 * u + 3.0 * v + 10.0)
}

/// Bytes one boundary point (a data point of a boundary curve) takes in a
/// stored step, at most: eight polyline samples (8 x 52), up to three knots
/// and three control points (at a corner; 3 x 25 + 3 x 52) and its index.
pub const STORED_BYTES_PER_BOUNDARY_POINT: f64 = 700.0;
/// A boundary curve's own bytes: its end knots, closing samples and keys.
pub const STORED_BYTES_PER_LOOP: f64 = 512.0;

/// What seeding a case made, as far as its stored size goes.
#[derive(Debug, Clone, Copy)]
pub struct Footprint {
    pub points: usize,
    /// Data points of all boundary curves.
    pub boundary_points: usize,
    pub loops: usize,
}

/// What a job will store: the points and boundary curves (at most) of the
/// steps its case's `output` keeps (step 0 included), and every step's report, whose size grows with the probes, the supports
/// and the Newton history (one solve's worth: a step cut into pieces adds
/// about 50 bytes an iteration of each).
pub fn stored_bytes(case: &Case, seeded: Footprint) -> f64 {
    let probes: f64 = case
        .probes
        .iter()
        .map(|p| serde_json::to_string(&p.name).map_or(0, |n| n.len()) as f64 + 160.0)
        .sum();
    let report = 1024.0
        + probes
        + 60.0 * case.supports.len() as f64
        + 50.0 * f64::from(case.analysis.newton.max_iterations + 1);
    let points = seeded.points as f64 * STORED_BYTES_PER_POINT
        + seeded.boundary_points as f64 * STORED_BYTES_PER_BOUNDARY_POINT
        + seeded.loops as f64 * STORED_BYTES_PER_LOOP;
    let load_steps = case.total_load_steps() as usize;
    // Reports of steps 0..=n; points of step 0, every `output.every`-th
    // and the last.
    points * case.output.point_steps(load_steps) as f64 + report * (load_steps + 1) as f64
}

/// What a 3D job will store: its points and surfaces (`surface_cells`,
/// each face patch's cells) at the steps its `output` keeps (step 0
/// included), and every step's report (as [`stored_bytes`]).
pub fn solid_stored_bytes(case: &SolidCase, points: usize, surface_cells: &[[usize; 2]]) -> f64 {
    let report = 1024.0
        + 60.0 * case.supports.len() as f64
        + 50.0 * f64::from(case.analysis.newton.max_iterations + 1);
    let load_steps = case.analysis.load_steps as usize;
    let surfaces: f64 = surface_cells.iter().map(|&c| surface_patch_bytes(c)).sum();
    (points as f64 * STORED_BYTES_PER_SOLID_POINT + surfaces)
        * case.output.point_steps(load_steps) as f64
        + report * (load_steps + 1) as f64
}

/// Refuses a job whose stored steps would take `bytes`, past the limit,
/// naming the field with the larger share of its own limit: the load
/// steps or the bodies' `points`.
fn check_stored_bytes(
    bytes: f64,
    case: &impl Steps,
    points: usize,
    limits: &Limits,
) -> Result<(), Rejection> {
    let steps = case.load_steps();
    if bytes <= limits.max_job_bytes as f64 {
        return Ok(());
    }
    let steps_share = steps as f64 / limits.max_load_steps as f64;
    let points_share = points as f64 / limits.max_points as f64;
    let path = if steps_share >= points_share {
        case.load_steps_field()
    } else {
        "bodies"
    };
    Err(Rejection::LimitExceeded {
        path: path.into(),
        message: format!(
            "{points} material points over {steps} load steps would store up to {bytes:.3e} bytes, \
             over this service's limit of {} bytes a job: fewer load steps or coarser bodies fit",
            limits.max_job_bytes
        ),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Config;

    fn example() -> serde_json::Value {
        mpm::case::builtin::json("cantilever-grid").unwrap()
    }

    fn read_err(body: &str) -> Rejection {
        read(body.as_bytes()).expect_err(body)
    }

    #[test]
    fn a_valid_case_reads_like_case_from_json() {
        let text = example().to_string();
        let (read_text, case) = read(text.as_bytes()).unwrap();
        assert_eq!(read_text, text);
        assert_eq!(case, Submitted::Plane(Case::from_json(&text).unwrap()));
    }

    #[test]
    fn text_that_is_not_json_is_malformed_wherever_it_goes_wrong() {
        for body in [
            "{\"version\": 1,",
            "not json",
            "",
            // A wrong field first, and then the text stops being JSON.
            "{\"version\": 1, \"no_such_field\": 1,",
            "{\"version\": 1, \"no_such_field\": 1e400}",
        ] {
            // The message is the JSON parser's, not the case's.
            let parser = serde_json::from_str::<serde_json::Value>(body).unwrap_err();
            assert_eq!(
                read_err(body),
                Rejection::MalformedJson(parser.to_string()),
                "{body}"
            );
        }
        let trailing = format!("{} x", example());
        assert!(matches!(read_err(&trailing), Rejection::MalformedJson(_)));
        assert!(matches!(read(b"\xff"), Err(Rejection::MalformedJson(_))));
    }

    #[test]
    fn json_that_is_not_a_case_names_the_field_as_case_from_json_does() {
        let mut typo = example();
        typo["bodies"][0]["material"]["youngs_modulos"] = 1.into();
        let mut range = example();
        range["bodies"][0]["material"]["poisson_ratio"] = 0.5.into();
        let duplicate = example().to_string().replacen("{", "{\"version\": 1, ", 1);
        let overflow =
            example()
                .to_string()
                .replacen("\"cell_size\":", "\"cell_size\":1e309,\"x\":", 1);
        for body in [
            typo.to_string(),
            range.to_string(),
            duplicate,
            "[]".into(),
            overflow,
        ] {
            let expected = Case::from_json(&body).unwrap_err();
            assert_eq!(
                read_err(&body),
                Rejection::InvalidCase {
                    path: expected.path,
                    message: expected.message
                },
                "{body}"
            );
        }
    }

    /// The per-point bound holds for the longest numbers JSON can give:
    /// a point whose every value is `-1.2345678901234567e-100` and whose
    /// body index is the largest.
    #[test]
    fn a_stored_point_takes_at_most_its_bound() {
        let worst = -1.2345678901234567e-100;
        let one = |n: usize| mpm::report::PointColumns {
            position: vec![[worst; 2]; n],
            displacement: vec![[worst; 2]; n],
            stress: vec![[worst; 4]; n],
            volume: vec![worst; n],
            jacobian: vec![worst; n],
            body: vec![u32::MAX; n],
            plastic_strain: vec![worst; n],
            yielding: vec![false; n],
        };
        holds_tightly(one, STORED_BYTES_PER_POINT);
    }

    /// The same for a 3D run's point (`SolidPointColumns`).
    #[test]
    fn a_stored_3d_point_takes_at_most_its_bound() {
        let worst = -1.2345678901234567e-100;
        let one = |n: usize| mpm::report::SolidPointColumns {
            position: vec![[worst; 3]; n],
            displacement: vec![[worst; 3]; n],
            stress: vec![[worst; 6]; n],
            volume: vec![worst; n],
            jacobian: vec![worst; n],
            body: vec![u32::MAX; n],
            plastic_strain: vec![worst; n],
            yielding: vec![false; n],
        };
        holds_tightly(one, STORED_BYTES_PER_SOLID_POINT);
    }

    /// The same for a 3D surface's control points, and a patch's own
    /// bytes: a patch of the largest values and knots serialised.
    #[test]
    fn a_stored_surface_takes_at_most_its_bound() {
        let worst = -1.2345678901234567e-100;
        let patch = |n: usize| mpm::boundary::face_patches::SurfaceOutput {
            body: usize::MAX,
            cells: [n, 1],
            closed: [false, false],
            degree: 3,
            knots: [
                (0..3 * n + 5).map(|_| 123456.0).collect(),
                vec![123456.0; 8],
            ],
            control_points: vec![[worst; 3]; (3 * n + 1) * 4],
        };
        // Each cell along u adds 12 control points and three knots.
        let bytes = |n: usize| serde_json::to_string(&patch(n)).unwrap().len() as f64;
        let marginal = (bytes(1001) - bytes(1)) / 1000.0;
        let bound = 12.0 * STORED_BYTES_PER_CONTROL_POINT + 3.0 * 12.0;
        assert!(
            marginal <= bound && marginal > 0.9 * bound,
            "{marginal} against {bound}"
        );
        assert!(bytes(1) <= surface_patch_bytes([1, 1]), "{}", bytes(1));
    }

    /// The bytes a point adds to the JSON of `columns(n)` (of `n` points)
    /// are at most `bound`, and over 0.9 of it.
    fn holds_tightly<T: serde::Serialize>(columns: impl Fn(usize) -> T, bound: f64) {
        let per_point = |n| serde_json::to_string(&columns(n)).unwrap().len();
        let marginal = (per_point(1001) - per_point(1)) as f64 / 1000.0;
        assert!(marginal <= bound, "{marginal} bytes a point");
        assert!(marginal > 0.9 * bound, "{marginal}: a loose bound");
    }

    /// A case whose `analysis.type` is `"3d"` reads as a 3D case, and is
    /// refused at its load steps and stored size as a plane-strain one.
    #[test]
    fn a_3d_case_reads_and_is_limited_as_a_plane_one() {
        let text = mpm::case::builtin::get("column3d").unwrap();
        let (_, case) = read(text.as_bytes()).unwrap();
        assert_eq!(case, Submitted::Solid(SolidCase::from_json(text).unwrap()));
        assert_eq!((case.title().is_some(), case.load_steps()), (true, 40));
        let mut limits = Config::new("unused").limits;
        let admitted = admit(case.clone(), &limits).unwrap();
        assert_eq!(admitted.points, 128);
        limits.max_load_steps = 39;
        assert!(matches!(
            admit(case.clone(), &limits),
            Err(Rejection::LimitExceeded { path, .. }) if path == "analysis.load_steps"
        ));
        limits.max_load_steps = 40;
        let Submitted::Solid(solid) = &case else {
            unreachable!()
        };
        // 128 points stored at 41 steps, and 41 reports.
        let bytes = solid_stored_bytes(solid, 128, &[]);
        assert!(
            bytes > 128.0 * 41.0 * STORED_BYTES_PER_SOLID_POINT,
            "{bytes}"
        );
        limits.max_job_bytes = bytes as u64 - 1;
        assert!(matches!(
            admit(case, &limits),
            Err(Rejection::LimitExceeded { path, .. }) if path == "analysis.load_steps"
        ));
    }

    #[test]
    fn limits_name_the_field() {
        let mut limits = Config::new("unused").limits;
        let case = Case::from_json(&example().to_string()).unwrap();
        let submitted = Submitted::Plane(case.clone());
        limits.max_load_steps = 4;
        assert!(matches!(
            check_load_steps(&case, &limits),
            Err(Rejection::LimitExceeded { path, .. }) if path == "analysis.load_steps"
        ));
        limits.max_load_steps = 5;
        limits.max_points = 10;
        assert!(matches!(
            admit(submitted, &limits),
            Err(Rejection::LimitExceeded { path, .. }) if path == "bodies"
        ));
        limits.max_points = 1000;
        let seeded = Footprint {
            points: 400,
            boundary_points: 80,
            loops: 1,
        };
        let stored = stored_bytes(&case, seeded);
        limits.max_job_bytes = stored as u64;
        let check = |limits: &Limits| check_stored_bytes(stored, &case, seeded.points, limits);
        assert!(check(&limits).is_ok());
        limits.max_job_bytes = stored as u64 - 1;
        // 5 of 5 load steps against 400 of 1000 points: the steps drive it.
        assert!(matches!(
            check(&limits),
            Err(Rejection::LimitExceeded { path, .. }) if path == "analysis.load_steps"
        ));
        limits.max_load_steps = 10_000;
        assert!(matches!(
            check(&limits),
            Err(Rejection::LimitExceeded { path, .. }) if path == "bodies"
        ));
        assert!(matches!(
            check_points(0, PointLimit::service(limits.max_points)),
            Err(Rejection::InvalidCase { path, .. }) if path == "bodies"
        ));
    }
}
