"""The compiled CDR decoders (:mod:`roe_sep.bag.cdr`) decode exactly what mcap_ros2 decodes, and the bag reader
built on them (:func:`roe_sep.bag.reader.decoded_messages`) reads exactly what mcap_ros2's reader reads: field by
field (types, float bits, the generated classes) on the golden bag and on schemas made to exercise CDR's alignment
rules, fuzzed bytes, and damaged files (refused with a BagError that names the file and the reason, where
mcap_ros2 raises too). No DDS."""

import math
import random
import re
import struct
from pathlib import Path

import pytest
from mcap.records import Schema
from mcap.writer import CompressionType, Writer
from mcap_ros2 import _dynamic
from mcap_ros2.decoder import DecoderFactory
from mcap_ros2.reader import read_ros2_messages

from roe_sep.bag import cdr
from roe_sep.bag.reader import decoded_messages
from roe_sep.errors import BagError

ROOT = Path(__file__).resolve().parents[2]
GOLDEN = ROOT / "bags" / "default_run" / "bag_0.mcap"


def differences(a, b, path="msg"):
    """Where two decoded messages differ (None: the same class layout, types and values, floats to the bit)."""
    if type(a).__name__ != type(b).__name__ or type(a) in (int, float, str, bytes, bool) and type(a) is not type(b):
        return f"{path}: {type(a).__name__} != {type(b).__name__}"
    if hasattr(type(a), "_type"):  # an mcap_ros2 message class
        ca, cb = type(a), type(b)
        if (ca._type, ca._full_text, list(ca.__slots__)) != (cb._type, cb._full_text, list(cb.__slots__)):
            return f"{path}: class {ca._type} differs"
        for k in ca.__slots__:
            d = differences(getattr(a, k), getattr(b, k), f"{path}.{k}")
            if d:
                return d
        return None
    if isinstance(a, list):
        if len(a) != len(b):
            return f"{path}: {len(a)} items != {len(b)}"
        for i, (x, y) in enumerate(zip(a, b)):
            d = differences(x, y, f"{path}[{i}]")
            if d:
                return d
        return None
    if isinstance(a, float):
        return None if struct.pack("<d", a) == struct.pack("<d", b) else f"{path}: {a!r} != {b!r}"
    return None if a == b else f"{path}: {a!r} != {b!r}"


def outcome(fn, data):
    try:
        return fn(data)
    except Exception as exc:  # noqa: BLE001
        return (type(exc), str(exc))


def schema(name, text, sid=1):
    return Schema(id=sid, name=name, encoding="ros2msg", data=text.encode())


def test_golden_bag_every_message_field_by_field():
    from mcap.reader import make_reader

    factory = DecoderFactory()
    mine, n = {}, 0
    with open(GOLDEN, "rb") as fh:
        for sch, channel, message in make_reader(fh).iter_messages():
            if sch.id not in mine:
                mine[sch.id] = cdr.decoder(sch, channel.message_encoding)
                assert mine[sch.id].fast is not None, f"{sch.name} not compiled"
            reference = factory.decoder_for(channel.message_encoding, sch)(message.data)
            d = differences(mine[sch.id].fast(message.data), reference)
            assert d is None, f"{channel.topic}: {d}"
            n += 1
    assert n > 1000 and len(mine) >= 10


EDGE = """\
uint8 KIND_A=1
string KIND_NAME="x"
bool flag
string name
float64 x
int8 i8
float32 f32
char c
byte by
int16 i16
uint64 u64
string[] names
float64[] xs
uint8[] raw
byte[4] fixed_raw
uint8[3] fixed_u8
char[3] chars
bool[2] flags
int32[<=3] bounded
float64[2] pair
builtin_interfaces/Time stamp
Inner inner
Inner[] inners
Inner[2] two_inners
Empty empty
uint16 after_empty
string<=5 short
string[2] two_names
int64[] i64s
uint16[] u16s
float32[] f32s
bool[] bits
char[] cs
Inner[<=2] few
float64 last
================================================================================
MSG: test_msgs/Inner
string label
float64 value
bool[] bits
int16 small
================================================================================
MSG: test_msgs/Empty
================================================================================
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec
"""


