#!/usr/bin/env bash
# Bootstrap the project environment: <repo>/.venv with ROS 2 Jazzy (PyPI wheels), the
# interface package roe_sep_msgs (msg_defs/, built with CMake into the venv prefix) and an
# editable install of roe_sep.
#
# Idempotent: every step is skipped when its inputs are unchanged (stamp files in
# .venv/.stamps/ hold a hash of the step's inputs). Re-run with nothing changed: ~1 s.
#
#   scripts/bootstrap.sh            # what `make setup` runs
#   BOOTSTRAP_FORCE=1 scripts/bootstrap.sh   # ignore the stamps, redo every step
#   PYTHON=/path/to/python3.11 scripts/bootstrap.sh
#
# Needs only python3.11 (+venv), a C/C++ compiler, cmake >= 3.21 and make. Works without a
# TTY (CI=true). Step logs are kept in .venv/.stamps/*.log and printed when a step fails.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="$ROOT/.venv"
STAMPS="$VENV/.stamps"
VPY="$VENV/bin/python"
BUILD_DIR="$ROOT/build/roe_sep_msgs"
FIXUP_CMAKE="$ROOT/scripts/cmake/ros_wheels_fixup.cmake"
JOBS="${BOOTSTRAP_JOBS:-$(nproc 2>/dev/null || echo 2)}"
# Bump a step's version to force it to re-run everywhere after changing how it works.
V_PIP=1 V_MSGS=1 V_PKG=1

# A parent python of this venv may have exported this guard of ros_wheels_bootstrapper
# (it sets LD_LIBRARY_PATH and re-execs once); with it set, a fresh interpreter would not
# get LD_LIBRARY_PATH and the ROS libraries would not load.
unset _ROS_WHEELS_BOOTSTRAP_COMPLETE
export PIP_DISABLE_PIP_VERSION_CHECK=1 PIP_NO_INPUT=1 PIP_PROGRESS_BAR=off

T0=$SECONDS
say() { printf '[bootstrap] %s\n' "$*"; }
die() { printf '[bootstrap] ERROR: %s\n' "$*" >&2; exit 1; }

# hash_of <stdin>  -> short sha256
hash_of() { sha256sum | cut -c1-16; }
# hash of the contents and names of the given files/dirs (relative to ROOT), sorted
hash_paths() {
  (cd "$ROOT" && find "$@" -type f ! -name '*.pyc' ! -path '*/__pycache__/*' -print0 2>/dev/null \
    | LC_ALL=C sort -z | xargs -0 -r sha256sum) | hash_of
}
stamp_ok() { [[ -z "${BOOTSTRAP_FORCE:-}" && -f "$STAMPS/$1" && "$(cat "$STAMPS/$1")" == "$2" ]]; }
stamp_set() { mkdir -p "$STAMPS" && printf '%s\n' "$2" > "$STAMPS/$1"; }
# run_logged <name> <cmd...> : run with output to .venv/.stamps/<name>.log, show the tail on failure
run_logged() {
  local name=$1; shift
  local log="$STAMPS/$name.log"
  mkdir -p "$STAMPS"
  if ! "$@" > "$log" 2>&1; then
    printf '[bootstrap] ERROR: step "%s" failed: %s\n---- last lines of %s ----\n' "$name" "$*" "$log" >&2
    grep -v 'is ignored: it is neither a file nor a directory' "$log" | tail -n 60 >&2 || true
    exit 1
  fi
}

# Serialise concurrent runs (e.g. two `make` invocations) on the same checkout.
mkdir -p "$ROOT/build"
if command -v flock >/dev/null 2>&1; then
  exec 9> "$ROOT/build/.bootstrap.lock"
  flock 9
fi

# ---------------------------------------------------------------- 0. interpreter + venv
if [[ -z "${PYTHON:-}" ]]; then
  if command -v python3.11 >/dev/null 2>&1; then PYTHON=python3.11; else PYTHON=python3; fi
fi
command -v "$PYTHON" >/dev/null 2>&1 || die "no $PYTHON on PATH"
PYVER="$("$PYTHON" -c 'import sys; print("%d.%d" % sys.version_info[:2])')"
[[ "$PYVER" == "3.11" ]] || die "$PYTHON is Python $PYVER; the ROS 2 Jazzy PyPI wheels need Python 3.11 (set PYTHON=...)"

if [[ ! -x "$VPY" ]] || ! "$VPY" -c 'import sys' >/dev/null 2>&1; then
  say "creating venv .venv ($("$PYTHON" -c 'import sys; print(sys.executable)'), Python $PYVER)"
  rm -rf "$VENV"
  "$PYTHON" -m venv "$VENV"
