# Sourced by tests/pg/run.sh and scripts/cluster_bench.sh: starts a throwaway PostgreSQL on
# loopback and exports ASHLAR_TEST_DATABASE_URL; the cluster is removed when the shell exits.
# Installs Debian's `postgresql` package if no server binaries are found. The cluster lives in
# a temporary directory owned by an unprivileged user when run as root (postgres refuses to run
# as root), on a free port, with a unix socket in the same directory.

find_bin() {
    local d
    for d in "$(pg_config --bindir 2>/dev/null || true)" /usr/lib/postgresql/*/bin /usr/local/bin /usr/bin; do
        if [ -n "$d" ] && [ -x "$d/initdb" ] && [ -x "$d/pg_ctl" ] && [ -x "$d/postgres" ]; then
            echo "$d"
            return 0
        fi
    done
    return 1
}

BIN="$(find_bin || true)"
if [ -z "$BIN" ]; then
    echo "tests/pg/server.sh: installing PostgreSQL from Debian's packages"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq postgresql >/dev/null
    BIN="$(find_bin)"
fi
echo "tests/pg/server.sh: PostgreSQL binaries in $BIN ($("$BIN/postgres" --version))"

TMP="$(mktemp -d /tmp/ashlar-pg.XXXXXX)"
RUN=()
if [ "$(id -u)" = 0 ]; then
    # postgres will not run as root: a dedicated system user owns the throwaway cluster.
    id ashlarpg >/dev/null 2>&1 || useradd --system --no-create-home --shell /usr/sbin/nologin ashlarpg
    chown ashlarpg "$TMP"
    chmod 755 "$TMP"
    RUN=(runuser -u ashlarpg --)
fi
PORT="${ASHLAR_PG_PORT:-$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')}"

stop() {
    "${RUN[@]}" "$BIN/pg_ctl" -D "$TMP/data" -m immediate stop >/dev/null 2>&1 || true
    rm -rf "$TMP"
}
trap stop EXIT

"${RUN[@]}" "$BIN/initdb" -D "$TMP/data" -U ashlar --auth=trust -E UTF8 --no-sync >"$TMP/initdb.log" 2>&1 \
    || { cat "$TMP/initdb.log"; exit 1; }
# fsync off: a throwaway cluster; the tests kill workers, not the database server.
"${RUN[@]}" "$BIN/pg_ctl" -D "$TMP/data" -l "$TMP/server.log" -w -t 60 \
    -o "-p $PORT -k $TMP -c listen_addresses=127.0.0.1 -c fsync=${ASHLAR_PG_FSYNC:-off} -c max_connections=300" start >/dev/null \
    || { cat "$TMP/server.log"; exit 1; }

export ASHLAR_TEST_DATABASE_URL="postgresql://ashlar@127.0.0.1:$PORT/postgres"
echo "tests/pg/server.sh: PostgreSQL on 127.0.0.1:$PORT"
