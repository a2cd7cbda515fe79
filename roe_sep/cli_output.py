"""Output of every ``roe-sep`` subcommand: indented JSON with ``--json`` (ground-segment scripts), else the
human table, followed by the figures written, if any."""

import json
import sys


def emit(rep, as_json, human):
    """Write ``rep`` as JSON or through ``human(rep)``; list ``rep["figures"]`` after the human table."""
    if as_json:
        json.dump(rep, sys.stdout, indent=2)
        sys.stdout.write("\n")
        return
    human(rep)
    for f in rep.get("figures", []):
        print(f"  figure: {f}")
