#!/usr/bin/env bash
# Cluster throughput benchmark (not a test): starts a throwaway PostgreSQL (fsync on, like the
# embedded store's synchronous=FULL), builds ashlar, runs scripts/cluster_bench.py.
#   bash scripts/cluster_bench.sh [JOBS]          # PROFILE=release for release numbers
#   BENCH=fanout bash scripts/cluster_bench.sh    # only the fanned-out PGA search rows
set -euo pipefail
cd "$(dirname "$0")/.."
PROFILE="${PROFILE:-dev}"
cargo build --locked --profile "$PROFILE" --bin ashlar
DIR=debug; [ "$PROFILE" = dev ] || DIR="$PROFILE"
export ASHLAR_PG_FSYNC=on
source tests/pg/server.sh
export PATH="$BIN:$PATH"
python3 -u scripts/cluster_bench.py "target/$DIR/ashlar" "$ASHLAR_TEST_DATABASE_URL" "$@"
