#!/usr/bin/env bash
# The real `ros2` command line against this package, as a ROS user works with it.
#
# ros2cli, launch and launch_ros are pure Python but not published as wheels. This script builds them (and
# rosidl_runtime_py, and composition_interfaces from rcl_interfaces, which launch_ros imports) from the archives in
# ../shared/ros2_sources (see its README.md) into a SEPARATE environment beside the PyPI ROS 2 wheels of .venv:
#
#   build/ros2cli/venv     a venv whose site-packages adds .venv's (site.addsitedir: the ROS 2 wheels, rclpy)
#                          plus the ros2cli/launch packages and colcon (colcon-core, colcon-ros, colcon-bash: PyPI)
#   build/ros2cli/prefix   composition_interfaces built with CMake (like msg_defs in scripts/bootstrap.sh)
#   build/ros2cli/ws       `colcon build` of this workspace (roe_sep): build/ install/ log/
#   build/ros2cli/env.sh   the environment (source it, then source ws/install/local_setup.bash)
#
# then runs the checks (`ros2 pkg executables`, `ros2 run` of every executable, `ros2 node/topic/param/lifecycle`,
# `ros2 interface show`, `ros2 launch roe_sep separation.launch.py`). Setup steps are cached by stamp files
# (inputs hashed): a second run skips them. Nothing is downloaded at run time; only pip from PyPI during setup.
#
#   scripts/ros2_cli.sh            # setup (cached) + every check; output dir build/ros2cli/checks
#   scripts/ros2_cli.sh setup      # setup only
#   scripts/ros2_cli.sh lifecycle  # setup + the check of invalid lifecycle transitions only (checks/lifecycle.txt)
#   ROS2_SOURCES=/path scripts/ros2_cli.sh
#   ROS2_CLI_DURATION=20000 scripts/ros2_cli.sh   # sim duration [s] of the launch run (default 20000)
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VPY="$ROOT/.venv/bin/python"
E="$ROOT/build/ros2cli"
STAMPS="$E/stamps"
MODE="${1:-all}"
DURATION="${ROS2_CLI_DURATION:-20000}"
export PIP_DISABLE_PIP_VERSION_CHECK=1 PIP_NO_INPUT=1 PIP_PROGRESS_BAR=off

say() { printf '[ros2_cli] %s\n' "$*"; }
die() { printf '[ros2_cli] ERROR: %s\n' "$*" >&2; exit 1; }

# the archives: $ROS2_SOURCES, else ../shared/ros2_sources beside this checkout or beside the main checkout of a
# git worktree
find_sources() {
  local c common
  [[ -n "${ROS2_SOURCES:-}" ]] && { echo "$ROS2_SOURCES"; return; }
  for c in "$ROOT/../shared/ros2_sources"; do [[ -d "$c" ]] && { (cd "$c" && pwd); return; }; done
  common="$(git -C "$ROOT" rev-parse --path-format=absolute --git-common-dir 2>/dev/null || true)"
  if [[ -n "$common" && -d "$(dirname "$common")/../shared/ros2_sources" ]]; then
    (cd "$(dirname "$common")/../shared/ros2_sources" && pwd); return
  fi
  echo ""
}
SRC="$(find_sources)"
[[ -n "$SRC" && -d "$SRC" ]] || die "no ros2_sources (../shared/ros2_sources); set ROS2_SOURCES"
[[ -x "$VPY" ]] || die "no project venv $VPY (scripts/bootstrap.sh)"

unset _ROS_WHEELS_BOOTSTRAP_COMPLETE
mkdir -p "$STAMPS"
exec 9> "$E/.lock"
flock 9

