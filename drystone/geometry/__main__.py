"""python -m drystone.geometry validate FILE...   check block files (exit 1 on the first problem)
python -m drystone.geometry make NAME OUT.json [key=value ...]   run a generator of drystone/geometry/generators.py"""
from __future__ import annotations

import json
import sys

from drystone.geometry import blockfile as bf
from drystone.geometry import generators


def main(argv: list[str]) -> int:
    if len(argv) >= 2 and argv[0] == "validate":
        for path in argv[1:]:
            try:
                bs = bf.load(path)
            except bf.GeometryError as exc:
                print(f"error: {exc}", file=sys.stderr)
                return 1
            print(f"{path}: ok, {len(bs.blocks)} blocks ({len(bs.ids('free'))} free)")
        return 0
    if len(argv) >= 3 and argv[0] == "make":
        params = {"generator": argv[1]}
        for kv in argv[3:]:
            k, v = kv.split("=", 1)
            try:
                params[k] = json.loads(v)
            except json.JSONDecodeError:
                params[k] = v
        try:
            p = bf.write(generators.generate(params), argv[2])
        except (KeyError, bf.GeometryError) as exc:
            print(f"error: {exc}", file=sys.stderr)
            return 1
        print(f"wrote {p}")
        return 0
    print(__doc__, file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
