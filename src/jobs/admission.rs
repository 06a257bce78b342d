//! What a submission must be to be queued: JSON, a valid case, and within
//! the service's limits. Each check names the field that fails it.

use mpm::{Case, CaseErrorKind, Simulation};

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

/// A case that may be queued, and the material points it makes.
#[derive(Debug)]
pub struct Admitted {
    pub case: Case,
    pub points: usize,
}

/// Reads a body as a case: the text and the case it holds. A body that is
/// not JSON (text after the case included) is `MalformedJson`; JSON that is
/// not a valid case is `InvalidCase` with the field path.
pub fn read(body: &[u8]) -> Result<(&str, Case), Rejection> {
    let text = std::str::from_utf8(body).map_err(|e| Rejection::MalformedJson(e.to_string()))?;
    let case = Case::from_json(text).map_err(|e| match e.kind {
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
    })?;
    Ok((text, case))
}

/// Checks a case against the limits and builds what a worker builds first
/// (CPU work: call it off the async threads), so that a case is refused
/// here, naming its field, rather than failing on the worker: a boundary
/// load or support that selects nothing, a grid-node support that holds no
/// node, a probe outside every body. The checks that cost microseconds
/// come first: the counts of every body's lattice, and the stored size
/// they imply (a lower bound, without the boundary curves).
pub fn admit(case: Case, limits: &Limits) -> Result<Admitted, Rejection> {
    check_load_steps(&case, limits)?;
    let point_limit = PointLimit::service(limits.max_points);
    if let Some(points) = check_fill_sizes(&case, point_limit)? {
        let at_least = Footprint {
            points: points as usize,
            boundary_points: 0,
            loops: 0,
        };
        check_stored_bytes(at_least, &case, limits)?;
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
    check_stored_bytes(footprint, &case, limits)?;
    Ok(Admitted { case, points })
}

/// Where a case gives its load steps: `analysis.load_steps`, or its stages.
fn load_steps_field(case: &Case) -> &'static str {
    if case.stages.is_empty() {
        "analysis.load_steps"
    } else {
        "stages"
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

/// Refuses a job whose stored steps would pass the limit, naming the field
/// with the larger share of its own limit: the load steps or the bodies'
/// points.
fn check_stored_bytes(seeded: Footprint, case: &Case, limits: &Limits) -> Result<(), Rejection> {
    let (points, steps) = (seeded.points, case.total_load_steps());
    let bytes = stored_bytes(case, seeded);
    if bytes <= limits.max_job_bytes as f64 {
        return Ok(());
    }
    let steps_share = steps as f64 / limits.max_load_steps as f64;
    let points_share = points as f64 / limits.max_points as f64;
    let path = if steps_share >= points_share {
        load_steps_field(case)
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
        assert_eq!(case, Case::from_json(&text).unwrap());
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
        let per_point = |n| serde_json::to_string(&one(n)).unwrap().len();
        let marginal = (per_point(1001) - per_point(1)) as f64 / 1000.0;
        assert!(
            marginal <= STORED_BYTES_PER_POINT,
            "{marginal} bytes a point"
        );
        assert!(
            marginal > 0.9 * STORED_BYTES_PER_POINT,
            "{marginal}: a loose bound"
        );
    }

    #[test]
    fn limits_name_the_field() {
        let mut limits = Config::new("unused").limits;
        let case = Case::from_json(&example().to_string()).unwrap();
        limits.max_load_steps = 4;
        assert!(matches!(
            check_load_steps(&case, &limits),
            Err(Rejection::LimitExceeded { path, .. }) if path == "analysis.load_steps"
        ));
        limits.max_load_steps = 5;
        limits.max_points = 10;
        assert!(matches!(
            admit(case.clone(), &limits),
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
        assert!(check_stored_bytes(seeded, &case, &limits).is_ok());
        limits.max_job_bytes = stored as u64 - 1;
        // 5 of 5 load steps against 400 of 1000 points: the steps drive it.
        assert!(matches!(
            check_stored_bytes(seeded, &case, &limits),
            Err(Rejection::LimitExceeded { path, .. }) if path == "analysis.load_steps"
        ));
        limits.max_load_steps = 10_000;
        assert!(matches!(
            check_stored_bytes(seeded, &case, &limits),
            Err(Rejection::LimitExceeded { path, .. }) if path == "bodies"
        ));
        assert!(matches!(
            check_points(0, PointLimit::service(limits.max_points)),
            Err(Rejection::InvalidCase { path, .. }) if path == "bodies"
        ));
    }
}
