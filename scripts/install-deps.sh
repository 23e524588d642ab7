#!/usr/bin/env bash
# Installs the Debian packages the project needs; a quick no-op when all are present.
# apt-get update runs only when something is missing. Run as root (or with sudo available).
set -euo pipefail
pkgs=(cmake g++ make libeigen3-dev libembree-dev libtbb-dev libopenmesh-dev
      nlohmann-json3-dev libbenchmark-dev libgtest-dev python3-matplotlib
      libcli11-dev libstb-dev pybind11-dev python3-pybind11 python3-dev python3-numpy python3-pytest)
if [ "${1:-}" = "--browser" ]; then pkgs+=(chromium); fi
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0
echo "install-deps: installing ${missing[*]}" >&2
sudo=""
[ "$(id -u)" -eq 0 ] || sudo="sudo"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
