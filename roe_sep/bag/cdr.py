"""Decoding of a bag's CDR messages compiled from the bag's own schema: the objects mcap_ros2 decodes, faster.

mcap_ros2 decodes a message by walking its parsed definition field by field (one aligned ``struct`` call per
number, one list comprehension per array), which costs more than everything else the run report does with a bag.
:func:`decoder` compiles a schema once into Python code: runs of fixed-size fields (nested messages, fixed arrays)
whose CDR alignment is known at compile time become one ``struct`` unpack with the padding in its format; strings,
sequences and alignments that depend on the data are read inline. The schema is the bag's (the ros2msg text in the
MCAP's schema record, parsed by mcap_ros2's own parser into the same definitions), never the installed message
classes: a bag recorded with other message versions decodes as its own schema says.

The decoded objects are mcap_ros2's (the same generated classes, type names, slots and values: ``float64[36]`` a
list of floats, ``uint8[]`` bytes, ``builtin_interfaces/Time`` as the schema defines it). Whatever the compiled code
does not cover -- big-endian data, ``wstring``, a definition mcap_ros2 cannot decode either, or a message it cannot
read (cut off) -- is decoded by mcap_ros2 itself, so a message decodes, or fails, exactly as mcap_ros2 has it.
"""

import functools
import keyword
import struct

from mcap.well_known import MessageEncoding, SchemaEncoding

from ..errors import UnsupportedSchema

try:  # the definitions and message classes of mcap_ros2 (not its public API): the same reading of a schema
    from mcap_ros2 import _dynamic
    from mcap_ros2.decoder import DecoderFactory, McapROS2DecodeError

    _COMPILE = all(hasattr(_dynamic, n) for n in ("TimeDefinition", "_for_each_msgdef", "_message_class",
                                                  "_read_message"))
except ImportError:  # pragma: no cover - mcap_ros2 is a dependency
    _COMPILE = False

# ros2msg primitive -> (struct code, size); CDR aligns a primitive to its size (from the start of the payload,
# after the 4-byte encapsulation header)
PRIMITIVES = {"bool": ("?", 1), "byte": ("B", 1), "char": ("b", 1), "int8": ("b", 1), "uint8": ("B", 1),
              "int16": ("h", 2), "uint16": ("H", 2), "int32": ("i", 4), "uint32": ("I", 4), "int64": ("q", 8),
              "uint64": ("Q", 8), "float32": ("f", 4), "float64": ("d", 8)}
BYTES = ("byte", "uint8")  # arrays of these decode to bytes (mcap_ros2's uint8_array), the others to lists
MAX_INLINE = 32  # nested messages inlined deeper than this: give up (a definition that contains itself)


