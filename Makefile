# roe_sep -- developer entry points. Everything runs from the project venv (.venv), which
# `make setup` (scripts/bootstrap.sh) creates/updates idempotently; it is a no-op (~1 s)
# when nothing changed, so every target depends on it.
SHELL := /bin/bash
VENV  := .venv
PY    := $(VENV)/bin/python

# extra arguments, e.g.  make test ARGS='-k planner -x'
ARGS ?=

.PHONY: setup demo test bench smoke chaos clean distclean

setup:
	@bash scripts/bootstrap.sh

demo: setup
	rm -rf out/demo && $(VENV)/bin/roe-sep run --out out/demo $(ARGS)

test: setup
	bash scripts/test.sh $(ARGS)

# fault injection alone: every node killed in turn, every topic fuzzed, 378 bad command-line inputs
chaos: setup
	bash scripts/test.sh -m fault -s $(ARGS)

bench: setup
	$(PY) bench/run_all.py $(ARGS)

# DDS round trip of a latched roe_sep_msgs/ManeuverPlan between two rclpy nodes (loopback only)
smoke: setup
	ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST ROS_DOMAIN_ID=$${ROS_DOMAIN_ID:-57} $(PY) scripts/smoke_dds.py

clean:
	rm -rf build install log out .pytest_cache .hypothesis

distclean: clean
	rm -rf $(VENV)
