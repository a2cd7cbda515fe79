"""A bad file never stops ground_bridge (issue 40): the public CCSDS examples (test/data/ccsds_examples), a file
that is no NDM and files of another epoch, dropped into ``input_dir``, each go to ``input_dir/rejected/`` with a
``.reason`` and an ERROR on ``/diagnostics``, while the node goes on: in a node restarted with them waiting, and in
a closed-loop ``roe-sep run`` whose bag and CCSDS set stay whole."""

import shutil
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from rosutil import rclpy, spin_until, start_node, stop_node  # noqa: I001  (skips without rclpy)

from roe_sep import interfaces
from roe_sep.core.od.radar import DEFAULT_EPOCH_UTC
from roe_sep.ndm import messages as ndm

pytestmark = pytest.mark.dds

DATA = Path(__file__).resolve().parents[1] / "data" / "ccsds_examples"
REFUSED = ("TDMExample2.txt", "TDMExample4.txt", "TDMExample6.txt", "TDMExample6.xml", "TDMExample8.txt")
"""Each refused in the run's span: Doppler only, 2005 epochs, a relay path (the issue's AttributeError), XSYE."""


def _bad_files(inp):
    """The refused public examples and a file that is no NDM into ``inp``; their names."""
    inp.mkdir(parents=True, exist_ok=True)
    for name in REFUSED:
        shutil.copy(DATA / name, inp / name)
    (inp / "garbage.tdm").write_text("CCSDS_TDM_VERS = 2.0\nthis is not a TDM\n")
    return (*REFUSED, "garbage.tdm")


def _rejected(inp, names):
    """Every file of ``names`` in rejected/ with a one-line, non-empty reason beside it, none left in ``inp``."""
    for name in names:
        reason = inp / "rejected" / f"{name}.reason"
        if not (inp / "rejected" / name).is_file() or not reason.is_file() or (inp / name).exists():
            return False
        text = reason.read_text()
        if not text.strip() or text.count("\n") != 1:
            return False
    return True


def test_a_node_restarted_with_bad_files_waiting_rejects_them_and_goes_on(tmp_path):
    inp = tmp_path / "in"
    names = _bad_files(inp)  # waiting when the node starts
    bridge = start_node("ground_bridge", "-p", f"output_dir:={tmp_path / 'ccsds'}", "-p", f"input_dir:={inp}",
                        "-p", "poll_period:=0.2")
    rclpy.init()
    node = rclpy.create_node("ground_bridge_input_test")
    try:
        diag = []
        node.create_subscription(DiagnosticArray, interfaces.DIAGNOSTICS_TOPIC, diag.append, interfaces.DIAGNOSTICS)
        assert spin_until(node, lambda: _rejected(inp, names), 60.0), sorted(p.name for p in inp.rglob("*"))
        assert "PATH 1,2,3,2,1 is not supported" in (inp / "rejected" / "TDMExample6.txt.reason").read_text()
        assert bridge.poll() is None
        # the ERRORs of files dropped once this node hears the bridge (those at its start went before discovery)
        assert spin_until(node, lambda: node.count_publishers(interfaces.DIAGNOSTICS_TOPIC) >= 1, 30.0)
        spin_until(node, lambda: False, 1.0)
        shutil.copy(DATA / "TDMExample6.txt", inp / "relay.txt")
        (inp / "garbage.tdm").write_text("not a TDM either\n")

        def errors_named():
            seen = {s.message for a in diag for s in a.status if s.level == DiagnosticStatus.ERROR}
            return all(any(f"TDM {n} rejected" in m for m in seen) for n in ("relay.txt", "garbage.tdm"))

        assert spin_until(node, errors_named, 30.0), [s.message for a in diag for s in a.status]
        assert any("PATH 1,2,3,2,1" in s.message for a in diag for s in a.status)
        assert bridge.poll() is None
        # and a good file after them is read
        p = ndm.TrackingPass("TIRA", 2, np.array([100.0, 110.0]), np.array([[1.7e6, 2.4, 0.19], [1.6e6, 2.5, 0.2]]),
                             10.0, 1.7e-4)
        ndm.write_message(inp / "good.kvn", ndm.build_tdm(DEFAULT_EPOCH_UTC, [p]), "kvn")
        assert spin_until(node, (inp / "processed" / "good.kvn").is_file, 30.0)
        assert bridge.poll() is None
    finally:
        node.destroy_node()
        rclpy.shutdown()
        code, log = stop_node(bridge, 30.0)
    assert code == 0, log
    assert "Traceback" not in log, log


def test_a_run_with_bad_files_in_its_input_dir_completes_with_a_whole_bag(tmp_path):
    from bagutil import mcap_file, read_mcap_ros2

    from roe_sep.run import run

    inp = tmp_path / "in"
    early = tmp_path / "early"
    names = _bad_files(early)  # waiting when the run starts (their ERRORs may precede the recorder's discovery)
    early.rename(inp)
    late = _bad_files(tmp_path / "late")  # dropped while the bag records: their ERRORs are in it
    params = tmp_path / "params.yaml"
    params.write_text(f"ground_bridge:\n  ros__parameters:\n    input_dir: '{inp}'\n    poll_period: 0.05\n")
    out = tmp_path / "run"
    duration = 6000.0

    def drop_late():
        deadline = time.monotonic() + 120.0
        while time.monotonic() < deadline and not list((out / "bag").glob("*.mcap")):
            time.sleep(0.05)
        time.sleep(1.0)
        for name in late:
            (tmp_path / "late" / name).rename(inp / f"late_{name}")

    dropper = threading.Thread(target=drop_late)
    dropper.start()
    rep = run(out=out, duration=duration, params=params, timeout=300)
    dropper.join()
    assert rep["run"]["completed"], rep["run"]["reason"]
    assert all(c == 0 for c in rep["run"]["exit_codes"].values()), rep["run"]["exit_codes"]
    assert _rejected(inp, names + tuple(f"late_{n}" for n in late)), sorted(p.name for p in inp.rglob("*"))
    # the bag is whole: closed with its summary (mcap's reader), the truth recorded to the end of the run
    topics = read_mcap_ros2(mcap_file(out / "bag"))
    truth = topics[interfaces.TRUTH_ROE_TOPIC]
    stamps = [m.header.stamp.sec + m.header.stamp.nanosec * 1e-9 for m, _t, _s in truth]
    assert max(stamps) >= duration - 60.0, max(stamps)
    assert (out / "ccsds" / "ephemeris.oem.xml").is_file()  # the CCSDS set went on
    statuses = [m for m, _t, _s in topics[interfaces.DIAGNOSTICS_TOPIC]]
    error = int.from_bytes(DiagnosticStatus.ERROR, "little")  # mcap_ros2 decodes a byte as an int
    errors = {s.message for a in statuses for s in a.status if s.level == error}
    assert all(any(f"TDM late_{n} rejected" in e for e in errors) for n in late), errors
