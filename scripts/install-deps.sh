#!/usr/bin/env bash
# Installs every Debian 12 package Candela needs to build, test and run.
# Idempotent; run as root (or with sudo available). Nothing is downloaded at build or run time.
set -euo pipefail
SUDO=""
if [ "$(id -u)" != 0 ]; then SUDO="sudo"; fi
PACKAGES=(
  build-essential cmake pkg-config ninja-build
  libopenvdb-dev libboost-iostreams-dev libnanovdb-dev libtbb-dev libembree-dev libglm-dev
  libopenexr-dev libpng-dev nlohmann-json3-dev libcli11-dev
  libglfw3-dev libimgui-dev libopencolorio-dev libgl1-mesa-dri
  libgtest-dev libbenchmark-dev xvfb xauth xdotool
  clang libclang-rt-14-dev
)
missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
