#!/usr/bin/env python3
"""Compares two `fragsim render --scheme all --executor all --json` reports row by row, ignoring
times (`*_ms`): prints the (scheme, executor) rows whose fragments, losses, mismatches or any other
field differ. Run the old binary twice as well: rows that differ between two runs of the same binary
(race-dependent parallel rows of the hazard schemes) are nondeterministic, not a change.

    python3 tools/behaviour/diff.py OLD.json NEW.json [OLD_AGAIN.json]
"""
import json
import sys


def rows(path):
    # JSON Lines: one record per (scheme, executor) (docs/json-schema.md); the version differs
    # between binaries by design.
    records = [json.loads(line) for line in open(path) if line.strip()]
    return {(r["scheme"], r["executor"]): {k: v for k, v in r.items()
                                           if not k.endswith("_ms") and k != "fragsim_version"}
            for r in records}


old, new = rows(sys.argv[1]), rows(sys.argv[2])
racy = set()
if len(sys.argv) > 3:
    again = rows(sys.argv[3])
    racy = {k for k in old if old[k] != again.get(k)}
print(f"rows: {len(old)} old, {len(new)} new; only new: {sorted(set(new) - set(old))}")
changed = sorted(k for k in old if old[k] != new.get(k))
for k in changed:
    fields = sorted(f for f in old[k] if old[k][f] != new.get(k, {}).get(f))
    print(f"{'racy ' if k in racy else 'CHANGED'} {k}: {fields}")
print(f"{len(changed)} rows differ; identical otherwise")