def _value(rng, ftype, msgdefs, depth=0):
    """A random value of a field type, as mcap_ros2's encoder takes it."""
    def one():
        t = ftype.type
        if not ftype.is_primitive_type():
            return _random_message(rng, msgdefs[f"{ftype.pkg_name}/{t}"], msgdefs, depth + 1)
        if t == "bool":
            return rng.random() < 0.5
        if t == "string":
            return "".join(rng.choice("ab\u00e9\u20ac ") for _ in range(rng.choice((0, 0, 1, 2, 3, 5, 8))))
        if t in ("float32", "float64"):
            v = rng.choice((0.0, -0.0, math.inf, -math.inf, math.nan, 1e-310, rng.uniform(-1e9, 1e9)))
            return struct.unpack("<f", struct.pack("<f", v))[0] if t == "float32" and math.isfinite(v) else v
        code, size = cdr.PRIMITIVES[t]
        lo, hi = (0, 256 ** size - 1) if code.isupper() else (-(256 ** size) // 2, 256 ** size // 2 - 1)
        return rng.randint(lo, hi)
    if not ftype.is_array:
        return one()
    n = ftype.array_size if ftype.is_fixed_size_array() else rng.randint(0, ftype.array_size or 4)
    if ftype.type in cdr.BYTES:
        return bytes(rng.randrange(256) for _ in range(n))
    return [one() for _ in range(n)]


def _random_message(rng, msgdef, msgdefs, depth=0):
    return {f.name: _value(rng, f.type, msgdefs, depth) for f in msgdef.fields}


@pytest.mark.parametrize("text", [EDGE, "string a\nfloat64 b\n", "bool a\nint64 b\nstring c\nint8 d\nfloat64[3] e\n",
                                  "uint8[] a\nfloat64 b\n", "float32 a\nfloat64[] b\nint16[] c\nfloat64 d\n"])
def test_alignment_edge_cases_and_fuzz(text):
    """Random messages of schemas that put every primitive after strings and sequences of every length (CDR
    alignment from the payload start, an empty sequence not aligning), then the same bytes cut off, extended and
    with bytes changed: wherever the compiled code decodes, it is mcap_ros2's result."""
    rng = random.Random(7)
    name = "test_msgs/msg/Edge"
    dec = cdr.decoder(schema(name, text), "cdr")
    assert dec.fast is not None, "not compiled"
    reference = DecoderFactory().decoder_for("cdr", schema(name, text))
    encode = _dynamic.serialize_dynamic(name, text)[name]
    msgdef = dec.msgdefs[name]
    fast_ok = 0
    for k in range(300):
        data = encode(_random_message(rng, msgdef, dec.msgdefs))
        assert differences(dec.fast(data), reference(data)) is None
        variants = [data[:rng.randrange(len(data))], data + bytes(rng.randrange(9))]
        mutated = bytearray(data)
        for _ in range(rng.randint(1, 4)):
            mutated[rng.randrange(4, len(data))] = rng.choice((0, 1, 2, 0xFF, 0x80, rng.randrange(256)))
        variants.append(bytes(mutated))
        for v in variants:
            fast = outcome(dec.fast, v)
            if not isinstance(fast, tuple):
                fast_ok += 1
                assert differences(fast, reference(v)) is None, v.hex()
            assert differences(outcome(dec, v), outcome(reference, v)) is None  # fast or not: mcap_ros2's outcome
    assert fast_ok > 100


def test_strings_of_length_zero_and_one_and_big_endian():
    """A string of length 0 or 1 (serializers differ) reads as ''; big-endian CDR goes to mcap_ros2."""
    name = "test_msgs/msg/S"
    text = "string a\nfloat64 b\nstring c\nint32 d\n"
    dec = cdr.decoder(schema(name, text), "cdr")
    reference = DecoderFactory().decoder_for("cdr", schema(name, text))
    for n in (0, 1):
        data = (b"\x00\x01\x00\x00" + struct.pack("<I", n) + b"\x00" * n + bytes(-(4 + n) % 8) + struct.pack("<d", 2.5)
                + struct.pack("<I", 3) + b"hi\x00" + b"\x00" + struct.pack("<i", -7))
        got = dec.fast(data)
        assert (got.a, got.b, got.c, got.d) == ("", 2.5, "hi", -7)
        assert differences(got, reference(data)) is None
    big = _dynamic.serialize_dynamic(name, text)[name]({"a": "x", "b": 1.5, "c": "yz", "d": 3})
    big = b"\x00\x00" + big[2:]  # the CDR_BE kind: the same bytes read big-endian by both
    assert differences(outcome(dec, big), outcome(reference, big)) is None


def test_uncovered_definitions_are_decoded_by_mcap_ros2():
    name = "test_msgs/msg/W"
    for text in ("wstring a\n", "Missing m\n", "time t\n"):
        dec = cdr.decoder(schema(name, text), "cdr")
        assert dec.fast is None
        data = b"\x00\x01\x00\x00" + bytes(16)
        assert differences(outcome(dec, data), outcome(DecoderFactory().decoder_for("cdr", schema(name, text)), data)) \
            is None
    assert cdr.decoder(schema(name, "int32 a\n"), "json") is None  # not CDR: no decoder, as mcap_ros2 has none
    with pytest.raises(Exception, match="schema parsing failed"):
        cdr.decoder(schema("other/msg/Name", "MSG: test_msgs/A\nint32 a\n"), "cdr")


def _reference(file, topics):
    return [(m.channel.topic, m.log_time_ns, m.ros_msg) for m in read_ros2_messages(str(file), topics=list(topics))]


def _same_reading(file, topics, refused=None):
    """``decoded_messages`` against mcap_ros2's reader: the same messages; or, where mcap_ros2 raises, a BagError
    naming the file and matching ``refused`` (the reason)."""
    mine = outcome(lambda f: decoded_messages(f, topics), file)
    ref = outcome(lambda f: _reference(f, topics), file)
    if refused is not None or isinstance(ref, tuple):
        assert isinstance(ref, tuple), "mcap_ros2 reads it"
        assert isinstance(mine, tuple) and mine[0] is BagError and str(file) in mine[1], mine
        assert refused is not None and re.search(refused, mine[1]), mine[1]
        return
    assert not isinstance(mine, tuple), mine
    assert len(mine) == len(ref)
    for (t1, l1, m1), (t2, l2, m2) in zip(mine, ref):
        assert (t1, l1) == (t2, l2)
        assert differences(m1, m2) is None


@pytest.mark.parametrize("topics", [("/sim/truth/roe",), ("/diagnostics", "/safety/status", "/od/estimate"),
                                    ("/sim/executed_maneuvers", "/acquisition/plan", "/separation/drift_stop_plan",
                                     "/safety/plan_check", "/sim/truth/roe", "/clock", "/rosout",
                                     "/parameter_events", "/radar/measurements"), ("/no/such/topic",)])
def test_reader_reads_what_mcap_ros2_reads(topics):
    _same_reading(GOLDEN, topics)


def _write(path, messages, chunk_size=600, chunking=True):
    """An MCAP file of ``(topic, log_time, payload)`` on two schemas (small chunks: messages of one log time in
    several chunks)."""
    with open(path, "wb") as fh:
        w = Writer(fh, chunk_size=chunk_size, compression=CompressionType.NONE, use_chunking=chunking)
        w.start(profile="ros2", library="test")
        s1 = w.register_schema("test_msgs/msg/A", "ros2msg", b"string a\nfloat64 b\n")
        s2 = w.register_schema("test_msgs/msg/B", "ros2msg", b"int8 k\nfloat64[2] v\n")
        channels = {"/a": w.register_channel("/a", "cdr", s1), "/b": w.register_channel("/b", "cdr", s2),
                    "/raw": w.register_channel("/raw", "json", 0)}
        for topic, log_time, payload in messages:
            w.add_message(channels[topic], log_time=log_time, data=payload, publish_time=log_time)
        w.finish()


def _payloads(rng, n):
    a = _dynamic.serialize_dynamic("test_msgs/msg/A", "string a\nfloat64 b\n")["test_msgs/msg/A"]
    b = _dynamic.serialize_dynamic("test_msgs/msg/B", "int8 k\nfloat64[2] v\n")["test_msgs/msg/B"]
    for i in range(n):
        t = rng.choice((5, 5, 7, 3, 100 + i, 50 - i % 7))  # ties across chunks, log times out of file order
        if rng.random() < 0.5:
            yield "/a", t, a({"a": "s" * (i % 5), "b": float(i)})
        else:
            yield "/b", t, b({"k": i % 100, "v": [float(i), -float(i)]})


def test_reader_order_ties_and_damaged_files(tmp_path):
    """Log-time order with ties across chunks (mcap's order: log time, then position in the file), a file without
    chunks: the same messages as mcap_ros2; a cut-off file, a message on a non-CDR channel and an undecodable
    message: a BagError that says so (mcap_ros2 raises too)."""
    rng = random.Random(3)
    msgs = list(_payloads(rng, 200))
    _write(tmp_path / "ties.mcap", msgs)
    for topics in (("/a",), ("/b",), ("/a", "/b")):
        _same_reading(tmp_path / "ties.mcap", topics)
    _write(tmp_path / "flat.mcap", msgs, chunking=False)
    _same_reading(tmp_path / "flat.mcap", ("/a", "/b"))
    data = (tmp_path / "ties.mcap").read_bytes()
    (tmp_path / "cut.mcap").write_bytes(data[: len(data) // 2])
    _same_reading(tmp_path / "cut.mcap", ("/a",), refused=r"mcap cannot read it \(\w+: .*\); `roe-sep bag info`")
    _write(tmp_path / "json.mcap", [*msgs[:20], ("/raw", 9, b"{}")])
    _same_reading(tmp_path / "json.mcap", ("/a", "/raw"), refused=r"no ROS 2 decoder for /raw \(message encoding "
                                                                   r"'json', schema 'none'\)")
    _same_reading(tmp_path / "json.mcap", ("/a", "/b"))
    _write(tmp_path / "bad.mcap", [*msgs[:30], ("/a", 6, b"\x00\x01\x00\x00\xff\xff\xff\x7f")])
    _same_reading(tmp_path / "bad.mcap", ("/a",), refused=r"the message on /a logged at 6 ns does not decode as "
                                                          r"test_msgs/msg/A \(\w+")


def test_scan_fast_chunks_and_indexes_equal_the_stream_reader(monkeypatch, tmp_path):
    """:class:`~roe_sep.bag.scan.Scan` reads chunks and message indexes itself: the same records as mcap's
    StreamReader, and ``info`` and ``recover`` the same on the golden bag and on copies with bytes changed (CRC
    failures, records that no longer fit) or cut off."""
    from roe_sep.bag import info, scan
    from roe_sep.bag.recover import recover

    def both(fn):
        fast = outcome(fn, None)
        monkeypatch.setattr(scan, "_FAST", {})
        slow = outcome(fn, None)
        monkeypatch.undo()
        return fast, slow

    fast, slow = both(lambda _: list(scan.Scan(GOLDEN).records()))
    assert fast == slow and len(fast) > 1000
    from mcap.reader import make_reader

    data = GOLDEN.read_bytes()
    with open(GOLDEN, "rb") as fh:
        chunks = [(ci.chunk_start_offset, ci.chunk_length) for ci in make_reader(fh).get_summary().chunk_indexes]
    no_crc = bytearray(data)
    for start, _ in chunks:  # a chunk's CRC 0: not checked, its damaged records are read as they are
        no_crc[start + 9 + 24:start + 9 + 28] = bytes(4)
    rng = random.Random(11)
    kinds = set()
    for k in range(24):
        damaged = bytearray(data if k < 12 else no_crc)
        if k % 3 == 2:
            damaged = damaged[: rng.randrange(len(data))]
        elif k < 12:
            for _ in range(k % 3 + 1):
                damaged[rng.randrange(8, len(data) - 8)] ^= 1 << rng.randrange(8)
        else:  # inside a chunk's records: lengths, opcodes, message headers
            start, length = rng.choice(chunks)
            for _ in range(k % 3 + 1):
                damaged[rng.randrange(start + 60, start + length)] = rng.choice((0, 1, 3, 4, 5, 0xFF, 0x10))
        file = tmp_path / f"damaged{k}.mcap"
        file.write_bytes(bytes(damaged))
        fast, slow = both(lambda _, f=file: info(f))
        assert fast == slow
        kinds.add(fast["damage_kind"] if isinstance(fast, dict) else "raised")
        results = []
        for fast_chunks in (True, False):
            if not fast_chunks:
                monkeypatch.setattr(scan, "_FAST", {})
            out = tmp_path / f"out{k}{fast_chunks}"
            r = outcome(lambda f, out=out: recover(f, out), file)
            if isinstance(r, dict):
                r = {**r, "output": None, "messages_written": list(scan.Scan(next(out.glob("*.mcap"))).records())}
                r["messages_written"] = [m for m in r["messages_written"] if type(m).__name__ == "Message"]
            results.append(r)
            monkeypatch.undo()
        assert results[0] == results[1]
    assert kinds >= {"corrupt", "truncated"}


def test_metadata_yaml_parsed_as_pyyaml_parses_it(tmp_path):
    import yaml

    from roe_sep.bag import metadata

    text = (ROOT / "bags" / "default_run" / "metadata.yaml").read_text(encoding="utf-8")
    assert metadata._load(text) == yaml.safe_load(text)
    with open(ROOT / "bags" / "default_run" / "metadata.yaml", encoding="utf-8") as fh:
        assert metadata._load(fh) == yaml.safe_load(text)
    for bad in (text[: len(text) // 2] + "\n  - [", "a: [1, 2\n", "\tb: 1\n", "a: 1\na: 2\n",
                "x: !!python/name:os.system\n"):
        path = tmp_path / "m.yaml"
        path.write_text(bad, encoding="utf-8")
        with open(path, encoding="utf-8") as fh:
            got = outcome(metadata._load, fh)
        with open(path, encoding="utf-8") as fh:
            want = outcome(yaml.safe_load, fh)
        assert got == want
