"""Record-by-record scan of a possibly unfinished MCAP file: the readable prefix, and why reading stopped.

Shared by :mod:`.reader` (``info`` of an unfinished bag) and :mod:`.recover` (rebuilding a complete bag).
"""

import collections
import io
import os
import struct

from mcap.data_stream import ReadDataStream
from mcap.exceptions import EndOfFile
from mcap.opcode import Opcode
from mcap.records import Channel, Chunk, Message, MessageIndex, Schema
from mcap.stream_reader import StreamReader, get_chunk_data_stream

from ..checks import one_line
from ..errors import BagError, IrregularBag

MAGIC = b"\x89MCAP0\r\n"
_FOOTER = 0x02
MAX_RECORD = 1 << 32  # bytes: a longer record length is corruption, not a chunk cut off by a crash
_HEAD = struct.Struct("<BQ")  # opcode, length of a record
MESSAGE_HEAD = struct.Struct("<HIQQ")  # channel id, sequence, log time, publish time of a Message record
MESSAGE_HEAD_SIZE = MESSAGE_HEAD.size  # 22 bytes, then the message data


def chunk_records(data: bytes):
    """``(opcode, start, end, record)`` of each record in a chunk's records section ``data`` (uncompressed), in
    file order: its body is ``data[start:end]``; ``record`` the parsed Channel or Schema, None for the others (a
    Message is ``MESSAGE_HEAD`` then its data). The records as mcap's ``breakup_chunk`` reads them, without a
    Python object per message; Irregular where it would read differently (a record running past the chunk, a
    Message shorter than its header, a Channel or Schema whose fields do not fill its length exactly)."""
    pos, n = 0, len(data)
    unpack_head = _HEAD.unpack_from
    while pos < n:
        if pos + 9 > n:
            raise IrregularBag(f"record header cut off at chunk byte {pos}")
        opcode, length = unpack_head(data, pos)
        start = pos + 9
        end = start + length
        if end > n:
            raise IrregularBag(f"record at chunk byte {pos} runs past the chunk")
        record = None
        if opcode == Opcode.MESSAGE:
            if length < MESSAGE_HEAD_SIZE:
                raise IrregularBag(f"message at chunk byte {pos} shorter than its header")
        elif opcode in (Opcode.CHANNEL, Opcode.SCHEMA):
            stream = ReadDataStream(io.BytesIO(data[start:end]))
            try:
                record = (Channel if opcode == Opcode.CHANNEL else Schema).read(stream)
            except Exception as exc:  # noqa: BLE001
                raise IrregularBag(f"record at chunk byte {pos}: {type(exc).__name__}") from None
            if stream.count != length:
                raise IrregularBag(f"record at chunk byte {pos} does not fill its length")
        yield opcode, start, end, record
        pos = end


def chunk_data(chunk) -> bytes:
    """The records section of a Chunk record, decompressed as mcap decompresses it (no CRC check)."""
    stream, length = get_chunk_data_stream(chunk, validate_crc=False)
    return stream.read(length)