class _Function:
    """The code of one decoding function: ``o`` is the read offset in the bytes ``b``; what is known of the
    alignment is ``(o - 4) % mod == rem`` plus ``run`` bytes of a pending fixed-size run starting at ``o``."""

    def __init__(self, compiler, indent="    "):
        self.c = compiler
        self.lines = []
        self.indent = indent
        self.mod, self.rem = 1, 0  # nothing known at the start of an element function
        self.fmt, self.run, self.count, self.assign = [], 0, 0, []
        self.objects = 0

    def emit(self, line):
        self.lines.append(self.indent + line)

    def new_object(self, msgdef):
        name = f"x{self.objects}"
        self.objects += 1
        self.emit(f"{name} = {self.c.cls(msgdef)}()")
        return name

    # -- fixed-size runs: one struct unpack ------------------------------------------------------------------------
    def align(self, size):
        """Pad the pending run to ``size`` (statically when the alignment is known, else flush and align ``o``)."""
        if size <= 1:
            return
        if size <= self.mod:
            pad = -(self.rem + self.run) % size
            if pad:
                self.fmt.append(f"{pad}x")
                self.run += pad
            return
        self.flush()
        self.emit(f"o += (4 - o) % {size}")
        self.mod, self.rem = size, 0

    def fixed(self, code, size, target, n=None):
        """A primitive (``n`` None), a fixed array of ``n`` primitives or ``n`` bytes (``code`` ``s``) into
        ``target``."""
        self.align(size)
        if code == "s":
            self.fmt.append(f"{n}s")
            self.assign.append(f"{target} = v[{self.count}]")
            self.count += 1
            self.run += n
        elif n is None:
            self.fmt.append(code)
            self.assign.append(f"{target} = v[{self.count}]")
            self.count += 1
            self.run += size
        else:
            self.fmt.append(f"{n}{code}")
            self.assign.append(f"{target} = list(v[{self.count}:{self.count + n}])")
            self.count += n
            self.run += n * size

    def pad_byte(self):
        """One byte read and dropped (the placeholder member of an empty message)."""
        self.fmt.append("x")
        self.run += 1

    def flush(self):
        if not self.run:
            return
        s = self.c.const(struct.Struct("<" + "".join(self.fmt)), "S")
        self.emit(f"v = {s}.unpack_from(b, o)" if self.count else f"{s}.unpack_from(b, o)")
        self.emit(f"o += {self.run}")
        for line in self.assign:
            self.emit(line)
        self.rem = (self.rem + self.run) % self.mod
        self.fmt, self.run, self.count, self.assign = [], 0, 0, []

    def unknown(self, mod=1):
        """After data-dependent lengths: only ``(o - 4) % mod == 0`` is known."""
        self.mod, self.rem = mod, 0

    # -- data-dependent parts ----------------------------------------------------------------------------------------
    def uint32(self, target):
        self.align(4)
        self.flush()
        self.emit(f"{target} = U32(b, o)[0]")
        self.emit("o += 4")
        self.rem = (self.rem + 4) % self.mod

    def string(self, target):
        self.uint32("n")
        self.emit("if n <= 1:")
        self.emit("    o += n")
        self.emit(f"    {target} = ''")
        self.emit("else:")
        self.emit(f"    {target} = b[o:o + n - 1].decode('utf-8')")
        self.emit("    o += n")
        self.unknown()

    def sequence(self, ftype, target):
        """A primitive array of ``n`` elements, ``n`` read (``[]``, ``[<=N]``) or fixed (strings)."""
        name = ftype.type
        if ftype.is_fixed_size_array() and ftype.array_size is not None:
            self.flush()
            self.emit(f"n = {ftype.array_size}")
        else:
            self.uint32("n")
        if name == "string":
            self.emit("a = []")
            self.emit("for _ in range(n):")
            inner = _Function(self.c, self.indent + "    ")  # each string aligns at run time
            inner.string("s")
            self.lines += inner.lines
            self.emit("    a.append(s)")
            self.emit(f"{target} = a")
            self.unknown()
            return
        if name not in PRIMITIVES:
            raise UnsupportedSchema(f"{name}[]")
        code, size = PRIMITIVES[name]
        if name in BYTES:
            self.emit(f"{target} = b[o:o + n]")
            self.emit("o += n")
            self.unknown()
            return
        self.emit("if n:")
        if size > self.mod:  # the first element aligns (an empty array does not)
            self.emit(f"    o += (4 - o) % {size}")
        elif -self.rem % size:
            self.emit(f"    o += {-self.rem % size}")
        self.emit(f"    {target} = list(unpack_from('<%d{code}' % n, b, o))")
        self.emit(f"    o += n * {size}")
        self.emit("else:")
        self.emit(f"    {target} = []")
        after = min(size, self.mod) if self.rem == 0 else 1  # n == 0: as before; n > 0: aligned to size
        self.unknown(after if size > 1 else 1)

    def message(self, msgdef, target, stack):
        """The fields of ``msgdef`` into the object ``target`` (inlined)."""
        key = str(msgdef.base_type)
        if len(stack) > MAX_INLINE or key in stack:
            raise UnsupportedSchema(f"{key} contains itself")
        stack = (*stack, key)
        if not msgdef.fields:
            self.pad_byte()
        for field in msgdef.fields:
            ftype = field.type
            if not field.name.isidentifier() or keyword.iskeyword(field.name):
                raise UnsupportedSchema(f"field name {field.name!r}")
            dest = f"{target}.{field.name}"
            if not ftype.is_primitive_type():
                nested = self.c.msgdefs.get(f"{ftype.pkg_name}/{ftype.type}")
                if nested is None:
                    raise UnsupportedSchema(f"no definition of {ftype.pkg_name}/{ftype.type}")
                if ftype.is_array:
                    fn = self.c.element(nested)
                    if ftype.is_fixed_size_array() and ftype.array_size is not None:
                        self.flush()
                        self.emit(f"n = {ftype.array_size}")
                    else:
                        self.uint32("n")
                    self.emit("a = []")
                    self.emit("for _ in range(n):")
                    self.emit(f"    e, o = {fn}(b, o)")
                    self.emit("    a.append(e)")
                    self.emit(f"{dest} = a")
                    self.unknown()
                else:
                    obj = self.new_object(nested)
                    self.emit(f"{dest} = {obj}")
                    self.message(nested, obj, stack)
            elif ftype.is_array:
                if (ftype.is_fixed_size_array() and ftype.array_size is not None and ftype.type in PRIMITIVES
                        and ftype.type != "string"):
                    code, size = PRIMITIVES[ftype.type]
                    if ftype.type in BYTES:
                        self.fixed("s", 1, dest, ftype.array_size)
                    else:
                        self.fixed(code, size, dest, ftype.array_size)
                else:
                    self.sequence(ftype, dest)
            elif ftype.type == "string":
                self.string(dest)
            elif ftype.type in PRIMITIVES:
                code, size = PRIMITIVES[ftype.type]
                self.fixed(code, size, dest)
            else:  # wstring, time, duration: mcap_ros2 raises NotImplementedError
                raise UnsupportedSchema(ftype.type)