hash_of() { sha256sum | cut -c1-16; }
stamp_ok() { [[ -f "$STAMPS/$1" && "$(cat "$STAMPS/$1")" == "$2" ]]; }
stamp_set() { printf '%s\n' "$2" > "$STAMPS/$1"; }
run_logged() {
  local name=$1; shift
  if ! "$@" > "$STAMPS/$name.log" 2>&1; then
    printf '[ros2_cli] ERROR: step "%s" failed: %s\n' "$name" "$*" >&2
    tail -n 40 "$STAMPS/$name.log" >&2
    exit 1
  fi
}

T0=$SECONDS
SITE="$("$VPY" -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')"
PYV="$("$VPY" -c 'import sys; print("%d.%d" % sys.version_info[:2])')"
VENV_REAL="$(cd "$ROOT/.venv" && pwd -P)"
SRC_KEY="$(cd "$SRC" && sha256sum ./*.tar.gz | hash_of)"

# ---------------------------------------------------------------- 1. the venv (+ .venv's site-packages)
KEY_VENV="v1-$SRC_KEY-$VENV_REAL"
if stamp_ok venv "$KEY_VENV" && [[ -x "$E/venv/bin/ros2" ]]; then
  say "venv build/ros2cli/venv: up to date"
else
  t=$SECONDS
  say "venv build/ros2cli/venv: ros2cli, launch, launch_ros, rosidl_runtime_py from $SRC; colcon from PyPI"
  rm -rf "$E/venv" "$E/src"
  "$VPY" -m venv "$E/venv"
  # the PyPI ROS 2 wheels of .venv (rclpy, messages, ament_index_python), with their .pth files processed
  "$E/venv/bin/python" - "$SITE" <<'EOF'
import sys, sysconfig, pathlib
pth = pathlib.Path(sysconfig.get_paths()["purelib"]) / "zz_roe_sep_ros_wheels.pth"
pth.write_text(f"import site; site.addsitedir({sys.argv[1]!r})\n")
EOF
  mkdir -p "$E/src"
  for a in ros2cli launch launch_ros rosidl_runtime_py rcl_interfaces; do
    tar xzf "$SRC/$a-jazzy.tar.gz" -C "$E/src"
  done
  # plain-PyPI deps of those packages that .venv lacks, and colcon
  run_logged pip-deps "$E/venv/bin/python" -m pip install wheel setuptools osrf-pycommon argcomplete \
    colcon-core colcon-ros colcon-bash colcon-package-selection colcon-library-path colcon-python-setup-py
  pkgs=()
  for p in launch/launch launch/launch_xml launch/launch_yaml launch_ros/launch_ros launch_ros/ros2launch \
           rosidl_runtime_py ros2cli/ros2cli ros2cli/ros2pkg ros2cli/ros2run ros2cli/ros2node ros2cli/ros2topic \
           ros2cli/ros2param ros2cli/ros2interface ros2cli/ros2lifecycle ros2cli/ros2service; do
    pkgs+=("$E/src/$p")
  done
  run_logged pip-ros2 "$E/venv/bin/python" -m pip install --no-deps --no-build-isolation "${pkgs[@]}"
  stamp_set venv "$KEY_VENV"
  say "venv: done in $((SECONDS - t)) s"
fi

# ---------------------------------------------------------------- 2. composition_interfaces (CMake)
KEY_CI="v1-$KEY_VENV-$(sha256sum "$ROOT/scripts/cmake/ros_wheels_fixup.cmake" | hash_of)"
if stamp_ok composition "$KEY_CI" && [[ -d "$E/prefix/lib/python$PYV/site-packages/composition_interfaces" ]]; then
  say "composition_interfaces: up to date"
