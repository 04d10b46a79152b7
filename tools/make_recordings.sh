#!/usr/bin/env bash
# Remakes the bundled recordings (content/assets/recordings/) from the bundled lessons with the
# simulated hand, after a change that moves the engine's forces on purpose. Builds first.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build build -j"$(nproc)" --target sulcus-cli bundled_cases
mkdir -p content/assets/recordings
for lesson in content/assets/lessons/*.json; do
  name=$(basename "$lesson" .json)
  build/bin/sulcus-cli lesson record "$lesson" --out "content/assets/recordings/$name.rec"
done
build/bin/sulcus-cli replay content/assets/recordings --check --jobs "$(nproc)"
