#!/usr/bin/env bash
# Takes a screenshot of the Rerun viewer on a recording without a display or a GPU (how
# docs/rerun_demo_viewer.png was made): a virtual X server (Xvfb) and Mesa's software Vulkan driver
# (lavapipe), then the viewer's own `--screenshot-to`. Not part of the tests.
#   apt-get install xvfb mesa-vulkan-drivers        (Debian)
#   bash scripts/rerun_screenshot.sh out/demo.rrd docs/rerun_demo_viewer.png
set -euo pipefail
cd "$(dirname "$0")/.."
rrd=${1:?recording (.rrd)}
png=${2:?screenshot (.png)}
display=:${RERUN_SCREENSHOT_DISPLAY:-77}
Xvfb "$display" -screen 0 1600x1000x24 >/dev/null 2>&1 &
xvfb=$!
trap 'kill $xvfb' EXIT
sleep 2
# the viewer runs on the CPU (llvmpipe); it loads the recording, lays it out by the blueprint
# ttmanip.viz sends, plays for a moment, saves the window at 2x and exits
DISPLAY=$display XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp} WGPU_BACKEND=vulkan \
    .venv/bin/rerun "$rrd" --window-size 1400x800 --screenshot-to "$png"
echo "wrote $png"
