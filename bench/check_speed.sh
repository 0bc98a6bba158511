#!/usr/bin/env bash
# Speed of the test run on a long CAM-style program: `klar check` of `cam_style.py long`
# (about 70,000 lines, 3-axis: contours with reduced-feed corners, adaptive-style clearing,
# parallel finishing) on the bench machine. Prints the planned machine time, the CPU time
# of the check (user + system), their ratio and the peak resident memory. Also times the
# program's parts on their own. With a folder, also each Klartext/ISO program in it (real CAM
# output kept outside the repository) and the folder's total.
#
# Usage: bench/check_speed.sh [PASSES] [FOLDER]     (default 7; builds the CLI in release mode)
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
cd "$here/.."
cargo build --release --quiet --bin klar
klar="${CARGO_TARGET_DIR:-target}/release/klar"
machine="$here/machine-jerk-1e5.toml"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

passes="${1:-7}"
folder="${2:-}"
python3 "$here/cam_style.py" long --passes "$passes" > "$work/long.h"
for kind in contour pocket parallel; do
    python3 "$here/cam_style.py" "$kind" > "$work/$kind.h"
done

printf '| program | lines | machine time | check CPU time | ratio | peak RSS |\n|---|---|---|---|---|---|\n'
for prog in long contour pocket parallel; do
    file="$work/$prog.h"
    lines=$(wc -l < "$file")
    /usr/bin/time -f '%U %S %M' -o "$work/time" "$klar" check "$file" --machine "$machine" \
        > "$work/out" 2>&1
    planned=$(sed -n 's/.*moves, \([0-9.]*\) s planned.*/\1/p' "$work/out")
    read -r user sys rss < "$work/time"
    awk -v p="$prog" -v n="$lines" -v t="$planned" -v u="$user" -v s="$sys" -v r="$rss" \
        'BEGIN { c = u + s; if (c < 0.01) c = 0.01;
                 printf "| %s | %d | %.1f s | %.2f s | %.0f× | %.1f MB |\n", p, n, t, c, t / c, r / 1024 }'
done

[ -n "$folder" ] || exit 0
# One row per program of the folder, then the folder's total (machine time over CPU time).
shopt -s nullglob
total_t=0
total_c=0
for file in "$folder"/*.h "$folder"/*.H "$folder"/*.i "$folder"/*.I; do
    lines=$(wc -l < "$file")
    if ! /usr/bin/time -f '%U %S %M' -o "$work/time" "$klar" check "$file" --machine "$machine" \
        > "$work/out" 2>&1; then
        printf '| %s | %d | not checked: %s |  |  |  |\n' "$(basename "$file")" "$lines" \
            "$(grep -m1 -i error "$work/out" || echo failed)"
        continue
    fi
    planned=$(sed -n 's/.*moves, \([0-9.]*\) s planned.*/\1/p' "$work/out")
    read -r user sys rss < "$work/time"
    awk -v p="$(basename "$file")" -v n="$lines" -v t="$planned" -v u="$user" -v s="$sys" -v r="$rss" \
        'BEGIN { c = u + s; if (c < 0.01) c = 0.01;
                 printf "| %s | %d | %.1f s | %.2f s | %.0f× | %.1f MB |\n", p, n, t, c, t / c, r / 1024 }'
    total_t=$(awk -v a="$total_t" -v b="$planned" 'BEGIN { print a + b }')
    total_c=$(awk -v a="$total_c" -v u="$user" -v s="$sys" 'BEGIN { print a + u + s }')
done
awk -v t="$total_t" -v c="$total_c" 'BEGIN { if (c < 0.01) c = 0.01;
    printf "| folder total |  | %.1f s | %.2f s | %.0f× |  |\n", t, c, t / c }'
