"""Hostile inputs for the readers' fuzz tests: valid files mutated token by token and line by line.

A mutation replaces a token with a value from :data:`VOCABULARY` (numbers at and past every
limit, YAML and JSON syntax, names), deletes, repeats, swaps or cuts lines, or inserts raw
characters; a few inputs are arbitrary text. Each reader must answer every input with a result
or one :class:`BilleError`.
"""
from __future__ import annotations

import re

from hypothesis import strategies as st

VOCABULARY = [
    "0", "1", "-1", "2", "7", "74", "0.5", "1.5", "-0.0", "1e9", "1000000000", "100000000000", "nan", ".nan", ".inf",
    "-.inf", "NaN", "Infinity", "true", "false", "null", "~", "''", '""', "[]", "{}", "[0, 0]", "[1, 2, 3]",
    "{x: 1}", "&a", "*a", "!!binary", "!!python/object", "|", ">", "-", ":", ",", "[", "]", "{", "}", "#", "'",
    '"', "\\", "\t", "\x00", "\u00e9", "\ufeff", "agent0", "agent1", "bob", "S7", "S5", "point", "classic",
    "wait", "fwd", "pick", "place", "north", "released", "finished", "done", "fault", "run", "../../x", "/etc",
    "x" * 300, "T" * 50, "@", ".", "map", "version", "type", "octile", "height", "width",
]
_TOKEN = re.compile(r"[A-Za-z_][\w-]*|-?\d+(?:\.\d+)?|\S")


@st.composite
def mutated(draw, seeds: list[str], vocabulary: list[str] = VOCABULARY) -> str:
    """A seed text with one to four mutations (module docstring), or now and then any text."""
    if draw(st.integers(0, 19)) == 0:
        return draw(st.text(max_size=200))
    text = draw(st.sampled_from(seeds))
    for _ in range(draw(st.integers(1, 4))):
        lines = text.split("\n")
        op = draw(st.sampled_from(["token", "token", "token", "delete", "repeat", "swap", "cut", "insert"]))
        if op == "token":
            spots = [m.span() for m in _TOKEN.finditer(text)]
            if not spots:
                continue
            a, b = draw(st.sampled_from(spots))
            text = text[:a] + draw(st.sampled_from(vocabulary)) + text[b:]
        elif op in ("delete", "repeat", "swap") and lines:
            k = draw(st.integers(0, len(lines) - 1))
            if op == "delete":
                del lines[k]
            elif op == "repeat":
                lines.insert(k, lines[k])
            else:
                j = draw(st.integers(0, len(lines) - 1))
                lines[k], lines[j] = lines[j], lines[k]
            text = "\n".join(lines)
        elif op == "cut":
            text = text[: draw(st.integers(0, len(text)))]
        else:
            k = draw(st.integers(0, len(text)))
            text = text[:k] + draw(st.text(max_size=5)) + text[k:]
    return text


JSON_VALUES = st.recursive(
    st.none() | st.booleans() | st.integers(-2, 2) | st.sampled_from([10**11, -(10**11), 2**63, 12, 13, 14, 500])
    | st.floats(allow_nan=True, allow_infinity=True) | st.text(max_size=8)
    | st.sampled_from(["pick", "place", "wait", "fwd", "initialize", "stateRequest", "cancelOrder", "FAILED", "r1",
                       "finished", "released", "fault", "done", "replan", "resume", "x" * 70]),
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=6), inner, max_size=3),
    max_leaves=6)


def _spots(value, path=()):
    yield path
    if isinstance(value, dict):
        for k, v in value.items():
            yield from _spots(v, path + (k,))
    elif isinstance(value, list):
        for i, v in enumerate(value):
            yield from _spots(v, path + (i,))


@st.composite
def mutated_json(draw, seed) -> object:
    """A JSON value with one to three changes: a value replaced (by any JSON, or by another value
    of the seed), a key or item removed or repeated."""
    import copy

    value = copy.deepcopy(seed)
    for _ in range(draw(st.integers(1, 3))):
        spots = list(_spots(value))
        path = draw(st.sampled_from(spots))
        if not path:
            continue
        parent = value
        for p in path[:-1]:
            parent = parent[p]
        op = draw(st.sampled_from(["replace", "replace", "other", "remove", "repeat"]))
        if op == "replace":
            parent[path[-1]] = draw(JSON_VALUES)
        elif op == "other":
            source = value
            for p in draw(st.sampled_from(spots)):
                source = source[p]
            parent[path[-1]] = copy.deepcopy(source)
        elif op == "remove":
            del parent[path[-1]]
        elif isinstance(parent, list):
            parent.insert(path[-1], copy.deepcopy(parent[path[-1]]))
        else:
            parent[draw(st.text(max_size=6))] = copy.deepcopy(parent[path[-1]])
    return value
