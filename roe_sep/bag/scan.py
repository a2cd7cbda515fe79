"""Record-by-record scan of a possibly unfinished MCAP file: the readable prefix, and why reading stopped.

Shared by :mod:`.reader` (``info`` of an unfinished bag) and :mod:`.recover` (rebuilding a complete bag).
"""

import io
import struct

from mcap.exceptions import EndOfFile
from mcap.stream_reader import StreamReader

from .errors import BagError

MAGIC = b"\x89MCAP0\r\n"
_FOOTER = 0x02


class Scan:
    """Iterate the records of a possibly truncated MCAP file. After :meth:`records` is exhausted: ``complete``
    (the footer was reached), ``valid_bytes`` (length of the readable prefix), ``reason`` (why reading stopped)."""

    def __init__(self, file):
        self.file = file
        self.complete = False
        self.valid_bytes = 0
        self.reason = ""
        self.profile = self.library = None

    def records(self):
        with open(self.file, "rb") as fh:
            if fh.read(8) != MAGIC:
                raise BagError(f"{self.file}: not an MCAP file (bad magic)")
            self.valid_bytes = 8
            while True:
                head = fh.read(9)
                if len(head) < 9:
                    self.reason = "end of file" if not head else f"record header cut off at byte {self.valid_bytes}"
                    return
                opcode, length = struct.unpack("<BQ", head)
                body = fh.read(length) if length < 1 << 32 else b""
                if len(body) < length:
                    self.reason = f"record (opcode 0x{opcode:02x}) cut off at byte {self.valid_bytes}"
                    return
                try:
                    parsed = self._parse(head + body)
                except Exception as exc:  # noqa: BLE001  (corrupt record: keep what came before)
                    self.reason = f"unreadable record (opcode 0x{opcode:02x}) at byte {self.valid_bytes}: {exc}"
                    return
                self.valid_bytes += 9 + length
                for rec in parsed:
                    if type(rec).__name__ == "Header":
                        self.profile, self.library = rec.profile, rec.library
                    yield rec
                if opcode == _FOOTER:
                    self.complete = True
                    self.reason = "complete"
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
