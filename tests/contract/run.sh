#!/usr/bin/env bash
# Contract test: the real `ashlar serve` binary checked against openapi.yaml by schemathesis,
# with every check enabled. Installs schemathesis (pinned) from the Python package index into a
# virtual environment under the target directory, starts the server on a free loopback port with
# a temporary data directory, runs the tests, stops the server. Exits non-zero on any failure.
#
# Usage: tests/contract/run.sh [extra schemathesis options]
#   ASHLAR_CONTRACT_MAX_EXAMPLES  examples per operation (default 40; the run takes about 2 min)
#   ASHLAR_CONTRACT_TOKEN_MAX_EXAMPLES  examples per operation of the second run, against a server
#                                 started with --tokens and a user token (default 8; under a minute)
set -euo pipefail
cd "$(dirname "$0")/../.."
ROOT=$PWD
TARGET=${CARGO_TARGET_DIR:-$ROOT/target}
VENV=$TARGET/contract-venv
SCHEMATHESIS_VERSION=4.32.5

# CPython 3.11's ast.parse can fail with "AST constructor recursion depth mismatch" when called
# from several threads at once (hypothesis does, under schemathesis workers): prefer a newer
# interpreter when there is one, and run schemathesis with one worker.
PYTHON=python3
for p in python3.13 python3.12; do
    if command -v "$p" >/dev/null 2>&1 && "$p" -c 'import venv' 2>/dev/null; then PYTHON=$p; break; fi
done
if ! "$VENV/bin/schemathesis" --version 2>/dev/null | grep -q "$SCHEMATHESIS_VERSION"; then
    rm -rf "$VENV"
    "$PYTHON" -m venv "$VENV"
    "$VENV/bin/pip" install --quiet --disable-pip-version-check "schemathesis==$SCHEMATHESIS_VERSION" \
        || { echo "contract: FAILED: schemathesis $SCHEMATHESIS_VERSION could not be installed from the Python package index; the HTTP contract was NOT tested" >&2; exit 1; }
fi

cargo build --locked --quiet --bin ashlar
BIN=$TARGET/debug/ashlar

WORK=$(mktemp -d)
"$BIN" serve --addr 127.0.0.1:0 --data "$WORK/data" --workers 1 >"$WORK/stdout" 2>"$WORK/server.log" &
PID=$!
PID2=""
cleanup() {
    kill -TERM "$PID" 2>/dev/null || true
    wait "$PID" 2>/dev/null || true
    if [ -n "$PID2" ]; then
        kill -TERM "$PID2" 2>/dev/null || true
        wait "$PID2" 2>/dev/null || true
    fi
    rm -rf "$WORK"
}
trap cleanup EXIT

ADDR=""
for _ in $(seq 1 200); do
    ADDR=$(sed -n 's/^ashlar serve: listening on //p' "$WORK/stdout")
    [ -n "$ADDR" ] && break
    kill -0 "$PID" 2>/dev/null || { cat "$WORK/server.log" >&2; echo "contract: the server did not start" >&2; exit 1; }
    sleep 0.05
done
[ -n "$ADDR" ] || { echo "contract: the server did not report its address" >&2; exit 1; }

# Positive contract: known-valid requests are accepted. Every bundled example scene (GET
# /v1/examples, what the web page offers) with every bundled motion is submitted as a job and
# must be answered 202; every bundled motion must be inspectable (200). schemathesis alone
# accepts 422 for generated bodies (the schema cannot say what makes a scene valid), so without
# this a server refusing every valid scene would pass.
"$VENV/bin/python" - "$ADDR" <<'EOF_POSITIVE' || { echo "contract: a known-valid request was refused (see above)" >&2; tail -n 20 "$WORK/server.log" >&2; exit 1; }
import json, sys, urllib.error, urllib.request
addr = sys.argv[1]
def call(method, path, body=None):
    data = None if body is None else json.dumps(body).encode()
    req = urllib.request.Request(addr + path, data=data, method=method,
                                 headers={"content-type": "application/json"})
    try:
        with urllib.request.urlopen(req, timeout=30) as r:
            return r.status, r.read().decode()
    except urllib.error.HTTPError as e:
        return e.code, e.read().decode()
