-- Schema version 4: the limits each process of a cluster enforces, published at start and
-- refreshed by its keeper thread (every lease/2), so that an API-only process
-- (`ashlar serve --workers 0`) reports in `GET /v1/limits` the limits its workers apply, and a
-- worker can tell at start that its flags differ from the API's. `limits` is a JSON object
-- (text); `role` is `api` (it takes submissions) or `worker` (it runs jobs).
CREATE TABLE process_limits (
    process TEXT NOT NULL,
    role TEXT NOT NULL,
    limits TEXT NOT NULL,
    seen_at TIMESTAMPTZ NOT NULL DEFAULT now(),
    PRIMARY KEY (process, role)
);
