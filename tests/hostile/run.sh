#!/usr/bin/env bash
# Hostile-client suite (docs/service.md): the real `ashlar serve` binary on loopback against the
# attacks of the issue (work budgets, huge and slow bodies, impossible values, huge artifacts
# read by ranges, half-sent requests, queue-limit races, wall-clock and disk limits). Asserts
# each refusal, that the server stays up, and its peak RSS under 300 MB; prints /healthz
# latency through the suite. Needs python3 (standard library only). Exits non-zero on failure.
set -euo pipefail
cd "$(dirname "$0")/../.."
TARGET=${CARGO_TARGET_DIR:-$PWD/target}
cargo build --locked --quiet --bin ashlar
exec python3 tests/hostile/hostile.py "$TARGET/debug/ashlar"
