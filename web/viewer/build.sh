#!/usr/bin/env bash
# Build the viewer bundles: web/viewer/dist/viewer.js (one classic script, three.js
# included) for the Rust exporter to inline into report.html, and dist/live.js, the
# script of the page `visage live --listen` serves.
# Runs `npm ci` only when node_modules is missing or package-lock.json changed
# since the last successful install (sha256 stamp kept inside node_modules).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")"

stamp=node_modules/.visage-lock.sha256
want=$(sha256sum package-lock.json | cut -d' ' -f1)
if [[ ! -d node_modules || ! -f $stamp || "$(cat "$stamp")" != "$want" ]]; then
  echo "build.sh: npm ci" >&2
  npm ci --no-audit --no-fund >&2  # stdout stays just the bundle path
  echo "$want" > "$stamp"
fi

npm run --silent build
test -s dist/viewer.js
test -s dist/live.js
echo "$(pwd)/dist/viewer.js"
