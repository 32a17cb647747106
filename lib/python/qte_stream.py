#!/usr/bin/env python3
"""qte_stream: reads QTE record streams (formats/record-stream.md) with the standard library,
NumPy (Debian's python3-numpy) and, for zstd-compressed fields, zstandard (Debian's
python3-zstandard); a python3 from elsewhere (pyenv, a venv) may lack them.

    import qte_stream
    for record in qte_stream.read_records("demos.rec"):
        print(record.index, record.type, record.fields["front.rgb"].shape)

`make install` puts this module where Debian's python3 finds it (/usr/local/lib/python3.X/
dist-packages); under another prefix, set PYTHONPATH=PREFIX/lib/python3.X/dist-packages, and
from a checkout add lib/python to sys.path or PYTHONPATH.

Records are checked as the C++ reader checks them; the first damage raises StreamError
("FILE: record I at byte O: what"). Arrays are read-only NumPy views of the payload (no copy);
str fields are Python strings. zstd-compressed fields need the `zstandard` module.
Run as a script (python3 -m qte_stream FILE...) to list the records of streams (like stream-dump).
"""
import collections
import os
import re
import struct
import sys
import zlib

import numpy as np

MAGIC = b"\x89QTE\r\n\x1a\n"
VERSION_MAJOR = 1
HEADER = struct.Struct("<8sHHI16sQII12sI")  # the 64-byte record header
DESCRIPTOR = struct.Struct("<BBBxHxxQ")  # dtype, ndim, encoding, name length, stored bytes
DTYPES = {1: "|u1", 2: "|i1", 3: "<u2", 4: "<i2", 5: "<u4", 6: "<i4", 7: "<u8", 8: "<i8",
          9: "<f4", 10: "<f8", 11: "|u1"}  # 11 is str: UTF-8 bytes
STR, MAX_DIMS, MAX_EXTENT = 11, 8, 1 << 40
RECORD_TYPE = re.compile(rb"[a-z0-9_]{1,16}")
FIELD_NAME = re.compile(rb"[A-Za-z0-9_.-]{1,255}")

Record = collections.namedtuple("Record", "type fields offset index")
# A task object of an observation written with `sim-step --objects` (or `demo-record
# --objects`): its id (the row), name, role ("target", "distractor" or "other"), pose (x, y, z,
# qx, qy, qz, qw, world frame) and bounding box in its own frame (lower and upper corner).
# held: True when the gripper holds it (objects.held), None in streams written before that field.
SceneObject = collections.namedtuple("SceneObject", "id name role pose box_min box_max held", defaults=(None,))
ROLES = {0: "other", 1: "target", 2: "distractor"}


class StreamError(Exception):
    """Damage (or an unreadable field); the message names file, record index and byte offset."""


