# shellcheck shell=bash disable=SC2154
# Shell functions shared by the table scripts (init_table.sh, init_phase_table.sh);
# sourced, not run. Expects $vio (the vio binary).

queue() {  # COMMAND...: run it in the background, at most JOBS (default 2) at once
  "$@" &
  jobs+=($!)
  if [ "${#jobs[@]}" -ge "${JOBS:-2}" ]; then wait "${jobs[0]}"; jobs=("${jobs[@]:1}"); fi
}
ate() {  # TRAJECTORY GROUNDTRUTH -> ATE rmse [m] (se3), or nan
  "$vio" eval --estimate="$1" --groundtruth="$2" --alignment=se3 --json="$1.se3.json" >/dev/null 2>&1 &&
    python3 -c "import json,sys; print('%.4f' % json.load(open(sys.argv[1]))['ate']['rmse_m'])" "$1.se3.json" ||
    echo nan
}
