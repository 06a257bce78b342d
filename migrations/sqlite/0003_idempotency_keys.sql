-- A client's Idempotency-Key on POST /jobs: the same key and the same body
-- return the job the first request made (its body is case_json). Keys are
-- kept as long as their job.
ALTER TABLE jobs ADD COLUMN idempotency_key TEXT;
CREATE UNIQUE INDEX jobs_by_idempotency_key ON jobs (idempotency_key)
    WHERE idempotency_key IS NOT NULL;
