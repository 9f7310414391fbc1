# Sourced by the training scripts: run `nift train` jobs side by side (one GPU shares them), each
# with its own log, and wait for all. NIFT overrides the command (e.g. NIFT="python3 -m app.cli").
#   launch LOG ARGS...   start `nift ARGS...` in the background, output to LOG
#   wait_all             wait for every launched job; fails if any failed
read -r -a nift <<< "${NIFT:-nift}"
pids=()

launch() {
  local log=$1
  shift
  "${nift[@]}" "$@" > "$log" 2>&1 &
  pids+=($!)
}

wait_all() {
  local status=0 pid
  for pid in "${pids[@]}"; do
    wait "$pid" || status=1
  done
  return $status
}
