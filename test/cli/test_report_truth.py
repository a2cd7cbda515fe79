"""The run report's truth read as arrays straight from the bag (:func:`roe_sep.report.read_truth`, a fixed layout)
equals the truth of the decoded messages that :func:`roe_sep.validate.truth` accepts, to the bit: on the golden
bag, with damaged samples mixed in (NaN, infinities, bounds, negative stamps), and where the arrays do not apply
(other string lengths, bad UTF-8, a second schema) the messages go one by one. No DDS."""

import math
import random
import struct
from pathlib import Path

import numpy as np
import pytest
from mcap.records import Schema

from roe_sep import interfaces, validate
from roe_sep.bag import cdr
from roe_sep.bag.reader import RawMessage
from roe_sep.report import Truth, _valid_items, read_topics, read_truth, truth_at, truth_secular_drift

ROOT = Path(__file__).resolve().parents[2]
BAG = ROOT / "bags" / "default_run"
TOPIC = interfaces.TRUTH_ROE_TOPIC


def _items():
    items = read_topics(BAG, (TOPIC,), raw=(TOPIC,))[TOPIC]
    assert items and all(isinstance(m, RawMessage) for _, m in items)
    return items


def _by_messages(items):
    decoded = [(t, m.decode(m.data) if isinstance(m, RawMessage) else m) for t, m in items]
    return Truth.of_messages(_valid_items(TOPIC, decoded))


def _bits(x):
    return np.asarray(x, dtype=float).tobytes()


def assert_same(a: Truth, b: Truth):
    assert len(a) == len(b)
    assert _bits(a.stamps) == _bits(b.stamps) and _bits(a.a) == _bits(b.a) and _bits(a.inc) == _bits(b.inc)
    assert _bits(a.roe) == _bits(b.roe) and _bits(a.u) == _bits(b.u) and _bits(a.a_da) == _bits(b.a_da)
    assert (a.final_roe is None) == (b.final_roe is None)
    if a.final_roe is not None:
        assert _bits(a.final_roe) == _bits(b.final_roe)
    assert [type(x) for x in a.stamps + a.a + a.inc] == [type(x) for x in b.stamps + b.a + b.inc]


