#!/usr/bin/env bash
# Makes docs/pictures/report_healthy_11.png: the bundled healthy_11 recording replayed into its
# HTML report, rendered by a headless Chromium (installed from Debian if missing; only this
# script needs it). Builds first.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

if ! command -v chromium >/dev/null; then
  if [ "$(id -u)" -eq 0 ]; then apt-get install -y -q chromium; else sudo apt-get install -y -q chromium; fi
fi
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build build -j"$(nproc)" --target sulcus-cli bundled_cases
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
build/bin/sulcus-cli replay content/assets/recordings/healthy_11.rec --report "$out/report.html"
chromium --headless --no-sandbox --disable-gpu --hide-scrollbars --window-size=1160,1560 \
  --screenshot="$out/report.png" "file://$out/report.html" 2>/dev/null
mkdir -p docs/pictures
cp "$out/report.png" docs/pictures/report_healthy_11.png
echo "docs/pictures/report_healthy_11.png"
