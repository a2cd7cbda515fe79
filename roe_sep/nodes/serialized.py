"""Messages of one type serialized by filling a template's bytes, many at a time (the simulator's truth streams), and
the decoding of a raw subscription's bytes (:func:`subscribe_decoded`: the inputs read at every step of a run, the
truth samples and the lockstep protocol's step and acknowledgement messages).

``publisher.publish(msg)`` converts the Python message field by field and serializes it (rmw's CDR) for every
message; rclpy also publishes a message already serialized (``publish(bytes)``, what a raw subscription receives
and a bag records). :class:`Serialized` lays out a message type's CDR once (XCDR1 little endian, as Fast DDS writes
it: the encapsulation header ``00 01 00 00``, every primitive aligned to its size up to 8 from the end of that
header, padding bytes zero), checks its layout against ``rclpy.serialization.serialize_message`` of the template, and
then writes the fields that change (the stamp, the numbers) of many messages into copies of the template's bytes
with one numpy assignment per field group: the bytes of a typed message with the same field values.
"""

import functools
from collections.abc import Mapping, Sequence

import numpy as np

# the fixed-size primitives of the ROS interface definitions, as numpy little-endian types (their CDR size and
# alignment are the numpy item size)
PRIMITIVES = {"double": "<f8", "float": "<f4", "int64": "<i8", "uint64": "<u8", "int32": "<i4", "uint32": "<u4",
              "int16": "<i2", "uint16": "<u2", "int8": "i1", "uint8": "u1", "octet": "u1", "char": "u1",
              "boolean": "?"}
HEADER = b"\x00\x01\x00\x00"  # CDR little endian, no options


def layout(msg) -> tuple[bytes, bytes, dict]:
    """The CDR bytes of ``msg`` (padding zero), a mask of their padding bytes (1: padding) and ``{field path:
    (offset, numpy type, count)}`` of every primitive field (count > 1: a fixed array), offsets from the start of
    the serialized message (the encapsulation header included). Strings are laid out with their current value;
    sequences and bounded or wide strings are not supported (ValueError)."""
    body, pad, fields = bytearray(), bytearray(), {}

    def align(size):
        gap = -len(body) % min(size, 8)
        body.extend(bytes(gap))
        pad.extend(b"\x01" * gap)

    def walk(m, prefix):
        for name, kind in type(m).get_fields_and_field_types().items():
            value, path = getattr(m, name), prefix + name
            base, _, count = kind.partition("[")
            if base in PRIMITIVES:
                if count and not count[:-1].isdigit():
                    raise ValueError(f"{path}: {kind} is not a fixed-size field")
                dtype = np.dtype(PRIMITIVES[base])
                n = int(count[:-1]) if count else 1
                align(dtype.itemsize)
                fields[path] = (len(HEADER) + len(body), dtype, n)
                data = np.asarray(value, dtype=dtype).reshape(n).tobytes()
                body.extend(data)
                pad.extend(bytes(len(data)))
            elif kind == "string":
                text = value.encode("utf-8") + b"\x00"
                align(4)
                body.extend(np.uint32(len(text)).astype("<u4").tobytes() + text)
                pad.extend(bytes(4 + len(text)))
            elif "/" in kind and not count and "<" not in kind:  # a nested message (not a sequence of them)
                walk(value, path + ".")
            else:
                raise ValueError(f"{path}: {kind} is not supported")

    walk(msg, "")
    return HEADER + bytes(body), bytes(len(HEADER)) + bytes(pad), fields


