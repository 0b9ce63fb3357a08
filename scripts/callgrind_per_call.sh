# Sourced by the benchmark scripts. Usage: callgrind_per_call CALLS DIR COMMAND...
# Runs COMMAND under callgrind with instrumentation off at start; the benchmark switches it on
# around CALLS calls per case and dumps each case as "robot/case". Prints one line per dump,
# "robot case instructions_per_call", and leaves the dumps and the log in DIR.
callgrind_per_call() {
  local calls="$1" dir="$2"
  shift 2
  rm -rf "$dir" && mkdir -p "$dir"
  valgrind --tool=callgrind --instr-atstart=no --callgrind-out-file="$dir/out" "$@" \
    >"$dir/log" 2>&1 || {
    cat "$dir/log" >&2
    return 1
  }
  # Each dump: "desc: Trigger: Client Request: robot/case" and "totals: Ir".
  local f label total
  for f in "$dir"/out.*; do
    label=$(sed -n 's/^desc: Trigger: Client Request: //p' "$f")
    total=$(sed -n 's/^totals: //p' "$f")
    [[ -n "$label" && -n "$total" ]] || continue
    echo "${label%%/*} ${label#*/} $(awk -v t="$total" -v n="$calls" 'BEGIN { printf "%.1f", t / n }')"
  done
}
