#!/usr/bin/env bash
# Renders the README's pictures: each scene headless, 60 fixed steps, 640 x 360 pixels, into
# docs/images/. Run from anywhere: `scripts/screenshots.sh`.
set -euo pipefail
cd "$(dirname "$0")/.."

scenes=(demo biceps tree forest sloth generated_forest terrain world valley props)
for name in "${scenes[@]}"; do
    cargo run --quiet -- run "scenes/$name.yaml" --frames 60 --size 640x360 --screenshot "docs/images/$name.png"
    echo "docs/images/$name.png"
done
# The terrain after the source's demonstrations (moved, turned, scaled, the light moved).
cargo run --quiet -- run scenes/terrain.yaml --input timelines/terrain_demonstrations.yaml --seconds 4.5 \
    --size 640x360 --screenshot docs/images/terrain_turned.png
echo "docs/images/terrain_turned.png"
# The torso with its belly outlined, and shrunk with the shift shown over the original.
cargo run --quiet -- run scenes/torso.yaml --input timelines/torso_shrink.yaml --seconds 0.04 \
    --size 640x360 --screenshot docs/images/torso_marked.png
cargo run --quiet -- run scenes/torso.yaml --input timelines/torso_shrink.yaml --seconds 0.2 \
    --size 640x360 --screenshot docs/images/torso_shrunk.png
echo "docs/images/torso_marked.png docs/images/torso_shrunk.png"

# Elastic bodies at rest, and the plums after the timeline has dropped them.
cargo run --quiet -- run scenes/softbody.yaml --seconds 3 --size 640x360 --screenshot docs/images/softbody.png
cargo run --quiet -- run scenes/fruit.yaml --seconds 1.5 --size 640x360 --screenshot docs/images/fruit.png
cargo run --quiet -- run scenes/fruit.yaml --input timelines/fruit_drop.yaml --seconds 6 \
    --size 640x360 --screenshot docs/images/fruit_dropped.png
echo "docs/images/softbody.png docs/images/fruit.png docs/images/fruit_dropped.png"
# The default scene, at the window's size, eight seconds in.
cargo run --quiet -- run scenes/canopy.yaml --seconds 8 --size 1280x720 --screenshot docs/images/canopy.png
echo "docs/images/canopy.png"
# A plum falling from where the sloth's hand took hold.
cargo run --quiet -- run scenes/sloth_fruit.yaml --seconds 6.5 --size 640x360 --screenshot docs/images/sloth_fruit.png
echo "docs/images/sloth_fruit.png"
# The sloth on a bough of the scanned tree, and its footfalls on the study's pole.
cargo run --quiet -- run scenes/scanned_tree.yaml --seconds 12 --size 640x360 --screenshot docs/images/scanned_tree.png
cargo run --quiet -- sloth gait scenes/sloth/pole.yaml --seconds 14 --skip 4 --plot docs/images/sloth_footfalls.png
echo "docs/images/scanned_tree.png docs/images/sloth_footfalls.png"

# The scene on the marker over the sample sequence's frame 50 (shown at step 100), and a marker.
cargo run --quiet -- run scenes/ar.yaml --frames 100 --size 640x480 --screenshot docs/images/ar.png
cargo run --quiet -- ar marker --dictionary 6x6_250 --id 23 --cell-px 16 --out docs/images/ar_marker.png --force
echo "docs/images/ar.png docs/images/ar_marker.png"

# The window with its panel, where a display server can be started (Xvfb).
if command -v xvfb-run >/dev/null; then
    xvfb-run -a -s "-screen 0 1280x720x24" cargo run --quiet -- play scenes/demo.yaml --screenshot docs/images/window.png --frames 120
    echo "docs/images/window.png"
else
    echo "xvfb-run not found: docs/images/window.png left as it is" >&2
fi

# The AR scene in the window with the overlay selected in the panel and its outline on, where
# xdotool can click (the entity list's entry, then the switch).
if command -v xvfb-run >/dev/null && command -v xdotool >/dev/null; then
    cargo build --quiet
    xvfb-run -a -s "-screen 0 1280x720x24" bash -c '
        "${CARGO_TARGET_DIR:-target}/debug/canopy" play scenes/ar.yaml --screenshot docs/images/ar_window.png --frames 400 &
        app=$!
        window="$(xdotool search --sync --name "^Canopy" | head -1)"
        sleep 3
        xdotool mousemove --window "$window" 1025 401 click 1
        sleep 0.5
        xdotool mousemove --window "$window" 1060 532 click 1
        wait "$app"'
    echo "docs/images/ar_window.png"
fi
