-- As migrations/sqlite/0005: claims of a job since its checkpoint last
-- moved on, which --max-attempts bounds.
ALTER TABLE jobs ADD COLUMN stalled_attempts BIGINT NOT NULL DEFAULT 0;
UPDATE jobs SET stalled_attempts = attempts;
