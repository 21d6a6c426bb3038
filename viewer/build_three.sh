#!/usr/bin/env bash
# Rebuilds three.bundle.js, the three.js the viewer page embeds, from the versions pinned in
# package.json / package-lock.json (three 0.187.0, esbuild 0.28.2): the classes three_entry.js
# names, tree-shaken and minified into one classic script that sets window.LAMBERT_THREE, with
# three.js's MIT license as its header. Needs node and npm (and the network, once); the build
# and CI use the committed bundle and need neither.
set -euo pipefail
cd "$(dirname "$0")"
npm ci --no-audit --no-fund >/dev/null
version=$(node -p "JSON.parse(require('fs').readFileSync('node_modules/three/package.json')).version")
{
  echo "/* three.js ${version} (https://threejs.org), bundled for lambert's viewer by viewer/build_three.sh."
  sed 's/^/ * /' node_modules/three/LICENSE
  echo " */"
  node_modules/.bin/esbuild three_entry.js --bundle --minify --format=iife \
    --global-name=LAMBERT_THREE --legal-comments=none --log-level=warning
} > three.bundle.js.tmp
mv three.bundle.js.tmp three.bundle.js
echo "viewer/three.bundle.js: $(wc -c < three.bundle.js) bytes (three ${version})"
