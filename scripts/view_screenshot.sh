#!/usr/bin/env bash
# The README's screenshot of `glint view`: the Cornell box, a traced mirror pixel, the
# view orbited to the side. Needs Xvfb, xdotool and ImageMagick (apt-get install -y xvfb
# xdotool imagemagick libgl1-mesa-dri) and a glint built with the `view` feature (the default).
# Usage: scripts/view_screenshot.sh path/to/glint docs/images/view_cornell.png
set -euo pipefail
BIN=$1 OUT=$2
export DISPLAY=:77 LIBGL_ALWAYS_SOFTWARE=1
Xvfb :77 -screen 0 1280x800x24 & XVFB=$!
trap 'kill $VIEW $XVFB 2>/dev/null || true' EXIT
sleep 2
"$BIN" view scenes/cornell_box.ron --width 640 --height 480 & VIEW=$!
sleep 8
xdotool windowfocus --sync "$(xdotool search --name 'glint view' | head -1)"
# The image starts 320 points from the left; (220, 240) on it is the mirror box.
xdotool mousemove 540 240; sleep 0.3; xdotool key r; sleep 4
xdotool mousemove 800 300 mousedown 1
for i in $(seq 1 14); do xdotool mousemove $((800 + 5 * i)) $((300 + i)); sleep 0.05; done
xdotool mouseup 1; xdotool mousemove 955 475; sleep 7
import -window root -crop 960x504+0+0 /tmp/view_screenshot.png
convert /tmp/view_screenshot.png -strip -colors 128 "PNG8:$OUT"
