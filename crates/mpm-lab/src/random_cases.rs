//! Random valid cases across the space users reach, seeded and
//! reproducible: case `index` of seed `seed` is the same case on every
//! machine ([`draw`]). Each is one of five scenes a user builds, with its
//! shape, basis, points, grid placement, material, supports, loads and
//! load steps drawn:
//!
//! - `cantilever`: a slender beam (length 4 to 10 depths), turned up to 30
//!   degrees or not, clamped at its root (by the grid's nodes when the root
//!   lies on a grid line, else by the implicit boundary method), under a
//!   dead tip shear or a follower pressure on its top, from small strain
//!   (`P L^2 / EI = 0.01`) to large rotation (6); elastic;
//! - `block`: a rectangle, a trapezoid (a quadrilateral) or a notched
//!   polygon on a rough floor, under gravity, a follower pressure, a dead
//!   traction with shear, or a prescribed push of its top; elastic, or
//!   plastic below its unconfined strength (pushed: any amount to 5%);
//! - `wedge`: a turned rectangle in a right-angled corner whose sides are
//!   inclined rollers, under gravity and a pressure on its top;
//! - `ring`: a quarter of a thick cylinder on two symmetry rollers, or a
//!   whole ring clamped outside, under an internal follower pressure;
//!   elastic or von Mises below Hill's limit `2 k ln(b / a)`;
//! - `layers`: two bodies of different materials, one on the other, on a
//!   rough floor, under a pressure on the top and gravity (less than
//!   Earth's where the lower body could not stand its weight).
//!
//! Each case's volume treatment (`analysis.volumetric`) is drawn too:
//! the points' own strains half the time, F-bar or the cell-mean strain a
//! quarter each, from a stream of its own, so that the rest of each case
//! is what it was before the treatment was drawn. From a third stream, a
//! third of the plastic cases are loaded in a first stage and then
//! reduced in strength to their factor of safety (a last stage of up to
//! 20 trials rising by 0.05, 0.1 or 0.2, half of them with the flow limit
//! 10); the rest of such a case is what it was.
//!
//! A drawn case is valid by construction (the case's own checks accept
//! it) and physically loaded below collapse: each is expected to finish.
//! Loads are drawn as fractions of the body's stiffness or strength.

use serde_json::{Value, json};

/// A small, fast generator (SplitMix64, Steele, Lea and Flood 2014): the
/// same sequence everywhere, no dependency.
#[derive(Debug, Clone)]
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    pub fn range(&mut self, low: f64, high: f64) -> f64 {
        low + (high - low) * self.uniform()
    }

    /// Log-uniform in [low, high] (both positive).
    pub fn log_range(&mut self, low: f64, high: f64) -> f64 {
        (low.ln() + (high.ln() - low.ln()) * self.uniform()).exp()
    }

    /// Uniform in low..=high.
    pub fn int(&mut self, low: u32, high: u32) -> u32 {
        low + (self.next_u64() % u64::from(high - low + 1)) as u32
    }

    pub fn chance(&mut self, p: f64) -> bool {
        self.uniform() < p
    }

    pub fn pick<T: Copy>(&mut self, items: &[T]) -> T {
        items[(self.next_u64() % items.len() as u64) as usize]
    }
}

/// The scene a case was drawn from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Scene {
    Cantilever,
    Block,
    Wedge,
    Ring,
    Layers,
}

impl Scene {
    pub const ALL: [Scene; 5] = [
        Scene::Cantilever,
        Scene::Block,
        Scene::Wedge,
        Scene::Ring,
        Scene::Layers,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Scene::Cantilever => "cantilever",
            Scene::Block => "block",
            Scene::Wedge => "wedge",
            Scene::Ring => "ring",
            Scene::Layers => "layers",
        }
    }
}

