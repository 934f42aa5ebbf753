#!/usr/bin/env bash
# Real-browser tests of `echothigh view` (issue 8) and of a trainee's exam
# session recorded in a database (`echothigh exam --trainee`, issue 14), called by .ci/run.
# Installs Debian's chromium (apt-get) and the pinned playwright-core (npm ci in
# web/), builds the binary, starts `echothigh view --port 0`, runs
# tests/browser/viewer.test.mjs against the URL it prints, and saves the
# screenshots and the server's log under target/browser-screenshots/. The
# server is stopped at the end, on failure too.
# Environment: CARGO_TARGET_DIR (default target), ECHOTHIGH_PROFILE (dev|release, default dev).
set -euo pipefail
cd "$(dirname "$0")/.."
root="$(pwd)"
shots="$root/target/browser-screenshots"
mkdir -p "$shots"

as_root() {
  if [ "$(id -u)" = 0 ]; then "$@"; else sudo "$@"; fi
}
apt_install() {
  as_root env DEBIAN_FRONTEND=noninteractive apt-get update -q
  as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends "$@"
}

if [ ! -x /usr/bin/chromium ]; then
  echo "browser-test: installing Debian's chromium"
  apt_install chromium
fi
if ! command -v npm >/dev/null; then
  echo "browser-test: installing node and npm"
  apt_install nodejs npm
fi
echo "browser-test: $(/usr/bin/chromium --version 2>/dev/null || echo 'chromium (version unknown)'), node $(node --version)"
(cd web && npm ci --no-audit --no-fund)

profile="${ECHOTHIGH_PROFILE:-dev}"
cargo build -p echothigh --profile "$profile"
target_dir="${CARGO_TARGET_DIR:-$root/target}"
if [ "$profile" = dev ]; then bin="$target_dir/debug/echothigh"; else bin="$target_dir/$profile/echothigh"; fi

out="$(mktemp)"
server=""
cleanup() {
  [ -n "$server" ] && kill "$server" 2>/dev/null || true
  [ -n "$server" ] && wait "$server" 2>/dev/null || true
  rm -f "$out"
}
trap cleanup EXIT

# Starts `echothigh ARGS... --port 0` in the background (its pid in $server,
# its stderr in $shots/LOG) and waits up to 60 s for the URL it prints (in $url).
start_server() {
  local name="$1" log="$2"
  shift 2
  "$bin" "$@" --port 0 >"$out" 2>"$shots/$log" &
  server=$!
  url=""
  for _ in $(seq 1 600); do
    url="$(sed -n 's/^echothigh viewer: \(http[^ ]*\)$/\1/p' "$out" | head -n 1)"
    [ -n "$url" ] && return 0
    if ! kill -0 "$server" 2>/dev/null; then
      echo "browser-test: echothigh $name exited before serving; its log:" >&2
      cat "$shots/$log" >&2
      exit 1
    fi
    sleep 0.1
  done
  echo "browser-test: no URL from echothigh $name within 60 s" >&2
  exit 1
}

start_server view server.log view
echo "browser-test: server at $url"

ECHOTHIGH_URL="$url" SCREENSHOT_DIR="$shots" CHROMIUM=/usr/bin/chromium ECHOTHIGH_SERVER_PID="$server" \
  node tests/browser/viewer.test.mjs

# Issue 14: a trainee's two-case session (two-point) in the page, recorded in
# a fresh SQLite database; then its rows are read back here, independently.
exam_dir="$(mktemp -d)"
mkdir "$exam_dir/cases"
cp cases/normal-average.toml cases/popliteal-acute.toml "$exam_dir/cases/"
db="$exam_dir/records.sqlite3"
trainee="browser-test-$$"
kill "$server" 2>/dev/null || true
wait "$server" 2>/dev/null || true
start_server exam exam-server.log exam --trainee "$trainee" --protocol two-point --cases "$exam_dir/cases" \
  --db "sqlite://$db"
echo "browser-test: exam server at $url"
ECHOTHIGH_URL="$url" ECHOTHIGH_TRAINEE="$trainee" SCREENSHOT_DIR="$shots" CHROMIUM=/usr/bin/chromium \
  node tests/browser/exam.test.mjs
kill -INT "$server"
wait "$server" || true
# The database holds what the page did: the trainee, one session with its
# two case attempts finished and scored, two calls per case (two-point), at
# least one press per site, and each case's ground truth.
python3 - "$db" "$trainee" <<'PY'
import sqlite3, sys
db, trainee = sys.argv[1], sys.argv[2]
c = sqlite3.connect(db)
q = lambda sql, *a: c.execute(sql, a).fetchone()[0]
tid = q("SELECT id FROM trainees WHERE name = ?", trainee)
cases = q("SELECT COUNT(*) FROM case_attempts a JOIN sessions s ON a.session_id = s.id "
          "WHERE s.trainee_id = ? AND a.finished_ms IS NOT NULL AND a.calls_total = 2", tid)
calls = q("SELECT COUNT(*) FROM calls")
events = q("SELECT COUNT(*) FROM events")
truth = q("SELECT COUNT(DISTINCT case_id) FROM truth_pieces")
ended = q("SELECT COUNT(*) FROM sessions WHERE trainee_id = ? AND ended_ms IS NOT NULL", tid)
print(f"browser-test: database: {cases} cases finished, {calls} calls, {events} events, "
      f"truth for {truth} cases, {ended} session(s) ended")
ok = cases == 2 and calls == 4 and events >= 4 and truth == 2 and ended == 1
sys.exit(0 if ok else "browser-test: the database does not hold the session the page ran")
PY
echo "browser-test: screenshots in $shots"
