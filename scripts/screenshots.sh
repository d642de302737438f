#!/usr/bin/env bash
# Renders the README's pictures: each scene headless, 60 fixed steps, 640 x 360 pixels, into
# docs/images/. Run from anywhere: `scripts/screenshots.sh`.
set -euo pipefail
cd "$(dirname "$0")/.."

scenes=(demo biceps tree forest sloth generated_forest)
for name in "${scenes[@]}"; do
    cargo run --quiet -- run "scenes/$name.yaml" --frames 60 --size 640x360 --screenshot "docs/images/$name.png"
    echo "docs/images/$name.png"
done
