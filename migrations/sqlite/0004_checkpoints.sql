-- The solver's state after a job's latest checkpointed step (mpm::Checkpoint,
-- postcard-encoded), and the job's Newton iterations at that step. A job
-- claimed again resumes from it; it is deleted when the job ends.
CREATE TABLE checkpoints (
    job_id            INTEGER PRIMARY KEY REFERENCES jobs (id) ON DELETE CASCADE,
    step              INTEGER NOT NULL,
    newton_iterations INTEGER NOT NULL,
    state             BLOB NOT NULL
);
-- The step the job's latest run resumed after (NULL: it started from step 1).
ALTER TABLE jobs ADD COLUMN resumed_from INTEGER;