status, text = call("GET", "/v1/examples")
assert status == 200, f"GET /v1/examples: {status} {text}"
items = json.loads(text)["examples"]
get = lambda e: json.loads(call("GET", e["url"])[1])
scenes = [(e["name"], get(e)) for e in items if e["kind"] == "scene"]
motions = [(e["name"], get(e)) for e in items if e["kind"] == "motion"]
assert scenes and motions, f"no bundled scenes or motions: {items}"
failed = []
accepted = []
for mname, motion in motions:
    status, text = call("POST", "/v1/motions/inspect", motion)
    print(f"contract: POST /v1/motions/inspect {mname}: {status}")
    if status != 200:
        failed.append(f"inspect {mname}: {status} {text[:300]}")
    for sname, scene in scenes:
        status, text = call("POST", "/v1/jobs", {"scene": scene, "motion": motion})
        print(f"contract: POST /v1/jobs {sname} + {mname}: {status}")
        if status != 202:
            failed.append(f"job {sname} + {mname}: {status} {text[:300]}")
        else:
            accepted.append(json.loads(text)["links"]["cancel"])
# A site analysis (docs/observations.md's two columns, A fell and B stands, under the bundled
# pulse) is accepted and runs to a result of the documented shape.
import time
# The runs above were only to be accepted: cancelled, so the one worker takes this next.
for url in accepted:
    call("POST", url)
scene = dict(scenes)["two-columns"]
body = {"scene": scene, "motions": [dict(motions)["half-sine-pulse"]],
        "observations": [{"criterion": "toppled:A", "observed": True},
                         {"criterion": {"kind": "fallen", "blocks": ["B"]}, "observed": False}],
        "range": {"min": 2, "max": 12, "units": "m/s2"}, "tolerance": 1, "scan_points": 3}
status, text = call("POST", "/v1/site-analyses", body)
print(f"contract: POST /v1/site-analyses two-columns + half-sine-pulse: {status}")
if status != 202:
    failed.append(f"site analysis: {status} {text[:300]}")
else:
    url = json.loads(text)["links"]["self"]
    for _ in range(1500):
        job = json.loads(call("GET", url)[1])
        if job["status"] in ("succeeded", "failed", "cancelled"):
            break
        time.sleep(0.2)
    res = job.get("result") or {}
    print(f"contract: site analysis {job['status']}: {[(r['lower'], r['upper']) for r in res.get('records', [])]}")
    if job["status"] != "succeeded" or len(res.get("records", [])) != 1 or "assumes" not in res.get("distribution", {}):
        failed.append(f"site analysis ended {job['status']}: {json.dumps(job)[:300]}")
for f in failed:
    print("contract: REFUSED a valid request:", f, file=sys.stderr)
sys.exit(1 if failed else 0)
EOF_POSITIVE

set +e
# Run from the temporary directory: schemathesis keeps a cache (.schemathesis/) in its working
# directory, which must not land in the source tree.
cd "$WORK"
"$VENV/bin/schemathesis" --no-color --config-file "$ROOT/tests/contract/schemathesis.toml" run "$ADDR/openapi.yaml" \
    --url "$ADDR" \
    --checks all \
    --max-examples "${ASHLAR_CONTRACT_MAX_EXAMPLES:-40}" \
    --seed 1 \
    --workers 1 \
    "$@"
STATUS=$?
set -e
if [ "$STATUS" -ne 0 ]; then
    echo "--- server log (tail) ---" >&2
    tail -n 50 "$WORK/server.log" >&2
    exit "$STATUS"
fi

