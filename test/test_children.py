"""roe_sep.children: a child of :func:`spawn` never outlives its parent, and a :func:`guarded` parent stops its
children on SIGINT, SIGTERM and SIGHUP (exit status 128 + signal number)."""

import signal
import subprocess
import sys
import textwrap

import pytest
from rosutil import ROOT, descendants, wait_gone

# a parent: spawns a child that sleeps (ignoring SIGTERM when asked), says "ready", then waits
PARENT = textwrap.dedent("""
    import signal, sys, time
    from roe_sep.children import exit_status, guarded, spawn
    child = ("import signal, time; "
             + ("signal.signal(signal.SIGTERM, signal.SIG_IGN); " if sys.argv[1] == "stubborn" else "")
             + "time.sleep(300)")
    def main():
        spawn([sys.executable, "-c", child])
        print("ready", flush=True)
        time.sleep(300)
    if sys.argv[2] == "guarded":
        try:
            with guarded(grace=2.0):
                main()
        except KeyboardInterrupt as exc:
            sys.exit(exit_status(exc))
    else:
        main()
""")


def start_parent(child, mode):
    proc = subprocess.Popen([sys.executable, "-c", PARENT, child, mode], cwd=ROOT, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)
    assert proc.stdout.readline().strip() == "ready", proc.stderr.read()
    tree = descendants(proc.pid)
    assert len(tree) == 1, tree
    return proc, tree


def test_a_sigkilled_parent_takes_its_child_with_it():
    """PR_SET_PDEATHSIG: the parent has no chance to clean up, the kernel signals the child."""
    proc, tree = start_parent("plain", "bare")
    proc.kill()
    proc.wait(timeout=10)
    assert wait_gone(tree, timeout=20.0) == {}


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM, signal.SIGHUP], ids=lambda s: s.name)
def test_a_guarded_parent_stops_even_a_child_that_ignores_sigterm(sig):
    """The signal raises Interrupted in the parent; leaving guarded() sends the child's group SIGTERM, then SIGKILL
    after the grace (the death signal, SIGTERM, would not end this child)."""
    proc, tree = start_parent("stubborn", "guarded")
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == 128 + sig, err
    assert wait_gone(tree, timeout=5.0) == {}
