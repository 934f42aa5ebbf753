#!/usr/bin/env bash
# Starts a private PostgreSQL cluster for the records tests (issue 14) and
# prints, on stdout, the lines to eval:
#   export ECHOTHIGH_TEST_POSTGRES=postgres://echothigh@127.0.0.1:PORT/echothigh_test
#   export ECHOTHIGH_PG_DATA=DIR      (stop it with: pg_ctl -D "$ECHOTHIGH_PG_DATA" stop)
# Usage: eval "$(.ci/postgres.sh)"; stop: .ci/postgres.sh --stop. Installs Debian's `postgresql` when no
# server binaries are found. The cluster lives in a fresh temp directory,
# listens on loopback only (127.0.0.1, first free port from 55432) and
# trusts local connections (a throwaway test cluster). initdb refuses root,
# so as root it runs as the `postgres` user. Progress goes to stderr.
set -euo pipefail

log() { echo "postgres.sh: $*" >&2; }
as_root() {
  if [ "$(id -u)" = 0 ]; then "$@"; else sudo "$@"; fi
}
pg_bin() { ls -d /usr/lib/postgresql/*/bin 2>/dev/null | sort -V | tail -n 1; }

if [ "${1:-}" = --stop ]; then
  # Stops the cluster started earlier (its data directory in ECHOTHIGH_PG_DATA).
  [ -n "${ECHOTHIGH_PG_DATA:-}" ] || exit 0
  if [ "$(id -u)" = 0 ]; then stop=(runuser -u postgres --); else stop=(); fi
  "${stop[@]}" "$(pg_bin)/pg_ctl" -D "$ECHOTHIGH_PG_DATA" -m fast -w stop >&2 || true
  exit 0
fi

bin="$(pg_bin)"
if [ -z "$bin" ] || [ ! -x "$bin/initdb" ]; then
  log "installing Debian's postgresql"
  as_root env DEBIAN_FRONTEND=noninteractive apt-get update -q >&2
  as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends postgresql >&2
  bin="$(pg_bin)"
fi
[ -x "$bin/initdb" ] || { log "no initdb after installing postgresql"; exit 1; }

dir="$(mktemp -d /tmp/echothigh-pg.XXXXXX)"
run=()
if [ "$(id -u)" = 0 ]; then
  chown postgres: "$dir"
  run=(runuser -u postgres --)
fi

port=55432
while (echo >"/dev/tcp/127.0.0.1/$port") 2>/dev/null; do
  port=$((port + 1))
  [ "$port" -lt 55532 ] || { log "no free port in 55432..55531"; exit 1; }
done

log "initdb in $dir/data (port $port)"
"${run[@]}" "$bin/initdb" -D "$dir/data" -U echothigh -A trust --no-sync -E UTF8 >&2
"${run[@]}" "$bin/pg_ctl" -D "$dir/data" -l "$dir/server.log" -w -t 60 \
  -o "-p $port -k $dir -c listen_addresses=127.0.0.1 -c fsync=off" start >&2
"${run[@]}" "$bin/createdb" -h 127.0.0.1 -p "$port" -U echothigh echothigh_test >&2
log "PostgreSQL $("$bin/postgres" --version | awk '{print $3}') up on 127.0.0.1:$port"
echo "export ECHOTHIGH_TEST_POSTGRES=postgres://echothigh@127.0.0.1:$port/echothigh_test"
echo "export ECHOTHIGH_PG_DATA=$dir/data"
