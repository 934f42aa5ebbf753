#!/usr/bin/env bash
# Copies the built three.js ES modules pinned in package-lock.json, with their
# licence, into crates/viewer/assets/web/vendor/, where `echothigh` embeds them.
# Usage: web/update-vendor.sh   (after changing the version in package.json:
# `npm install three@<version> --save-exact` in web/, then this script).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
dest="$here/../crates/viewer/assets/web/vendor"
cd "$here"
npm ci --no-audit --no-fund
src="$here/node_modules/three"
mkdir -p "$dest"
cp "$src/build/three.module.min.js" "$src/build/three.core.min.js" "$dest/"
cp "$src/LICENSE" "$dest/LICENSE-three.txt"
version="$(node -p "require('$src/package.json').version")"
echo "three.js $version (npm package \"three\", built ES modules, MIT licence)" > "$dest/VERSION"
echo "vendored three.js $version into $dest"