class Scan:
    """Iterate the records of a possibly truncated MCAP file. After :meth:`records` is exhausted: ``complete``
    (the footer was reached), ``valid_bytes`` (length of the readable prefix), ``reason`` (why reading stopped),
    ``size`` (of the file) and ``kind``: ``"complete"``, ``"truncated"`` (the file just ends early: a recording cut
    off by a crash, everything before the cut is good) or ``"corrupt"`` (a record that fails its CRC or cannot be
    parsed, a record length beyond :data:`MAX_RECORD`, or a file that ends with the closing magic but whose records
    stop before the footer: the bytes after ``valid_bytes`` hold data that cannot be read)."""

    def __init__(self, file, message_counts=False):
        self.file = file
        self.message_counts = message_counts
        self.complete = False
        self.valid_bytes = 0
        self.reason = ""
        self.kind = ""
        self.size = 0
        self.profile = self.library = None

    def _stop(self, fh, reason, corrupt=False):
        self.reason = reason
        fh.seek(max(self.size - len(MAGIC), 0))
        closed = self.size >= 2 * len(MAGIC) and fh.read(len(MAGIC)) == MAGIC  # the writer finished the file
        self.kind = "corrupt" if corrupt or closed else "truncated"

    def records(self):
        with open(self.file, "rb") as fh:
            self.size = os.fstat(fh.fileno()).st_size
            if fh.read(8) != MAGIC:
                raise BagError(f"{self.file}: not an MCAP file (bad magic)")
            self.valid_bytes = 8
            while True:
                head = fh.read(9)
                if len(head) < 9:
                    self._stop(fh, "end of file before the footer" if not head
                               else f"record header cut off at byte {self.valid_bytes}")
                    return
                opcode, length = struct.unpack("<BQ", head)
                if length >= MAX_RECORD:
                    self._stop(fh, f"record (opcode 0x{opcode:02x}) at byte {self.valid_bytes} claims an impossible "
                                   f"length of {length} bytes", corrupt=True)
                    return
                body = fh.read(length)
                if len(body) < length:
                    self._stop(fh, f"record (opcode 0x{opcode:02x}) of {length} bytes cut off at byte "
                                   f"{self.valid_bytes}")
                    return
                try:
                    parsed = self._parse(head + body, self.message_counts)
                except Exception as exc:  # noqa: BLE001  (corrupt record: keep what came before)
                    self._stop(fh, f"unreadable record (opcode 0x{opcode:02x}) at byte {self.valid_bytes}: "
                                   f"{type(exc).__name__}: {one_line(exc)}", corrupt=True)
                    return
                self.valid_bytes += 9 + length
                for rec in parsed:
                    if type(rec).__name__ == "Header":
                        self.profile, self.library = rec.profile, rec.library
                    yield rec
                if opcode == _FOOTER:
                    if fh.read(len(MAGIC)) == MAGIC:
                        self.complete = True
                        self.reason = self.kind = "complete"
                    else:
                        self._stop(fh, f"closing magic after the footer missing at byte {self.valid_bytes}")
                    return

    @staticmethod
    def _parse(record: bytes, message_counts=False) -> list:
        """The records of one top-level record as mcap's StreamReader reads them (a Chunk: the records inside it,
        CRC checked); with ``message_counts`` a Chunk's messages as one :class:`MessageCounts`."""
        fast = _FAST.get(record[0])
        if fast is not None:
            out = fast(record, message_counts)
            if out is not None:
                return out
        out = []
        reader = StreamReader(io.BytesIO(record), skip_magic=True, validate_crcs=True)
        try:
            for rec in reader.records:
                out.append(rec)
        except EndOfFile:
            pass
        return out


MessageCounts = collections.namedtuple("MessageCounts", "counts start end")
MessageCounts.__doc__ = """The Message records of a chunk (:class:`Scan` with ``message_counts``): per channel id
their number, the least and the greatest log time (None without a message)."""


def _chunk(record: bytes, message_counts: bool):
    """What mcap's StreamReader reads of a Chunk record (its Channel, Schema and Message records, the CRC of its
    data checked), read with :func:`chunk_records`; None for anything unusual (the CRC failing, a chunk that does
    not fill its record, an irregular one): the StreamReader then reads it and says what is wrong."""
    try:
        stream = ReadDataStream(io.BytesIO(record))
        stream.read1()
        length = stream.read8()
        chunk = Chunk.read(stream)
        if stream.count > 9 + length:
            return None
        data_stream, size = get_chunk_data_stream(chunk, validate_crc=True)
        data = data_stream.read(size)
        out = []
        counts, start, end = {}, None, None
        unpack = MESSAGE_HEAD.unpack_from
        for opcode, begin, stop, rec in chunk_records(data):
            if opcode == Opcode.MESSAGE:
                channel_id, sequence, log_time, publish_time = unpack(data, begin)
                if message_counts:
                    counts[channel_id] = counts.get(channel_id, 0) + 1
                    if start is None or log_time < start:
                        start = log_time
                    if end is None or log_time > end:
                        end = log_time
                else:
                    out.append(Message(channel_id=channel_id, log_time=log_time,
                                       data=data[begin + MESSAGE_HEAD_SIZE:stop], publish_time=publish_time,
                                       sequence=sequence))
            elif rec is not None:
                out.append(rec)
        if message_counts:
            out.append(MessageCounts(counts, start, end))
        return out
    except Exception:  # noqa: BLE001 -- the StreamReader reads it again and reports it
        return None


_INDEX_HEAD = struct.Struct("<HI")


def _message_index(record: bytes, message_counts: bool):
    """A MessageIndex record as mcap reads it, when its entries fill their length exactly; else None."""
    length = len(record) - 9
    if length < 6:
        return None
    channel_id, size = _INDEX_HEAD.unpack_from(record, 9)
    if size % 16 or 6 + size > length:
        return None
    return [MessageIndex(channel_id, list(_INDEX_ENTRY.iter_unpack(record[15:15 + size])))]


_INDEX_ENTRY = struct.Struct("<QQ")
_FAST = {Opcode.CHUNK: _chunk, Opcode.MESSAGE_INDEX: _message_index}