elif [[ "$(cat "$STAMPS/venv" 2>/dev/null || true)" != "$PYVER" ]] && [[ -f "$STAMPS/venv" ]]; then
  die ".venv was made with Python $(cat "$STAMPS/venv"), not $PYVER: remove .venv and re-run"
fi
stamp_set venv "$PYVER"

# ---------------------------------------------------------------- 1. pip requirements
KEY_PIP="v$V_PIP-py$PYVER-$(hash_paths requirements.txt)"
if stamp_ok pip "$KEY_PIP"; then
  say "python deps: up to date"
else
  say "python deps: pip install -r requirements.txt (ROS 2 Jazzy wheels + deps; log .venv/.stamps/pip.log)"
  t=$SECONDS
  run_logged pip "$VPY" -m pip install -r "$ROOT/requirements.txt"
  stamp_set pip "$KEY_PIP"
  say "python deps: done in $((SECONDS - t)) s"
fi

# ---------------------------------------------------------------- 2. roe_sep_msgs (CMake)
SITE="$("$VPY" -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')"
KEY_MSGS="v$V_MSGS-$KEY_PIP-$(hash_paths msg_defs scripts/cmake)-$VENV"
if stamp_ok msgs "$KEY_MSGS" && [[ -f "$SITE/roe_sep_msgs/msg/__init__.py" ]]; then
  say "roe_sep_msgs: up to date"
else
  say "roe_sep_msgs: cmake configure/build/install msg_defs -> .venv (log .venv/.stamps/msgs-*.log)"
  t=$SECONDS
  command -v cmake >/dev/null 2>&1 || die "cmake not found (apt-get install cmake)"
  # always a clean build dir: msg sets change rarely, and a copied/moved checkout would
  # otherwise trip over the absolute paths cached in CMakeCache.txt
  rm -rf "$BUILD_DIR"
  export AMENT_PREFIX_PATH="$VENV" CMAKE_PREFIX_PATH="$VENV"
  run_logged msgs-configure cmake -S "$ROOT/msg_defs" -B "$BUILD_DIR" \
    -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_INSTALL_PREFIX="$VENV" \
    -DPython3_EXECUTABLE="$VPY" \
    -DBUILD_TESTING=OFF \
    -DCMAKE_PROJECT_INCLUDE="$FIXUP_CMAKE"
  run_logged msgs-build cmake --build "$BUILD_DIR" --parallel "$JOBS"
  run_logged msgs-install cmake --install "$BUILD_DIR"
  unset AMENT_PREFIX_PATH CMAKE_PREFIX_PATH
  stamp_set msgs "$KEY_MSGS"
  say "roe_sep_msgs: done in $((SECONDS - t)) s"
fi

# ---------------------------------------------------------------- 3. roe_sep (editable)
# The top-level __init__.py files are part of the key: setuptools' editable finder maps the
# packages found at install time, so a newly created package needs a re-install.
KEY_PKG="v$V_PKG-$KEY_PIP-$(hash_paths setup.py setup.cfg package.xml resource)-$(cd "$ROOT" && find . -maxdepth 2 -name __init__.py -not -path './.venv/*' | LC_ALL=C sort | hash_of)"
if stamp_ok pkg "$KEY_PKG"; then
  say "roe_sep: up to date (editable install)"
else
  say "roe_sep: pip install -e . (log .venv/.stamps/pkg.log)"
  t=$SECONDS
  # PEP 660 editable install with the venv's setuptools: console scripts land in .venv/bin
  # (the legacy `setup.py develop` path would honour setup.cfg's script_dir=$base/lib/roe_sep).
  run_logged pkg "$VPY" -m pip install --no-build-isolation --use-pep517 -e "$ROOT"
  stamp_set pkg "$KEY_PKG"
  say "roe_sep: done in $((SECONDS - t)) s"
fi

# ---------------------------------------------------------------- sanity check (only after changes)
if [[ "$(cat "$STAMPS/checked" 2>/dev/null || true)" != "$KEY_PIP $KEY_MSGS $KEY_PKG" ]]; then
  "$VPY" - <<'EOF' || die "sanity import failed (see above)"
import rclpy  # noqa: F401
from roe_sep_msgs.msg import ManeuverPlan, EjectionEvent, RelativeOrbitalElements, ImpulsiveManeuver, OrbitalElements  # noqa: F401
from diagnostic_msgs.msg import DiagnosticArray  # noqa: F401
from rosgraph_msgs.msg import Clock  # noqa: F401
EOF
  printf '%s\n' "$KEY_PIP $KEY_MSGS $KEY_PKG" > "$STAMPS/checked"
  say "sanity import (rclpy, roe_sep_msgs, diagnostic_msgs, rosgraph_msgs): ok"
fi
say "ready: .venv ($((SECONDS - T0)) s)"
