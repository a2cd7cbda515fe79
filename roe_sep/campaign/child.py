"""``python -m roe_sep.campaign.child SPEC_JSON``: one campaign run, :func:`roe_sep.run.run` with the given keyword
arguments, every node in this process (started by :func:`roe_sep.campaign.runner.execute` in a process group of its own;
the kernel kills it when its worker dies).
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
