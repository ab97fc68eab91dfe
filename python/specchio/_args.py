"""Arguments checked by name on the Python side, said as the native module says them
(`time: '0' (a str); give a number ...`)."""

from __future__ import annotations

import numbers
from typing import Any, Optional

from ._specchio import SpecchioError


def shown(value: Any) -> str:
    """`value` for a message: its repr and type where the repr is short, else its type."""
    kind = type(value).__name__
    kind = f"{'an' if kind[:1] in 'aeio' else 'a'} {kind}"
    text = repr(value)
    return f"{text} ({kind})" if len(text) <= 40 else kind


def whole(name: str, value: Any) -> None:
    """Refuses, naming it, an argument that is not a whole number of at least 1 (a bool is
    none, though Python counts it as an int)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < 1:
        raise SpecchioError(f"{name}: {shown(value)}; must be a whole number of at least 1")


def function_or_none(name: str, value: Any) -> None:
    """Refuses, naming it, an argument that should be called back and cannot be: before any
    work, not at the first call."""
    if value is not None and not callable(value):
        raise SpecchioError(f"{name}: {shown(value)}; give a function of (done, total), or None")


def flag(name: str, value: Any) -> None:
    """Refuses, naming it, a switch that is not True or False: ``ray="no"`` is truthy, and
    would start a cluster."""
    if not isinstance(value, bool):
        raise SpecchioError(f"{name}: {shown(value)}; give True or False")


def environment(name: str, value: Any) -> Optional[dict[str, str]]:
    """A dict of str to str (environment variables) checked by name, or None: a list, a key
    that is not a str or a value that is not one is refused before any worker starts (a
    value of None became the string "None" before)."""
    if value is None:
        return None
    if not isinstance(value, dict):
        raise SpecchioError(f"{name}: {shown(value)}; give a dict of str to str, or None")
    for key, item in value.items():
        if not isinstance(key, str) or not key or "=" in key or "\0" in key:
            raise SpecchioError(f"{name}: the key {shown(key)}; give variable names as str, without '='")
        # A number is written as Python writes it (``{"LP_NUM_THREADS": 1}``); None or a
        # bool would become the word "None" or "True".
        number = isinstance(item, (int, float)) and not isinstance(item, bool)
        if not (isinstance(item, str) or number) or "\0" in str(item):
            raise SpecchioError(f"{name}[{key!r}]: {shown(item)}; give the value as a str (or a number)")
    return {key: str(item) for key, item in value.items()}
