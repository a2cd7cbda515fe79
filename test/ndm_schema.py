"""XML Schema validation of NDM/XML files for the tests (lxml), against one of two schema sets:

* **official**: the CCSDS NDM/XML 2.0.0 schema set of the SANA registry (``ndmxml-2.0.0-master-2.0.xsd`` and the
  files it includes), unqualified variant, copied unchanged into ``test/data/ndmxml-2.0.0/`` (provenance in its
  README.md; ``$ROE_SEP_NDM_XSD_DIR`` points elsewhere, e.g. at the qualified variant's directory for a check).
* **models**: an XML Schema written here from ccsds-ndm's models of that same schema set (``ccsds_ndm.models.ndmxml2``,
  generated from the official XSDs with xsdata). Every complex type with its elements in schema order, their
  ``minOccurs``/``maxOccurs`` (required, lists, explicit bounds), attributes (units, ``id``/``version`` fixed),
  enumerations, numeric types and the facets the models keep (``pattern``: the CCSDS epoch format;
  ``min``/``max`` inclusive/exclusive: e.g. ``MAN_DELTA_MASS < 0``). What the models flatten is looser here than in
  the official set: a ``choice`` becomes a sequence of optional elements, and ``xsd:string``-derived enumerations in
  metadata (``REF_FRAME`` of the OPM/OEM) are plain strings. The library's own XML reader checks none of these
  facets, so this is an independent check of what the writer produced, not a round trip.
"""

import dataclasses
import enum
import os
import types
import typing
from pathlib import Path

from lxml import etree

XS = "http://www.w3.org/2001/XMLSchema"
OFFICIAL_DIRS = [Path(os.environ["ROE_SEP_NDM_XSD_DIR"])] if os.environ.get("ROE_SEP_NDM_XSD_DIR") else []
OFFICIAL_DIRS.append(Path(__file__).resolve().parent / "data" / "ndmxml-2.0.0")
OFFICIAL_MASTER = "ndmxml-2.0.0-master-2.0.xsd"
FACETS = {"pattern": "pattern", "min_inclusive": "minInclusive", "min_exclusive": "minExclusive",
          "max_inclusive": "maxInclusive", "max_exclusive": "maxExclusive", "min_length": "minLength",
          "max_length": "maxLength", "length": "length", "total_digits": "totalDigits",
          "fraction_digits": "fractionDigits"}
BUILTIN = {str: "xs:string", float: "xs:double", int: "xs:integer", bool: "xs:boolean"}


def official_schema():
    """lxml XMLSchema of the official NDM/XML 2.0.0 set (parsed once)."""
    global _OFFICIAL
    if _OFFICIAL is None:
        found = [d / OFFICIAL_MASTER for d in OFFICIAL_DIRS if (d / OFFICIAL_MASTER).is_file()]
        if not found:
            raise FileNotFoundError(f"no {OFFICIAL_MASTER} in {' or '.join(map(str, OFFICIAL_DIRS))}")
        _OFFICIAL = etree.XMLSchema(etree.parse(str(found[0])))
    return _OFFICIAL


_OFFICIAL = None


def schema_location(path):
    """``xsi:noNamespaceSchemaLocation`` of the root element of an XML file (None when absent)."""
    return etree.parse(str(path)).getroot().get("{http://www.w3.org/2001/XMLSchema-instance}noNamespaceSchemaLocation")


def _strip_optional(tp):
    if typing.get_origin(tp) in (typing.Union, types.UnionType):
        args = [a for a in typing.get_args(tp) if a is not type(None)]
        if len(args) != 1:
            raise TypeError(f"unsupported union {tp}")
        return args[0]
    return tp


