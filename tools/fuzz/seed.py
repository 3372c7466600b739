#!/usr/bin/env python3
"""Fuzz seeds from dump directories (docs/dump-format.md), written by `fragsim render --dump`.

    seed.py DUMP_DIR                      a `dump_parse` seed on stdout
    seed.py DUMP_DIR OTHER_DUMP_DIR       a `compare` seed: the reference, then the candidate

A `dump_parse` input is the header's bytes, a NUL, then each array file in the order the parser
asks for them (the header's arrays sorted by name), each as a little-endian u16 length and that
many bytes (tests/fuzz_support/dump.rs, `Blob`). A `compare` input is the reference's input
behind its little-endian u32 length, then the candidate's (tests/fuzz_support/compare.rs).
Triangle exports (`fragsim export-scene --out FILE`) are `triangles` seeds as they are.
"""
import json
import struct
import sys
from pathlib import Path


def blob(directory: Path) -> bytes:
    header = (directory / "dump.json").read_bytes()
    out = bytearray(header + b"\0")
    # The parser walks `arrays` as a BTreeMap: by name, in byte order.
    for name, spec in sorted(json.loads(header)["arrays"].items(), key=lambda kv: kv[0].encode()):
        data = (directory / spec["file"]).read_bytes()
        if len(data) > 0xFFFF:
            sys.exit(f"{directory}: array {name} has {len(data)} bytes, more than a seed chunk holds")
        out += struct.pack("<H", len(data)) + data
    return bytes(out)


def main() -> None:
    dirs = [Path(d) for d in sys.argv[1:]]
    if len(dirs) == 1:
        sys.stdout.buffer.write(blob(dirs[0]))
    elif len(dirs) == 2:
        first = blob(dirs[0])
        sys.stdout.buffer.write(struct.pack("<I", len(first)) + first + blob(dirs[1]))
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main()
