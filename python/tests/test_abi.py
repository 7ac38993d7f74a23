"""The ctypes mirrors of python/polarlux/_lib.py against the C structures.

tests/abi_sizes.c (built by make as build/tests/abi_sizes; $POLARLUX_ABI_SIZES
names another) prints what the C compiler lays out: sizeof of each
structure, offsetof and sizeof of each member. Each ctypes.Structure of _lib
names its C structure (_c_name_); its size and every field's offset and size
must be the same. A mirror that fell behind its structure makes the library
write past or misread it (pytest used to die of a segfault): conftest.py
runs these tests first and skips the others when one fails.
"""
import ctypes
import os
import subprocess

import pytest

from polarlux import _lib

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
ABI_SIZES = os.environ.get("POLARLUX_ABI_SIZES", os.path.join(ROOT, "build", "tests", "abi_sizes"))

MIRRORS = sorted((v for v in vars(_lib).values()
                  if isinstance(v, type) and issubclass(v, ctypes.Structure) and v is not ctypes.Structure),
                 key=lambda cls: cls.__name__)


def c_layout():
    """{struct: (sizeof, {member: (offset, size)})} as tests/abi_sizes.c prints it."""
    if not os.path.exists(ABI_SIZES):
        pytest.fail(f"{ABI_SIZES} is missing: build it with 'make build/tests/abi_sizes' "
                    "(make check-python does), or set POLARLUX_ABI_SIZES")
    out = subprocess.run([ABI_SIZES], capture_output=True, text=True, check=True).stdout
    layout = {}
    for line in out.splitlines():
        w = line.split()
        if w[0] == "struct":
            layout[w[1]] = (int(w[2]), {})
        else:
            layout[w[1]][1][w[2]] = (int(w[3]), int(w[4]))
    return layout


@pytest.fixture(scope="module")
def layout():
    return c_layout()


def layout_problems(cls, size, members):
    """What differs between the ctypes mirror cls and its C structure, one line each."""
    c, py = cls._c_name_, cls.__name__
    fields = [name for name, _ in cls._fields_]
    probs = [f"{c}.{m} (offset {members[m][0]}, {members[m][1]} bytes) is missing from ctypes {py}"
             for m in members if m not in fields]
    probs += [f"{c}.{f}: ctypes {py} declares it but tests/abi_sizes.c lists no such member of {c}"
              for f in fields if f not in members]
    shifted = []
    for f in fields:
        if f not in members:
            continue
        off, sz = members[f]
        d = getattr(cls, f)
        if d.size != sz:
            probs.append(f"{c}.{f}: {sz} bytes in C, {d.size} in ctypes {py} (another type)")
        if d.offset != off:
            shifted.append(f"{c}.{f}: offset {off} in C, {d.offset} in ctypes {py} "
                           "(a field before it is missing, extra or of another type)")
    if shifted:
        probs.append(shifted[0] + (f"; {len(shifted) - 1} later fields shifted too" if len(shifted) > 1 else ""))
    if ctypes.sizeof(cls) != size:
        probs.append(f"sizeof({c}) is {size} in C, {ctypes.sizeof(cls)} in ctypes {py}")
    return probs


def test_every_mirror_names_a_listed_struct(layout):
    for cls in MIRRORS:
        name = getattr(cls, "_c_name_", None)
        if not name:
            pytest.fail(f"ctypes {cls.__name__} in polarlux/_lib.py names no C structure (_c_name_ = \"plx_...\")",
                        pytrace=False)
        if name not in layout:
            pytest.fail(f"ctypes {cls.__name__} mirrors {name}, which tests/abi_sizes.c does not list: add it there",
                        pytrace=False)
    stale = set(layout) - {cls._c_name_ for cls in MIRRORS}
    if stale:
        pytest.fail(f"tests/abi_sizes.c lists structures no ctypes class mirrors: {', '.join(sorted(stale))}",
                    pytrace=False)


@pytest.mark.parametrize("cls", MIRRORS, ids=lambda cls: cls.__name__)
def test_mirror_layout(layout, cls):
    if getattr(cls, "_c_name_", None) not in layout:
        pytest.fail(f"ctypes {cls.__name__}: no C structure to compare (test_every_mirror_names_a_listed_struct)")
    probs = layout_problems(cls, *layout[cls._c_name_])
    if probs:
        pytest.fail(f"ctypes {cls.__name__} (python/polarlux/_lib.py) differs from {cls._c_name_}:\n  "
                    + "\n  ".join(probs), pytrace=False)