class _Compiler:
    def __init__(self, msgdefs, class_cache):
        self.msgdefs = msgdefs
        self.class_cache = class_cache
        self.namespace = {"U32": struct.Struct("<I").unpack_from, "unpack_from": struct.unpack_from}
        self.functions = []
        self.elements = {}
        self.classes = {}

    def const(self, value, prefix):
        name = f"{prefix}{len(self.namespace)}"
        self.namespace[name] = value
        return name

    def cls(self, msgdef):
        """The name of the class of ``msgdef`` (mcap_ros2's, from the decoder's class cache: one per type name)."""
        key = str(msgdef.base_type)
        if key not in self.classes:
            self.classes[key] = (msgdef, self.const(_dynamic._message_class(msgdef, self.class_cache), "C"))
        elif self.classes[key][0] is not msgdef:  # two definitions of one type name: mcap_ros2's order decides
            raise UnsupportedSchema(f"two definitions of {key}")
        return self.classes[key][1]

    def element(self, msgdef):
        """The name of a function ``(b, o) -> (object, o)`` decoding one ``msgdef`` (an array element)."""
        key = str(msgdef.base_type)
        if key not in self.elements:
            name = f"_element{len(self.elements)}"
            self.elements[key] = name
            fn = _Function(self)
            obj = fn.new_object(msgdef)
            fn.message(msgdef, obj, ())
            fn.flush()
            fn.emit(f"return {obj}, o")
            self.functions.append([f"def {name}(b, o):", *fn.lines])
        return self.elements[key]

    def top(self, msgdef):
        fn = _Function(self)
        fn.mod, fn.rem = 8, 0  # the payload starts aligned
        fn.emit("o = 4")
        obj = fn.new_object(msgdef)
        fn.message(msgdef, obj, ())
        fn.flush()
        fn.emit(f"return {obj}")
        self.functions.append(["def decode(b):", *fn.lines])
        source = "\n".join("\n".join(f) for f in self.functions) + "\n"
        exec(compile(source, f"<cdr {msgdef.base_type}>", "exec"), self.namespace)  # noqa: S102 (our own code)
        return self.namespace["decode"], source


