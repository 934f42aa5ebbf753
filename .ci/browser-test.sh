#!/usr/bin/env bash
# Real-browser test of `echothigh view` (issue 8), called by .ci/run.
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
"$bin" view --port 0 >"$out" 2>"$shots/server.log" &
server=$!
cleanup() {
  kill "$server" 2>/dev/null || true
  wait "$server" 2>/dev/null || true
  rm -f "$out"
}
trap cleanup EXIT

url=""
for _ in $(seq 1 600); do
  url="$(sed -n 's/^echothigh viewer: \(http[^ ]*\)$/\1/p' "$out" | head -n 1)"
  [ -n "$url" ] && break
  if ! kill -0 "$server" 2>/dev/null; then
    echo "browser-test: echothigh view exited before serving; its log:" >&2
    cat "$shots/server.log" >&2
    exit 1
  fi
  sleep 0.1
done
if [ -z "$url" ]; then
  echo "browser-test: no URL from echothigh view within 60 s" >&2
  exit 1
fi
echo "browser-test: server at $url"

ECHOTHIGH_URL="$url" SCREENSHOT_DIR="$shots" CHROMIUM=/usr/bin/chromium ECHOTHIGH_SERVER_PID="$server" \
  node tests/browser/viewer.test.mjs
echo "browser-test: screenshots in $shots"
