#!/bin/sh
# Rebuild the studio's vendored JavaScript (static/vendor/) from npm at pinned versions, licences included.
# Users never run this: the built files are committed. Needs node and npm.   sh plugins/citygen_studio/vendor.sh
set -eu
THREE=0.187.0
CODEMIRROR=5.65.21
here=$(cd "$(dirname "$0")" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
(cd "$work" && npm install --silent --no-audit --no-fund --ignore-scripts "three@$THREE" "codemirror@$CODEMIRROR")
out="$here/static/vendor"
rm -rf "$out"
copy() {  # copy PACKAGE FILE...: files of an installed package, keeping their relative paths
  package=$1; shift
  for file in "$@"; do
    mkdir -p "$out/$package/$(dirname "$file")"
    cp "$work/node_modules/$package/$file" "$out/$package/$file"
  done
}
copy three LICENSE build/three.module.js build/three.core.js examples/jsm/loaders/GLTFLoader.js \
  examples/jsm/utils/BufferGeometryUtils.js examples/jsm/utils/SkeletonUtils.js examples/jsm/controls/OrbitControls.js
copy codemirror LICENSE lib/codemirror.js lib/codemirror.css addon/mode/simple.js addon/lint/lint.js \
  addon/lint/lint.css addon/hint/show-hint.js addon/hint/show-hint.css
printf 'three %s\ncodemirror %s\n' "$THREE" "$CODEMIRROR" > "$out/VERSIONS"
