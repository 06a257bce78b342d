-- Claims of a job since its checkpoint last moved on: a worker that died
-- after storing a later checkpoint than the one its run resumed from made
-- progress, and does not count against --max-attempts (jobs.attempts
-- still counts every claim).
ALTER TABLE jobs ADD COLUMN stalled_attempts INTEGER NOT NULL DEFAULT 0;
UPDATE jobs SET stalled_attempts = attempts;