def fixed_layout(msgdefs, schema_name: str, sample: bytes):
    """Where each primitive of a message lies in ``sample`` (little-endian CDR) when every field is fixed-size but
    strings: ``(fields, strings, end)`` with ``fields`` ``[(path, offset, struct code, count or None)]`` (``path``
    like ``header.stamp.sec``), ``strings`` the offsets of the strings' length words and ``end`` the offset after
    the last field. Every message of this schema with the same length words (and length) has this layout: a
    topic of such messages reads as one NumPy record array. UnsupportedSchema for sequences, arrays of messages and
    what :class:`Decoder` does not compile."""
    fields, strings = [], []
    o = 4

    def walk(msgdef, prefix, stack):
        nonlocal o
        key = str(msgdef.base_type)
        if len(stack) > MAX_INLINE or key in stack:
            raise UnsupportedSchema(f"{key} contains itself")
        if not msgdef.fields:
            o += 1
        for field in msgdef.fields:
            ftype, path = field.type, prefix + field.name
            if not ftype.is_primitive_type():
                nested = msgdefs.get(f"{ftype.pkg_name}/{ftype.type}")
                if nested is None or ftype.is_array:
                    raise UnsupportedSchema(f"{path}: {ftype}")
                walk(nested, path + ".", (*stack, key))
            elif ftype.type == "string" and not ftype.is_array:
                o += -(o - 4) % 4
                strings.append(o)
                o += 4 + struct.unpack_from("<I", sample, o)[0]
            elif ftype.type in PRIMITIVES and (not ftype.is_array or ftype.is_fixed_size_array()
                                                and ftype.array_size is not None):
                code, size = PRIMITIVES[ftype.type]
                if ftype.is_array and ftype.type in BYTES:
                    code, size = "s", 1
                o += -(o - 4) % size
                n = ftype.array_size if ftype.is_array else None
                fields.append((path, o, code, n))
                o += size * (n or 1)
            else:
                raise UnsupportedSchema(f"{path}: {ftype}")

    walk(msgdefs[schema_name], "", ())
    return fields, strings, o


def definitions(schema_name: str, schema_text: str) -> dict:
    """The parsed definitions of a schema as mcap_ros2's decoder has them (``{name: MessageSpecification}``, nested
    types by full and short name, ``builtin_interfaces/Time`` and ``Duration`` unless the schema defines them);
    McapROS2DecodeError when the text does not define ``schema_name`` (mcap_ros2's own check)."""
    msgdefs = {"builtin_interfaces/Time": _dynamic.TimeDefinition,
               "builtin_interfaces/Duration": _dynamic.TimeDefinition}
    names = set()

    def handle(cur, short, msgdef):
        msgdefs[cur] = msgdefs[short] = msgdef
        names.update((cur, short))

    _dynamic._for_each_msgdef(schema_name, schema_text, handle)
    if schema_name not in names:
        raise McapROS2DecodeError(f'schema parsing failed for "{schema_name}"')
    return msgdefs


class Decoder:
    """A callable ``bytes -> message`` for one schema: the compiled code (:attr:`source`, None when the schema
    is not covered) with mcap_ros2 for everything else (:attr:`generic`); both make the same classes."""

    def __init__(self, schema_name: str, schema_text: str):
        self.msgdefs = definitions(schema_name, schema_text)
        self.class_cache = {}
        msgdefs, cache = self.msgdefs, self.class_cache
        self.generic = lambda data: _dynamic._read_message(schema_name, msgdefs, data, cache)
        self.fast, self.source = None, None
        try:
            self.fast, self.source = _Compiler(msgdefs, cache).top(msgdefs[schema_name])
        except Exception:  # noqa: BLE001 -- UnsupportedSchema, or anything mcap_ros2 would refuse too: it decodes
            self.fast, self.source = None, None

    def __call__(self, data):
        fast = self.fast
        if fast is not None and len(data) >= 4 and data[1] & 1:  # little-endian CDR
            try:
                return fast(data)
            except Exception:  # noqa: BLE001 -- cut off, bad UTF-8, ...: mcap_ros2 decodes it or raises what it raises
                pass
        return self.generic(data)


def decoder(schema, message_encoding: str):
    """The :class:`Decoder` of an MCAP schema record for a channel's message encoding; mcap_ros2's own decoder
    (its DecoderFactory) when the compiled one is unavailable; None where mcap_ros2 has none (not CDR, not
    ros2msg)."""
    if message_encoding != MessageEncoding.CDR or schema is None or schema.encoding != SchemaEncoding.ROS2:
        return None
    if not _COMPILE:  # pragma: no cover
        return DecoderFactory().decoder_for(message_encoding, schema)
    return _decoder(schema.name, schema.data.decode())


@functools.lru_cache(maxsize=64)
def _decoder(schema_name: str, schema_text: str) -> Decoder:
    """One :class:`Decoder` per schema text in a process (compiling one costs about a millisecond; a campaign's
    worker builds the report of every run)."""
    return Decoder(schema_name, schema_text)
