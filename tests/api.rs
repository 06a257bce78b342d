//! The HTTP API against a real server, on a real SQLite file and on a real
//! PostgreSQL database: every test runs on both (`sqlite::` and
//! `postgres::`).

mod common;

use std::collections::BTreeSet;
use std::time::Duration;

use mpm_service::jobs::admission::{Footprint, stored_bytes};

use common::{example, filled_at_1mm, is_final, slow_case, spawn_app, spawn_app_with};
use serde_json::{Value, json};

const LONG: Duration = Duration::from_secs(120);

fn a_job_runs_to_success_and_its_steps_match_the_cli() {
    let app = spawn_app();
    let case = example("cantilever-grid");
    let id = app.submit(&case);
    let job = app.wait_for(id, LONG, is_final);
    assert_eq!(job["status"], "succeeded", "{job}");
    assert_eq!(job["progress"], json!({"step": 5, "of": 5}));
    assert!(job["solve_seconds"].as_f64().unwrap() > 0.0);

    // Step 0, the undeformed state, then the five load steps.
    let steps = app.get_json(&format!("/jobs/{id}/steps"));
    assert_eq!(steps["steps"].as_array().unwrap().len(), 6);
    assert_eq!(steps["steps"][0]["step"], 0);
    let start = app.get_json(&format!("/jobs/{id}/steps/0"));
    assert_eq!(start["report"]["load_factor"], 0.0);
    assert_eq!(start["points"]["displacement"][0], json!([0.0, 0.0]));

    // The CLI on the same case writes the same step file.
    let (out, cli) = cli_run("cantilever-grid", 5);
    let api = app.get_json(&format!("/jobs/{id}/steps/5"));
    for field in ["position", "displacement", "stress", "volume", "jacobian"] {
        let a = api["points"][field].to_string();
        let c = cli["points"][field].to_string();
        assert_eq!(
            a, c,
            "points.{field} differ between the service and the CLI"
        );
    }
    assert_eq!(api["report"]["probes"], cli["report"]["probes"]);
    assert_eq!(api["boundaries"].to_string(), cli["boundaries"].to_string());
    // The beam's boundary: one loop through its 2 (40 + 8) - 4 outer points.
    assert_eq!(api["boundaries"][0]["points"].as_array().unwrap().len(), 92);

    let result = app.get_json(&format!("/jobs/{id}/result"));
    let tip = result["probes"]["tip"].as_array().unwrap();
    assert_eq!(tip.len(), 6);
    assert_eq!(tip[0]["displacement"], json!([0.0, 0.0]));
    assert_eq!(
        tip[5]["displacement"],
        cli["report"]["probes"][0]["displacement"]
    );
    // The bilinear basis bent past its cells: the result warns, as the
    // CLI's summary does.
    let cli_summary: Value =
        serde_json::from_str(&std::fs::read_to_string(out.0.join("summary.json")).unwrap())
            .unwrap();
    assert_eq!(result["warnings"][0]["kind"], "bilinear_crossing");
    assert_eq!(result["warnings"], cli_summary["warnings"]);
    assert_eq!(result["newton"][5]["cutbacks"], 0);

    let (status, vtu) = app.get(&format!("/jobs/{id}/steps/5?format=vtu"));
    assert_eq!(status, 200);
    assert!(vtu.starts_with("<?xml") && vtu.contains("NumberOfPoints=\"320\""));
    // The boundary as the CLI writes it: one polyline of the loop's samples
    // (the values read back from the stored JSON may differ in the last
    // digit: serde_json's float parsing is not exact).
    let (status, vtp) = app.get(&format!("/jobs/{id}/steps/5?format=vtp"));
    assert_eq!(status, 200);
    let cli_vtp = std::fs::read_to_string(out.0.join("steps/step_0005_boundary.vtp")).unwrap();
    assert_eq!(piece(&vtp), piece(&cli_vtp));
    assert!(piece(&vtp).unwrap().contains("NumberOfLines=\"1\""));

    let (status, _) = app.get(&format!("/jobs/{id}/steps/6"));
    assert_eq!(status, 404);

    // The job's archive: the files `mpm run` wrote, by the same names (the
    // run's own bookkeeping aside), with the same step documents' points.
    let mut zip = archive_like_the_cli(&app, id, &out);
    let archived: BTreeSet<String> = zip.file_names().map(|n| n.unwrap().into_owned()).collect();
    assert_eq!(archived.len(), 4 + 3 * 6, "{archived:?}");
    // Dated when the job ended, not zip's 1980: the job's finished_at, to
    // the two seconds a zip's time holds.
    let finished = app.get_json(&format!("/jobs/{id}"))["finished_at"]
        .as_str()
        .unwrap()
        .to_string();
    let dated = zip.by_name("case.json").unwrap().last_modified().unwrap();
    let stamp = format!(
        "{:04}-{:02}-{:02}T{:02}:{:02}",
        dated.year(),
        dated.month(),
        dated.day(),
        dated.hour(),
        dated.minute()
    );
    assert_eq!(stamp, finished[..16], "{finished}");
    let mut read = |name: &str| {
        let mut text = String::new();
        std::io::Read::read_to_string(&mut zip.by_name(name).unwrap(), &mut text).unwrap();
        text
    };
    let archived_step: Value = serde_json::from_str(&read("steps/step_0005.json")).unwrap();
    assert_eq!(
        archived_step["points"].to_string(),
        api["points"].to_string()
    );
    assert_eq!(
        archived_step["points"]["position"].to_string(),
        cli["points"]["position"].to_string()
    );
    let summary: Value = serde_json::from_str(&read("summary.json")).unwrap();
    let cli_summary: Value =
        serde_json::from_str(&std::fs::read_to_string(out.0.join("summary.json")).unwrap())
            .unwrap();
    assert_eq!(summary["steps"].as_array().unwrap().len(), 5);
    for k in 0..5 {
        let probes = |s: &Value| s["steps"][k]["probes"].clone();
        assert_eq!(probes(&summary), probes(&cli_summary), "step {}", k + 1);
    }
    assert_eq!(
        read("points.pvd").lines().count(),
        read("boundary.pvd").lines().count()
    );
    assert!(read("points.pvd").contains("file=\"steps/step_0005.vtu\""));
}