else
  t=$SECONDS
  say "composition_interfaces: cmake build from rcl_interfaces -> build/ros2cli/prefix"
  rm -rf "$E/prefix" "$E/cmake-composition"
  AMENT_PREFIX_PATH="$ROOT/.venv" CMAKE_PREFIX_PATH="$ROOT/.venv" \
    run_logged composition-configure cmake -S "$E/src/rcl_interfaces/composition_interfaces" \
      -B "$E/cmake-composition" -DCMAKE_BUILD_TYPE=Release -DCMAKE_INSTALL_PREFIX="$E/prefix" \
      -DPython3_EXECUTABLE="$VPY" -DBUILD_TESTING=OFF \
      -DCMAKE_PROJECT_INCLUDE="$ROOT/scripts/cmake/ros_wheels_fixup.cmake"
  run_logged composition-build cmake --build "$E/cmake-composition" --parallel 2
  run_logged composition-install cmake --install "$E/cmake-composition"
  stamp_set composition "$KEY_CI"
  say "composition_interfaces: done in $((SECONDS - t)) s"
fi

# ---------------------------------------------------------------- 3. the environment file
LIBS="$ROOT/.venv/lib:$E/prefix/lib"
for d in "$SITE"/ros_*.libs; do [[ -d "$d" ]] && LIBS="$LIBS:$d"; done
cat > "$E/env.sh" <<EOF
# generated by scripts/ros2_cli.sh: the ros2cli environment beside the PyPI ROS 2 wheels of .venv
export PATH="$E/venv/bin:\$PATH"
export LD_LIBRARY_PATH="$LIBS\${LD_LIBRARY_PATH:+:\$LD_LIBRARY_PATH}"
export PYTHONPATH="$E/prefix/lib/python$PYV/site-packages\${PYTHONPATH:+:\$PYTHONPATH}"
export AMENT_PREFIX_PATH="$E/prefix:$E/venv:$ROOT/.venv\${AMENT_PREFIX_PATH:+:\$AMENT_PREFIX_PATH}"
export _ROS_WHEELS_BOOTSTRAP_COMPLETE=1
export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST
unset ROS_LOCALHOST_ONLY
EOF
# shellcheck disable=SC1091
source "$E/env.sh"
python -c 'import launch_ros.actions, ros2cli, rosidl_runtime_py, composition_interfaces.srv, rclpy' \
  || die "the ros2cli environment does not import (see above)"

# ---------------------------------------------------------------- 4. colcon build of this workspace
KEY_WS="v1-$KEY_CI-$(cd "$ROOT" && git ls-files -co --exclude-standard -- setup.py setup.cfg package.xml resource \
  roe_sep config launch | grep -v __pycache__ | LC_ALL=C sort | xargs -r sha256sum | hash_of)"
if stamp_ok ws "$KEY_WS" && [[ -f "$E/ws/install/local_setup.bash" ]]; then
  say "colcon build: up to date"
else
  t=$SECONDS
  say "colcon build --paths $ROOT -> build/ros2cli/ws/install"
  rm -rf "$E/ws/build/roe_sep" "$E/ws/install/roe_sep"
  mkdir -p "$E/ws"
  (cd "$E/ws" && run_logged colcon colcon --log-base "$E/ws/log" build --paths "$ROOT" \
     --build-base "$E/ws/build" --install-base "$E/ws/install" --event-handlers console_direct-)
  stamp_set ws "$KEY_WS"
  say "colcon build: done in $((SECONDS - t)) s"
fi
set +u
# shellcheck disable=SC1091
source "$E/ws/install/local_setup.bash"
set -u
say "setup ready in $((SECONDS - T0)) s (source build/ros2cli/env.sh && source build/ros2cli/ws/install/local_setup.bash)"
[[ "$MODE" == "setup" ]] && exit 0