/// A drawn case and the classes it belongs to.
#[derive(Debug, Clone)]
pub struct Drawn {
    pub seed: u64,
    pub index: usize,
    pub scene: Scene,
    /// `gimp`, `bspline2`, `bspline3` or `linear`.
    pub basis: &'static str,
    /// The material model of the (first) body.
    pub model: &'static str,
    /// What loads it: `gravity`, `pressure`, `traction`, `pushed`, ...
    pub load: &'static str,
    /// `grid` or `ibm`.
    pub support: &'static str,
    pub per_cell: u32,
    pub load_steps: u32,
    /// `small` or `large`: whether the load is drawn to strain the body
    /// by more than a percent or turn it by more than a few degrees.
    pub magnitude: &'static str,
    /// `standard`, `fbar` or `cell_mean` (`analysis.volumetric`).
    pub volumetric: &'static str,
    /// `none`, or whether the case ends in a strength reduction with or
    /// without a flow limit: `reduced` or `reduced, flow limit`.
    pub reduction: &'static str,
    pub case: Value,
}

impl Drawn {
    /// A one-line description: the classes and the seed to draw it again.
    pub fn label(&self) -> String {
        format!(
            "seed {} case {}: {} {} {} {} ({} support, {} points a cell, {} steps, {}, {}, strength reduction {})",
            self.seed,
            self.index,
            self.scene.name(),
            self.basis,
            self.model,
            self.load,
            self.support,
            self.per_cell,
            self.load_steps,
            self.magnitude,
            self.volumetric,
            self.reduction
        )
    }
}

/// What a drawn material's strength allows: the pressure that fails it
/// unconfined in plane strain (infinite for an elastic one).
struct MaterialDraw {
    spec: Value,
    model: &'static str,
    youngs_modulus: f64,
    /// Unconfined plane-strain compressive strength (Pa).
    strength: f64,
    /// Shear strength `k` of a von Mises material (Pa), for Hill's limit.
    shear_strength: Option<f64>,
}

const BASES: [&str; 4] = ["gimp", "bspline2", "bspline3", "linear"];

/// The volume treatments, the points' own strains twice.
const VOLUMETRIC: [&str; 4] = ["standard", "standard", "fbar", "cell_mean"];