/// A 3D case (`mpm example column3d`, 40 load steps) runs as a job, and
/// its steps, VTU files and archive are what `mpm run` writes for it;
/// 3D cases are refused as plane-strain ones are, naming the field.
fn a_3d_job_runs_and_its_steps_match_the_cli() {
    let app = spawn_app_with(|c| c.limits.max_points = 1000);
    let case = example("column3d");
    let id = app.submit(&case);
    let job = app.wait_for(id, LONG, is_final);
    assert_eq!(job["status"], "succeeded", "{job}");
    assert_eq!(job["progress"], json!({"step": 40, "of": 40}));
    assert_eq!(job["points"], 128);
    let steps = app.get_json(&format!("/jobs/{id}/steps"));
    assert_eq!(steps["steps"].as_array().unwrap().len(), 41);
    let start = app.get_json(&format!("/jobs/{id}/steps/0"));
    assert_eq!(start["points"]["displacement"][0], json!([0.0, 0.0, 0.0]));

    let (out, cli) = cli_run("column3d", 40);
    let api = app.get_json(&format!("/jobs/{id}/steps/40"));
    assert_eq!(api["points"].to_string(), cli["points"].to_string());
    assert_eq!(api["boundaries"].to_string(), cli["boundaries"].to_string());
    assert_eq!(api["boundaries"].as_array().unwrap().len(), 6);
    assert_eq!(api["report"]["reactions"], cli["report"]["reactions"]);
    // The column's top has come down by about 26 m of its 50 (AMPLE's
    // -25.940 m exactly, `tests/verification/column3d.rs`).
    let top = (api["points"]["position"].as_array().unwrap().iter())
        .map(|x| x[2].as_f64().unwrap())
        .fold(f64::MIN, f64::max);
    assert!((20.0..26.0).contains(&top), "{top}");

    let (status, vtu) = app.get(&format!("/jobs/{id}/steps/40?format=vtu"));
    assert_eq!(status, 200);
    // Raw appended binary after the XML head.
    let cli_vtu = std::fs::read(out.0.join("steps/step_0040.vtu")).unwrap();
    let cli_vtu = String::from_utf8_lossy(&cli_vtu);
    assert_eq!(piece(&vtu), piece(&cli_vtu));
    assert!(piece(&vtu).unwrap().contains("NumberOfPoints=\"128\""));
    // The surfaces as VTP: the CLI's file.
    let (status, vtp) = app.get(&format!("/jobs/{id}/steps/40?format=vtp"));
    assert_eq!(status, 200);
    let cli_vtp = std::fs::read_to_string(out.0.join("steps/step_0040_boundary.vtp")).unwrap();
    assert_eq!(vtp, cli_vtp);

    // The archive holds the files `mpm run` wrote, by the same names: per
    // step its document, points and surfaces; the case, summary and two
    // series.
    let zip = archive_like_the_cli(&app, id, &out);
    assert_eq!(zip.len(), 4 + 3 * 41);

    // A plane-strain field in a 3D case, a vector of two components where
    // three are needed, and bodies over the point limit.
    let with = |f: &dyn Fn(&mut Value)| {
        let mut c = example("column3d");
        f(&mut c);
        c.to_string()
    };
    for (body, path) in [
        (with(&|c| c["probes"] = json!([])), "probes"),
        (
            with(&|c| c["loads"]["gravity"] = json!([0.0, -10.0])),
            "loads.gravity",
        ),
        (
            with(&|c| c["bodies"][0]["points"]["per_cell"] = 4.into()),
            "bodies",
        ),
    ] {
        let (status, _, at) = rejection(&app, &body);
        assert_eq!((status, at.as_deref()), (422, Some(path)), "{body}");
    }
}

/// `mpm run --example NAME` into a new directory, and the step document
/// it wrote for `step`.
fn cli_run(name: &str, step: usize) -> (common::TempDir, Value) {
    let out = common::TempDir::new("cli");
    let status = std::process::Command::new(env!("CARGO_BIN_EXE_mpm"))
        .args(["run", "--example", name, "--out"])
        .arg(&out.0)
        .output()
        .unwrap();
    assert!(status.status.success());
    let document = out.0.join(format!("steps/step_{step:04}.json"));
    let cli = serde_json::from_str(&std::fs::read_to_string(document).unwrap()).unwrap();
    (out, cli)
}

/// The `<Piece ...>` line of a VTK file: its counts.
fn piece(text: &str) -> Option<String> {
    text.lines()
        .find(|l| l.contains("<Piece"))
        .map(str::to_owned)
}

/// Job `id`'s archive, checked to hold the files `mpm run` wrote in
/// `out`, by the same names (the run's own bookkeeping aside).
fn archive_like_the_cli(
    app: &common::TestApp,
    id: i64,
    out: &common::TempDir,
) -> zip::ZipArchive<std::io::Cursor<Vec<u8>>> {
    let mut response = app
        .agent
        .get(format!("{}/jobs/{id}/archive", app.base))
        .call()
        .unwrap();
    assert_eq!(response.status().as_u16(), 200);
    let bytes = response.body_mut().read_to_vec().unwrap();
    let zip = zip::ZipArchive::new(std::io::Cursor::new(bytes)).unwrap();
    let archived: BTreeSet<String> = zip.file_names().map(|n| n.unwrap().into_owned()).collect();
    let written: BTreeSet<String> = walkdir(&out.0)
        .iter()
        .map(|p| p.strip_prefix(&out.0).unwrap().to_str().unwrap().to_owned())
        .filter(|name| name != "reports.jsonl")
        .collect();
    assert_eq!(archived, written);
    zip
}

/// Every file under `dir`, recursively.
fn walkdir(dir: &std::path::Path) -> Vec<std::path::PathBuf> {
    let mut files = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            files.extend(walkdir(&path));
        } else {
            files.push(path);
        }
    }
    files
}

/// `(status, error.code, error.details.path)` of a rejected submission.
fn rejection(app: &common::TestApp, body: &str) -> (u16, String, Option<String>) {
    let (status, text) = app.post("/jobs", body);
    let v: Value =
        serde_json::from_str(&text).unwrap_or_else(|_| panic!("error body is JSON: {text}"));
    let code = v["error"]["code"].as_str().unwrap().to_string();
    assert!(!v["error"]["message"].as_str().unwrap().is_empty());
    (
        status,
        code,
        v["error"]["details"]["path"].as_str().map(String::from),
    )
}

