"""``--foxglove [PORT]`` of ``roe-sep run`` and ``roe-sep replay``: the live view of the ``foxglove_view`` node on
ws://127.0.0.1:PORT (Foxglove WebSocket protocol). ``run`` starts the node with the other nodes; ``replay`` (which
owns its argument parsing) starts it beside the replay here."""

import argparse
import signal
import subprocess
import sys
import threading
import time

from ..children import spawn

DEFAULT_PORT = 8765


def port_number(text):
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--foxglove expects a TCP port number, got {text!r}") from None
    if not 0 < value < 65536:
        raise argparse.ArgumentTypeError(f"--foxglove expects a port in [1, 65535], got {value}")
    return value


def split_foxglove(argv):
    """``(argv without --foxglove [PORT], port or None)``; ArgumentTypeError for a bad port."""
    rest, port, k = [], None, 0
    while k < len(argv):
        if argv[k] == "--foxglove":
            if k + 1 < len(argv) and argv[k + 1].isdigit():
                port = port_number(argv[k + 1])
                k += 2
                continue
            port = DEFAULT_PORT
        elif argv[k].startswith("--foxglove="):
            port = port_number(argv[k].split("=", 1)[1])
        else:
            rest.append(argv[k])
        k += 1
    return rest, port


def with_foxglove(port, body, sim_time=False, ready_timeout=30.0):
    """Run ``body()`` with a ``foxglove_view`` node serving ``port``; the node is stopped (SIGINT) afterwards."""
    cmd = [sys.executable, "-m", "roe_sep.nodes.foxglove_view", "--ros-args", "-p", f"port:={port}",
           "-p", f"use_sim_time:={'true' if sim_time else 'false'}"]
    proc = spawn(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    deadline = time.monotonic() + ready_timeout
    ready = False
    while time.monotonic() < deadline and not ready:
        line = proc.stdout.readline()
        if not line:
            break
        ready = "Foxglove WebSocket server on" in line
        print(line, end="", file=sys.stderr)
    if not ready:
        proc.kill()
        out = proc.communicate()[0]
        print(f"roe-sep: error: --foxglove {port}: the view did not start\n{out}", file=sys.stderr)
        return 2
    threading.Thread(target=lambda: [print(x, end="", file=sys.stderr) for x in proc.stdout], daemon=True).start()
    try:
        return body()
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            proc.wait(timeout=10.0)
        except subprocess.TimeoutExpired:
            proc.kill()
