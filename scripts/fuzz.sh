#!/usr/bin/env bash
# Coverage-guided fuzzing of every fuzz target (fuzz/fuzz_targets/) with cargo-fuzz and
# libFuzzer on the stable toolchain: RUSTC_BOOTSTRAP=1 lets stable rustc take the
# instrumentation flags cargo-fuzz passes. Installs cargo-fuzz when it is missing.
#
#   scripts/fuzz.sh [SECONDS] [TARGET...]
#
# SECONDS per target (default $KLAR_FUZZ_SECONDS, else 60); TARGETs default to all. Each run
# is one process (-jobs=1 -workers=1), so it takes one core.
#
# Seeds are built fresh on every run from the repository (programs/ with bad/, iso/, lathe/;
# machines/*.toml; protocol traffic written here) and ../shared/corpus when it exists. The
# corpus libFuzzer grows stays in fuzz/corpus/TARGET and crashes go to fuzz/artifacts/TARGET/
# (both git-ignored), so a later run continues from what the earlier ones found.
#
# Environment: KLAR_FUZZ_SECONDS (time per target), KLAR_FUZZ_SANITIZER (default none: the
# targets are safe Rust, and without ASan they run about twice as fast; `address` for ASan),
# KLAR_FUZZ_TIMEOUT (seconds one input may take before libFuzzer calls it a hang, default 20).
#
# Per target it prints the executions, exec/s, libFuzzer's coverage (cov: and ft: of the
# last stats line), the corpus size and any crash artifact; at the end a table of all of them.
# The exit status is 1 when a target left a crash, timeout or out-of-memory artifact.
set -euo pipefail

root=$(cd "$(dirname "$0")/.." && pwd)
all_targets=(klartext tnc_iso lathe_din machine_toml slcan canopen pipeline)