fn invalid_submissions_are_4xx_naming_the_field_and_create_nothing() {
    let app = spawn_app_with(|c| {
        c.limits.max_points = 1000;
        c.limits.max_body_bytes = 64 * 1024;
    });
    let with = |f: &dyn Fn(&mut Value)| {
        let mut case = example("cantilever-grid");
        f(&mut case);
        case.to_string()
    };
    assert_eq!(rejection(&app, "{\"version\": 1,").0, 400);
    assert_eq!(rejection(&app, "{\"version\": 1,").1, "malformed_json");

    let cases: Vec<(String, &str)> = vec![
        (
            with(&|c| c["bodies"][0]["material"]["youngs_modulos"] = 1.into()),
            "bodies[0].material",
        ),
        (
            with(&|c| c["bodies"][0]["material"]["youngs_modulus"] = (-1.0).into()),
            "bodies[0].material.youngs_modulus",
        ),
        (
            with(&|c| c["bodies"][0]["material"]["poisson_ratio"] = 0.5.into()),
            "bodies[0].material.poisson_ratio",
        ),
        (
            with(&|c| {
                c["bodies"][0]["geometry"] = json!({"rectangle": {"min": [0, 0], "max": [0, 2]}})
            }),
            "bodies[0].geometry.rectangle.max",
        ),
        (with(&|c| c["grid"]["cell_size"] = 0.05.into()), "bodies"), // 32000 points > 1000
        // 2e11 points: refused from the bounding box, before any is made.
        (
            with(&|c| c["bodies"][0]["points"] = json!({"spacing": 1e-5})),
            "bodies",
        ),
        (with(&|c| c["bodies"] = json!([])), "bodies"),
        (
            with(&|c| c["loads"]["boundary"] = json!([{"on": {"y": 7.0}, "pressure": 1.0}])),
            "loads.boundary[0].on",
        ),
        // Forces of 1e308 overflowed; the job "succeeded" with null
        // reactions, and its result and archive answered 500.
        (
            with(&|c| c["loads"]["gravity"] = json!([1e308, -10.0])),
            "loads.gravity[0]",
        ),
        // PostgreSQL's text cannot hold NUL: 500 there, 201 on SQLite.
        (with(&|c| c["title"] = "beam\u{0}".into()), "title"),
        // Checked before queued, not failed on the worker: a support
        // between grid lines holds no node,
        (
            with(&|c| c["supports"][0]["on"] = json!({"x": 0.3})),
            "supports[0].on",
        ),
        // a body outside the grid's extent has no nodes,
        (
            with(&|c| c["grid"]["extent"] = json!({"min": [0, 0], "max": [5, 5]})),
            "bodies[0].geometry",
        ),
        // a probe outside every body follows nothing,
        (
            with(&|c| c["probes"][0]["at"] = json!([30.0, 1.0])),
            "probes[0].at",
        ),
        // and a body a millionth of a cell across is no body (a 5e-324 m
        // wide one's boundary was NaN, and its VTP answered 500).
        (
            with(&|c| {
                c["bodies"][0]["geometry"] =
                    json!({"rectangle": {"min": [0, 0], "max": [5e-324, 2]}})
            }),
            "bodies[0].geometry",
        ),
    ];
    for (body, path) in &cases {
        let (status, code, got) = rejection(&app, body);
        assert_eq!(status, 422, "{path}: {code}");
        assert_eq!(got.as_deref(), Some(*path), "{body}");
    }
    let huge = format!("{{\"title\": \"{}\"}}", "x".repeat(100 * 1024));
    let (status, code, _) = rejection(&app, &huge);
    assert_eq!((status, code.as_str()), (413, "payload_too_large"));
    assert_eq!(app.total_jobs(), 0);
}

fn cancel_stops_a_running_job_keeping_its_steps_and_cancels_a_queued_one() {
    let app = spawn_app();
    let running = app.submit(&slow_case(400));
    let queued = app.submit(&slow_case(400));
    app.wait_for(running, LONG, |j| j["progress"]["step"].as_i64() >= Some(1));

    let (status, body) = app.post(&format!("/jobs/{queued}/cancel"), "");
    assert_eq!(status, 200, "{body}");
    assert_eq!(
        app.get_json(&format!("/jobs/{queued}"))["status"],
        "cancelled"
    );

    let (status, body) = app.post(&format!("/jobs/{running}/cancel"), "");
    assert_eq!(status, 202, "{body}");
    let job = app.wait_for(running, LONG, is_final);
    assert_eq!(job["status"], "cancelled", "{job}");
    let done = job["progress"]["step"].as_i64().unwrap();
    assert!((1..400).contains(&done), "{job}");
    let steps = app.get_json(&format!("/jobs/{running}/steps"));
    assert_eq!(steps["steps"].as_array().unwrap().len() as i64, done + 1);

    let (status, _) = app.post(&format!("/jobs/{running}/cancel"), "");
    assert_eq!(status, 409);
    let (status, _) = app.post("/jobs/999/cancel", "");
    assert_eq!(status, 404);
}

/// An ended job is deleted with its steps; a running one is refused until
/// cancelled; /health counts the jobs of each status.
fn delete_removes_an_ended_job_and_refuses_a_running_one() {
    let app = spawn_app();
    let running = app.submit(&slow_case(400));
    app.wait_for(running, LONG, |j| j["progress"]["step"].as_i64() >= Some(1));
    let health = app.get_json("/health");
    assert_eq!(health["jobs"]["running"], 1, "{health}");
    assert_eq!(health["jobs"]["succeeded"], 0, "{health}");

    let (status, body) = app.delete(&format!("/jobs/{running}"));
    assert_eq!(status, 409, "{body}");
    assert!(body.contains("cancel it first"), "{body}");
    let (status, _) = app.post(&format!("/jobs/{running}/cancel"), "");
    assert_eq!(status, 202);
    app.wait_for(running, LONG, is_final);

    let (status, body) = app.delete(&format!("/jobs/{running}"));
    assert_eq!(status, 204, "{body}");
    assert_eq!(app.get(&format!("/jobs/{running}")).0, 404);
    assert_eq!(app.get(&format!("/jobs/{running}/steps/1")).0, 404);
    assert_eq!(app.delete(&format!("/jobs/{running}")).0, 404);
    assert_eq!(app.total_jobs(), 0);
    let health = app.get_json("/health");
    assert_eq!(health["jobs"]["cancelled"], 0, "{health}");
}

/// `output.every` thins the stored points (reports stay every step), and
/// `output.fields` the columns; step 0 and the last step keep their points.
fn output_every_and_fields_thin_what_a_job_stores() {
    let app = spawn_app();
    let mut case = example("cantilever-grid");
    case["output"] = json!({"every": 2, "fields": ["stress"]});
    let id = app.submit(&case);
    assert_eq!(app.wait_for(id, LONG, is_final)["status"], "succeeded");
    let steps = app.get_json(&format!("/jobs/{id}/steps"));
    assert_eq!(steps["steps"].as_array().unwrap().len(), 6);
    for k in 0..=5 {
        let step = app.get_json(&format!("/jobs/{id}/steps/{k}"));
        assert_eq!(step["report"]["step"], k);
        let vtu = app.get(&format!("/jobs/{id}/steps/{k}?format=vtu")).0;
        if [0, 2, 4, 5].contains(&k) {
            let columns: BTreeSet<&str> = step["points"]
                .as_object()
                .unwrap()
                .keys()
                .map(String::as_str)
                .collect();
            assert_eq!(columns, BTreeSet::from(["position", "stress"]), "step {k}");
            assert_eq!(step["boundaries"].as_array().unwrap().len(), 1);
            assert_eq!(vtu, 200);
        } else {
            assert!(step["points"].is_null(), "step {k}: {}", step["points"]);
            assert_eq!(vtu, 404, "step {k}");
        }
    }
    let (status, body) = app.post("/jobs", &{
        case["output"]["every"] = 0.into();
        case.to_string()
    });
    assert_eq!(status, 422, "{body}");
    assert!(body.contains("output.every"), "{body}");
}