class Serialized:
    """Serialized ``template`` messages with the ``groups`` filled per message: ``{name: field paths}``, each group
    consecutive fields of one primitive type without padding between them (one column of the rows, of shape
    ``(len(paths),)`` or a scalar for one path). Every other byte is the template's (its frame_id, zero
    covariance). The layout is checked against rclpy's serialization of the template (ValueError if they differ
    anywhere but in padding bytes, which rmw leaves as they were in its buffer)."""

    def __init__(self, template, groups: Mapping[str, Sequence[str]]):
        from rclpy.serialization import serialize_message

        data, pad, fields = layout(template)
        reference = serialize_message(template)
        keep = np.frombuffer(pad, np.uint8) == 0
        if len(reference) != len(data) or np.any((np.frombuffer(reference, np.uint8)
                                                   != np.frombuffer(data, np.uint8)) & keep):
            raise ValueError(f"{type(template).__name__}: CDR layout differs from rclpy's serialization")
        names, formats, offsets = [], [], []
        for name, paths in groups.items():
            offset, dtype, _ = fields[paths[0]]
            for k, path in enumerate(paths):
                if fields[path][:2] != (offset + k * dtype.itemsize, dtype) or fields[path][2] != 1:
                    raise ValueError(f"{name}: {list(paths)} are not consecutive {dtype} fields")
            names.append(name)
            formats.append(dtype if len(paths) == 1 else (dtype, len(paths)))
            offsets.append(offset)
        self.template = np.frombuffer(data, np.uint8)
        self.dtype = np.dtype({"names": names, "formats": formats, "offsets": offsets, "itemsize": len(data)})

    def rows(self, n: int) -> np.ndarray:
        """``n`` copies of the template as a structured array ``(n,)`` whose columns are the groups (fill them)."""
        return np.tile(self.template, (n, 1)).view(self.dtype)[:, 0]

    @staticmethod
    def messages(rows: np.ndarray) -> list[bytes]:
        """The serialized messages of filled :meth:`rows`, ready for ``publish``."""
        raw = rows.view(np.uint8).reshape(len(rows), rows.dtype.itemsize)
        return [row.tobytes() for row in raw]


@functools.lru_cache(maxsize=None)
def decoder_for(msg_type):
    """``bytes -> message`` for a raw subscription to ``msg_type`` (what ``create_subscription(..., raw=True)``
    delivers), or None when the type's definition cannot be compiled (then subscribe typed).

    The message is decoded by the bag reader's compiled CDR decoder (:mod:`roe_sep.bag.cdr`) from the installed
    definition: about 2 µs against rclpy's 15-17 µs for a RelativeOrbitalElements, the same values (a float64 is
    the same Python float, an integer the same int). The object is mcap_ros2's class of the type: the same field
    names and nesting; a fixed array is a list, where rclpy gives a numpy array. One per type in a process (the
    compiled code is shared; a fork server compiles them once for all its runs)."""
    from ..bag.cdr import Decoder
    from ..bag.definitions import full_text
    from ..errors import DefinitionNotFound

    name = f"{msg_type.__module__.split('.')[0]}/msg/{msg_type.__name__}"
    try:
        dec = Decoder(name, full_text(name))
    except (DefinitionNotFound, OSError, ValueError):
        return None
    return dec if dec.fast is not None else None


def subscribe_decoded(node, msg_type, topic, callback, qos, *, on_error):
    """``node.create_subscription(msg_type, topic, callback, qos)`` for a topic read at every step of a run: the
    bytes taken raw and decoded by :func:`decoder_for` (typed when the type has no compiled decoder). The compiled
    decoder reads the plain little-endian CDR (XCDR1, :data:`HEADER`) that Fast DDS writes; other bytes (another
    encapsulation, e.g. XCDR2 from another DDS, or bytes it refuses) are deserialized by rclpy, as a typed
    subscription would; bytes neither decodes go to ``on_error(exc)`` instead of ``callback``, and the node goes
    on."""
    decode = decoder_for(msg_type)
    if decode is None:
        return node.create_subscription(msg_type, topic, callback, qos)
    from rclpy.serialization import deserialize_message

    def take(data):
        msg = None
        if data[:2] == HEADER[:2]:
            try:
                msg = decode(data)
            except Exception:  # noqa: BLE001 -- rclpy's own deserialization below
                pass
        if msg is None:
            try:
                msg = deserialize_message(bytes(data), msg_type)
            except Exception as exc:  # noqa: BLE001 -- bytes that do not decode: dropped and reported
                on_error(exc)
                return
        callback(msg)

    return node.create_subscription(msg_type, topic, take, qos, raw=True)
