//! The `mpm` binary as a user runs it.

use std::path::PathBuf;
use std::process::Command;

fn mpm() -> Command {
    Command::new(env!("CARGO_BIN_EXE_mpm"))
}

/// A directory of its own for a test, removed when it drops (the tests
/// left theirs in /tmp).
struct Scratch(PathBuf);

impl std::ops::Deref for Scratch {
    type Target = std::path::Path;
    fn deref(&self) -> &std::path::Path {
        &self.0
    }
}

impl AsRef<std::ffi::OsStr> for Scratch {
    fn as_ref(&self) -> &std::ffi::OsStr {
        self.0.as_os_str()
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn temp_dir(name: &str) -> Scratch {
    let dir = std::env::temp_dir().join(format!("mpm-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    Scratch(dir)
}

/// Runs `mpm ARGS OUT` and requires success.
fn run_ok(args: &[&str], out: &std::path::Path) {
    let status = mpm().args(args).arg(out).output().unwrap();
    assert!(
        status.status.success(),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
}

#[test]
fn run_writes_summary_step_files_and_a_series() {
    let out = temp_dir("run");
    run_ok(&["run", "--example", "cantilever-grid", "--out"], &out);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let steps = summary["steps"].as_array().unwrap();
    assert_eq!(steps.len(), 5);
    // The tip goes down under self-weight, and by about the 2.7 m that a
    // 1500 N/m load gives this beam (see the cantilever example's title).
    let tip = steps[4]["probes"]["tip"]["displacement"][1]
        .as_f64()
        .unwrap();
    assert!(tip < -2.0 && tip > -3.5, "{tip}");
    // Each step's pieces, cut tries and their iterations, and the run's
    // totals of them.
    for key in [
        "substeps",
        "cutbacks",
        "failed_iterations",
        "newton_iterations",
    ] {
        let sum: u64 = steps.iter().map(|s| s[key].as_u64().unwrap()).sum();
        assert_eq!(summary[key].as_u64(), Some(sum), "{key}");
    }
    assert!(steps.iter().all(|s| s["substeps"].as_u64() >= Some(1)));
    // The bilinear basis, bent: points leave their cells, and the summary
    // says what that does to its answers.
    assert!(steps[4]["points_in_new_cells"].as_u64() > Some(0));
    assert_eq!(summary["warnings"][0]["kind"], "bilinear_crossing");
    for k in 1..=5 {
        let step: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(out.join(format!("steps/step_{k:04}.json"))).unwrap(),
        )
        .unwrap();
        assert_eq!(
            step["points"]["position"].as_array().unwrap().len(),
            summary["points"].as_u64().unwrap() as usize
        );
        assert!(out.join(format!("steps/step_{k:04}.vtu")).exists());
        assert!(out.join(format!("steps/step_{k:04}_boundary.vtp")).exists());
        assert_eq!(step["boundaries"].as_array().unwrap().len(), 1);
    }
    // Step 0, the undeformed state, starts the series.
    assert!(out.join("steps/step_0000.vtu").exists());
    let pvd = std::fs::read_to_string(out.join("points.pvd")).unwrap();
    assert_eq!(pvd.matches("<DataSet").count(), 6);
    let pvd = std::fs::read_to_string(out.join("boundary.pvd")).unwrap();
    assert_eq!(pvd.matches("<DataSet").count(), 6);
}

/// Writes `case` to a fresh directory and runs it there.
fn run_case(name: &str, case: &serde_json::Value) -> std::process::Output {
    let dir = temp_dir(name);
    let path = dir.join("case.json");
    std::fs::write(&path, case.to_string()).unwrap();
    mpm()
        .arg("run")
        .arg(&path)
        .arg("--out")
        .arg(dir.join("out"))
        .output()
        .unwrap()
}

fn example(name: &str) -> serde_json::Value {
    serde_json::from_slice(&mpm().args(["example", name]).output().unwrap().stdout).unwrap()
}

#[test]
fn invalid_case_exits_2_and_names_the_field() {
    let mut case = example("column");
    case["bodies"][0]["material"]["poisson_ratio"] = 0.5.into();
    let out = run_case("invalid", &case);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bodies[0].material.poisson_ratio"), "{err}");
}

#[test]
fn failed_solve_exits_1_and_says_where() {
    let mut case = example("cantilever-grid");
    // The whole self-weight of a very soft beam in one step: Newton cannot
    // follow it in two iterations.
    case["analysis"]["load_steps"] = 1.into();
    case["analysis"]["newton"] = serde_json::json!({"max_iterations": 2});
    let out = run_case("diverge", &case);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("load step 1") && err.contains("residual"),
        "{err}"
    );
}

/// `mpm study cantilever --quick`: every sweep row is in the CSV with a
/// number or a failure reason, the markdown has both support methods and
/// the band width table, and the three plots are SVG.
#[test]
fn quick_study_writes_tables_and_plots() {
    let out = temp_dir("study");
    run_ok(&["study", "cantilever", "--quick", "--out"], &out);
    let csv = std::fs::read_to_string(out.join("cantilever.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    // Two methods x (h = 1.5: 3 point counts; h = 0.75: 3) + 5 band widths.
    assert_eq!(rows.len(), 2 * 6 + 5, "{csv}");
    for row in &rows {
        let fields: Vec<&str> = row.split(',').collect();
        let converged = fields[6].parse::<f64>().is_ok_and(|v| v < 0.0);
        let failed = !fields.last().unwrap().is_empty();
        assert!(converged != failed, "{row}");
    }
    // The paper's case itself (IBM, 1.5 m cells, 896 points) converges.
    assert!(
        rows.iter()
            .any(|r| r.starts_with("sweep,ibm,1.5,896,,") && r.ends_with(',')),
        "{csv}"
    );
    let md = std::fs::read_to_string(out.join("cantilever.md")).unwrap();
    for heading in [
        "## Supports: ibm",
        "## Supports: grid",
        "## Band width (IBM)",
    ] {
        assert!(md.contains(heading), "{md}");
    }
    for plot in ["tip", "relative", "error"] {
        let svg = std::fs::read_to_string(out.join(format!("cantilever-{plot}.svg"))).unwrap();
        assert!(
            svg.starts_with("<svg") && svg.contains("<polyline"),
            "{plot}"
        );
    }
    let bad = mpm()
        .args(["study", "cantilever", "--basis", "quadratic", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(bad.status.code(), Some(2));
}

/// An empty token once turned authentication off without a word; the
/// service now refuses to start with one (exit 2, naming the setting).
#[test]
fn serve_refuses_an_empty_token() {
    let dir = temp_dir("empty-token");
    let mut child = mpm()
        .args(["serve", "--addr", "127.0.0.1:0", "--token", ""])
        .arg("--database")
        .arg(dir.join("jobs.sqlite"))
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(20);
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if std::time::Instant::now() > deadline {
            child.kill().unwrap();
            panic!("mpm serve started with an empty token");
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    };
    let mut stderr = String::new();
    std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut stderr).unwrap();
    assert_eq!(status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("MPM_TOKEN"), "{stderr}");
}

/// A non-empty output directory is refused; `--force` removes the files of
/// the earlier run (a 600-file leftover once stayed beside a 5-step series)
/// and nothing else. Step 0 is written, and `output.every` thins the point
/// files while the summary keeps every step.
#[test]
fn force_replaces_an_earlier_run_and_output_every_thins_the_files() {
    let out = temp_dir("force");
    std::fs::create_dir_all(out.join("steps")).unwrap();
    std::fs::write(out.join("steps/step_0099.vtu"), "stale").unwrap();
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    let refused = mpm()
        .args(["run", "--example", "cantilever-grid", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(refused.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&refused.stderr).contains("--force"));

    let mut case = example("cantilever-grid");
    case["output"] = serde_json::json!({"every": 2});
    let path = out.join("notes-case.json");
    std::fs::write(&path, case.to_string()).unwrap();
    let status = mpm()
        .arg("run")
        .arg(&path)
        .arg("--force")
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        status.status.success(),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
    assert!(!out.join("steps/step_0099.vtu").exists(), "stale file kept");
    assert!(
        out.join("notes.txt").exists(),
        "a file the run does not own was removed"
    );
    let written: Vec<usize> = (0..=5)
        .filter(|k| out.join(format!("steps/step_{k:04}.vtu")).exists())
        .collect();
    assert_eq!(written, [0, 2, 4, 5]);
    let pvd = std::fs::read_to_string(out.join("points.pvd")).unwrap();
    assert_eq!(pvd.matches("<DataSet").count(), 4);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["steps"].as_array().unwrap().len(), 5);
}

/// `case` run straight, and run again, killed once its step 4 is written
/// and resumed with `mpm run --resume`: the scratch folder and its two
/// output directories.
fn killed_at_step_4_and_resumed(
    case: &serde_json::Value,
    name: &str,
) -> (Scratch, std::path::PathBuf, std::path::PathBuf) {
    let dir = temp_dir(name);
    let path = dir.join("case.json");
    std::fs::write(&path, case.to_string()).unwrap();
    let straight = dir.join("straight");
    run_ok(&["run", path.to_str().unwrap(), "--out"], &straight);

    let stopped = dir.join("stopped");
    let mut child = mpm()
        .arg("run")
        .arg(&path)
        .arg("--out")
        .arg(&stopped)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let start = std::time::Instant::now();
    while !stopped.join("steps/step_0004.json").exists() {
        assert!(start.elapsed().as_secs() < 120, "no step 4");
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(
        !stopped.join("summary.json").exists(),
        "killed after it finished"
    );
    let resumed = mpm()
        .arg("run")
        .arg("--resume")
        .arg(&stopped)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&resumed.stderr);
    assert!(resumed.status.success(), "{stderr}");
    assert!(stderr.contains("resuming after step"), "{stderr}");
    (dir, straight, stopped)
}

/// A run killed mid-way goes on from its last checkpoint with `--resume`
/// and ends where an uninterrupted run ends, with every step's report.
#[test]
fn resume_goes_on_from_the_last_checkpoint() {
    // The self-weight column widened to 8000 points over 30 steps: tens of
    // milliseconds a step, time to kill it part-way.
    let mut case = example("column");
    case["grid"]["cell_size"] = 0.5.into();
    case["grid"]["extent"] = serde_json::json!({"min": [0.0, 0.0], "max": [10.0, 50.0]});
    case["bodies"][0]["geometry"]["rectangle"]["max"] = serde_json::json!([10.0, 50.0]);
    case["supports"][1]["on"]["x"] = 10.0.into();
    case["analysis"]["load_steps"] = 30.into();
    let (_dir, straight, stopped) = killed_at_step_4_and_resumed(&case, "resume");
    let read = |dir: &std::path::Path, file: &str| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(dir.join(file)).unwrap()).unwrap()
    };
    let summary = read(&stopped, "summary.json");
    assert_eq!(summary["steps"].as_array().unwrap().len(), 30);
    // Step 4's files were written; its checkpoint, written after them, may
    // not have been.
    assert!(
        summary["resumed_from"].as_u64().unwrap() >= 3,
        "{}",
        summary["resumed_from"]
    );
    let a = read(&stopped, "steps/step_0030.json");
    let b = read(&straight, "steps/step_0030.json");
    assert_eq!(a["points"]["position"], b["points"]["position"]);
    assert_eq!(a["report"]["probes"], b["report"]["probes"]);
    let pvd = std::fs::read_to_string(stopped.join("points.pvd")).unwrap();
    assert_eq!(pvd.matches("<DataSet").count(), 31, "steps 0 to 30");
    assert!(!stopped.join("checkpoint.bin").exists());
}

/// `--summary-only` writes the summary and no step folder (it once left an
/// empty `steps/`).
#[test]
fn summary_only_writes_no_step_folder() {
    let out = temp_dir("summary-only");
    run_ok(
        &[
            "run",
            "--example",
            "cantilever-grid",
            "--summary-only",
            "--out",
        ],
        &out,
    );
    assert!(out.join("summary.json").exists());
    assert!(!out.join("steps").exists());
}

/// The case-format example in the user guide is a case that runs, with its
/// point load and probe inside its body (the load once sat outside it).
#[test]
fn the_guides_case_example_runs_and_its_points_lie_in_its_body() {
    let guide = include_str!("../docs/guide.md");
    let section = guide
        .split("## Case format (JSON, version 1)")
        .nth(1)
        .expect("the guide has a case-format section");
    let text = section
        .split("```json\n")
        .nth(1)
        .and_then(|s| s.split("```").next())
        .expect("the section opens with a JSON example");
    let case: serde_json::Value = serde_json::from_str(text).expect("the example is JSON");
    let rectangle = &case["bodies"][0]["geometry"]["rectangle"];
    let inside = |p: &serde_json::Value| {
        (0..2).all(|k| {
            let v = p[k].as_f64().unwrap();
            rectangle["min"][k].as_f64().unwrap() <= v && v <= rectangle["max"][k].as_f64().unwrap()
        })
    };
    for load in case["loads"]["point_loads"].as_array().unwrap() {
        assert!(
            inside(&load["at"]),
            "point load at {} outside the body",
            load["at"]
        );
    }
    for probe in case["probes"].as_array().unwrap() {
        assert!(
            inside(&probe["at"]),
            "probe at {} outside the body",
            probe["at"]
        );
    }
    let output = run_case("readme-example", &case);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
}

/// Runs the built-in `cantilever-grid` case, edited, from `dir/case.json`
/// into `dir/out`: its exit code and standard error.
fn run_edited_example(
    dir: &std::path::Path,
    edit: impl Fn(&mut serde_json::Value),
) -> (Option<i32>, String) {
    let mut case: serde_json::Value =
        serde_json::from_str(mpm::case::builtin::get("cantilever-grid").unwrap()).unwrap();
    edit(&mut case);
    let path = dir.join("case.json");
    std::fs::write(&path, case.to_string()).unwrap();
    let run = mpm()
        .args(["run"])
        .arg(&path)
        .arg("--out")
        .arg(dir.join("out"))
        .output()
        .unwrap();
    (
        run.status.code(),
        String::from_utf8_lossy(&run.stderr).into_owned(),
    )
}

/// A cell size typed in mm for m asked for billions of points, and the
/// run allocated 8 GB before it aborted: it is refused (exit 2) with the
/// count before any point is made, and `--max-points` raises the limit.
#[test]
fn a_case_over_the_point_limit_is_refused_before_seeding() {
    let dir = temp_dir("point-limit");
    let (code, stderr) = run_edited_example(&dir, |case| case["grid"]["cell_size"] = 0.001.into());
    assert_eq!(code, Some(2), "{stderr}");
    assert!(stderr.contains("80000000 material points"), "{stderr}");
    assert!(stderr.contains("--max-points"), "{stderr}");

    // The built-in example's 320 points, against a limit of 100 and 1000.
    let small = mpm()
        .args([
            "run",
            "--example",
            "cantilever-grid",
            "--summary-only",
            "--max-points",
            "100",
            "--out",
        ])
        .arg(dir.join("small"))
        .output()
        .unwrap();
    assert_eq!(
        small.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&small.stderr)
    );
    run_ok(
        &[
            "run",
            "--example",
            "cantilever-grid",
            "--summary-only",
            "--max-points",
            "1000",
            "--out",
        ],
        &dir.join("small"),
    );
}

/// A Young's modulus of 1 meant as 1 MPa fails the first step with an
/// inverted point: the message hints at units, and offers no --resume,
/// as no checkpoint was written.
#[test]
fn a_first_step_failing_under_loads_far_beyond_the_stiffness_hints_at_units() {
    let dir = temp_dir("units");
    let (code, stderr) = run_edited_example(&dir, |case| {
        case["bodies"][0]["material"]["youngs_modulus"] = 1.0.into()
    });
    assert_eq!(code, Some(1), "{stderr}");
    assert!(stderr.contains("load step 1"), "{stderr}");
    assert!(stderr.contains("are the units SI"), "{stderr}");
    assert!(!stderr.contains("--resume"), "{stderr}");
}

/// A staged run through the command line: each step of summary.json names
/// its stage, the series runs by step (a stage's load factor starts again
/// at each stage), and the peaks name the largest reaction of each stage's
/// supports and the step it came at: for the pushed top, its last.
#[test]
fn a_staged_run_names_its_stages_and_its_peaks() {
    let top = |d: f64| serde_json::json!({ "on": { "y": 1.0 }, "fix": "y", "method": "ibm", "displacement": [0.0, d] });
    let rollers = [
        serde_json::json!({ "on": { "x": 0.0 }, "fix": "normal", "method": "ibm" }),
        serde_json::json!({ "on": { "y": 0.0 }, "fix": "normal", "method": "ibm" }),
    ];
    let case = serde_json::json!({
        "version": 1,
        "analysis": {},
        "grid": { "cell_size": 0.25, "origin": [0.1, 0.07] },
        "basis": "gimp",
        "bodies": [{
            "geometry": { "rectangle": { "min": [0.0, 0.0], "max": [1.0, 1.0] } },
            "points": { "per_cell": 2 },
            "material": { "model": "hencky", "youngs_modulus": 1e6, "poisson_ratio": 0.3, "density": 0.0 }
        }],
        "stages": [
            { "name": "confine", "load_steps": 2, "supports": [rollers[0], rollers[1], top(0.0)],
              "loads": { "boundary": [{ "on": { "x": 1.0 }, "pressure": 2.0e4 }] } },
            { "name": "push", "load_steps": 3, "supports": [rollers[0], rollers[1], top(-0.02)] }
        ]
    });
    let dir = temp_dir("staged");
    let path = dir.join("case.json");
    std::fs::write(&path, case.to_string()).unwrap();
    let out = dir.join("out");
    run_ok(&["run", path.to_str().unwrap(), "--out"], &out);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let steps = summary["steps"].as_array().unwrap();
    let stages: Vec<&str> = steps.iter().map(|s| s["stage"].as_str().unwrap()).collect();
    assert_eq!(stages, ["confine", "confine", "push", "push", "push"]);
    assert_eq!(summary["load_steps"], 5);
    let pvd = std::fs::read_to_string(out.join("points.pvd")).unwrap();
    for k in 0..=5 {
        assert!(pvd.contains(&format!("timestep=\"{k}\"")), "{pvd}");
    }
    let top_force = |s: &serde_json::Value| s["reactions"][2][1].as_f64().unwrap().abs();
    let peak = summary["peaks"]["reactions"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["stage"] == "push" && p["support"] == 2)
        .expect("a peak for the pushed top");
    assert_eq!(peak["step"], 5);
    let largest = steps[2..].iter().map(top_force).fold(0.0, f64::max);
    assert_eq!(peak["value"][1].as_f64().unwrap().abs(), largest);
    assert!(largest > top_force(&steps[1]));
}

/// The built-in 3D column runs from the command line: a step a line, every
/// step's document (JSON) and points (VTU, in a series), and a summary
/// whose base reaction carries the column's weight, rho0 g L h^2 = 390625
/// N, in z.
#[test]
fn a_3d_case_runs_and_its_base_carries_the_weight() {
    let out = temp_dir("run3d");
    run_ok(&["run", "--example", "column3d", "--out"], &out);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let steps = summary["steps"].as_array().unwrap();
    assert_eq!(steps.len(), 40);
    let base = steps[39]["reactions"][4].as_array().unwrap();
    assert_eq!(base.len(), 3);
    let weight = 80.0 * 10.0 * 50.0 * 3.125 * 3.125;
    assert!(
        (base[2].as_f64().unwrap() - weight).abs() < 1e-6 * weight,
        "{base:?}"
    );
    // Per step its document, its points (VTU) and its surfaces (VTP).
    let files = std::fs::read_dir(out.join("steps")).unwrap().count();
    assert_eq!(files, 3 * 41);
    let last: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("steps/step_0040.json")).unwrap())
            .unwrap();
    assert_eq!(last["report"]["reactions"], steps[39]["reactions"]);
    assert_eq!(last["points"]["stress"][0].as_array().unwrap().len(), 6);
    let series = std::fs::read_to_string(out.join("points.pvd")).unwrap();
    assert!(series.contains("steps/step_0040.vtu"), "{series}");
    let surfaces = std::fs::read_to_string(out.join("boundary.pvd")).unwrap();
    assert!(
        surfaces.contains("steps/step_0040_boundary.vtp"),
        "{surfaces}"
    );
    assert_eq!(last["boundaries"].as_array().unwrap().len(), 6);
    // A finished run keeps no checkpoint: there is nothing to resume.
    assert!(!out.join("checkpoint.bin").exists());
    let resumed = mpm().args(["run", "--resume"]).arg(&*out).output().unwrap();
    assert_eq!(resumed.status.code(), Some(2));
    let err = String::from_utf8_lossy(&resumed.stderr);
    assert!(err.contains("before its first checkpoint"), "{err}");
}

/// A 3D run killed mid-way goes on from its last checkpoint with
/// `--resume` and ends where an uninterrupted run ends, as a plane-strain
/// run does (`resume_goes_on_from_the_last_checkpoint`).
#[test]
fn a_3d_run_resumes_from_its_last_checkpoint() {
    // The 3D column at 0.78125 m cells: 8192 points over 40 steps.
    let mut case = example("column3d");
    case["grid"]["cell_size"] = 0.78125.into();
    let (_dir, straight, stopped) = killed_at_step_4_and_resumed(&case, "resume3d");
    let read = |dir: &std::path::Path, file: &str| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(dir.join(file)).unwrap()).unwrap()
    };
    let summary = read(&stopped, "summary.json");
    assert_eq!(summary["steps"].as_array().unwrap().len(), 40);
    assert!(summary["resumed_from"].as_u64().unwrap() >= 3, "{summary}");
    let a = read(&stopped, "steps/step_0040.json");
    let b = read(&straight, "steps/step_0040.json");
    assert_eq!(a["points"]["position"], b["points"]["position"]);
    assert_eq!(a["report"]["reactions"], b["report"]["reactions"]);
    let pvd = std::fs::read_to_string(stopped.join("points.pvd")).unwrap();
    assert_eq!(pvd.matches("<DataSet").count(), 41, "steps 0 to 40");
    assert!(!stopped.join("checkpoint.bin").exists());
}

/// A 3D case with a field of the plane-strain case, or a vector of two
/// components, is refused with its path named (exit 2).
#[test]
fn a_2d_field_in_a_3d_case_is_refused_by_name() {
    let column = example("column3d");
    let mut probes = column.clone();
    probes["probes"] = serde_json::json!([{ "name": "top", "at": [1.0, 1.0, 50.0] }]);
    let mut gravity = column.clone();
    gravity["loads"]["gravity"] = serde_json::json!([0.0, -10.0]);
    let mut rectangle = column.clone();
    rectangle["bodies"][0]["geometry"] =
        serde_json::json!({ "rectangle": { "min": [0.0, 0.0], "max": [1.0, 1.0] } });
    for (name, case, path) in [
        ("probes", probes, "probes"),
        ("gravity", gravity, "loads.gravity"),
        ("rectangle", rectangle, "bodies[0].geometry"),
    ] {
        let out = run_case(&format!("solid-{name}"), &case);
        assert_eq!(out.status.code(), Some(2), "{name}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(path), "{name}: {err}");
    }
}
