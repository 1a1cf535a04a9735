-- Schema version 3: ownership (`ashlar serve --tokens`). `owner` is the owner id of the token
-- that submitted a job (never the token); NULL when the server ran without tokens (only an
-- admin token then sees the job). Child runs carry their search's owner.
ALTER TABLE jobs ADD COLUMN owner TEXT;
CREATE INDEX jobs_owner ON jobs (owner, seq) WHERE owner IS NOT NULL;
CREATE INDEX jobs_finished ON jobs (finished_ms) WHERE parent IS NULL;
