#!/usr/bin/env bash
# Installs every build and test dependency from the Debian (bookworm) archive.
# Idempotent: when every package is already installed it touches neither apt nor the network.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

packages=(
  cmake ninja-build g++ pkg-config
  libglm-dev libopenmesh-dev libeigen3-dev nlohmann-json3-dev libtinygltf-dev
  libgtest-dev libgmock-dev libbenchmark-dev libfcl-dev valgrind
  libhidapi-dev libusb-1.0-0-dev umockdev
  libglfw3-dev libimgui-dev libstb-dev
  xvfb xauth libgl1-mesa-dri xdotool binutils
)

# One dpkg-query for all packages; unknown ones simply do not appear as installed.
installed=" $(dpkg-query -W -f='${Package}=${db:Status-Status} ' "${packages[@]}" 2>/dev/null || true) "
missing=()
for p in "${packages[@]}"; do
  [[ "$installed" == *" $p=installed "* ]] || missing+=("$p")
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} packages installed"
  exit 0
fi

if [ "$(id -u)" -eq 0 ]; then
  as_root=()
elif command -v sudo >/dev/null 2>&1; then
  as_root=(sudo)
else
  echo "setup: missing packages (${missing[*]}) and neither root nor sudo to install them" >&2
  exit 1
fi

echo "setup: installing ${missing[*]}"
# env, because sudo may drop DEBIAN_FRONTEND from the environment.
"${as_root[@]}" env DEBIAN_FRONTEND=noninteractive apt-get update
"${as_root[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends "${missing[@]}"
