#!/usr/bin/env bash
# Frame times of the window against the headless simulation and raster of the same scenes,
# scene by scene in turn, on a virtual 1280 x 720 X display (Xvfb). Prints a Markdown table.
#
# Headless: `crates/canopy_bench/benches/headless_frames.rs`, a fixed step and a 980 x 720 raster (the window's
# 3D view) every frame. Window: `canopy play --max-fps 0` (no frame cap) for N frames, the mean
# frame time it reports with its capture. The two alternate, ROUNDS times per scene; the table
# gives the median of each. Run from anywhere: `scripts/frame_times.sh [N] [ROUNDS]`.
set -euo pipefail
cd "$(dirname "$0")/.."
frames="${1:-300}"
rounds="${2:-3}"
scenes=(crates/canopy_bench/benches/scenes/empty.yaml scenes/demo.yaml scenes/biceps.yaml scenes/tree.yaml scenes/forest.yaml
    scenes/generated_forest.yaml scenes/sloth.yaml scenes/terrain.yaml)

cargo build --quiet --bin canopy
cargo bench --quiet -p canopy_bench --profile dev --bench headless_frames --no-run 2>/dev/null
canopy="${CARGO_TARGET_DIR:-target}/debug/canopy"
shot="$(mktemp -d)/window.png"

window_run() { # SCENE -> "frame simulation raster" mean milliseconds
    xvfb-run -a -s "-screen 0 1280x720x24" "$canopy" play "$1" --max-fps 0 --screenshot "$shot" --frames "$frames" 2>&1 |
        sed -n 's/.*frames: \([0-9.]*\) ms a frame on average, \([0-9.]*\) ms simulation, \([0-9.]*\) ms raster.*/\1 \2 \3/p'
}
median() { sort -n | awk '{v[NR]=$1} END {print v[int((NR+1)/2)]}'; }

echo "| scene | headless ms/frame | window ms/frame | of which raster | window / headless |"
echo "|---|---:|---:|---:|---:|"
for scene in "${scenes[@]}"; do
    headless=(); window=(); raster=()
    for _ in $(seq "$rounds"); do
        headless+=("$(cargo bench --quiet -p canopy_bench --profile dev --bench headless_frames -- "$scene" 2>/dev/null | awk '{print $2}')")
        read -r w _ r <<<"$(window_run "$scene")"
        window+=("$w"); raster+=("$r")
    done
    h=$(printf '%s\n' "${headless[@]}" | median)
    w=$(printf '%s\n' "${window[@]}" | median)
    r=$(printf '%s\n' "${raster[@]}" | median)
    echo "| $(basename "$scene" .yaml) | $h | $w | $r | $(echo "scale=2; $w / $h" | bc) |"
done
