-- Schema version 2: many worker processes. A claimed job carries a lease (token, owner,
-- expiry) that the owner's heartbeat extends; every claim is logged in job_attempts so that
-- "who ran what, and how did it end" survives crashes; `parent` links the child runs of a
-- fanned-out search to their search.
ALTER TABLE jobs
    ADD COLUMN lease_token UUID,
    ADD COLUMN lease_until TIMESTAMPTZ,
    ADD COLUMN worker TEXT,
    ADD COLUMN parent UUID;
CREATE INDEX jobs_leases ON jobs (lease_until) WHERE status = 'running';
CREATE INDEX jobs_parent ON jobs (parent) WHERE parent IS NOT NULL;
CREATE TABLE job_attempts (
    token UUID PRIMARY KEY,
    job_id UUID NOT NULL REFERENCES jobs (id) ON DELETE CASCADE,
    worker TEXT NOT NULL,
    claimed_at TIMESTAMPTZ NOT NULL DEFAULT now(),
    ended_at TIMESTAMPTZ,
    -- succeeded | failed | cancelled | requeued | expired; NULL while running.
    outcome TEXT
);
CREATE INDEX job_attempts_job ON job_attempts (job_id);
