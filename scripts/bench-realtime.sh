#!/usr/bin/env bash
# The servo loop's timing benchmark against the independent peers (../shared/peers): three
# CiA 402 drive emulators on the emulated slcan hub, a program moving all three axes back and
# forth for the whole duration, optionally with busy loops loading every core. Prints klar's
# summary (underruns, wake-up lateness p50 / p99 / p99.99 / max).
#
#   scripts/bench-realtime.sh [--period S] [--seconds N] [--fifo] [--load]
#
# The figures in docs/canopen.md: `--period 0.002 --seconds 600 --fifo --load` and
# `--period 0.004 --seconds 600 --load`. KLAR names the binary (default target/release/klar,
# else target/debug/klar); scripts/setup-peers.sh makes the Python venv.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
period=0.004 seconds=600 fifo="" load=""
while [ $# -gt 0 ]; do
  case "$1" in
    --period) period=$2; shift 2 ;;
    --seconds) seconds=$2; shift 2 ;;
    --fifo) fifo="--fifo"; shift ;;
    --load) load=yes; shift ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
  esac
done
klar=${KLAR:-}
if [ -z "$klar" ]; then
  klar="$root/target/release/klar"
  [ -x "$klar" ] || klar="$root/target/debug/klar"
fi
python="$root/.venv/bin/python"
peers="$root/../shared/peers"
[ -x "$python" ] || { echo "run scripts/setup-peers.sh first" >&2; exit 2; }
# The emulators stand in for drives, which do not share this computer's cores: where
# allowed they run in SCHED_FIFO (below klar's servo thread), so the load does not starve them.
rt=()
if chrt -f 40 true 2>/dev/null; then rt=(chrt -f 40); else echo "note: emulators without SCHED_FIFO" >&2; fi
dir=$(mktemp -d)
pids=()
cleanup() { for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done; rm -rf "$dir"; }
trap cleanup EXIT

"${rt[@]}" "$python" "$peers/slcan_hub.py" --port klar="$dir/can_klar" --port n1="$dir/can_n1" \
  --port n2="$dir/can_n2" --port n3="$dir/can_n3" >/dev/null 2>&1 &
pids+=($!)
for _ in $(seq 50); do [ -e "$dir/can_n3" ] && break; sleep 0.1; done
for n in 1 2 3; do
  "${rt[@]}" "$python" "$peers/cia402_drive.py" --iface slcan --channel "$dir/can_n$n" --bitrate 1000000 \
    --node-id "$n" --no-log-cyclic --log "$dir/drive$n.jsonl" >/dev/null 2>&1 &
  pids+=($!)
done
for n in 1 2 3; do
  for _ in $(seq 150); do grep -q bootup "$dir/drive$n.jsonl" 2>/dev/null && break; sleep 0.1; done
done

{
  cat <<TOML
name = "bench: three drive emulators on the slcan hub"
servo_period = $period
tolerance = 0.01
start_homed = true

[canopen.main]
bus = { adapter = "slcan", port = "$dir/can_klar", bitrate = 1000000 }
heartbeat_ms = 100
sdo_timeout_ms = 1000
boot_timeout_ms = 5000
state_timeout_ms = 3000
# The first answers after the emulators start may come late; a pipelined cycle waits only for
# answers later than a whole period.
pdo_wait_ms = 50.0
# Python emulators on a loaded computer now and then answer a few SYNCs late.
max_missed_pdos = 25
TOML
  for a in X:1 Y:2 Z:3; do
    cat <<TOML

[[axis]]
letter = "${a%%:*}"
kind = "linear"
travel = [-300.0, 300.0]
max_velocity = 100.0
max_acceleration = 1000.0
max_jerk = 20000.0
backend = { kind = "canopen", bus = "main", drive = { node = ${a##*:}, counts_per_unit = 1000.0, quick_stop_deceleration = 500.0 } }
TOML
  done
} >"$dir/machine.toml"

# One round trip (X50 Y40 Z30 and back at 50 mm/s) takes about 2.9 s.
reps=$(awk -v s="$seconds" 'BEGIN { r = int(s / 2.9); if (r < 1) r = 1; print r }')
cat >"$dir/bench.h" <<PGM
0  BEGIN PGM BENCH MM
1  LBL 1
2  L X+50 Y+40 Z+30 R0 F3000
3  L X+0 Y+0 Z+0
4  LBL 0
5  CALL LBL 1 REP $reps
6  END PGM BENCH MM
PGM

if [ -n "$load" ]; then
  for _ in $(seq "$(nproc)"); do sh -c 'while :; do :; done' & pids+=($!); done
fi
echo "klar: $klar; period $period s; about $seconds s; ${fifo:-no --fifo}; load: ${load:-none}; $(nproc) cores"
"$klar" run "$dir/bench.h" --machine "$dir/machine.toml" --realtime $fifo
