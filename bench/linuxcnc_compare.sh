#!/usr/bin/env bash
# klar beside LinuxCNC 2.9 on identical paths: each program's compensated op stream
# (`klar ops --compensated`) becomes G-code for LinuxCNC's planner (headless, 1 ms servo,
# G64 P0.01), klar runs the program itself, and both traces are judged by finite differences
# against the bench limits (X Y Z 100 mm/s, 1000 mm/s², klar's jerk 1e5 mm/s³). Prints one
# table row per program: both times, their ratio, the peak acceleration and jerk of each
# against the limits, the largest distance of klar's trace from the path. The G-code carries
# the program's spindle and coolant functions as comments, so LinuxCNC does not stop for
# them; klar's time is given twice, for the program as it stands (stopping where a TNC
# does) and for the same work as LinuxCNC's (its blocks of only M3/M4/M5/M8/M9 taken out),
# and the ratio is of the second.
#
# Usage: bench/linuxcnc_compare.sh [PROGRAM.h | FOLDER]...
#   Without arguments: the benchmark programs (bench/programs), the dense polylines and
#   the CAM-style programs (bench/cam_style.py). A folder takes every *.h and *.H in it,
#   so real programs can stay outside the repository.
# Needs LinuxCNC (see ../shared/tools/linuxcnc/README.md; LINUXCNC_TOOLS points elsewhere),
# root for its realtime layer, and numpy/scipy (PYTHON, default python3).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
cd "$here/.."
tools="${LINUXCNC_TOOLS:-$here/../../shared/tools/linuxcnc}"
python="${PYTHON:-python3}"
cargo build --release --quiet --bin klar
klar="${CARGO_TARGET_DIR:-target}/release/klar"
[[ "$klar" = /* ]] || klar="$(pwd)/$klar"
machine="$here/machine-jerk-1e5.toml"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

programs=()
if [ $# -eq 0 ]; then
    programs+=("$here"/programs/*.h)
    # Closed polylines of 2000 chords on circles of radius 25 and 5 mm at F3000.
    for r in 25 5; do
        python3 - "$r" > "$work/poly_r$r.h" <<'PY'
import math, sys
r, n = float(sys.argv[1]), 2000
print(f"0 BEGIN PGM POLY MM")
for k in range(1, n + 1):
    phi = 2 * math.pi * k / n
    x, y = (-r + r * math.cos(phi), r * math.sin(phi)) if k < n else (0.0, 0.0)
    print(f"{k} L X{x:+.6f} Y{y:+.6f}" + (" F3000" if k == 1 else ""))
print(f"{n + 1} END PGM POLY MM")
PY
        programs+=("$work/poly_r$r.h")
    done
    for kind in contour pocket parallel; do
        python3 "$here/cam_style.py" "$kind" > "$work/cam_$kind.h"
        programs+=("$work/cam_$kind.h")
    done
else
    for arg in "$@"; do
        if [ -d "$arg" ]; then
            while IFS= read -r f; do programs+=("$f"); done \
                < <(find "$arg" -maxdepth 1 -type f \( -name '*.h' -o -name '*.H' \) | sort)
        else
            programs+=("$arg")
        fi
    done
fi

printf '| program | klar | klar, same work | LinuxCNC | klar/LinuxCNC | klar a/A, j/J | LinuxCNC a/A, j/J | klar path deviation |\n'
printf '|---|---|---|---|---|---|---|---|\n'
for prog in "${programs[@]}"; do
    name="$(basename "$prog")"
    base="$work/${name%.*}"
    if ! "$klar" ops "$prog" --machine "$machine" --compensated > "$base.ops" 2> "$base.err"; then
        printf '| %s | refused: %s | | | | | |\n' "$name" "$(head -1 "$base.err")"
        continue
    fi
    python3 "$tools/ops2ngc.py" < "$base.ops" > "$base.ngc" 2> /dev/null
    "$klar" run "$prog" --machine "$machine" --trace "$base.klar.csv" --quiet > /dev/null
    grep -vE '^[[:space:]]*[0-9]*[[:space:]]*M0?[34589][[:space:]]*(;.*)?'$'\r''?$' "$prog" \
        > "$base.same.h" || true
    "$klar" run "$base.same.h" --machine "$machine" --trace "$base.same.csv" --quiet > /dev/null
    TP_P=0.01 "$tools/run_tp.sh" "$base.ngc" 100 1000 "$base.lcnc.csv" > "$base.tp" 2>&1 \
        || { printf '| %s | LinuxCNC run failed | | | | | |\n' "$name"; continue; }
    "$python" "$tools/analyze_traces.py" --ops "$base.ops" --v 100 --a 1000 --j 1e5 --json \
        "$base.klar.csv" "$base.same.csv" "$base.lcnc.csv" > "$base.json"
    "$python" - "$name" "$base.json" <<'PY'
import json, sys
name, path = sys.argv[1], sys.argv[2]
k, same, l = json.load(open(path))
print(f"| {name} | {k['T']:.3f} s | {same['T']:.3f} s | {l['T']:.3f} s | {same['T'] / l['T']:.3f} "
      f"| {max(k['a_ratio'], same['a_ratio']):.3f}, {max(k['j_ratio'], same['j_ratio']):.2f} "
      f"| {l['a_ratio']:.3f}, {l['j_ratio']:.2f} "
      f"| {1000 * max(k['dev_mm'], same['dev_mm']):.2f} µm |")
PY
done
