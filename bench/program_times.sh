#!/usr/bin/env bash
# Program times of the look-ahead planner's benchmark programs on the simulated bench machine
# (X Y Z: 100 mm/s, 1000 mm/s², tolerance 0.01 mm, 1 ms servo period), once with jerk
# 1e5 mm/s³ and once with jerk effectively unlimited (1e9 mm/s³). Prints one table row per
# program: the machine time `klar run` reports for each machine.
#
# Usage: bench/program_times.sh            (from anywhere; builds the CLI in release mode)
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
cd "$here/.."
cargo build --release --quiet --bin klar
klar="${CARGO_TARGET_DIR:-target}/release/klar"

work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

# A closed polyline of N chords on a circle of radius R, started at the origin (centre at
# X-R), at feed F mm/min.
polyline() {
    local name="$1" r="$2" n="$3" f="$4"
    awk -v name="$name" -v r="$r" -v n="$n" -v f="$f" 'BEGIN {
        pi = atan2(0, -1)
        printf "0 BEGIN PGM %s MM\n", name
        for (k = 1; k <= n; k++) {
            phi = 2 * pi * k / n
            x = -r + r * cos(phi); y = r * sin(phi)
            if (k == n) { x = 0; y = 0 }
            printf "%d L X%+.6f Y%+.6f%s\n", k, x, y, (k == 1 ? sprintf(" F%d", f) : "")
        }
        printf "%d END PGM %s MM\n", n + 1, name
    }' > "$work/$name.h"
}
polyline POLY_R25 25 2000 3000
polyline POLY_R5 5 2000 3000

# Dense code as a post-processor prints it: a full R25 circle in 0.01 mm chords (15708 of
# them) with coordinates rounded to 1 µm, at F3000; started at the origin (centre at X-25).
awk 'BEGIN {
    pi = atan2(0, -1); r = 25; n = 15708
    printf "0 BEGIN PGM DENSE_R25_1UM MM\n"
    for (k = 1; k <= n; k++) {
        phi = 2 * pi * k / n
        x = -r + r * cos(phi); y = r * sin(phi)
        if (k == n) { x = 0; y = 0 }
        printf "%d L X%+.3f Y%+.3f%s\n", k, x, y, (k == 1 ? " F3000" : "")
    }
    printf "%d END PGM DENSE_R25_1UM MM\n", n + 1
}' > "$work/DENSE_R25_1UM.h"

machine_time() {
    "$klar" run "$1" --machine "$2" | awk '/^machine time:/ { print $3 }'
}

printf "%-44s %12s %12s\n" "program" "j=1e5" "j=unlimited"
for prog in \
    "$here/programs/line.h" \
    "$here/programs/circle.h" \
    "$here/programs/square_r1.h" \
    "$work/POLY_R25.h" \
    "$work/POLY_R5.h" \
    "$here/programs/helix_p2.h" \
    "$here/programs/square_r10_plunge.h" \
    "$here/programs/helix_p1_f3000.h" \
    "$work/DENSE_R25_1UM.h"; do
    a="$(machine_time "$prog" "$here/machine-jerk-1e5.toml")"
    b="$(machine_time "$prog" "$here/machine-jerk-unlimited.toml")"
    printf "%-44s %10s s %10s s\n" "$(basename "$prog")" "$a" "$b"
done
