#!/usr/bin/env bash
# Speed of the test run on a long CAM-style program: `klar check` of `cam_style.py long`
# (about 70,000 lines, 3-axis: contours with reduced-feed corners, adaptive-style clearing,
# parallel finishing) on the bench machine. Prints the planned machine time, the CPU time
# of the check (user + system), their ratio and the peak resident memory. Also times the
# program's parts on their own.
#
# Usage: bench/check_speed.sh [PASSES]     (default 7; builds the CLI in release mode)
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
cd "$here/.."
cargo build --release --quiet --bin klar
klar="${CARGO_TARGET_DIR:-target}/release/klar"
machine="$here/machine-jerk-1e5.toml"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

passes="${1:-7}"
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
