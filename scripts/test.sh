#!/usr/bin/env bash
# Run the test suite in the project venv, isolated from any other ROS 2 traffic:
# DDS discovery restricted to this host, and a ROS_DOMAIN_ID picked per test session so
# that concurrent sessions on one machine do not see each other's nodes/topics.
#   scripts/test.sh [pytest args...]
#   ROE_SEP_TEST_DOMAIN_ID=42 scripts/test.sh   # force a domain id
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"

export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST
export ROS_STATIC_PEERS=""
unset ROS_LOCALHOST_ONLY          # deprecated in Jazzy; RANGE above is the setting
# 1..100 (valid: 0..101 on Linux with Fast DDS; 0 is the default everyone else uses)
export ROS_DOMAIN_ID="${ROE_SEP_TEST_DOMAIN_ID:-$(( ($$ % 100) + 1 ))}"
# a stale guard inherited from a parent venv python would stop ros_wheels_bootstrapper
# from setting LD_LIBRARY_PATH for the ROS libraries
unset _ROS_WHEELS_BOOTSTRAP_COMPLETE

echo "[test] ROS_DOMAIN_ID=$ROS_DOMAIN_ID ROS_AUTOMATIC_DISCOVERY_RANGE=$ROS_AUTOMATIC_DISCOVERY_RANGE"
# no path given: pytest.ini testpaths (test/)
exec "$ROOT/.venv/bin/python" -m pytest -q "$@"
