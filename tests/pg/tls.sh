#!/usr/bin/env bash
# TLS to PostgreSQL (tests/service/pg_tls.rs): a throwaway cluster (server.sh) switched to `ssl = on`
# with a certificate from a CA made here by `openssl`, and a pg_hba.conf that accepts TCP
# clients over TLS only (`hostssl`). Fails if the tests were skipped.
set -euo pipefail
cd "$(dirname "$0")/../.."
if ! command -v openssl >/dev/null 2>&1; then
    echo "tests/pg/tls.sh: installing openssl from Debian's packages"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq openssl >/dev/null
fi
source tests/pg/server.sh

# The certificates: a CA, a server certificate it signs for DNS name `localhost` only (so
# 127.0.0.1 passes verify-ca but not verify-full), and an unrelated CA for the "wrong CA" case.
CERTS="$TMP/certs"
mkdir -p "$CERTS"
(
    cd "$CERTS"
    openssl req -x509 -newkey rsa:2048 -nodes -days 2 -subj "/CN=ashlar test CA" \
        -keyout ca.key -out ca.pem 2>/dev/null
    openssl req -x509 -newkey rsa:2048 -nodes -days 2 -subj "/CN=some other CA" \
        -keyout wrong-ca.key -out wrong-ca.pem 2>/dev/null
    openssl req -newkey rsa:2048 -nodes -subj "/CN=localhost" \
        -keyout server.key -out server.csr 2>/dev/null
    printf 'subjectAltName=DNS:localhost\nbasicConstraints=CA:FALSE\nkeyUsage=digitalSignature,keyEncipherment\nextendedKeyUsage=serverAuth\n' > server.ext
    openssl x509 -req -in server.csr -CA ca.pem -CAkey ca.key -CAcreateserial -days 2 \
        -extfile server.ext -out server.crt 2>/dev/null
    # A client certificate for user `ashlar` (database `certdb` demands one: `cert` below).
    openssl req -newkey rsa:2048 -nodes -subj "/CN=ashlar" \
        -keyout client.key -out client.csr 2>/dev/null
    printf 'basicConstraints=CA:FALSE\nkeyUsage=digitalSignature,keyEncipherment\nextendedKeyUsage=clientAuth\n' > client.ext
    openssl x509 -req -in client.csr -CA ca.pem -CAkey ca.key -CAcreateserial -days 2 \
        -extfile client.ext -out client.crt 2>/dev/null
    # Revocation lists (`sslcrl`) signed by the CA: one revoking nothing, one revoking the
    # server's certificate.
    printf '[ca]\ndefault_ca = test_ca\n[test_ca]\ndatabase = index.txt\ncrlnumber = crlnumber\ndefault_md = sha256\ndefault_crl_days = 2\n' > crl.cnf
    : > index.txt
    echo 01 > crlnumber
    openssl ca -batch -config crl.cnf -keyfile ca.key -cert ca.pem -gencrl -out empty.crl 2>/dev/null
    openssl ca -batch -config crl.cnf -keyfile ca.key -cert ca.pem -revoke server.crt 2>/dev/null
    openssl ca -batch -config crl.cnf -keyfile ca.key -cert ca.pem -gencrl -out revoked.crl 2>/dev/null
)
DATA="$TMP/data"
cp "$CERTS/server.crt" "$CERTS/server.key" "$CERTS/ca.pem" "$DATA/"
chmod 600 "$DATA/server.key"
if [ "${#RUN[@]}" -gt 0 ]; then chown ashlarpg "$DATA/server.crt" "$DATA/server.key" "$DATA/ca.pem"; fi
chmod -R a+rX "$CERTS"
cat >> "$DATA/postgresql.conf" <<EOF
ssl = on
ssl_cert_file = 'server.crt'
ssl_key_file = 'server.key'
ssl_ca_file = 'ca.pem'
EOF
# TCP only over TLS, except database `plaindb` (TLS or plain text) and `nossldb` (plain text
# only: libpq's `prefer` retry); the Unix socket stays open for the test harness's own set-up.
cat > "$DATA/pg_hba.conf" <<EOF
local   all    all                trust
hostssl certdb all 127.0.0.1/32   cert
hostssl certdb all ::1/128        cert
host      plaindb all 127.0.0.1/32 trust
hostssl   nossldb all 127.0.0.1/32 reject
hostnossl nossldb all 127.0.0.1/32 trust
hostssl all    all 127.0.0.1/32   trust
hostssl all    all ::1/128        trust
EOF
"${RUN[@]}" "$BIN/pg_ctl" -D "$DATA" -w -t 60 restart -l "$TMP/server.log" \
    -o "-p $PORT -k $TMP -c listen_addresses=127.0.0.1 -c fsync=off -c max_connections=300" >/dev/null \
    || { cat "$TMP/server.log"; exit 1; }
echo "tests/pg/tls.sh: PostgreSQL with ssl = on, hostssl only, on 127.0.0.1:$PORT"

export ASHLAR_TEST_TLS_PORT="$PORT"
export ASHLAR_TEST_TLS_CERTS="$CERTS"
LOG="$TMP/tls-test.log"
set +e
cargo test --locked --test service pg_tls:: -- --test-threads=2 --nocapture "$@" 2>&1 | tee "$LOG"
status=${PIPESTATUS[0]}
set -e
if grep -q "SKIPPED" "$LOG"; then
    echo "tests/pg/tls.sh: tests were skipped although a server was started" >&2
    exit 1
fi
exit "$status"
