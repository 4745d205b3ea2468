#!/usr/bin/env bash
# Renders every layout of `doorbench view` into docs/images/viewer-LAYOUT.png from a fresh
# `doorbench demo`, so that docs/viewer.md shows what the viewer shows today. Run after changing the viewer; commit the PNGs with the change. Needs xvfb-run
# (package xvfb) and a built doorbench (DOORBENCH=path/to/doorbench, default build/app/doorbench).
set -euo pipefail
cd "$(dirname "$0")/.."
doorbench=${DOORBENCH:-build/app/doorbench}
images=docs/images
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p "$images"
"$doorbench" --quiet demo --out "$work/demo" > /dev/null
demo=$work/demo
shot() {  # LAYOUT, then the view arguments
  local layout=$1
  shift
  rm -f "$images/viewer-$layout.png"
  xvfb-run -a -s '-screen 0 1600x1200x24' "$doorbench" view --screenshot \
    "$images/viewer-$layout.png" --layout "$layout" --width 1200 --height 760 "$@" > /dev/null
  rm -f "$images/viewer-$layout.png.json"  # the pixels only: the JSON names temporary paths
  echo "$images/viewer-$layout.png"
}
shot browser "$demo/session.h5"
shot channels "$demo/session.h5"
shot loop "$demo/session.h5"
shot fit "$demo/undeclared-effect.h5" --loop "$demo/loop"
shot overlay "$demo/undeclared-effect.h5" "$demo/haptic-playback.h5"
shot steps --loop "$demo/loop"
shot tuning "$demo/undeclared-effect.h5" --loop "$demo/loop"