fn a_failed_solve_says_where_and_the_service_keeps_serving() {
    let app = spawn_app();
    let mut case = example("cantilever-grid");
    case["analysis"]["load_steps"] = 1.into();
    case["analysis"]["newton"] = json!({"max_iterations": 2});
    let id = app.submit(&case);
    let job = app.wait_for(id, LONG, is_final);
    assert_eq!(job["status"], "failed");
    let error = &job["error"];
    assert_eq!(error["kind"], "not_converged", "{job}");
    assert_eq!(error["step"], 1);
    assert_eq!(error["iteration"], 2);
    assert!(error["residual"].as_f64().unwrap() > 1e-9);

    assert_eq!(app.get("/health").0, 200);
    let next = app.submit(&example("cantilever-grid"));
    assert_eq!(app.wait_for(next, LONG, is_final)["status"], "succeeded");
}

fn fifty_concurrent_submissions_are_all_accepted_and_all_finish() {
    let app = spawn_app();
    let mut case = example("column");
    case["analysis"]["load_steps"] = 4.into();
    let body = case.to_string();
    let ids: Vec<i64> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..50)
            .map(|_| {
                let (agent, base, body) = (common::agent(), app.base.clone(), body.clone());
                s.spawn(move || {
                    let (status, text) =
                        common::request(&agent, "POST", &format!("{base}/jobs"), Some(&body));
                    assert_eq!(status, 201, "{text}");
                    serde_json::from_str::<Value>(&text).unwrap()["id"]
                        .as_i64()
                        .unwrap()
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    assert_eq!(ids.iter().collect::<BTreeSet<_>>().len(), 50);
    for id in ids {
        assert_eq!(app.wait_for(id, LONG, is_final)["status"], "succeeded");
    }
    let page = app.get_json("/jobs?status=succeeded&limit=20");
    assert_eq!(page["total"], 50);
    assert_eq!(page["jobs"].as_array().unwrap().len(), 20);
    assert_eq!(page["next"], "/jobs?status=succeeded&limit=20&offset=20");
    assert_eq!(app.get("/jobs?status=done").0, 400);
}

fn a_token_guards_every_endpoint_but_health() {
    let app = spawn_app_with(|c| c.token = Some("s3cret".into()));
    // Without the token, /health says up or down and nothing more (it
    // showed job counts, the database's size and its kind).
    let (status, body) = app.get("/health");
    assert_eq!(status, 200);
    let health: Value = serde_json::from_str(&body).unwrap();
    assert_eq!(health, json!({"status": "ok"}));
    let mut response = app
        .agent
        .get(format!("{}/health", app.base))
        .header("authorization", "Bearer s3cret")
        .call()
        .unwrap();
    let health: Value = response.body_mut().read_json().unwrap();
    assert!(health["database_bytes"].as_i64().unwrap() > 0, "{health}");
    assert_eq!(health["database"], "ok");
    let (status, body) = app.get("/jobs");
    assert_eq!(status, 401);
    assert!(body.contains("unauthorized"));
    let response = app
        .agent
        .get(format!("{}/jobs", app.base))
        .header("authorization", "Bearer s3cret")
        .call()
        .unwrap();
    assert_eq!(response.status().as_u16(), 200);
}

/// The contract and the server agree: the spec documents exactly the
/// routes the router declares, its example case is accepted, every
/// documented GET answers, and every field of every JSON answer is in the
/// contract (a field added to a response type and not to `openapi.yaml`
/// fails here).
fn openapi_matches_the_routes_and_its_example_is_accepted() {
    let spec: serde_yaml::Value = serde_yaml::from_str(&mpm_service::http::OPENAPI).unwrap();
    let json_spec: Value = serde_json::to_value(&spec).unwrap();
    let paths = spec["paths"].as_mapping().unwrap();
    let documented: BTreeSet<String> = paths
        .keys()
        .map(|k| k.as_str().unwrap().to_string())
        .collect();
    let router_source = [
        include_str!("../src/http/mod.rs"),
        include_str!("../src/http/viewer.rs"),
    ]
    .concat();
    let declared: BTreeSet<String> = router_source
        .split(".route(\"")
        .skip(1)
        .map(|s| s.split('"').next().unwrap().to_string())
        .collect();
    assert_eq!(documented, declared);

    let app = spawn_app();
    let example = &paths[&serde_yaml::Value::from("/jobs")]["post"]["requestBody"]["content"]["application/json"]
        ["example"];
    let example: Value = serde_json::to_value(example).unwrap();
    let id = app.submit(&example);
    assert_eq!(app.wait_for(id, LONG, is_final)["status"], "succeeded");
    for (path, item) in paths {
        let path = path.as_str().unwrap();
        if item.get("get").is_none() {
            continue;
        }
        let url = path
            .replace("{id}", &id.to_string())
            .replace("{step}", "1")
            .replace("{file}", "viewer.js");
        let (status, body) = app.get(&url);
        assert_eq!(status, 200, "GET {url}: {body}");
        let schema = &json_spec["paths"][path]["get"]["responses"]["200"]["content"]["application/json"]
            ["schema"];
        if !schema.is_null() {
            let answer: Value = serde_json::from_str(&body).unwrap();
            let mut missing = Vec::new();
            undeclared(&json_spec, schema, &answer, "", &mut missing);
            assert!(
                missing.is_empty(),
                "GET {url}: not in the contract: {missing:?}"
            );
        }
    }
    let (status, body) = app.get("/no/such/route");
    assert_eq!(status, 404);
    assert!(body.contains("not_found"));
}

/// Collects in `out` the paths of the fields of `value` that `schema` (of
/// the OpenAPI document `spec`) does not declare: keys of an object whose
/// schema lists `properties` but not that key and takes no
/// `additionalProperties`; recursing through `$ref`, `allOf`, `oneOf`,
/// `anyOf`, properties, maps and items.
fn undeclared(spec: &Value, schema: &Value, value: &Value, at: &str, out: &mut Vec<String>) {
    let schema = match schema["$ref"].as_str() {
        Some(pointer) => spec.pointer(pointer.trim_start_matches('#')).unwrap(),
        None => schema,
    };
    for part in schema["allOf"].as_array().into_iter().flatten() {
        undeclared(spec, part, value, at, out);
    }
    for key in ["oneOf", "anyOf"] {
        if let Some(branches) = schema[key].as_array() {
            let fewest = branches
                .iter()
                .map(|branch| {
                    let mut found = Vec::new();
                    undeclared(spec, branch, value, at, &mut found);
                    found
                })
                .min_by_key(Vec::len)
                .unwrap_or_default();
            out.extend(fewest);
        }
    }
    match value {
        Value::Object(map) => {
            let properties = schema["properties"].as_object();
            let extra = &schema["additionalProperties"];
            for (key, field) in map {
                let path = format!("{at}.{key}");
                match properties.and_then(|p| p.get(key)) {
                    Some(declared) => undeclared(spec, declared, field, &path, out),
                    None if extra.is_object() => undeclared(spec, extra, field, &path, out),
                    None if properties.is_some() && extra != &Value::Bool(true) => out.push(path),
                    None => {}
                }
            }
        }
        Value::Array(items) if schema["items"].is_object() => {
            for (k, item) in items.iter().enumerate() {
                undeclared(spec, &schema["items"], item, &format!("{at}[{k}]"), out);
            }
        }
        _ => {}
    }
}

/// Peak resident memory of this process so far (Linux), in bytes.
fn peak_memory() -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
        .map_or(0, |kb| kb * 1024)
}

/// Bodies whose bounding boxes are tiny but whose lattices are not: a thin
/// rectangle (1e-9 m x 5000 m at 1 mm: a column of 5e6 points) and a sliver
/// polygon (on the grid's lattice a column of 1e9 sites to scan for a
/// handful of points; on its own it once made patches of 5e8 points, and
/// now as many as its area holds, three).
/// Counting from the bounding box's area let the first through to be
/// seeded (24.8 s and 3.0 GB before its 422) and the second scanned (15 s
/// of CPU). Per-direction counts refuse both before anything is seeded:
/// 0.4 ms a request (median of 21, release build, this machine). Asserted with room for a loaded
/// machine: under 2 s each (seeding would take tens of seconds) and under
/// 200 MB of peak memory in all (seeding would take gigabytes).
fn bodies_over_the_limits_are_refused_from_their_lattice_counts() {
    let app = spawn_app();
    let with = |geometry: Value, lattice: &str| {
        let mut case = filled_at_1mm(geometry);
        case["bodies"][0]["points"]["lattice"] = lattice.into();
        case.to_string()
    };
    let sliver = json!({"polygon": {"vertices": [[0, 0], [1e-6, 0], [0, 1e6]]}});
    let peak_before = peak_memory();
    for (body, path) in [
        (
            with(
                json!({"rectangle": {"min": [0, 0], "max": [1e-9, 5000]}}),
                "body",
            ),
            "bodies",
        ),
        // On the grid's lattice, a column of 1e9 sites to scan.
        (with(sliver, "grid"), "bodies[0].points"),
    ] {
        let start = std::time::Instant::now();
        let (status, code, got) = rejection(&app, &body);
        let seconds = start.elapsed().as_secs_f64();
        assert_eq!((status, code.as_str()), (422, "limit_exceeded"), "{path}");
        assert_eq!(got.as_deref(), Some(path));
        assert!(seconds < 2.0, "{path}: {seconds} s");
    }
    let grown = peak_memory().saturating_sub(peak_before);
    assert!(grown < 200 << 20, "peak memory grew by {grown} bytes");
    assert_eq!(app.total_jobs(), 0);
}

/// `(status, error code, details)` of a GET or POST that must fail with the
/// one error body.
fn error_of(app: &common::TestApp, method: &str, path: &str) -> (u16, String, Value) {
    let (status, text) = match method {
        "GET" => app.get(path),
        _ => app.post(path, "{}"),
    };
    let v: Value = serde_json::from_str(&text)
        .unwrap_or_else(|_| panic!("{method} {path}: the error body is JSON: {text:?}"));
    let code = v["error"]["code"].as_str().unwrap_or_default().to_string();
    (status, code, v["error"]["details"].clone())
}

/// Path and query parse errors and wrong methods answered with axum's plain
/// text (or an empty body) until the extractors and the router's fallbacks
/// kept the contract; an offset near i64::MAX overflowed the next link.
fn errors_from_paths_queries_and_methods_keep_the_contract() {
    let app = spawn_app();
    for path in ["/jobs/abc", "/jobs/9223372036854775808", "/jobs/1/steps/x"] {
        let (status, code, _) = error_of(&app, "GET", path);
        assert_eq!((status, code.as_str()), (404, "not_found"), "{path}");
    }
    for (path, parameter) in [
        ("/jobs?limit=1e9", "limit"),
        ("/jobs?limit=9223372036854775808", "limit"),
        ("/jobs?limit=1&limit=2", "query"),
        ("/jobs?offset=9223372036854775807", "offset"),
        ("/jobs?offset=-1", "offset"),
    ] {
        let (status, code, details) = error_of(&app, "GET", path);
        assert_eq!((status, code.as_str()), (400, "bad_query"), "{path}");
        assert_eq!(details["parameter"], parameter, "{path}");
    }
    let (status, code, _) = error_of(&app, "POST", "/health");
    assert_eq!((status, code.as_str()), (405, "method_not_allowed"));
}

/// With a token: the scheme is read in any case (RFC 7235), and an unknown
/// route or method answers 401 like the known ones, so routes cannot be
/// listed without the token.
fn a_token_is_read_in_any_case_and_hides_the_routes() {
    let app = spawn_app_with(|c| c.token = Some("s3cret".into()));
    let get = |path: &str, authorization: &str| match app
        .agent
        .get(format!("{}{path}", app.base))
        .header("authorization", authorization)
        .call()
    {
        Ok(r) => r.status().as_u16(),
        Err(ureq::Error::StatusCode(code)) => code,
        Err(e) => panic!("{e}"),
    };
    assert_eq!(get("/jobs", "bearer s3cret"), 200);
    assert_eq!(get("/jobs", "BEARER s3cret"), 200);
    assert_eq!(get("/jobs", "Bearer s3creT"), 401);
    assert_eq!(get("/no/such/route", "Bearer nope"), 401);
    assert_eq!(get("/no/such/route", "Bearer s3cret"), 404);
    assert_eq!(app.get("/no/such/route").0, 401);
    assert_eq!(app.post("/health", "{}").0, 401);
}

/// A full queue answers 429 with Retry-After and creates nothing; a place
/// freed (here by a cancel) takes the next submission. No worker runs, so
/// the queue's length is what was submitted.
fn a_full_queue_answers_429_with_retry_after() {
    let app = spawn_app_with(|c| {
        c.workers = 0;
        c.limits.max_queued = 2;
    });
    let case = example("cantilever-grid");
    let first = app.submit(&case);
    app.submit(&case);
    let response = app
        .agent
        .post(format!("{}/jobs", app.base))
        .header("content-type", "application/json")
        .config()
        .http_status_as_error(false)
        .build()
        .send(case.to_string())
        .unwrap();
    assert_eq!(response.status().as_u16(), 429);
    assert_eq!(
        response
            .headers()
            .get("retry-after")
            .map(|v| v.to_str().unwrap()),
        Some("10")
    );
    let body: Value =
        serde_json::from_str(&response.into_body().read_to_string().unwrap()).unwrap();
    assert_eq!(body["error"]["code"], "queue_full");
    assert_eq!(body["error"]["details"]["max_queued"], 2);
    assert_eq!(app.total_jobs(), 2);
    assert_eq!(app.post(&format!("/jobs/{first}/cancel"), "").0, 200);
    app.submit(&case);
    assert_eq!(app.total_jobs(), 3);
}

/// `(status, headers, body)` of `POST /jobs` with these extra headers.
fn submit_with(
    app: &common::TestApp,
    headers: &[(&str, &str)],
    body: &str,
) -> (u16, ureq::http::HeaderMap, Value) {
    let mut request = app
        .agent
        .post(format!("{}/jobs", app.base))
        .header("content-type", "application/json");
    for (name, value) in headers {
        request = request.header(*name, *value);
    }
    let response = request
        .config()
        .http_status_as_error(false)
        .build()
        .send(body)
        .unwrap();
    let status = response.status().as_u16();
    let headers = response.headers().clone();
    let text = response.into_body().read_to_string().unwrap();
    (status, headers, serde_json::from_str(&text).unwrap())
}

/// A POST whose response is lost leaves a job the client cannot know
/// about; retried with the same `Idempotency-Key` and body it gets that job
/// (200, same id and Location), even racing itself or with the queue full.
/// The key with another body is 422; a malformed key is 400 naming the
/// header. Nothing runs (no workers), so the jobs counted are the ones made.
fn an_idempotency_key_makes_a_retried_submission_return_the_same_job() {
    let app = spawn_app_with(|c| {
        c.workers = 0;
        c.limits.max_queued = 8;
    });
    let case = example("cantilever-grid").to_string();
    let key = [("Idempotency-Key", "run-42/attempt")];
    let (status, headers, first) = submit_with(&app, &key, &case);
    assert_eq!(status, 201, "{first}");
    let id = first["id"].as_i64().unwrap();
    let (status, again_headers, again) = submit_with(&app, &key, &case);
    assert_eq!(status, 200, "{again}");
    assert_eq!(again["id"], id);
    assert_eq!(again_headers.get("location"), headers.get("location"));
    assert_eq!(app.total_jobs(), 1);

    let mut other = example("cantilever-grid");
    other["analysis"]["load_steps"] = 2.into();
    let (status, _, reused) = submit_with(&app, &key, &other.to_string());
    assert_eq!(status, 422, "{reused}");
    assert_eq!(reused["error"]["code"], "idempotency_key_reused");
    assert_eq!(reused["error"]["details"]["header"], "Idempotency-Key");
    assert_eq!(reused["error"]["details"]["job"], id);

    let long = "k".repeat(256);
    for bad in ["", "has space", "caf\u{e9}", long.as_str()] {
        let (status, _, body) = submit_with(&app, &[("Idempotency-Key", bad)], &case);
        assert_eq!(status, 400, "{bad:?}: {body}");
        assert_eq!(body["error"]["code"], "bad_header");
        assert_eq!(body["error"]["details"]["header"], "Idempotency-Key");
    }
    assert_eq!(app.total_jobs(), 1);

    // Eight clients race with one new key: one job, made once (one 201),
    // and all eight get it.
    let answers: Vec<(u16, i64)> = std::thread::scope(|s| {
        let racers: Vec<_> = (0..8)
            .map(|_| {
                s.spawn(|| {
                    let (status, _, job) =
                        submit_with(&app, &[("Idempotency-Key", "raced")], &case);
                    (status, job["id"].as_i64().unwrap_or(-1))
                })
            })
            .collect();
        racers.into_iter().map(|r| r.join().unwrap()).collect()
    });
    let ids: BTreeSet<i64> = answers.iter().map(|a| a.1).collect();
    assert_eq!(ids.len(), 1, "{answers:?}");
    let made = answers.iter().filter(|a| a.0 == 201).count();
    assert_eq!(made, 1, "{answers:?}");
    assert!(
        answers.iter().all(|a| a.0 == 201 || a.0 == 200),
        "{answers:?}"
    );
    assert_eq!(app.total_jobs(), 2);

    // With the queue full, a retry still gets its job; a new key does not.
    for _ in 0..6 {
        assert_eq!(submit_with(&app, &[], &case).0, 201);
    }
    assert_eq!(submit_with(&app, &[], &case).0, 429);
    assert_eq!(submit_with(&app, &key, &case).0, 200);
    assert_eq!(
        submit_with(&app, &[("Idempotency-Key", "new")], &case).0,
        429
    );
}

/// A job's stored steps are estimated from its points and load steps before
/// it is queued, and refused over `max_job_bytes` naming the field further
/// over its own limit. The estimate bounds what a run stores: the
/// cantilever's step documents, as served, take between half of it and
/// all of it.
fn a_job_that_would_store_too_much_is_refused_naming_the_field() {
    let app = spawn_app();
    let case = example("cantilever-grid");
    let id = app.submit(&case);
    let job = app.wait_for(id, LONG, is_final);
    assert_eq!(job["status"], "succeeded", "{job}");
    let points = job["points"].as_u64().unwrap() as usize;
    let steps = job["progress"]["of"].as_u64().unwrap() as u32;
    let documents: Vec<String> = (1..=steps)
        .map(|k| app.get(&format!("/jobs/{id}/steps/{k}")).1)
        .collect();
    let served: usize = documents.iter().map(String::len).sum();
    let first: Value = serde_json::from_str(&documents[0]).unwrap();
    let curves = first["boundaries"].as_array().unwrap();
    let seeded = Footprint {
        points,
        boundary_points: curves
            .iter()
            .map(|b| b["points"].as_array().unwrap().len())
            .sum(),
        loops: curves.len(),
    };
    let estimate = stored_bytes(&mpm::Case::from_json(&case.to_string()).unwrap(), seeded);
    let ratio = served as f64 / estimate;
    assert!(
        (0.5..=1.0).contains(&ratio),
        "{seeded:?}: served {served} of {estimate} bytes"
    );
    eprintln!("{seeded:?}: served {served} of {estimate} bytes");
    let just_under = estimate as u64 - 1;
    // 5 of 10,000 load steps against a few hundred of a million points.
    let app = spawn_app_with(|c| c.limits.max_job_bytes = just_under);
    let (status, code, path) = rejection(&app, &case.to_string());
    assert_eq!((status, code.as_str()), (422, "limit_exceeded"));
    assert_eq!(path.as_deref(), Some("analysis.load_steps"));
    // With the points at their limit, they drive it.
    let app = spawn_app_with(|c| {
        c.limits.max_job_bytes = just_under;
        c.limits.max_points = points;
    });
    let (_, _, path) = rejection(&app, &case.to_string());
    assert_eq!(path.as_deref(), Some("bodies"));
    assert_eq!(app.total_jobs(), 0);
}

/// Checking a submission has a time limit: past it the client gets 503
/// with Retry-After, and nothing is queued. The case is a sliver on the
/// grid's lattice whose seeding scans 2e8 lattice sites (two columns; about 3 s) for a handful of points:
/// slow, but small in memory.
fn a_submission_whose_check_runs_out_of_time_is_503() {
    let app = spawn_app_with(|c| {
        c.limits.admission_time_limit = Duration::from_millis(50);
        c.limits.max_points = 100_000_000;
    });
    let mut sliver = filled_at_1mm(json!({"polygon": {"vertices": [[0, 0], [1e-6, 0], [0, 1e5]]}}));
    sliver["bodies"][0]["points"]["lattice"] = "grid".into();
    let (status, headers, body) = submit_with(&app, &[], &sliver.to_string());
    assert_eq!(status, 503, "{body}");
    assert_eq!(body["error"]["code"], "unavailable");
    assert_eq!(
        headers.get("retry-after").map(|v| v.to_str().unwrap()),
        Some("10")
    );
    assert_eq!(app.total_jobs(), 0);
}

/// Any web page a user visits could submit and cancel jobs on a service
/// without a token (the default): browsers send forms, text and bodiless
/// POSTs anywhere without asking. A submission must be declared JSON
/// (415), and a request from a page of another origin that would change
/// jobs is 403. Every response carries the browser's safety headers.
fn browsers_on_other_pages_cannot_change_jobs() {
    let app = spawn_app_with(|c| c.workers = 0);
    let case = example("cantilever-grid").to_string();
    let post = |content_type: &str, origin: Option<&str>, path: &str, body: &str| {
        let mut request = app
            .agent
            .post(format!("{}{path}", app.base))
            .header("content-type", content_type);
        if let Some(origin) = origin {
            request = request.header("origin", origin);
        }
        let mut response = request.send(body).unwrap();
        let status = response.status().as_u16();
        let body: Value = response.body_mut().read_json().unwrap_or(Value::Null);
        (status, body["error"]["code"].clone())
    };
    for kind in [
        "text/plain",
        "application/x-www-form-urlencoded",
        "application/xml",
    ] {
        assert_eq!(
            post(kind, None, "/jobs", &case),
            (415, json!("unsupported_media_type")),
            "{kind}"
        );
    }
    let evil = Some("http://evil.example");
    assert_eq!(
        post("application/json", evil, "/jobs", &case),
        (403, json!("cross_origin"))
    );
    let id = app.submit(&example("cantilever-grid"));
    assert_eq!(
        post("text/plain", evil, &format!("/jobs/{id}/cancel"), ""),
        (403, json!("cross_origin"))
    );
    // The viewer's own requests come from the service's origin.
    let own = app.base.clone();
    assert_eq!(post("application/json", Some(&own), "/jobs", &case).0, 201);
    assert_eq!(
        post("text/plain", Some(&own), &format!("/jobs/{id}/cancel"), "").0,
        200
    );
    assert_eq!(app.total_jobs(), 2);

    for path in ["/", "/jobs", "/health"] {
        let response = app.agent.get(format!("{}{path}", app.base)).call().unwrap();
        let header = |name: &str| {
            response
                .headers()
                .get(name)
                .map(|v| v.to_str().unwrap().to_string())
        };
        assert!(
            header("content-security-policy").is_some_and(|p| p.contains("frame-ancestors 'none'")),
            "{path}"
        );
        assert_eq!(header("x-content-type-options").as_deref(), Some("nosniff"));
        assert_eq!(header("x-frame-options").as_deref(), Some("DENY"));
    }
}

/// Simultaneous submissions at the queue's limit: exactly the limit's
/// number are queued. PostgreSQL took all 200 at a limit of 50, SQLite
/// 55: the count and the insert were apart.
fn the_queue_limit_holds_under_simultaneous_submissions() {
    let app = spawn_app_with(|c| {
        c.workers = 0;
        c.limits.max_queued = 10;
    });
    let case = example("cantilever-grid").to_string();
    let statuses: Vec<u16> = std::thread::scope(|s| {
        let posts: Vec<_> = (0..40)
            .map(|_| s.spawn(|| app.post("/jobs", &case).0))
            .collect();
        posts.into_iter().map(|p| p.join().unwrap()).collect()
    });
    assert_eq!(
        statuses.iter().filter(|&&s| s == 201).count(),
        10,
        "{statuses:?}"
    );
    assert!(
        statuses.iter().all(|&s| s == 201 || s == 429),
        "{statuses:?}"
    );
    assert_eq!(app.total_jobs(), 10);
}

/// A client that sends its body slowly, or stops reading its response,
/// holds the server's memory while it does (300 unread 5.9 MB steps held
/// 1.7 GB): past the client timeout the body gets 408 and the unread
/// response's connection is closed.
fn slow_clients_are_let_go_after_the_client_timeout() {
    use std::io::{Read, Write};
    let app = spawn_app_with(|c| c.limits.client_timeout = Duration::from_millis(500));
    let addr = app.base.trim_start_matches("http://").to_string();

    let mut trickle = std::net::TcpStream::connect(&addr).unwrap();
    write!(
        trickle,
        "POST /jobs HTTP/1.1\r\nhost: {addr}\r\ncontent-type: application/json\r\ncontent-length: 1000\r\n\r\n{{\"version\""
    )
    .unwrap();
    trickle
        .set_read_timeout(Some(Duration::from_secs(10)))
        .unwrap();
    let mut answer = String::new();
    let _ = trickle.read_to_string(&mut answer);
    assert!(answer.starts_with("HTTP/1.1 408"), "{answer}");
    assert!(answer.contains("request_timeout"), "{answer}");

    // A step of some 40 MB, more than the sockets' buffers hold (a few MB
    // each way on loopback).
    let mut case = example("cantilever-grid");
    case["grid"]["cell_size"] = 0.025.into();
    case["analysis"]["load_steps"] = 1.into();
    let id = app.submit(&case);
    let done = app.wait_for(id, Duration::from_secs(120), |j| {
        j["status"] != "queued" && j["status"] != "running"
    });
    assert_eq!(done["status"], "succeeded", "{done}");
    let mut unread = std::net::TcpStream::connect(&addr).unwrap();
    write!(
        unread,
        "GET /jobs/{id}/steps/1 HTTP/1.1\r\nhost: {addr}\r\n\r\n"
    )
    .unwrap();
    std::thread::sleep(Duration::from_secs(3));
    // Read what reached this side before the server gave up: the
    // response, sent in chunks as it is read from the database, stops
    // short of its last chunk, and the connection is closed.
    unread
        .set_read_timeout(Some(Duration::from_secs(10)))
        .unwrap();
    let mut received = Vec::new();
    let ended = unread.read_to_end(&mut received);
    assert!(ended.is_ok(), "the server closed the connection: {ended:?}");
    let text = String::from_utf8_lossy(&received);
    let head = &text[..text.find("\r\n\r\n").unwrap()].to_ascii_lowercase();
    assert!(head.contains("transfer-encoding: chunked"), "{head}");
    assert!(
        !text.ends_with("\r\n0\r\n\r\n"),
        "{} bytes, all of it: the server waited for the client",
        received.len()
    );
    assert!(received.len() < 20_000_000, "{}", received.len());
}

/// A step's document is streamed from the database a piece at a time, and
/// is the same document, byte for byte, as the one stored whole.
fn a_large_step_is_streamed_as_stored() {
    let app = spawn_app();
    let mut case = example("cantilever-grid");
    case["grid"]["cell_size"] = 0.05.into();
    case["analysis"]["load_steps"] = 1.into();
    let id = app.submit(&case);
    let done = app.wait_for(id, Duration::from_secs(120), is_final);
    assert_eq!(done["status"], "succeeded", "{done}");
    let mut response = common::agent()
        .get(format!("{}/jobs/{id}/steps/1", app.base))
        .call()
        .unwrap();
    assert_eq!(
        response.headers().get("transfer-encoding").unwrap(),
        "chunked"
    );
    let body = response
        .body_mut()
        .with_config()
        .limit(100_000_000)
        .read_to_string()
        .unwrap();
    // Several pieces of `PIECE` (512 KiB) characters.
    assert!(body.len() > 2_000_000, "{}", body.len());
    #[derive(serde::Deserialize)]
    struct Parts<'a> {
        #[serde(borrow)]
        report: &'a serde_json::value::RawValue,
        #[serde(borrow)]
        points: &'a serde_json::value::RawValue,
        #[serde(borrow)]
        boundaries: &'a serde_json::value::RawValue,
    }
    let parts: Parts = serde_json::from_str(&body).unwrap();
    let whole = format!(
        r#"{{"report":{},"points":{},"boundaries":{}}}"#,
        parts.report, parts.points, parts.boundaries
    );
    assert!(whole == body, "the pieces did not join into the document");
    let step: Value = serde_json::from_str(&body).unwrap();
    assert_eq!(step["report"]["step"], 1);
    assert_eq!(
        step["points"]["position"].as_array().unwrap().len() as i64,
        done["points"].as_i64().unwrap()
    );
}

/// Past the service's header limits, a request gets 431 in the error body,
/// naming the limits; hyper's own (bare) 431 comes only far past them.
fn too_many_headers_get_431_in_the_error_body() {
    use std::io::{Read, Write};
    let app = spawn_app();
    let addr = app.base.trim_start_matches("http://").to_string();
    let send = |head: String| {
        let mut stream = std::net::TcpStream::connect(&addr).unwrap();
        write!(
            stream,
            "GET /health HTTP/1.1\r\nhost: {addr}\r\nconnection: close\r\n{head}\r\n"
        )
        .unwrap();
        stream
            .set_read_timeout(Some(Duration::from_secs(10)))
            .unwrap();
        let mut answer = String::new();
        let _ = stream.read_to_string(&mut answer);
        answer
    };
    let many: String = (0..150).map(|i| format!("x-h{i}: {i}\r\n")).collect();
    let large = format!("x-large: {}\r\n", "a".repeat(100_000));
    for head in [many, large] {
        let answer = send(head);
        assert!(answer.starts_with("HTTP/1.1 431"), "{answer}");
        let body: Value = serde_json::from_str(&answer[answer.find("\r\n\r\n").unwrap() + 4..])
            .unwrap_or_else(|e| panic!("{e}: {answer}"));
        assert_eq!(body["error"]["code"], "headers_too_large", "{body}");
        assert_eq!(body["error"]["details"]["max_headers"], 100, "{body}");
    }
    let fine: String = (0..90).map(|i| format!("x-h{i}: {i}\r\n")).collect();
    assert!(send(fine).starts_with("HTTP/1.1 200"));
}

common::on_both_databases!(
    browsers_on_other_pages_cannot_change_jobs,
    the_queue_limit_holds_under_simultaneous_submissions,
    slow_clients_are_let_go_after_the_client_timeout,
    a_large_step_is_streamed_as_stored,
    too_many_headers_get_431_in_the_error_body,
    output_every_and_fields_thin_what_a_job_stores,
    delete_removes_an_ended_job_and_refuses_a_running_one,
    a_job_runs_to_success_and_its_steps_match_the_cli,
    a_3d_job_runs_and_its_steps_match_the_cli,
    invalid_submissions_are_4xx_naming_the_field_and_create_nothing,
    cancel_stops_a_running_job_keeping_its_steps_and_cancels_a_queued_one,
    a_failed_solve_says_where_and_the_service_keeps_serving,
    fifty_concurrent_submissions_are_all_accepted_and_all_finish,
    a_token_guards_every_endpoint_but_health,
    openapi_matches_the_routes_and_its_example_is_accepted,
    bodies_over_the_limits_are_refused_from_their_lattice_counts,
    errors_from_paths_queries_and_methods_keep_the_contract,
    a_token_is_read_in_any_case_and_hides_the_routes,
    a_full_queue_answers_429_with_retry_after,
    an_idempotency_key_makes_a_retried_submission_return_the_same_job,
    a_job_that_would_store_too_much_is_refused_naming_the_field,
    a_submission_whose_check_runs_out_of_time_is_503,
);
