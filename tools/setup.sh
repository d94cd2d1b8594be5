#!/usr/bin/env bash
# Installs idmpc's Debian 12 dependencies (idempotent; needs root or sudo); arguments name extra
# packages (tools/sanitize.sh: clang).
set -euo pipefail
pkgs=(build-essential cmake libmujoco-dev libtinyxml2-dev libqhull-dev libeigen3-dev libcli11-dev
      nlohmann-json3-dev libgtest-dev libbenchmark-dev libosmesa6-dev ffmpeg python3-matplotlib
      pybind11-dev python3-dev python3-numpy python3-pytest parallel "$@")
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "idmpc setup: installing ${missing[*]}" >&2
  sudo_cmd=()
  [ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
  export DEBIAN_FRONTEND=noninteractive
  "${sudo_cmd[@]}" apt-get update -qq
  "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