# ---------------------------------------------------------------- 5. the checks
OUT="$E/checks"
rm -rf "$OUT"
mkdir -p "$OUT"
export ROS_DOMAIN_ID="${ROS_DOMAIN_ID:-$(( ($$ % 100) + 1 ))}"
say "checks (ROS_DOMAIN_ID=$ROS_DOMAIN_ID): outputs in build/ros2cli/checks"
PIDS=()  # process groups of the nodes started here (setsid: `ros2 run` and its node process)
cleanup() {  # SIGINT to each group, up to 15 s to exit cleanly, then SIGKILL
  local p i
  for p in "${PIDS[@]}"; do kill -INT -- "-$p" 2>/dev/null || true; done
  for i in $(seq 30); do
    local alive=0
    for p in "${PIDS[@]}"; do kill -0 -- "-$p" 2>/dev/null && alive=1; done
    [[ $alive == 0 ]] && break
    sleep 0.5
  done
  for p in "${PIDS[@]}"; do kill -KILL -- "-$p" 2>/dev/null || true; done
  wait 2>/dev/null || true
  PIDS=()
}
trap cleanup EXIT
section() { printf '\n==== %s\n' "$*"; }
# ros2 <args> with its output in the report (never the daemon: every call discovers the graph itself, within its
# --spin-time; on a loaded machine discovery can take longer: "Node not found" is retried, up to 3 attempts)
r2() {
  local out code attempt
  printf '$ ros2 %s\n' "$*"
  for attempt in 1 2 3; do
    code=0
    out="$(timeout 60 ros2 "$@" 2>&1)" || code=$?
    grep -q "Node not found" <<< "$out" || break
  done
  printf '%s\n' "$out"
  [[ $code == 0 ]] || printf '(exit status %s)\n' "$code"
}

# every managed node started by `ros2 run` with the default autostart (active at once), `ros2 run roe_sep
# lifecycle_manager` beside them (it reads each node's state and adopts the active ones), then transitions invalid
# from the active state sent from outside: ChangeState by id and by label (`ros2 service call`), and `ros2 lifecycle
# set` (which checks the available transitions itself). Every node must still run and answer, and the manager exit
# 0 on SIGINT. `scripts/ros2_cli.sh lifecycle` runs this check alone (after the setup).
check_invalid_transitions() {
  local share n p code manager deadline active
  local managed=(planner radar radar_od ic_planner safety_monitor)
  share="$(ros2 pkg prefix --share roe_sep)"
  printf '/**:\n  ros__parameters:\n    use_sim_time: false\n    scenario_file: %s\nplanner:\n  ros__parameters:\n    mc_samples: 2000\n' \
    "$share/config/default.yaml" > "$OUT/params_lifecycle.yaml"
  for n in "${managed[@]}"; do
    setsid ros2 run roe_sep "$n" --ros-args --params-file "$share/config/bag_params.yaml" \
      --params-file "$OUT/params_lifecycle.yaml" > "$OUT/run_lifecycle_$n.log" 2>&1 &
    PIDS+=($!)
  done
  deadline=$((SECONDS + 120))
  while :; do  # until every node says active (autostart), at most 120 s
    active=0
    for n in "${managed[@]}"; do
      timeout 30 ros2 lifecycle get "/$n" --no-daemon --spin-time 2 2>/dev/null | grep -q '^active' && active=$((active + 1))
    done
    [[ $active == "${#managed[@]}" || $SECONDS -ge $deadline ]] && break
    sleep 1
  done
  setsid ros2 run roe_sep lifecycle_manager > "$OUT/run_lifecycle_manager.log" 2>&1 &
  manager=$!
  PIDS+=("$manager")
  deadline=$((SECONDS + 120))
  until grep -q "managed nodes active\|ERROR" "$OUT/run_lifecycle_manager.log" 2>/dev/null || [[ $SECONDS -ge $deadline ]]; do
    sleep 1
  done
  {
  section "manager beside active nodes (autostart)"
  cat "$OUT/run_lifecycle_manager.log"
  section "invalid transitions"
  for n in "${managed[@]}"; do
    r2 service call "/$n/change_state" lifecycle_msgs/srv/ChangeState '{transition: {id: 1}}'
    r2 service call "/$n/change_state" lifecycle_msgs/srv/ChangeState '{transition: {label: cleanup}}'
    r2 lifecycle set "/$n" configure --no-daemon --spin-time 3
  done
  section "after the invalid transitions"
  for n in "${managed[@]}"; do
    r2 lifecycle get "/$n" --no-daemon --spin-time 3
    r2 param get "/$n" autostart --no-daemon --spin-time 3
  done
  section "node processes"
  for p in "${PIDS[@]}"; do
    if kill -0 "$p" 2>/dev/null; then printf 'running: %s\n' "$(ps -o args= "$p" | grep -o 'roe_sep [a-z_]*')"; else
      code=0; wait "$p" || code=$?; printf 'exited with status %s: pid %s\n' "$code" "$p"; fi
  done
  section "node logs (warnings, errors)"
  for n in "${managed[@]}"; do
    grep -h "WARN\|ERROR\|Traceback\|RCLError" "$OUT/run_lifecycle_$n.log" | sed "s|^|$n: |" || true
  done
  section "manager SIGINT"
  kill -INT -- "-$manager" 2>/dev/null || true
  code=0
  wait "$manager" || code=$?
  printf 'lifecycle_manager exit status %s\n' "$code"
  } > "$OUT/lifecycle.txt" 2>&1
  cleanup
}
if [[ "$MODE" == "lifecycle" ]]; then
  check_invalid_transitions
  say "lifecycle check: $OUT/lifecycle.txt"
  exit 0