secs=${KLAR_FUZZ_SECONDS:-60}
if [[ $# -gt 0 && $1 =~ ^[0-9]+$ ]]; then
    secs=$1
    shift
fi
if [[ $# -gt 0 ]]; then
    targets=("$@")
else
    targets=("${all_targets[@]}")
fi
for t in "${targets[@]}"; do
    if [[ ! -f $root/fuzz/fuzz_targets/$t.rs ]]; then
        echo "fuzz.sh: no fuzz target '$t' (targets: ${all_targets[*]})" >&2
        exit 2
    fi
done
sanitizer=${KLAR_FUZZ_SANITIZER:-none}
timeout=${KLAR_FUZZ_TIMEOUT:-20}

if ! cargo fuzz --version >/dev/null 2>&1; then
    echo "fuzz.sh: installing cargo-fuzz"
    cargo install cargo-fuzz --locked
fi
export RUSTC_BOOTSTRAP=1

corpus_root=$root/fuzz/corpus
artifact_root=$root/fuzz/artifacts
seed_root=$corpus_root/.seeds
log_root=$corpus_root/.logs
mkdir -p "$corpus_root" "$artifact_root" "$seed_root" "$log_root"

shared=$root/../shared/corpus

# Program files of one extension from the repository's programs and the shared corpus.
program_files() {
    local ext=$1
    {
        find "$root/programs" -type f -name "*.$ext"
        if [[ -d $shared ]]; then
            find "$shared" -type f -name "*.$ext"
        fi
    } | sort
}

# Copies files into a seed folder, each under a name of its own.
seed_copy() {
    local dir=$1 prefix=$2
    shift 2
    local f n=0
    for f in "$@"; do
        n=$((n + 1))
        cp "$f" "$dir/$prefix-$n-$(basename "$f")"
    done
}

# Copies files into a seed folder behind one byte (the pipeline target's dialect byte).
seed_prefixed() {
    local dir=$1 byte=$2
    shift 2
    local f n=0
    for f in "$@"; do
        n=$((n + 1))
        { printf "\\x$byte"; cat "$f"; } >"$dir/$byte-$n-$(basename "$f")"
    done
}

make_seeds() {
    local t=$1 dir=$seed_root/$1
    rm -rf "$dir"
    mkdir -p "$dir"
    local h=() i=() nc=()
    mapfile -t h < <(program_files h)
    mapfile -t i < <(program_files i)
    mapfile -t nc < <(program_files nc)
    case $t in
        # The interpreters pick the dialect by content first: every program seeds each.
        klartext | tnc_iso | lathe_din) seed_copy "$dir" p "${h[@]}" "${i[@]}" "${nc[@]}" ;;
        machine_toml) seed_copy "$dir" m "$root"/machines/*.toml ;;
        pipeline)
            seed_copy "$dir" h "${h[@]}"
            seed_prefixed "$dir" 01 "${i[@]}"
            seed_prefixed "$dir" 02 "${nc[@]}"
            ;;
        slcan)
            printf 't1238112233445566778899\r' >"$dir/data"
            printf 'T1234567F8AABBCCDDEEFF0011\rt70110\rr1230\rR123456780\r\a\r' >"$dir/mixed"
            printf 'S6\rO\rC\rV1013\rN1234\rF00\rZ1\r' >"$dir/commands"
            ;;
        canopen)
            # [id hi, id lo, len, data...]: boot-up, heartbeat, EMCY, TPDO1, SDO answer.
            printf '\x07\x01\x01\x00\x07\x01\x01\x05' >"$dir/bootup"
            printf '\x00\x81\x08\x10\x23\x80\x01\x02\x03\x04\x05' >"$dir/emcy"
            printf '\x01\x81\x08\x37\x06\x00\x00\x10\x27\x00\x00' >"$dir/tpdo"
            printf '\x05\x81\x08\x43\x41\x60\x00\x37\x06\x00\x00' >"$dir/sdo"
            ;;
    esac
}

dict_args() {
    case $1 in
        klartext | tnc_iso | lathe_din | pipeline) echo "-dict=$root/fuzz/programs.dict" ;;
    esac
}

echo "fuzz.sh: building the targets (sanitizer: $sanitizer)"
(cd "$root/fuzz" && cargo fuzz build -s "$sanitizer")

declare -a rows=()
found=0
for t in "${targets[@]}"; do
    make_seeds "$t"
    mkdir -p "$corpus_root/$t" "$artifact_root/$t"
    log_dir=$log_root/$t
    rm -rf "$log_dir"
    mkdir -p "$log_dir"
    before=$(find "$artifact_root/$t" -type f | sort)
    echo "fuzz.sh: $t for $secs s ($(find "$seed_root/$t" -type f | wc -l) seeds)"
    started=$(date +%s)
    # libFuzzer's job mode writes the run's output to fuzz-0.log in the working folder.
    # shellcheck disable=SC2046
    (cd "$log_dir" && cargo fuzz run --fuzz-dir "$root/fuzz" -s "$sanitizer" "$t" \
        "$corpus_root/$t" "$seed_root/$t" -- \
        -jobs=1 -workers=1 -max_total_time="$secs" -timeout="$timeout" \
        -print_final_stats=1 -artifact_prefix="$artifact_root/$t/" $(dict_args "$t")) \
        >"$log_dir/driver.log" 2>&1 || true
    took=$(($(date +%s) - started))
    log=$log_dir/fuzz-0.log
    [[ -f $log ]] || log=$log_dir/driver.log
    last=$(grep -E '^#[0-9]+.* cov: ' "$log" | tail -n 1 || true)
    execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -n 1)
    rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -n 1)
    cov=$(sed -n 's/.* cov: \([0-9]*\).*/\1/p' <<<"$last")
    ft=$(sed -n 's/.* ft: \([0-9]*\).*/\1/p' <<<"$last")
    corp=$(sed -n 's/.* corp: \([0-9]*\/[0-9]*[a-zA-Z]*\).*/\1/p' <<<"$last")
    execs=${execs:-$(sed -n 's/^#\([0-9]*\).*/\1/p' <<<"$last")}
    new=$(comm -13 <(echo "$before") <(find "$artifact_root/$t" -type f | sort) | sed '/^$/d')
    echo "  executions ${execs:-?}, ${rate:-?} exec/s, cov ${cov:-?}, ft ${ft:-?}," \
        "corpus ${corp:-?}, ${took} s (log: $log)"
    if [[ -n $new ]]; then
        found=1
        echo "  ARTIFACTS:"
        sed 's/^/    /' <<<"$new"
        grep -E 'panicked at|ERROR: libFuzzer|SUMMARY|deadly signal' "$log" | head -n 5 |
            sed 's/^/    /' || true
    else
        echo "  no crash"
    fi
    rows+=("| $t | ${execs:-?} | ${rate:-?} | ${cov:-?} | ${ft:-?} | ${took} s | $(echo "$new" | sed '/^$/d' | wc -l) |")
done

echo
echo "| target | executions | exec/s | cov | ft | time | new artifacts |"
echo "|---|---|---|---|---|---|---|"
printf '%s\n' "${rows[@]}"
exit "$found"
