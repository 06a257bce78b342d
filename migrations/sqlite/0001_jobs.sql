-- Jobs and their per-step results. Times are Unix seconds (REAL).
CREATE TABLE jobs (
    id                INTEGER PRIMARY KEY AUTOINCREMENT,
    -- The names live in one place in the code: JobStatus (src/jobs/status.rs).
    status            TEXT NOT NULL CHECK (status IN ('queued', 'running', 'succeeded', 'failed', 'cancelled')),
    case_json         TEXT NOT NULL,
    title             TEXT,
    points            INTEGER NOT NULL,
    load_steps        INTEGER NOT NULL,
    steps_done        INTEGER NOT NULL DEFAULT 0,
    newton_iterations INTEGER NOT NULL DEFAULT 0,
    attempts          INTEGER NOT NULL DEFAULT 0,
    cancel_requested  INTEGER NOT NULL DEFAULT 0,
    lease_owner       TEXT,
    lease_expires_at  REAL,
    created_at        REAL NOT NULL,
    started_at        REAL,
    finished_at       REAL,
    solve_seconds     REAL,
    -- JSON: {"kind", "message", "step", "iteration", "residual"}
    error             TEXT
);

CREATE INDEX jobs_by_status ON jobs (status, id);

CREATE TABLE steps (
    job_id  INTEGER NOT NULL REFERENCES jobs (id) ON DELETE CASCADE,
    step    INTEGER NOT NULL,
    -- mpm::StepReport as JSON
    report  TEXT NOT NULL,
    -- mpm::output::PointColumns as JSON
    points  TEXT NOT NULL,
    PRIMARY KEY (job_id, step)
);