fi

{
section "pkg executables"
r2 pkg executables roe_sep
r2 pkg prefix roe_sep
section "interface show"
r2 interface show roe_sep_msgs/msg/ManeuverPlan
r2 interface list --only-msgs | grep roe_sep_msgs || true
} > "$OUT/static.txt"
say "pkg/interface: $(grep -c '^roe_sep ' "$OUT/static.txt") executables listed"

# every node executable, standalone, with the installed config/ parameter file of the reference run (the share
# directory of the colcon install) plus a few standalone values; each is then seen by `ros2 node list`
SHARE="$(ros2 pkg prefix --share roe_sep)"
cat > "$OUT/params.yaml" <<EOF
/**:
  ros__parameters:
    use_sim_time: false
    scenario_file: $SHARE/config/default.yaml
planner:
  ros__parameters:
    mc_samples: 2000
recorder:
  ros__parameters:
    output: $OUT/standalone_bag
ground_bridge:
  ros__parameters:
    output_dir: $OUT/standalone_ccsds
foxglove_view:
  ros__parameters:
    port: 0
EOF
EXES=(planner radar radar_od ic_planner safety_monitor ejector ground_bridge recorder analysis_server foxglove_view sim)
for exe in "${EXES[@]}"; do
  setsid ros2 run roe_sep "$exe" --ros-args --params-file "$SHARE/config/bag_params.yaml" --params-file "$OUT/params.yaml" \
    > "$OUT/run_$exe.log" 2>&1 &
  PIDS+=($!)
done
# until every node is in the graph (at most 90 s: ten interpreters start at once on the 2 cores, and a loaded
# machine took longer than the 17 s a fixed wait gave); the listing below is then the one reported
deadline=$((SECONDS + 90))
while :; do
  seen="$(timeout 60 ros2 node list --no-daemon --spin-time 3 2>/dev/null || true)"
  missing=()
  for exe in "${EXES[@]}"; do grep -qx "/$exe" <<< "$seen" || missing+=("$exe"); done
  [ "${#missing[@]}" -eq 0 ] || [ "$SECONDS" -ge "$deadline" ] && break
  sleep 1
done
{
section "node list (every executable started with ros2 run)"
r2 node list --no-daemon --spin-time 5
for exe in "${missing[@]}"; do  # what a node that never appeared said
  printf '\n---- not seen after 90 s: %s (its log, last lines)\n' "$exe"
  tail -n 20 "$OUT/run_$exe.log" || true
done
section "topic list"
r2 topic list --no-daemon --spin-time 3 -t
section "lifecycle"
for n in planner radar radar_od ic_planner safety_monitor; do r2 lifecycle get "/$n" --no-daemon --spin-time 3; done
r2 lifecycle list /planner --no-daemon --spin-time 3
section "param"
r2 param list /planner --no-daemon --spin-time 3
r2 param get /planner k --no-daemon --spin-time 3
r2 param get /planner autostart --no-daemon --spin-time 3
r2 param get /radar seed --no-daemon --spin-time 3
section "topic echo/hz"
r2 topic echo /separation/drift_stop_plan --once --no-daemon --spin-time 3 --qos-durability transient_local \
  --qos-reliability reliable --timeout 5
printf '$ ros2 topic hz /diagnostics --window 5\n'
timeout -s INT 8 ros2 topic hz /diagnostics --window 5 2>&1 || true
} > "$OUT/standalone.txt" 2>&1
cleanup
say "ros2 run: $(grep -c '^/' <(sed -n '/node list/,/topic list/p' "$OUT/standalone.txt")) nodes in ros2 node list"

# managed nodes left unconfigured (autostart:=false), then driven by `ros2 lifecycle set`; the planner with a bad
# parameter (k must be odd): its configure transition fails and its log names the parameter
setsid ros2 run roe_sep safety_monitor --ros-args -p autostart:=false -p use_sim_time:=false \
  > "$OUT/run_managed_safety_monitor.log" 2>&1 &
PIDS+=($!)
setsid ros2 run roe_sep planner --ros-args -p autostart:=false -p k:=2 > "$OUT/run_managed_planner.log" 2>&1 &
PIDS+=($!)
sleep 6
{
section "lifecycle set (autostart:=false)"
r2 lifecycle get /safety_monitor --no-daemon --spin-time 3
r2 param list /safety_monitor --no-daemon --spin-time 3
r2 lifecycle set /safety_monitor configure --no-daemon --spin-time 3
r2 lifecycle get /safety_monitor --no-daemon --spin-time 3
r2 lifecycle set /safety_monitor activate --no-daemon --spin-time 3
r2 lifecycle get /safety_monitor --no-daemon --spin-time 3
section "a parameter error at configure (planner k:=2)"
r2 lifecycle set /planner configure --no-daemon --spin-time 6
r2 lifecycle get /planner --no-daemon --spin-time 3
} > "$OUT/managed.txt" 2>&1
cleanup
printf '$ (log of planner k:=2)\n%s\n' "$(grep -i 'configure failed' "$OUT/run_managed_planner.log")" >> "$OUT/managed.txt"

check_invalid_transitions
say "invalid transitions: $(grep -c '^active \[3\]' "$OUT/lifecycle.txt") of 4 managed nodes active after them"

# the whole scenario with ros2 launch (report.json in OUT/launch), the XML front-end with the managed start-up
# (OUT/launch_xml), and `roe-sep run` of the colcon install for the same seed and duration (OUT/run): the same report
run_timed() {  # name, command...: output in OUT/<name>.txt
  local name=$1; shift
  local t=$SECONDS
  { printf '$ %s\n' "$*"; timeout 900 "$@" 2>&1 || printf '(exit status %s)\n' "$?"; } > "$OUT/$name.txt"
  printf '(%s s)\n' "$((SECONDS - t))" >> "$OUT/$name.txt"
  say "$name: done in $((SECONDS - t)) s; report $([[ -f "$OUT/$name/report.json" ]] && echo "$OUT/$name/report.json" || echo MISSING)"
}
run_timed launch ros2 launch roe_sep separation.launch.py output:="$OUT/launch" seed:=1 duration:="$DURATION"
run_timed launch_xml ros2 launch roe_sep separation.launch.xml output:="$OUT/launch_xml" seed:=1 \
  duration:="$DURATION" managed:=true
run_timed run ros2 run roe_sep roe-sep run --out "$OUT/run" --seed 1 --duration "$DURATION"
say "all checks done in $((SECONDS - T0)) s"
