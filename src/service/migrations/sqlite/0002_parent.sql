-- Schema version 2: fanned-out PGA searches. `parent` links a search's child runs to it.
ALTER TABLE jobs ADD COLUMN parent TEXT;
CREATE INDEX IF NOT EXISTS jobs_parent ON jobs(parent) WHERE parent IS NOT NULL;