class _Writer:
    def __init__(self):
        self.root = etree.Element(f"{{{XS}}}schema", nsmap={"xs": XS})
        self.done = {}

    def _sub(self, parent, tag, **attrs):
        return etree.SubElement(parent, f"{{{XS}}}{tag}", {k: str(v) for k, v in attrs.items()})

    def simple(self, parent, tp, meta):
        """Put the simple type of a field (enumeration, builtin + facets) on ``parent`` (an element/attribute)."""
        facets = {FACETS[k]: v for k, v in meta.items() if k in FACETS}
        # xsdata merges a restriction of a restriction (inclinationType [0, 180] of angleType [-180, 360)): both
        # bounds of a side are kept in the metadata, XML Schema allows one per side, the tighter one is in force
        if "maxInclusive" in facets and "maxExclusive" in facets:
            facets.pop("maxExclusive" if facets["maxInclusive"] < facets["maxExclusive"] else "maxInclusive")
        if "minInclusive" in facets and "minExclusive" in facets:
            facets.pop("minExclusive" if facets["minInclusive"] > facets["minExclusive"] else "minInclusive")
        if isinstance(tp, type) and issubclass(tp, enum.Enum):
            base, values = "xs:string", [m.value for m in tp]
        elif tp in BUILTIN:
            base, values = BUILTIN[tp], []
        else:
            raise TypeError(f"unsupported simple type {tp}")
        if not facets and not values:
            parent.set("type", base)
            return
        restr = self._sub(self._sub(parent, "simpleType"), "restriction", base=base)
        for v in values:
            self._sub(restr, "enumeration", value=v)
        for k, v in facets.items():
            if k == "pattern":
                self._sub(restr, "pattern", value=v)
            else:
                self._sub(restr, k, value=repr(v) if isinstance(v, float) else v)

    def complex(self, cls):
        """Name of the complexType of a model class (written once)."""
        if cls in self.done:
            return self.done[cls]
        name = f"T{len(self.done)}_{cls.__name__}"
        self.done[cls] = name
        ct = self._sub(self.root, "complexType", name=name)
        hints = typing.get_type_hints(cls)
        fields = [f for f in dataclasses.fields(cls)]
        text = [f for f in fields if f.metadata.get("type") is None and "name" not in f.metadata]
        elems = [f for f in fields if f.metadata.get("type") == "Element"]
        attrs = [f for f in fields if f.metadata.get("type") == "Attribute"]
        if {f.metadata.get("type") for f in fields} - {None, "Element", "Attribute"}:
            raise TypeError(f"{cls.__name__}: unsupported field kinds")
        if text:
            if elems or len(text) != 1:
                raise TypeError(f"{cls.__name__}: mixed content is not supported")
            ext_parent = self._sub(self._sub(ct, "simpleContent"), "extension")
            tmp = etree.Element("tmp")
            self.simple(tmp, _strip_optional(hints[text[0].name]), text[0].metadata)
            if tmp.get("type"):
                ext_parent.set("base", tmp.get("type"))
            else:  # a restricted text: a named simple type for the base
                st_name = f"{name}_text"
                st = tmp[0]
                st.set("name", st_name)
                self.root.append(st)
                ext_parent.set("base", st_name)
            attr_parent = ext_parent
        else:
            seq = self._sub(ct, "sequence")
            for f in elems:
                tp = hints[f.name]
                is_list = typing.get_origin(tp) is list
                inner = typing.get_args(tp)[0] if is_list else _strip_optional(tp)
                lo = f.metadata.get("min_occurs", 1 if f.metadata.get("required") else 0)
                hi = f.metadata.get("max_occurs", "unbounded" if is_list else 1)
                el = self._sub(seq, "element", name=f.metadata.get("name", f.name), minOccurs=lo, maxOccurs=hi)
                if dataclasses.is_dataclass(inner):
                    el.set("type", self.complex(inner))
                else:
                    self.simple(el, inner, f.metadata)
            attr_parent = ct
        for f in attrs:
            at = self._sub(attr_parent, "attribute", name=f.metadata.get("name", f.name),
                           use="required" if f.metadata.get("required") else "optional")
            if not f.init and isinstance(f.default, str):  # id="CCSDS_OPM_VERS", version="2.0"
                at.set("fixed", f.default)
                at.set("type", "xs:string")
            else:
                self.simple(at, _strip_optional(hints[f.name]), f.metadata)
        return name


def model_schema(root_cls):
    """lxml XMLSchema of one message (``ccsds_ndm.models.ndmxml2.Opm``...) written from the library's models."""
    w = _Writer()
    type_name = w.complex(root_cls)
    etree.SubElement(w.root, f"{{{XS}}}element", name=root_cls.Meta.name, type=type_name)
    return etree.XMLSchema(w.root)


def errors(schema, path_or_text):
    """Schema violations of an XML file or text (empty: valid), as 'line N: message'."""
    src = str(path_or_text)
    doc = etree.fromstring(src.encode()) if src.lstrip().startswith("<") else etree.parse(src).getroot()
    if schema.validate(doc):
        return []
    return [f"line {e.line}: {e.message}" for e in schema.error_log]
