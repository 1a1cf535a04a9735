#!/usr/bin/env bash
# End-to-end test of the web page: the real `ashlar serve` binary driven by headless Chromium
# (Debian's `chromium` package) through playwright-core (npm, pinned in package-lock.json).
# Installs Chromium with apt when it is missing and the npm dependencies, builds and starts the
# server on a free loopback port with a temporary data directory, runs tests/web/e2e.mjs, stops
# the server. Exits non-zero on any failure.
#
#   ASHLAR_SCREENSHOT  where to write the screenshot of the finished run
#                      (default target/web-screenshot.png; docs/web-screenshot.png is a copy)
#   ASHLAR_BIN         use this ashlar binary instead of building one
set -euo pipefail
cd "$(dirname "$0")/../.."
ROOT=$PWD
TARGET=${CARGO_TARGET_DIR:-$ROOT/target}

if ! command -v chromium >/dev/null 2>&1; then
    SUDO=""
    [ "$(id -u)" -eq 0 ] || SUDO=sudo
    $SUDO apt-get update -q
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q chromium
fi
(cd tests/web && npm ci --no-audit --no-fund --loglevel=error)

if [ -n "${ASHLAR_BIN:-}" ]; then
    BIN=$ASHLAR_BIN
else
    cargo build --locked --quiet --bin ashlar
    BIN=$TARGET/debug/ashlar
fi

# One of the repository's recorded ground motions.
RECORD=$ROOT/data/ground-motions/friuli-1976-tolmezzo-000.at2

WORK=$(mktemp -d)
PIDS=()
cleanup() {
    for pid in "${PIDS[@]}"; do kill -TERM "$pid" 2>/dev/null || true; done
    for pid in "${PIDS[@]}"; do wait "$pid" 2>/dev/null || true; done
    rm -rf "$WORK"
}
trap cleanup EXIT

# start_server NAME ARGS...: `ashlar serve` on a free loopback port, its address in ADDR.
start_server() {
    local name=$1
    shift
    # Created before the server starts: the loop below may read it before the server's shell opens it.
    : >"$WORK/$name.stdout"
    "$BIN" serve --addr 127.0.0.1:0 --data "$WORK/$name-data" --workers 1 "$@" >"$WORK/$name.stdout" 2>"$WORK/$name.log" &
    local pid=$!
    PIDS+=("$pid")
    ADDR=""
    for _ in $(seq 1 200); do
        ADDR=$(sed -n 's/^ashlar serve: listening on //p' "$WORK/$name.stdout")
        [ -n "$ADDR" ] && return 0
        kill -0 "$pid" 2>/dev/null || { cat "$WORK/$name.log" >&2; echo "web e2e: the $name server did not start" >&2; exit 1; }
        sleep 0.05
    done
    echo "web e2e: the $name server did not report its address" >&2
    exit 1
}

# A second server that asks for a token (the page's token prompt, docs/service.md --tokens).
TOKEN=web-e2e-token-$RANDOM$RANDOM-0123456789
echo "user $TOKEN" >"$WORK/tokens"
start_server tokens --tokens "$WORK/tokens"
ADDR_TOKENS=$ADDR
start_server server

# The bundled column with its column reduced to a segment: the server must name the field.
python3 - "$ROOT/examples/column.json" "$WORK/bad-scene.json" <<'PY'
import json, sys
scene = json.load(open(sys.argv[1]))
scene["blocks"][1]["vertices"] = [[-0.2, 0.0], [0.2, 0.0]]
json.dump(scene, open(sys.argv[2], "w"))
PY

set +e
ASHLAR_URL=$ADDR ASHLAR_URL_TOKENS=$ADDR_TOKENS ASHLAR_TOKEN=$TOKEN ASHLAR_RECORD=$RECORD ASHLAR_SCENE_BAD=$WORK/bad-scene.json \
ASHLAR_SCREENSHOT=${ASHLAR_SCREENSHOT:-$TARGET/web-screenshot.png} \
    node tests/web/e2e.mjs
STATUS=$?
set -e
# The server's log went to a file: plain text, no ANSI colour codes (those are for a terminal).
if grep -q $'\x1b' "$WORK/server.log"; then
    echo "FAIL the server's log file holds ANSI escape codes:" >&2
    head -n 3 "$WORK/server.log" | cat -v >&2
    STATUS=1
else
    echo "ok   the server's log file is plain text (no ANSI escape codes)"
fi
if [ "$STATUS" -ne 0 ]; then
    echo "--- server log (tail) ---" >&2
    tail -n 40 "$WORK/server.log" >&2
fi
exit "$STATUS"
