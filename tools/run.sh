#!/usr/bin/env bash
# Builds Sulcus and runs it. With a display and the desktop app built, starts the app with the
# given arguments (by default the bundled healthy_11 lesson); otherwise replays the bundled
# healthy_11 lesson recording headless, checks its scores and writes its report to
# out/replay/healthy_11.html (and .json), then runs every paper scene headless
# (content/assets/scenes/paper/*.json) into out/paper/<scene>/ and the bundled healthy_11 case
# into out/cases/healthy_11/, with plots, printing each run's summary line. Exits non-zero when
# any run does.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

tools/setup.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo
cmake --build build -j"$(nproc)"

if [ -n "${DISPLAY:-}" ] && [ -x build/bin/sulcus ]; then
  exec build/bin/sulcus "$@"
fi

if [ $# -gt 0 ]; then
  echo "run: no display (or no desktop app): arguments ignored, running the paper scenes headless" >&2
fi

shopt -s nullglob
scenes=(content/assets/scenes/paper/*.json)
if [ ${#scenes[@]} -eq 0 ]; then
  echo "run: no scenes in content/assets/scenes/paper/" >&2
  exit 2
fi

worst=0
# The bundled lesson, recorded with the simulated hand, replayed and scored again.
status=0
mkdir -p out/replay
build/bin/sulcus-cli replay content/assets/recordings/healthy_11.rec --check \
  --report out/replay/healthy_11.html || status=$?
build/bin/sulcus-cli replay content/assets/recordings/healthy_11.rec \
  --report out/replay/healthy_11.json >/dev/null || status=$?
if [ "$status" -ne 0 ]; then
  echo "run: content/assets/recordings/healthy_11.rec: the replay exited with status $status" >&2
  worst=$status
else
  echo "run: the session report is out/replay/healthy_11.html"
fi
for scene in "${scenes[@]}"; do
  name=$(basename "$scene" .json)
  status=0
  build/bin/sulcus-cli run "$scene" --out "out/paper/$name" --plot || status=$?
  if [ "$status" -ne 0 ]; then
    echo "run: $scene: sulcus-cli exited with status $status" >&2
    if [ "$status" -gt "$worst" ]; then worst=$status; fi
  fi
done
# The bundled healthy case: the probe inserted at all six sites of tooth 11.
status=0
build/bin/sulcus-cli run build/cases/healthy_11/scene.json --out out/cases/healthy_11 --plot || status=$?
if [ "$status" -ne 0 ]; then
  echo "run: build/cases/healthy_11/scene.json: sulcus-cli exited with status $status" >&2
  if [ "$status" -gt "$worst" ]; then worst=$status; fi
fi
exit "$worst"
