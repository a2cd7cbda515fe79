"""``python -m roe_sep.campaign.child SPEC_JSON``: one campaign run, :func:`roe_sep.run.run` with the given keyword
arguments, every node in this process (forked by the worker's fork server, :mod:`roe_sep.campaign.forkserver`, in a
process group of its own that the kernel kills when the fork server ends; the same as a fresh interpreter running
this module).
Exit 0 once ``report.json`` is written; 1 with a one-line reason on stderr otherwise."""

import json
import sys

from ..checks import one_line


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    spec = json.loads(argv[0])
    from ..run import run

    try:
        run(config=spec.get("config"), out=spec["out"], params=spec["params"], duration=spec.get("duration"),
            seed=spec["seed"], timeout=float(spec["timeout"]), domain_id=spec["domain_id"], in_process=True,
            ground_bridge=bool(spec.get("ccsds")))
    except Exception as exc:  # noqa: BLE001  (one line for the campaign table)
        print(f"{type(exc).__name__}: {one_line(exc)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
