"""Record-by-record scan of a possibly unfinished MCAP file: the readable prefix, and why reading stopped.

Shared by :mod:`.reader` (``info`` of an unfinished bag) and :mod:`.recover` (rebuilding a complete bag).
"""

import io
import os
import struct

from mcap.exceptions import EndOfFile
from mcap.stream_reader import StreamReader

from ..checks import one_line
from ..errors import BagError

MAGIC = b"\x89MCAP0\r\n"
_FOOTER = 0x02
MAX_RECORD = 1 << 32  # bytes: a longer record length is corruption, not a chunk cut off by a crash


class Scan:
    """Iterate the records of a possibly truncated MCAP file. After :meth:`records` is exhausted: ``complete``
    (the footer was reached), ``valid_bytes`` (length of the readable prefix), ``reason`` (why reading stopped),
    ``size`` (of the file) and ``kind``: ``"complete"``, ``"truncated"`` (the file just ends early: a recording cut
    off by a crash, everything before the cut is good) or ``"corrupt"`` (a record that fails its CRC or cannot be
    parsed, a record length beyond :data:`MAX_RECORD`, or a file that ends with the closing magic but whose records
    stop before the footer: the bytes after ``valid_bytes`` hold data that cannot be read)."""

    def __init__(self, file):
        self.file = file
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
                    parsed = self._parse(head + body)
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
    def _parse(record: bytes) -> list:
        out = []
        reader = StreamReader(io.BytesIO(record), skip_magic=True, validate_crcs=True)
        try:
            for rec in reader.records:
                out.append(rec)
        except EndOfFile:
            pass
        return out