def pad64(n):
    return -(-n // 64) * 64


def read_records(source, max_record_bytes=4 << 30):
    """Yields the Records of a stream: a path ("-" is stdin) or a binary file object."""
    if isinstance(source, str) and source == "-":
        yield from _records(sys.stdin.buffer, "<stdin>", max_record_bytes)
    elif isinstance(source, (str, bytes)) or hasattr(source, "__fspath__"):
        with open(source, "rb") as f:
            yield from _records(f, str(source), max_record_bytes)
    else:
        yield from _records(source, getattr(source, "name", "<stream>"), max_record_bytes)


def _read(f, n):
    chunks, have = [], 0
    while have < n:  # in pieces, so that a damaged length on a short file allocates little
        chunk = f.read(min(n - have, 64 << 20))
        if not chunk:
            break
        chunks.append(chunk)
        have += len(chunk)
    return chunks[0] if len(chunks) == 1 else b"".join(chunks)


def _records(f, name, max_record_bytes):
    offset = index = 0
    while True:
        def error(what, in_payload=None):  # field errors name their descriptor's offset
            at = offset if in_payload is None else offset + 64 + in_payload
            return StreamError(f"{name}: record {index} at byte {at}: {what}")

        head = _read(f, 64)
        if not head:
            return  # a clean end: only ever at a record boundary
        if len(head) < 64:
            raise error(f"truncated stream: expected a 64-byte record header, "
                        f"got {len(head)} bytes")
        magic, major, minor, count, rtype, size, crc, _, _, head_crc = HEADER.unpack(head)
        if magic != MAGIC:
            raise error(f"bad magic: expected {MAGIC.hex(' ')} (a QTE record stream), "
                        f"got {magic.hex(' ')}")
        if zlib.crc32(head[:60]) != head_crc:
            raise error("header checksum mismatch (damaged header)")
        if major != VERSION_MAJOR:
            raise error(f"unsupported format version {major}.{minor}: "
                        f"this reader reads {VERSION_MAJOR}.x")
        rtype = rtype.rstrip(b"\0")
        if b"\0" in rtype:
            raise error("record type not NUL-padded")
        if not RECORD_TYPE.fullmatch(rtype):
            raise error(f"invalid record type '{rtype.decode('latin-1')}': "
                        "expected 1-16 characters of [a-z0-9_]")
        if size % 64:
            raise error(f"payload length {size} is not a multiple of 64")
        if size > max_record_bytes:
            raise error(f"absurd payload length {size} bytes: expected at most {max_record_bytes}")
        if count > size // 64:
            raise error(f"field count {count} cannot fit in a payload of {size} bytes")
        payload = _read(f, size)
        if len(payload) < size:
            raise error(f"truncated stream: '{rtype.decode()}' record needs {size} payload "
                        f"bytes, got {len(payload)}")
        if zlib.crc32(payload) != crc:
            raise error("payload checksum mismatch (damaged payload)")
        fields = _fields(payload, count, max_record_bytes, error)
        yield Record(rtype.decode(), fields, offset, index)
        offset, index = offset + 64 + size, index + 1


def _fields(payload, count, max_field_bytes, error):
    fields, at, size = {}, 0, len(payload)
    for i in range(count):
        def bad(what, where=at):
            return error(f"field {i}: {what}", where)

        if size - at < DESCRIPTOR.size:
            raise bad("descriptor runs past the payload end")
        code, ndim, encoding, name_len, stored = DESCRIPTOR.unpack_from(payload, at)
        if code not in DTYPES:
            raise bad(f"unknown dtype code {code} (expected 1-11)")
        if ndim > MAX_DIMS:
            raise bad(f"ndim {ndim} (expected at most 8)")
        if encoding > 1:
            raise bad(f"unknown encoding {encoding} (expected 0 raw or 1 zstd)")
        if not 1 <= name_len <= 255:
            raise bad(f"name length {name_len} (expected 1-255)")
        if size - at < pad64(16 + 8 * ndim + name_len):
            raise bad("descriptor runs past the payload end")
        shape, elements = struct.unpack_from(f"<{ndim}q", payload, at + 16), 1
        for k, extent in enumerate(shape):
            if not 0 <= extent <= MAX_EXTENT:
                raise bad(f"extent {extent} in dimension {k}")
            elements *= extent  # Python integers: no overflow
            if elements > MAX_EXTENT:
                raise bad("more than 2^40 elements")
        raw_name = payload[at + 16 + 8 * ndim:at + 16 + 8 * ndim + name_len]
        if not FIELD_NAME.fullmatch(raw_name):
            raise bad("invalid field name (expected [A-Za-z0-9_.-])")
        name = raw_name.decode("ascii")
        if name in fields:
            raise bad(f"duplicate field name '{name}'")
        if code == STR and ndim != 1:
            raise bad(f"'{name}': str fields are 1-d")
        dtype = np.dtype(DTYPES[code])
        raw_bytes = elements * dtype.itemsize
        at += pad64(16 + 8 * ndim + name_len)
        if stored > size - at:
            raise bad(f"'{name}': data of {stored} bytes runs past the payload end")
        if encoding == 0 and stored != raw_bytes:
            raise bad(f"'{name}': shape {list(shape)} needs {raw_bytes} bytes, stored {stored}")
        if encoding == 0:
            data, start = payload, at
        else:
            data, start = _unzstd(payload[at:at + stored], raw_bytes, max_field_bytes,
                                  lambda what: bad(f"'{name}': {what}")), 0
        if code == STR:  # like the C++ reader, accept bad UTF-8 (and keep its bytes)
            fields[name] = data[start:start + raw_bytes].decode("utf-8", "surrogateescape")
        else:
            fields[name] = np.frombuffer(data, dtype, elements, start).reshape(shape)
        at += pad64(stored)
    if at != size:
        raise error(f"{size - at} bytes after the last field: expected the payload to end "
                    "there (field count too small?)")
    return fields


def _unzstd(data, raw_bytes, max_field_bytes, bad):
    try:
        import zstandard
    except ImportError:
        raise bad("field is zstd-compressed: reading it needs the Python module zstandard "
                  "(Debian: apt install python3-zstandard; or pip install zstandard)") from None
    if raw_bytes > max_field_bytes:
        raise bad(f"decompressed size {raw_bytes} exceeds the limit of {max_field_bytes}")
    try:
        declared = zstandard.frame_content_size(data)
        if declared != raw_bytes:
            raise bad(f"zstd frame declares {declared if declared >= 0 else 'no'} bytes, "
                      f"shape needs {raw_bytes}")
        out = zstandard.ZstdDecompressor().decompress(data)
    except zstandard.ZstdError as e:
        raise bad(f"zstd data does not decompress to {raw_bytes} bytes ({e})") from None
    if len(out) != raw_bytes:
        raise bad(f"zstd data does not decompress to {raw_bytes} bytes")
    return out


def scene_objects(record):
    """The task objects an observation carries (objects.*), as SceneObjects in id order; None
    when it carries none (a stream written without --objects). `held` is None in streams
    written before objects.held."""
    f = record.fields
    if "objects.pose" not in f:
        return None
    names = f["objects.names"].split(",") if f["objects.names"] else []
    pose, box, role = (np.asarray(f[k]) for k in ("objects.pose", "objects.box", "objects.role"))
    if not (len(names) == len(role) == len(pose) == len(box)):
        raise StreamError(f"record {record.index} at byte {record.offset}: objects.names, objects.role, "
                          f"objects.pose and objects.box disagree on the number of objects")
    held = np.asarray(f["objects.held"]).reshape(-1) if "objects.held" in f else None
    if held is not None and len(held) != len(names):
        raise StreamError(f"record {record.index} at byte {record.offset}: objects.held and objects.names "
                          f"disagree on the number of objects")
    return [SceneObject(i, names[i], ROLES.get(int(role[i]), "other"), pose[i], box[i, :3], box[i, 3:],
                        None if held is None else bool(held[i]))
            for i in range(len(names))]


def main(paths):
    for path in paths or ["-"]:
        for record in read_records(path):
            print(f"#{record.index} @{record.offset} {record.type} ({len(record.fields)} fields)")
            for name, value in record.fields.items():
                if isinstance(value, str):
                    size = len(value.encode("utf-8", "surrogateescape"))
                    print(f"  {name}  str [{size}]  {value!r}")
                    continue
                flat = value.reshape(-1)
                shown = " ".join(str(v) for v in flat[:6]) + (" ..." if flat.size > 6 else "")
                shown = shown if value.ndim == 0 or not shown else f"[{shown}]"
                print(f"  {name}  {value.dtype.name} {list(value.shape)}  {shown}".rstrip())


if __name__ == "__main__":
    try:
        main(sys.argv[1:])
    except BrokenPipeError:  # e.g. `python3 -m qte_stream demos.rec | head`: stop quietly
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        sys.exit(141)
    except (StreamError, OSError) as e:
        sys.exit(f"qte_stream: {e}")
