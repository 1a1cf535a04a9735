#!/usr/bin/env bash
# S3 artifacts (tests/s3_artifacts.rs, built with `--features s3`) against a local
# S3-compatible server: moto's server from the Python package index, in a virtual environment
# under the target directory, on a free loopback port. Its boto3 is the test's independent S3
# client. Outside CI it skips (exit 0, with a loud message) only when moto cannot be installed
# because the package index is unreachable; under CI (`CI=true`, as .ci/run sets) that is a
# failure too: a CI run that could not test S3 must not pass. Any other failure, or a skipped
# test, fails.
set -euo pipefail
cd "$(dirname "$0")/../.."
ROOT=$PWD
TARGET=${CARGO_TARGET_DIR:-$ROOT/target}
VENV=$TARGET/s3-venv
MOTO_VERSION=5.2.5

if ! "$VENV/bin/python" -c "import moto, boto3, sys; sys.exit(moto.__version__ != '$MOTO_VERSION')" 2>/dev/null; then
    rm -rf "$VENV"
    python3 -m venv "$VENV"
    if ! "$VENV/bin/pip" install --quiet --disable-pip-version-check "moto[server]==$MOTO_VERSION"; then
        if ! "$VENV/bin/pip" index versions moto >/dev/null 2>&1; then
            if [ "${CI:-}" = true ]; then
                echo "tests/s3/run.sh: FAILED under CI: the Python package index is unreachable, so no S3 server (moto) could be installed; S3 artifacts were NOT tested" >&2
                exit 1
            fi
            echo "SKIPPED tests/s3/run.sh: the Python package index is unreachable, so no S3 server (moto) could be installed; S3 artifacts were NOT tested (CI=true makes this a failure)" >&2
            exit 0
        fi
        echo "tests/s3/run.sh: installing moto[server]==$MOTO_VERSION failed" >&2
        exit 1
    fi
fi

WORK=$(mktemp -d /tmp/ashlar-s3.XXXXXX)
PORT=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
"$VENV/bin/moto_server" -H 127.0.0.1 -p "$PORT" >"$WORK/moto.log" 2>&1 &
MOTO=$!
cleanup() {
    kill "$MOTO" 2>/dev/null || true
    wait "$MOTO" 2>/dev/null || true
    rm -rf "$WORK"
}
trap cleanup EXIT

export AWS_ACCESS_KEY_ID=ashlar-test AWS_SECRET_ACCESS_KEY=ashlar-test-secret AWS_REGION=us-east-1
export ASHLAR_TEST_S3_ENDPOINT="http://127.0.0.1:$PORT"
export ASHLAR_TEST_S3_BUCKET=ashlar-artifacts
export ASHLAR_TEST_S3_PYTHON="$VENV/bin/python"
# Wait for the server, then create the bucket (object_store does not create buckets).
"$VENV/bin/python" - <<'EOF'
import os, time, boto3
s3 = boto3.client("s3", endpoint_url=os.environ["ASHLAR_TEST_S3_ENDPOINT"])
for attempt in range(100):
    try:
        s3.create_bucket(Bucket=os.environ["ASHLAR_TEST_S3_BUCKET"])
        break
    except Exception as e:  # not listening yet
        if attempt == 99:
            raise
        time.sleep(0.2)
print("tests/s3/run.sh: moto S3 server on", os.environ["ASHLAR_TEST_S3_ENDPOINT"])
EOF

LOG="$WORK/test.log"
set +e
cargo test --locked --features s3 --test s3_artifacts -- --test-threads=1 --nocapture "$@" 2>&1 | tee "$LOG"
status=${PIPESTATUS[0]}
set -e
if grep -q "SKIPPED" "$LOG"; then
    echo "tests/s3/run.sh: tests were skipped although an S3 server was started" >&2
    exit 1
fi
exit "$status"