def test_arrays_equal_the_messages_on_the_golden_bag():
    items = _items()
    from roe_sep.report import _truth_arrays

    arrays = _truth_arrays([m for _, m in items])
    assert arrays is not None and len(arrays) == len(items) > 100
    assert_same(arrays, _by_messages(items))
    assert_same(read_truth(items), arrays)
    # the report's functions give the same on the Truth and on the messages
    decoded = [(t, m.decode(m.data)) for t, m in items]
    for t in (arrays.stamps[0] - 1.0, arrays.stamps[len(arrays) // 2], arrays.stamps[-1] + 600.0):
        x, y = truth_at(arrays, t, 0.3), truth_at(decoded, t, 0.3)
        assert (x is None and y is None) or _bits(x) == _bits(y)
        x, y = truth_secular_drift(arrays, t, [0.0, 3000.0]), truth_secular_drift(decoded, t, [0.0, 3000.0])
        assert x == y


def _layout(item):
    fields, strings, end = cdr.fixed_layout(item.decode.msgdefs, item.schema.name, item.data)
    return {path: (off, code, n) for path, off, code, n in fields}


def test_damaged_samples_are_dropped_as_validate_drops_them():
    """Values that :func:`roe_sep.validate.truth` refuses, written into serialized samples at their offsets: the
    arrays keep exactly the samples the messages' check keeps."""
    items = _items()[:400]
    layout = _layout(items[0][1])
    rng = random.Random(5)
    bad = [math.nan, math.inf, -math.inf, 1e308, -1e308, 0.0, -0.0, 7e6 + 1e5, 1.0000001e7, -1.0000001e7, 4.0, 1e-300]
    damaged = []
    for k, (t, m) in enumerate(items):
        data = bytearray(m.data)
        if k % 3:
            path = rng.choice([p for p in layout if p not in ("header.stamp.sec", "header.stamp.nanosec")])
            off, code, n = layout[path]
            slot = off + 8 * rng.randrange(n or 1)
            struct.pack_into("<d", data, slot, rng.choice(bad))
        if k % 7 == 0:
            off = layout[rng.choice(("header.stamp.sec", "header.stamp.nanosec"))][0]
            struct.pack_into("<I", data, off, rng.choice((0xFFFFFFFF, 1_000_000_000, 999_999_999, 0x80000000, 0)))
        damaged.append((t, RawMessage(m.schema, m.decode, bytes(data))))
    got, want = read_truth(damaged), _by_messages(damaged)
    assert 0 < len(want) < len(damaged)
    assert_same(got, want)


def test_other_layouts_go_one_by_one():
    items = _items()[:50]
    t, m = items[3]
    # another frame_id length in one sample: not one layout
    layout_off = 12  # header.stamp (8 bytes) after the 4-byte encapsulation: frame_id's length word
    n = int.from_bytes(m.data[layout_off:layout_off + 4], "little")
    longer = m.data[:layout_off] + (n + 8).to_bytes(4, "little") + m.data[layout_off + 4:layout_off + 4 + n - 1] \
        + b"EXTRAEXT\x00" + m.data[layout_off + 4 + n:]
    mixed = [*items[:3], (t, RawMessage(m.schema, m.decode, longer)), *items[4:]]
    from roe_sep.report import _truth_arrays

    assert _truth_arrays([x for _, x in mixed]) is None
    assert_same(read_truth(mixed), _by_messages(mixed))
    # a frame_id that is not UTF-8: decoding raises, as mcap_ros2 raises
    bad = bytearray(m.data)
    bad[layout_off + 4] = 0xFF
    with pytest.raises(UnicodeDecodeError):
        read_truth([*items[:3], (t, RawMessage(m.schema, m.decode, bytes(bad))), *items[4:]])
    # a second schema (the same text under another record) still one layout; another text: one by one
    other = Schema(id=99, name=m.schema.name, encoding=m.schema.encoding, data=m.schema.data + b"\n")
    dec = cdr.decoder(other, "cdr")
    two = [*items[:3], (t, RawMessage(other, dec, m.data)), *items[4:]]
    assert _truth_arrays([x for _, x in two]) is None
    assert_same(read_truth(two), _by_messages(two))
    # decoded messages (a bag mcap_ros2 read): the same Truth
    assert_same(read_truth([(t, x.decode(x.data)) for t, x in items]), read_truth(items))
    assert len(read_truth([])) == 0 and read_truth([]).final_roe is None


def test_roe_accepted_is_roe():
    """The element-wise check against :func:`roe_sep.validate.roe` on random values around every bound."""
    from types import SimpleNamespace as NS

    rng = random.Random(2)
    edges = [math.nan, math.inf, -math.inf, 0.0, -0.0]
    rows = []
    for _ in range(3000):
        def pick(good, bad):
            return rng.choice(bad) if rng.random() < 0.02 else rng.choice(good)

        chief = {name: pick([lo, hi, (lo + hi) / 2], [lo - 1e-9, hi + 1e-6, *edges])
                 for name, lo, hi, _ in validate.ELEMENT_BOUNDS}
        values = {k: pick([0.0, -0.0, 1e7, -1e7, 123.0], [1.0000001e7, -2e7, *edges]) for k in validate.ROE_FIELDS}
        cov = [pick([0.0, 1.0, -0.0], edges[:3]) for _ in range(36)]
        sec, nsec = pick([0, 5, 2**31 - 1], [-1, -2**31]), pick([0, 999_999_999], [1_000_000_000, 2**32 - 1])
        rows.append((sec, nsec, chief, values, cov))
    got = validate.roe_accepted(np.array([r[0] for r in rows], dtype=np.int32),
                                np.array([r[1] for r in rows], dtype=np.uint32),
                                {n: np.array([r[2][n] for r in rows]) for n, *_ in validate.ELEMENT_BOUNDS},
                                {k: np.array([r[3][k] for r in rows]) for k in validate.ROE_FIELDS},
                                np.array([r[4] for r in rows]))
    want = []
    for sec, nsec, chief, values, cov in rows:
        msg = NS(header=NS(stamp=NS(sec=sec, nanosec=nsec)), chief=NS(**chief), covariance=cov, **values)
        try:
            validate.truth(msg)
            want.append(True)
        except ValueError:
            want.append(False)
    assert got.tolist() == want and 0 < sum(want) < len(want)


def test_the_report_keeps_the_verdicts_and_what_happened():
    """The golden bag's report: the passive-safety verdicts (named as such, one count per truth check) beside the
    truth's actual approach, whose closest approach is the simulator's (on its 10-s grid, so at most a few cm above
    the refined one) within the refinement's bound."""
    from roe_sep.report import build_report

    rep = build_report(BAG, 280800.0)
    ps = rep["passive_safety"]
    assert set(ps) == {"keep_out", "passive_safety", "evaporation"}
    assert all(v["held"] and v["checks"] > 400 and v["failed_checks"] == 0 for v in ps.values())
    ap = rep["actual_approach"]
    closest = ap["closest_approach"]
    assert closest["distance"] <= rep["min_distance"] <= closest["distance"] + closest["bound"] + 0.05
    assert abs(closest["epoch"] - rep["min_distance_epoch"]) < 10.0 and not closest["at_end"]
    assert rep["ejection_epoch"] < ap["departure_epoch"] < closest["epoch"]
    assert ap["keep_out_time"] == 0.0 and ap["keep_out_entries"] == 0 and not ap["keep_out_violated"]
    assert ap["sampling"]["truth_step"] == 300.0 and ap["keep_out_radius"] == 1000.0
    assert ap["after_first_orbit"]["distance"] >= closest["distance"]
    assert ap["nearest"] == {k: closest[k] for k in ("distance", "epoch", "bound")}  # no approach before departing


def test_a_keep_out_above_the_closest_approach_is_violated_in_the_truth():
    """The golden truth against a keep-out sphere 100 m beyond its closest approach: the pair comes back inside it,
    and the truth says so (entries, time inside)."""
    from roe_sep.core.relmotion.orbit import mean_motion
    from roe_sep.core.safety.approach import actual_approach

    msgs = read_topics(BAG, (interfaces.TRUTH_RTN_TOPIC,))[interfaces.TRUTH_RTN_TOPIC]
    t = np.array([m.header.stamp.sec + m.header.stamp.nanosec * 1e-9 for _, m in msgs])
    pos = np.array([[m.position.x, m.position.y, m.position.z] for _, m in msgs])
    vel = np.array([[m.velocity.x, m.velocity.y, m.velocity.z] for _, m in msgs])
    n = float(mean_motion(7.0e6))
    base = actual_approach(t, pos, vel, n, 1000.0, start=602.78547875)
    closer = actual_approach(t, pos, vel, n, base.closest_distance + 100.0, start=602.78547875)
    assert not base.keep_out_violated and closer.keep_out_violated and closer.keep_out_entries >= 1
    assert closer.keep_out_s > 0.0
