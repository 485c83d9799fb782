#!/usr/bin/env bash
# Installs what `splatffd export SCENE --web DIR` copies into a web player folder: the PlayCanvas engine
# (npm `playcanvas`, MIT; its UMD build build/playcanvas.min.js) into content/cache/web (gitignored), or
# $SPLATFFD_CACHE_DIR/web. With --test it also installs puppeteer-core (no browser of its own: it drives the
# system's Debian chromium) into content/cache/web-test for the browser test
# (tests/tools/splatffd/web_player_test.cpp, label slow). Install scripts are not run. Idempotent: an
# installed pinned version is not fetched again.
# Usage: tools/fetch_web_engine.sh [--test] [playcanvas-version]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cache="${SPLATFFD_CACHE_DIR:-$root/content/cache}"
version=2.23.3
driver_version=24.43.1
test=0
for arg in "$@"; do
  case $arg in
    --test) test=1 ;;
    -h|--help) sed -n '2,8p' "$0"; exit 0 ;;
    -*) echo "fetch_web_engine.sh: unknown option $arg" >&2; exit 2 ;;
    *) version=$arg ;;
  esac
done
command -v npm >/dev/null || { echo "fetch_web_engine.sh: npm not found (tools/bootstrap.sh installs it)" >&2; exit 1; }

installed_version() {  # prints the version of package $2 under prefix $1, or nothing
  local pkg="$1/node_modules/$2/package.json"
  [[ -f $pkg ]] && node -e 'console.log(require(process.argv[1]).version)' "$pkg" 2>/dev/null || true
}

if [[ $(installed_version "$cache/web" playcanvas) != "$version" ]]; then
  mkdir -p "$cache/web"
  npm install --prefix "$cache/web" --no-audit --no-fund --ignore-scripts --no-save "playcanvas@$version"
fi
engine="$cache/web/node_modules/playcanvas/build/playcanvas.min.js"
[[ -f $engine ]] || { echo "fetch_web_engine.sh: $engine missing after the install" >&2; exit 1; }
echo "fetch_web_engine.sh: playcanvas $version: $engine"

if ((test)); then
  if [[ $(installed_version "$cache/web-test" puppeteer-core) != "$driver_version" ]]; then
    mkdir -p "$cache/web-test"
    npm install --prefix "$cache/web-test" --no-audit --no-fund --ignore-scripts --no-save \
      "puppeteer-core@$driver_version"
  fi
  echo "fetch_web_engine.sh: puppeteer-core $driver_version: $cache/web-test/node_modules/puppeteer-core"
fi
