"""JSON that every parser reads: NaN and infinities, which Python's json
writes as the non-standard NaN/Infinity, become null."""

import json
import math


def finite(value):
    """`value` with every non-finite float (nested in dicts, lists, tuples) replaced by None."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: finite(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [finite(v) for v in value]
    return value


def dump(value, f, **options):
    json.dump(finite(value), f, allow_nan=False, **options)
