"""The end of a process that used ROS (roe_sep.process_exit): the exit status, the output and the exit handlers as
with ``sys.exit``, the DDS participant deleted (no shared-memory segment left in /dev/shm), and ``sys.exit`` itself
where the teardown is still needed (no ROS, a context still up, a non-daemon thread)."""

import signal
import subprocess
import sys
import time

import pytest
from rosutil import DDS_SHM, ROOT, dds_segments, ros_env


def python(code, env=None):
    return subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env or ros_env(), capture_output=True,
                          text=True, timeout=120)


def test_without_ros_it_is_sys_exit():
    out = python("import atexit\nfrom roe_sep.process_exit import can_skip_teardown, exit_process\n"
                 "atexit.register(lambda: print('atexit ran'))\nprint(can_skip_teardown(), end=' ')\n"
                 "exit_process(3)")
    assert out.returncode == 3 and out.stdout == "False atexit ran\n", out


SKIP_CASES = """
import threading, rclpy
from roe_sep.process_exit import can_skip_teardown
rclpy.init()
node = rclpy.create_node("process_exit_test")
up = can_skip_teardown()
node.destroy_node()
rclpy.try_shutdown()
down = can_skip_teardown()
stop = threading.Event()
t = threading.Thread(target=stop.wait)
t.start()
busy = can_skip_teardown()
stop.set()
t.join()
print(up, down, busy, can_skip_teardown())
"""


@pytest.mark.dds
def test_the_teardown_is_skipped_only_once_ros_is_down_and_no_other_thread_runs():
    out = python(SKIP_CASES)
    assert out.returncode == 0 and out.stdout.split() == ["False", "True", "False", "True"], out


FAST_EXIT = """
import atexit, ctypes, rclpy
from roe_sep.process_exit import can_skip_teardown, exit_process
rclpy.init()
rclpy.create_node("process_exit_test").destroy_node()
rclpy.try_shutdown()
atexit.register(lambda: print("atexit ran", end=" "))
print(can_skip_teardown(), end=" ")  # block-buffered: stdout is a pipe, PYTHONUNBUFFERED unset
ctypes.CDLL(None).printf(b"from C")  # C's stdout buffer
exit_process(5)
"""


@pytest.mark.dds
def test_with_ros_down_the_status_the_output_and_the_exit_handlers_are_those_of_sys_exit():
    env = {k: v for k, v in ros_env().items() if k != "PYTHONUNBUFFERED"}
    out = python(FAST_EXIT, env)
    assert out.returncode == 5 and out.stdout == "True atexit ran from C", out


@pytest.mark.dds
def test_a_node_process_stopped_by_sigint_exits_0_and_leaves_no_dds_segment():
    """The safety monitor's suite process (managed nodes: their handles are garbage in reference cycles until
    collected; without the collection its participant's segment stayed in /dev/shm)."""
    before = dds_segments()
    proc = subprocess.Popen([sys.executable, "-m", "roe_sep.nodes.suite", "--executor", "events", "safety_monitor"],
                            cwd=ROOT, env=ros_env(), stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        deadline = time.monotonic() + 60
        while not dds_segments() - before and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.1)
        if not dds_segments() - before:
            pytest.skip("Fast DDS's shared-memory transport is not in use here (no segment in /dev/shm)")
        time.sleep(1.0)
        proc.send_signal(signal.SIGINT)
        out, _ = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == 0, out
    assert not dds_segments() - before, f"left in {DDS_SHM}: {sorted(dds_segments() - before)}"


def test_the_node_modules_and_the_command_end_through_it():
    """Every node module run as ``python -m`` and the ``roe-sep`` command (console script and ``-m``) end through
    exit_process; the console script is the setup.py entry point ``roe_sep.cli:entry``."""
    nodes = ROOT / "roe_sep" / "nodes"
    mains = [p for p in nodes.glob("*.py") if 'if __name__ == "__main__":' in p.read_text(encoding="utf-8")]
    servers = [p for p in mains if "def main(" in p.read_text(encoding="utf-8") and p.stem != "parameters"]
    assert len(servers) >= 12
    for p in servers:
        assert p.read_text(encoding="utf-8").rstrip().endswith("exit_process(main())"), p.name
    assert "'roe-sep = roe_sep.cli:entry'" in (ROOT / "setup.py").read_text(encoding="utf-8")
    assert (ROOT / "roe_sep" / "cli" / "__main__.py").read_text(encoding="utf-8").rstrip().endswith("entry()")
