# roe_sep -- developer entry points. Everything runs from the project venv (.venv), which
# `make setup` (scripts/bootstrap.sh) creates/updates idempotently; it is a no-op (~1 s)
# when nothing changed, so every target depends on it.
SHELL := /bin/bash
VENV  := .venv
PY    := $(VENV)/bin/python

# extra arguments, e.g.  make test ARGS='-k planner -x'
ARGS ?=

.PHONY: setup demo test test-unit docs golden bench smoke chaos clean distclean

setup:
	@bash scripts/bootstrap.sh

demo: setup
	rm -rf out/demo && $(VENV)/bin/roe-sep run --out out/demo $(ARGS)

test: setup
	bash scripts/test.sh $(ARGS)

# the fast loop: no DDS (no node, no rclpy.init, no run or campaign) and no slow test (pytest.ini's markers)
test-unit: setup
	bash scripts/test.sh -m "not dds and not slow" $(ARGS)

# the API reference from the docstrings (docs/api: Sphinx autodoc + autosummary, numpydoc), warnings as errors;
# out/docs/index.html (test/test_api_docs.py builds it the same way)
docs: setup
	rm -rf out/docs docs/api/generated
	$(PY) -m sphinx -W --keep-going -b html -q docs/api out/docs

# re-record the reference run bags/default_run and its report from the current code, with the command it was
# recorded with (seed 0, the scenario's default); test/cli/test_golden.py compares a fresh run with it
golden: setup
	rm -rf out/golden
	$(VENV)/bin/roe-sep run --params config/bag_params.yaml --out out/golden --json > /dev/null
	rm -rf bags/default_run && cp -r out/golden/bag bags/default_run
	cp out/golden/report.json bags/default_run.report.json

# fault injection alone: every node killed in turn, every topic fuzzed, the bad command-line inputs of
# test/cli/test_cli_bad_input.py (docs/failures.md)
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