/// Case `index` of batch `seed`.
pub fn draw(seed: u64, index: usize) -> Drawn {
    let mut rng = Rng::new(seed ^ (index as u64).wrapping_mul(0xD1B5_4A32_D192_ED03));
    // A few draws to mix the two words before the first choice.
    for _ in 0..3 {
        rng.next_u64();
    }
    let scene = rng.pick(&Scene::ALL);
    let basis = rng.pick(&BASES);
    let per_cell = rng.int(1, 4);
    let load_steps = if rng.chance(0.2) {
        rng.int(1, 3)
    } else {
        rng.log_range(1.5, 50.49).round() as u32
    };
    // The B-splines' grid nodes hold coefficients, not the field: their
    // supports are the IBM's.
    let grid_ok = matches!(basis, "gimp" | "linear");
    let mut drawn = match scene {
        Scene::Cantilever => cantilever(&mut rng, grid_ok),
        Scene::Block => block(&mut rng, grid_ok),
        Scene::Wedge => wedge(&mut rng),
        Scene::Ring => ring(&mut rng),
        Scene::Layers => layers(&mut rng, grid_ok),
    };
    drawn.case["version"] = json!(1);
    drawn.case["title"] = json!(format!("random case {index} of seed {seed}"));
    drawn.case["basis"] = json!(basis);
    drawn.case["analysis"]["load_steps"] = json!(load_steps);
    let volumetric = Rng::new(seed ^ (index as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0x5EED)
        .pick(&VOLUMETRIC);
    drawn.case["analysis"]["volumetric"] = json!(volumetric);
    if let Some(bodies) = drawn.case["bodies"].as_array_mut() {
        for body in bodies {
            body["points"] = json!({ "per_cell": per_cell });
        }
    }
    let mut reducing = Rng::new(seed ^ (index as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F) ^ 0x5AFE);
    let plastic = matches!(drawn.model, "von_mises" | "drucker_prager" | "mohr_coulomb");
    let reduction = if plastic && reducing.chance(1.0 / 3.0) {
        let increment = reducing.pick(&[0.05, 0.1, 0.2]);
        let flow_limit = reducing.pick(&[0.0, 10.0]);
        then_reduced(&mut drawn.case, increment, flow_limit);
        if flow_limit > 0.0 {
            "reduced, flow limit"
        } else {
            "reduced"
        }
    } else {
        "none"
    };
    Drawn {
        seed,
        index,
        scene,
        basis,
        per_cell,
        load_steps,
        volumetric,
        reduction,
        ..drawn
    }
}

/// Makes `case` two stages: its loads, supports and load steps, then a
/// strength reduction of up to 20 trials rising by `increment` (the
/// bisection's tolerance an eighth of it) with the flow limit `flow_limit`.
fn then_reduced(case: &mut Value, increment: f64, flow_limit: f64) {
    let object = case.as_object_mut().expect("a case is an object");
    let loads = object.remove("loads").unwrap_or_else(|| json!({}));
    let supports = object.remove("supports").unwrap_or_else(|| json!([]));
    let load_steps = (case["analysis"].as_object_mut())
        .and_then(|a| a.remove("load_steps"))
        .unwrap_or_else(|| json!(1));
    case["stages"] = json!([
        { "name": "load", "load_steps": load_steps, "loads": loads, "supports": supports },
        { "name": "safety", "load_steps": 20,
          "strength_reduction": { "increment": increment, "tolerance": increment / 8.0, "flow_limit": flow_limit } }
    ]);
}

/// The scene's part of a draw: the case without its basis, points and
/// steps, and its classes.
fn scene_draw(
    scene: Scene,
    material: &MaterialDraw,
    load: &'static str,
    support: &'static str,
    magnitude: &'static str,
    case: Value,
) -> Drawn {
    Drawn {
        seed: 0,
        index: 0,
        scene,
        basis: "",
        model: material.model,
        load,
        support,
        per_cell: 0,
        load_steps: 0,
        magnitude,
        volumetric: "standard",
        reduction: "none",
        case,
    }
}

/// An elastic material: Hencky, or small-strain linear when `linear_ok`.
fn elastic(rng: &mut Rng, linear_ok: bool) -> MaterialDraw {
    let youngs_modulus = rng.log_range(1e6, 1e9);
    let nu = if rng.chance(0.25) {
        rng.pick(&[0.0, 0.45, 0.49])
    } else {
        rng.range(0.0, 0.49)
    };
    let model = if linear_ok && rng.chance(0.3) {
        "linear_elastic"
    } else {
        "hencky"
    };
    MaterialDraw {
        spec: json!({ "model": model, "youngs_modulus": youngs_modulus,
                      "poisson_ratio": nu, "density": rng.range(1000.0, 3000.0) }),
        model,
        youngs_modulus,
        strength: f64::INFINITY,
        shear_strength: None,
    }
}

/// A plastic material: von Mises, Drucker-Prager or Mohr-Coulomb.
fn plastic(rng: &mut Rng) -> MaterialDraw {
    let youngs_modulus = rng.log_range(1e6, 1e9);
    let nu = rng.range(0.2, 0.49);
    let density = rng.range(1500.0, 2500.0);
    let model = rng.pick(&["von_mises", "drucker_prager", "mohr_coulomb"]);
    if model == "von_mises" {
        let yield_stress = youngs_modulus * rng.log_range(1e-3, 1e-2);
        let hardening = if rng.chance(0.5) {
            0.0
        } else {
            youngs_modulus * rng.log_range(1e-3, 1e-1)
        };
        let k = yield_stress / 3f64.sqrt();
        return MaterialDraw {
            spec: json!({ "model": model, "youngs_modulus": youngs_modulus, "poisson_ratio": nu,
                          "density": density, "yield_stress": yield_stress, "hardening": hardening }),
            model,
            youngs_modulus,
            strength: 2.0 * k,
            shear_strength: Some(k),
        };
    }
    let cohesion = youngs_modulus * rng.log_range(1e-4, 1e-2);
    let phi: f64 = rng.pick(&[0.0, 10.0, 20.0, 30.0, 40.0]);
    let psi = rng.pick(&[0.0, 0.5, 1.0]) * phi;
    let (s, c) = phi.to_radians().sin_cos();
    MaterialDraw {
        spec: json!({ "model": model, "youngs_modulus": youngs_modulus, "poisson_ratio": nu,
                      "density": density, "cohesion": cohesion, "friction_angle": phi,
                      "dilation_angle": psi }),
        model,
        youngs_modulus,
        // Unconfined: sigma_1 = 2 c cos(phi) / (1 - sin(phi)).
        strength: 2.0 * cohesion * c / (1.0 - s),
        shear_strength: None,
    }
}

/// The grid: `h`, its origin at a random place in a cell, or with `y` (or
/// `x`) on a grid line when a grid support holds the line there.
fn grid(rng: &mut Rng, h: f64, x_line: Option<f64>, y_line: Option<f64>) -> Value {
    let origin = [
        x_line.unwrap_or_else(|| -rng.uniform() * h),
        y_line.unwrap_or_else(|| -rng.uniform() * h),
    ];
    json!({ "cell_size": h, "origin": origin })
}

fn rotate(p: [f64; 2], about: [f64; 2], angle: f64) -> [f64; 2] {
    let (s, c) = angle.to_radians().sin_cos();
    let (dx, dy) = (p[0] - about[0], p[1] - about[1]);
    [about[0] + c * dx - s * dy, about[1] + s * dx + c * dy]
}

fn cantilever(rng: &mut Rng, grid_ok: bool) -> Drawn {
    let depth = rng.range(0.2, 1.0);
    let length = depth * rng.range(4.0, 10.0);
    let material = elastic(rng, false);
    let h = depth / rng.range(2.0, 6.0);
    let turned = rng.chance(0.4);
    let angle = if turned { rng.range(-30.0, 30.0) } else { 0.0 };
    let by_grid = grid_ok && !turned && rng.chance(0.5);
    // EI per unit width; P L^2 / EI from small strain to large rotation.
    let nu = material.spec["poisson_ratio"].as_f64().unwrap_or(0.0);
    let ei = material.youngs_modulus / (1.0 - nu * nu) * depth.powi(3) / 12.0;
    let large = rng.chance(0.5);
    let k = if large {
        rng.range(1.0, 6.0)
    } else {
        rng.log_range(0.01, 1.0)
    };
    let force = k * ei / (length * length);
    let about = [0.0, 0.0];
    let corner = |x: f64, y: f64| rotate([x, y], about, angle);
    let root = [corner(0.0, 0.0), corner(0.0, depth)];
    let tip = [corner(length, 0.0), corner(length, depth)];
    let top = [corner(0.0, depth), corner(length, depth)];
    let support = if by_grid {
        json!({ "on": { "x": 0.0 }, "fix": "xy" })
    } else {
        json!({ "on": { "segment": root }, "fix": "xy", "method": "ibm" })
    };
    let follower = rng.chance(0.4);
    let (load, loads) = if follower {
        // The same moment at the root from a pressure over the length:
        // q L^2 / 2 = P L.
        let pressure = 2.0 * force / length;
        (
            "pressure",
            json!({ "boundary": [ { "on": { "segment": top }, "pressure": pressure } ] }),
        )
    } else {
        let t = force / depth;
        let (s, c) = angle.to_radians().sin_cos();
        (
            "traction",
            json!({ "boundary": [ { "on": { "segment": tip }, "traction": [s * t, -c * t] } ] }),
        )
    };
    let case = json!({
        "analysis": {},
        "grid": grid(rng, h, by_grid.then_some(0.0), None),
        "bodies": [ {
            "name": "beam",
            "geometry": { "rectangle": { "min": [0.0, 0.0], "max": [length, depth],
                                         "angle": angle, "about": about } },
            "material": material.spec,
        } ],
        "loads": loads,
        "supports": [support],
    });
    scene_draw(
        Scene::Cantilever,
        &material,
        load,
        if by_grid { "grid" } else { "ibm" },
        if large { "large" } else { "small" },
        case,
    )
}

fn block(rng: &mut Rng, grid_ok: bool) -> Drawn {
    let width = rng.range(0.5, 4.0);
    let height = width * rng.range(0.3, 2.0);
    let material = if rng.chance(0.5) {
        plastic(rng)
    } else {
        elastic(rng, true)
    };
    let small = material.model == "linear_elastic" || rng.chance(0.5);
    let h = width.min(height) / rng.range(2.0, 8.0);
    let shape = rng.pick(&["rectangle", "quadrilateral", "polygon"]);
    // The top edge, from its left end to its right.
    let (geometry, top) = match shape {
        "rectangle" => (
            json!({ "rectangle": { "min": [0.0, 0.0], "max": [width, height] } }),
            [[0.0, height], [width, height]],
        ),
        "quadrilateral" => {
            let (left, right) = (rng.range(0.0, 0.3) * width, rng.range(0.0, 0.3) * width);
            let rise = rng.range(-0.2, 0.2) * height;
            let top = [[left, height], [width - right, height + rise]];
            (
                json!({ "quadrilateral": { "vertices": [[0.0, 0.0], [width, 0.0], top[1], top[0]] } }),
                top,
            )
        }
        _ => {
            // A block with a notch cut from one side, half its height.
            let notch = [rng.range(0.2, 0.4) * width, rng.range(0.3, 0.6) * height];
            (
                json!({ "polygon": { "vertices": [
                    [0.0, 0.0], [width, 0.0], [width, notch[1]], [width - notch[0], notch[1]],
                    [width - notch[0], height], [0.0, height]] } }),
                [[0.0, height], [width - notch[0], height]],
            )
        }
    };
    let by_grid = grid_ok && rng.chance(0.5);
    let support = if by_grid {
        json!({ "on": { "y": 0.0 }, "fix": "xy" })
    } else {
        json!({ "on": { "y": 0.0 }, "fix": "xy", "method": "ibm" })
    };
    let e = material.youngs_modulus;
    // The stress the loads are drawn against: a fraction of the strength,
    // or a strain of the stiffness.
    let scale = if small {
        e * rng.log_range(1e-5, 1e-3)
    } else {
        (e * rng.range(0.01, 0.1)).min(0.6 * material.strength)
    }
    .min(0.6 * material.strength);
    let load = rng.pick(&["gravity", "pressure", "traction", "pushed"]);
    let mut supports = vec![support];
    let mut case = json!({
        "analysis": {},
        "grid": grid(rng, h, None, by_grid.then_some(0.0)),
        "bodies": [ { "name": "block", "geometry": geometry, "material": material.spec } ],
    });
    let density = case["bodies"][0]["material"]["density"]
        .as_f64()
        .unwrap_or(2000.0);
    match load {
        "gravity" => {
            // rho g H at the base = the drawn stress.
            let g = scale / (density * height);
            case["loads"] = json!({ "gravity": [0.0, -g] });
        }
        "pressure" => {
            case["loads"] =
                json!({ "boundary": [ { "on": { "segment": top }, "pressure": scale } ] });
        }
        "traction" => {
            let shear = rng.range(-0.2, 0.2) * scale;
            case["loads"] = json!({ "boundary": [ { "on": { "segment": top }, "traction": [shear, -scale] } ] });
        }
        _ => {
            // Pushed down (and held sideways or not) by the IBM; plastic
            // bodies any amount to 5% of their height.
            let strain = if material.strength.is_finite() {
                rng.range(0.001, 0.05)
            } else {
                scale / e
            };
            let fix = rng.pick(&["xy", "y"]);
            supports.push(
                json!({ "on": { "segment": top }, "fix": fix, "method": "ibm",
                                  "displacement": [0.0, -strain * height] }),
            );
        }
    }
    case["supports"] = json!(supports);
    scene_draw(
        Scene::Block,
        &material,
        load,
        if by_grid { "grid" } else { "ibm" },
        if small { "small" } else { "large" },
        case,
    )
}

fn wedge(rng: &mut Rng) -> Drawn {
    let width = rng.range(0.5, 3.0);
    let height = width * rng.range(0.5, 1.5);
    let angle = rng.range(5.0, 40.0);
    let material = elastic(rng, true);
    let small = material.model == "linear_elastic" || rng.chance(0.5);
    let h = width.min(height) / rng.range(2.0, 6.0);
    let about = [0.0, 0.0];
    let corner = |x: f64, y: f64| rotate([x, y], about, angle);
    let base = [corner(0.0, 0.0), corner(width, 0.0)];
    let side = [corner(0.0, 0.0), corner(0.0, height)];
    let top = [corner(0.0, height), corner(width, height)];
    let e = material.youngs_modulus;
    let scale = e * if small {
        rng.log_range(1e-5, 1e-3)
    } else {
        rng.range(0.01, 0.05)
    };
    let density = material.spec["density"].as_f64().unwrap_or(2000.0);
    let g = 0.5 * scale / (density * height);
    let case = json!({
        "analysis": {},
        "grid": grid(rng, h, None, None),
        "bodies": [ { "name": "wedge",
            "geometry": { "rectangle": { "min": [0.0, 0.0], "max": [width, height],
                                         "angle": angle, "about": about } },
            "material": material.spec } ],
        "loads": { "gravity": [0.0, -g],
                   "boundary": [ { "on": { "segment": top }, "pressure": 0.5 * scale } ] },
        "supports": [
            { "on": { "segment": base }, "fix": "normal", "method": "ibm" },
            { "on": { "segment": side }, "fix": "normal", "method": "ibm" }
        ],
    });
    scene_draw(
        Scene::Wedge,
        &material,
        "gravity and pressure",
        "ibm",
        if small { "small" } else { "large" },
        case,
    )
}

fn ring(rng: &mut Rng) -> Drawn {
    let inner = rng.range(0.5, 1.0);
    let outer = inner * rng.range(1.5, 3.0);
    let material = if rng.chance(0.5) {
        let mut m = plastic(rng);
        // Von Mises only: Hill's limit is the reference the load is
        // drawn below.
        while m.model != "von_mises" {
            m = plastic(rng);
        }
        m
    } else {
        elastic(rng, true)
    };
    let small = material.model == "linear_elastic" || rng.chance(0.5);
    let h = (outer - inner) / rng.range(2.0, 6.0);
    let pressure = match material.shear_strength {
        Some(k) => rng.range(0.1, 0.8) * 2.0 * k * (outer / inner).ln(),
        None => {
            material.youngs_modulus
                * if small {
                    rng.log_range(1e-5, 1e-3)
                } else {
                    rng.range(0.01, 0.05)
                }
        }
    };
    let center = [0.0, 0.0];
    let quarter = rng.chance(0.6);
    let (geometry, supports) = if quarter {
        (
            json!({ "annulus_sector": { "center": center, "inner_radius": inner,
                    "outer_radius": outer, "start_angle": 0.0, "end_angle": 90.0 } }),
            json!([
                { "on": { "segment": [[inner, 0.0], [outer, 0.0]] }, "fix": "normal", "method": "ibm" },
                { "on": { "segment": [[0.0, inner], [0.0, outer]] }, "fix": "normal", "method": "ibm" }
            ]),
        )
    } else {
        (
            json!({ "annulus": { "center": center, "inner_radius": inner, "outer_radius": outer } }),
            json!([ { "on": { "center": center, "radius": outer }, "fix": "xy", "method": "ibm" } ]),
        )
    };
    let case = json!({
        "analysis": {},
        "grid": grid(rng, h, None, None),
        "bodies": [ { "name": "ring", "geometry": geometry, "material": material.spec } ],
        "loads": { "boundary": [ { "on": { "center": center, "radius": inner }, "pressure": pressure } ] },
        "supports": supports,
    });
    scene_draw(
        Scene::Ring,
        &material,
        "pressure",
        "ibm",
        if small { "small" } else { "large" },
        case,
    )
}

fn layers(rng: &mut Rng, grid_ok: bool) -> Drawn {
    let width = rng.range(1.0, 4.0);
    let (lower, upper) = (rng.range(0.2, 0.6) * width, rng.range(0.1, 0.4) * width);
    let below = if rng.chance(0.5) {
        plastic(rng)
    } else {
        elastic(rng, false)
    };
    let above = elastic(rng, false);
    let h = lower.min(upper) / rng.range(1.5, 4.0);
    // The top body spans the middle half, or all of the width.
    let (left, right) = if rng.chance(0.5) {
        (0.25 * width, 0.75 * width)
    } else {
        (0.0, width)
    };
    let soft = below.youngs_modulus.min(above.youngs_modulus);
    let small = rng.chance(0.5);
    let scale = if small {
        soft * rng.log_range(1e-5, 1e-3)
    } else {
        soft * rng.range(0.01, 0.05)
    }
    .min(0.3 * below.strength);
    let by_grid = grid_ok && rng.chance(0.5);
    let mut support = json!({ "on": { "y": 0.0 }, "fix": "xy" });
    if !by_grid {
        support["method"] = json!("ibm");
    }
    let top = lower + upper;
    // Earth's gravity, unless the lower body could not stand under the
    // weight of both: the stress at its base below a third of its strength
    // (a cohesive soil's free face stands to about twice its unconfined
    // strength over its unit weight).
    let density = [&below, &above]
        .map(|m| m.spec["density"].as_f64().unwrap_or(2000.0))
        .into_iter()
        .fold(0.0, f64::max);
    let g = 9.81f64.min(0.3 * below.strength / (density * top));
    let case = json!({
        "analysis": {},
        "grid": grid(rng, h, None, by_grid.then_some(0.0)),
        "bodies": [
            { "name": "lower", "geometry": { "rectangle": { "min": [0.0, 0.0], "max": [width, lower] } },
              "material": below.spec },
            { "name": "upper", "geometry": { "rectangle": { "min": [left, lower], "max": [right, top] } },
              "material": above.spec }
        ],
        "loads": { "gravity": [0.0, -g],
                   "boundary": [ { "on": { "y": top }, "pressure": scale } ] },
        "supports": [support],
    });
    scene_draw(
        Scene::Layers,
        &below,
        "gravity and pressure",
        if by_grid { "grid" } else { "ibm" },
        if small { "small" } else { "large" },
        case,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_case_is_the_same_at_every_draw_and_differs_from_its_neighbours() {
        let a = draw(7, 12);
        assert_eq!(a.case, draw(7, 12).case);
        assert_ne!(a.case, draw(7, 13).case);
        assert_ne!(a.case, draw(8, 12).case);
    }

    #[test]
    fn every_drawn_case_is_valid() {
        for index in 0..400 {
            let d = draw(1, index);
            if let Err(e) = mpm::Case::from_json(&d.case.to_string()) {
                panic!("{}: {e}\n{}", d.label(), d.case);
            }
        }
    }

    #[test]
    fn the_draws_cover_every_scene_basis_and_model() {
        let drawn: Vec<Drawn> = (0..400).map(|i| draw(1, i)).collect();
        for scene in Scene::ALL {
            assert!(drawn.iter().any(|d| d.scene == scene), "{scene:?}");
        }
        for basis in BASES {
            assert!(drawn.iter().any(|d| d.basis == basis), "{basis}");
        }
        for model in [
            "hencky",
            "linear_elastic",
            "von_mises",
            "drucker_prager",
            "mohr_coulomb",
        ] {
            assert!(drawn.iter().any(|d| d.model == model), "{model}");
        }
        assert!(drawn.iter().any(|d| d.load_steps == 1));
        assert!(drawn.iter().any(|d| d.load_steps >= 40));
        assert!(drawn.iter().all(|d| (1..=50).contains(&d.load_steps)));
        for reduction in ["none", "reduced", "reduced, flow limit"] {
            assert!(
                drawn.iter().any(|d| d.reduction == reduction),
                "{reduction}"
            );
        }
    }
}
