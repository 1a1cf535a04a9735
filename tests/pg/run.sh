#!/usr/bin/env bash
# Runs the PostgreSQL cluster tests (tests/service/pg_cluster/) and the store contract on both
# stores (tests/service/store_contract.rs) against a throwaway PostgreSQL on
# loopback (see server.sh). Fails if the tests were skipped.
set -euo pipefail
cd "$(dirname "$0")/../.."
source tests/pg/server.sh
LOG="$TMP/test.log"
# Two test threads: the cluster tests spawn their own worker processes.
set +e
cargo test --locked --test service -- pg_cluster:: store_contract:: --test-threads=2 --nocapture "$@" 2>&1 | tee "$LOG"
status=${PIPESTATUS[0]}
set -e
if grep -q "SKIPPED" "$LOG"; then
    echo "tests/pg/run.sh: tests were skipped although a server was started" >&2
    exit 1
fi
exit "$status"
