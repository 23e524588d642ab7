#!/usr/bin/env bash
# Installs the Debian packages the project needs; a quick no-op when all are present.
# apt-get update runs only when something is missing. Run as root (or with sudo available).
#   --viewer   also node and npm, and the mesh viewer's npm packages (npm ci in viewer/, pinned by
#              viewer/package-lock.json; needs the npm registry the first time)
#   --browser  all of --viewer, and Chromium for `make test-browser`
set -euo pipefail
pkgs=(cmake g++ make libeigen3-dev libembree-dev libtbb-dev libopenmesh-dev
      nlohmann-json3-dev libbenchmark-dev libgtest-dev python3-matplotlib
      libcli11-dev libstb-dev zlib1g-dev pybind11-dev python3-pybind11 python3-dev python3-numpy python3-pytest
      python3-pip python3-setuptools python3-wheel python3-venv python3-skimage python3-nibabel
      python3-distributed)
viewer=""
case "${1:-}" in
  --browser) pkgs+=(chromium); viewer=1 ;;
  --viewer) viewer=1 ;;
esac
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
# Checked as commands, not packages: a newer Node from elsewhere (nodesource) will do as well.
if [ -n "$viewer" ]; then
  command -v node >/dev/null || missing+=(nodejs)
  command -v npm >/dev/null || missing+=(npm)
fi
if [ ${#missing[@]} -gt 0 ]; then
  echo "install-deps: installing ${missing[*]}" >&2
  sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  export DEBIAN_FRONTEND=noninteractive
  $sudo apt-get update -qq
  $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
if [ -n "$viewer" ]; then
  # npm ci again only when the lock file changed since the last install (npm writes
  # node_modules/.package-lock.json on every install).
  dir="$(cd "$(dirname "$0")/.." && pwd)/viewer"
  stamp="$dir/node_modules/.package-lock.json"
  if [ ! -f "$stamp" ] || [ "$dir/package-lock.json" -nt "$stamp" ]; then
    echo "install-deps: npm ci in viewer/ (three.js, esbuild, playwright-core)" >&2
    (cd "$dir" && npm ci --no-audit --no-fund --loglevel=error)
  fi
fi
