#!/usr/bin/env bash
# Headless screenshot of the `viewer` example: runs it under Xvfb with Mesa's software
# OpenGL until the simulated time reaches SECONDS, then the viewer saves its window to
# docs/img/viewer.png (`--screenshot`) and exits. Installs what it needs with apt-get.
# Not part of `cargo test` or .ci/run.
#
# Usage: scripts/viewer-screenshot.sh [SCENE] [SECONDS]
#        (defaults: assets/scenes/default.ron, 1.5)
set -euo pipefail
cd "$(dirname "$0")/.."
scene=${1:-assets/scenes/default.ron}
after=${2:-1.5}
out=docs/img/viewer.png

# Xvfb and xauth (for xvfb-run); the libraries miniquad opens at run time: libGL (GLX,
# Mesa's llvmpipe through libgl1-mesa-dri), libX11 and libXi.
packages=(xvfb xauth libgl1 libglx-mesa0 libgl1-mesa-dri libx11-6 libxi6)
missing=()
for package in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed" || missing+=("$package")
done
if ((${#missing[@]})); then
    sudo=""
    if [ "$(id -u)" -ne 0 ]; then sudo=sudo; fi
    echo "installing: ${missing[*]}"
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

cargo build --release --features viewer --example viewer
mkdir -p "$(dirname "$out")"
rm -f "$out"
# The viewer exits by itself after the screenshot; the timeout stops it if it hangs.
LIBGL_ALWAYS_SOFTWARE=1 timeout 300 xvfb-run -a -s "-screen 0 1280x720x24" \
    cargo run --release --features viewer --example viewer -- "$scene" --screenshot "$out" --after "$after"
test -s "$out"
echo "wrote $out"