# Second run: the same contract against a server started with --tokens, every request carrying
# a user token (docs/service.md, "Access"). Fewer examples and no coverage phase (its ~50 s of
# boundary values do not depend on the token and ran above): it checks that authentication and
# ownership change nothing of the contract for a token's own jobs. Before it: without a token
# 401 problem+json, and another token's job 404.
printf 'user contract-user-token-0001\nuser contract-user-token-0002\nadmin contract-admin-token-01\n' >"$WORK/tokens"
"$BIN" serve --addr 127.0.0.1:0 --data "$WORK/data2" --workers 1 --tokens "$WORK/tokens" >"$WORK/stdout2" 2>"$WORK/server2.log" &
PID2=$!
ADDR2=""
for _ in $(seq 1 200); do
    ADDR2=$(sed -n 's/^ashlar serve: listening on //p' "$WORK/stdout2")
    [ -n "$ADDR2" ] && break
    kill -0 "$PID2" 2>/dev/null || { cat "$WORK/server2.log" >&2; echo "contract: the server with --tokens did not start" >&2; exit 1; }
    sleep 0.05
done
[ -n "$ADDR2" ] || { echo "contract: the server with --tokens did not report its address" >&2; exit 1; }
"$VENV/bin/python" - "$ADDR2" "$ROOT" <<'EOF_TOKENS' || { echo "contract: access control with --tokens failed (see above)" >&2; exit 1; }
import json, sys, urllib.error, urllib.request
addr, root = sys.argv[1], sys.argv[2]
def call(method, path, token=None, body=None):
    h = {"content-type": "application/json"}
    if token:
        h["authorization"] = "Bearer " + token
    data = None if body is None else json.dumps(body).encode()
    req = urllib.request.Request(addr + path, data=data, method=method, headers=h)
    try:
        with urllib.request.urlopen(req, timeout=30) as r:
            return r.status, r.headers, r.read().decode()
    except urllib.error.HTTPError as e:
        return e.code, e.headers, e.read().decode()
st, h, _ = call("GET", "/v1/jobs")
assert st == 401 and h.get("content-type") == "application/problem+json", f"no token: {st}"
load = lambda n: json.load(open(f"{root}/examples/{n}"))
st, _, text = call("POST", "/v1/jobs", "contract-user-token-0001",
                   {"scene": load("column.json"), "motion": load("half-sine-pulse.json")})
assert st == 202, f"submit with a token: {st} {text}"
jid = json.loads(text)["id"]
st, _, _ = call("GET", f"/v1/jobs/{jid}", "contract-user-token-0002")
assert st == 404, f"another user's job: {st}"
st, _, text = call("GET", f"/v1/jobs/{jid}", "contract-admin-token-01")
assert st == 200 and "signed_links" in json.loads(text), f"the admin reads it, with signed links: {st}"
site = {"scene": load("two-columns.json"), "motions": [load("half-sine-pulse.json")],
        "observations": [{"criterion": "toppled:A", "observed": True}],
        "range": {"min": 2, "max": 12}, "tolerance": 5, "scan_points": 2}
st, _, text = call("POST", "/v1/site-analyses", "contract-user-token-0001", site)
assert st == 202, f"a site analysis with a token: {st} {text}"
sid = json.loads(text)["id"]
st, _, _ = call("GET", f"/v1/site-analyses/{sid}", "contract-user-token-0002")
assert st == 404, f"another user's site analysis: {st}"
st, _, _ = call("GET", f"/v1/site-analyses/{sid}", "contract-user-token-0001")
assert st == 200, f"its owner's site analysis: {st}"
print("contract: --tokens: 401 without a token, 404 for another user's job, 200 for the admin")
EOF_TOKENS
set +e
"$VENV/bin/schemathesis" --no-color --config-file "$ROOT/tests/contract/schemathesis.toml" run "$ADDR2/openapi.yaml" \
    --url "$ADDR2" \
    --header "Authorization: Bearer contract-user-token-0001" \
    --checks all \
    --max-examples "${ASHLAR_CONTRACT_TOKEN_MAX_EXAMPLES:-8}" \
    --phases examples,fuzzing,stateful \
    --seed 2 \
    --workers 1 \
    "$@"
STATUS=$?
set -e
if [ "$STATUS" -ne 0 ]; then
    echo "--- server with --tokens log (tail) ---" >&2
    tail -n 50 "$WORK/server2.log" >&2
fi
exit "$STATUS"
