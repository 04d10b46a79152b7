#!/usr/bin/env bash
# Runs the desktop app with the mouse device while xdotool drives the real pointer: left-drags
# that move the probe in the view plane, wheel steps in depth, right-drags that tilt it. Meant to
# run inside `xvfb-run` (DISPLAY set). The app stops by itself after SECONDS of servo time and
# writes REPORT; the exit code is the app's (124 when it did not finish in time).
#   mouse_session.sh SULCUS CASE_DIR SECONDS REPORT
set -u
bin=$1 case_dir=$2 seconds=$3 report=$4

"$bin" --case "$case_dir" --device mouse --seconds "$seconds" --report "$report" --size 1600x900 &
app=$!

# The window appears once the case is loaded.
wid=""
for _ in $(seq 1 200); do
  wid=$(xdotool search --name "^Sulcus" 2>/dev/null | head -n 1)
  [ -n "$wid" ] && break
  kill -0 "$app" 2>/dev/null || break
  sleep 0.1
done
if [ -z "$wid" ]; then
  echo "mouse_session: the app window did not appear" >&2
  wait "$app"
  exit $?
fi

# A point of the 3D view that no panel covers (the panels line the left, right and bottom edges).
cx=760 cy=300
drag() {  # button, dx per step, dy per step, steps
  xdotool mousemove --window "$wid" "$cx" "$cy" mousedown "$1" 2>/dev/null || return 1
  for _ in $(seq 1 "$4"); do
    xdotool mousemove_relative -- "$2" "$3" 2>/dev/null || return 1
    sleep 0.03
  done
  xdotool mouseup "$1" 2>/dev/null || return 1
}

deadline=$((SECONDS + ${seconds%.*} + 90))
while kill -0 "$app" 2>/dev/null && [ "$SECONDS" -lt "$deadline" ]; do
  # W inserts along the probe's own axis: from its start over a site's line, down the sulcus
  # to the pocket floor (about 14 mm); S withdraws. Then drags in the view plane, sideways
  # against the tooth, along the arch, in depth (wheel) and tilted (right-drag).
  xdotool windowfocus "$wid" 2>/dev/null
  xdotool key --delay 15 --repeat 160 w 2>/dev/null
  drag 1 4 0 10
  drag 1 -4 0 20
  drag 1 4 0 10
  xdotool key --delay 15 --repeat 160 s 2>/dev/null
  drag 1 3 0 8             # along the arch
  xdotool click --repeat 2 4 2>/dev/null   # wheel: into the view
  drag 3 2 0 6             # tilt
  drag 3 -2 0 6            # and back
  xdotool click --repeat 2 5 2>/dev/null
  drag 1 -3 0 8
  sleep 0.2
done

if kill -0 "$app" 2>/dev/null; then
  echo "mouse_session: the app did not stop after ${seconds} s" >&2
  kill "$app"
  wait "$app"
  exit 124
fi
wait "$app"
