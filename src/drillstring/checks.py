"""Checks of the arguments a user gives the API and the engine (numbers, counts, seeds): one line naming the
argument, its value and the allowed range, raised before any work.

A wrong *type* (a string, a bool, a list where a number is expected) raises :class:`TypeError`; a number
outside its range raises :class:`ValueError`. NumPy scalars are accepted wherever Python numbers are
(``np.int64(2)`` is an integer, ``np.float32(0.5)`` a real number) and are returned as Python numbers.
"""

from __future__ import annotations

import math
import numbers

#: Largest seed: seeds are unsigned 64-bit integers (NumPy's SeedSequence and the stores keep them so).
MAX_SEED = 2**64 - 1


def _shown(value, unit: str) -> str:
    return f"{value!r} {unit}".rstrip() if unit else repr(value)


def real_number(name: str, value, *, unit: str = "", low: float | None = None, high: float | None = None,
                low_open: bool = False, high_open: bool = False, allowed: str | None = None) -> float:
    """``value`` as a finite float in [low, high] (an end is excluded when ``*_open``); TypeError for
    anything but a real number, ValueError outside the range. ``allowed`` words the range in messages."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name} = {_shown(value, unit)}: must be a number, not {type(value).__name__}")
    x = float(value)
    if allowed is None:
        if high is None:
            allowed = "a finite number" + ("" if low is None else f" {'>' if low_open else '>='} {low:g}")
        elif low is None:
            allowed = f"a finite number {'<' if high_open else '<='} {high:g}"
        else:
            allowed = (f"a number in {'(' if low_open else '['}{low:g}, {high:g}{')' if high_open else ']'}"
                       f"{' ' + unit if unit else ''}")
    if not math.isfinite(x) or (low is not None and (x < low or (low_open and x == low))) or (
            high is not None and (x > high or (high_open and x == high))):
        raise ValueError(f"{name} = {_shown(value, unit)}: must be {allowed}")
    return x


def integer(name: str, value, *, low: int | None = None, high: int | None = None, allowed: str | None = None) -> int:
    """``value`` as a Python int in [low, high]; TypeError for anything but an integer (a float such as
    2.0 included), ValueError outside the range."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(f"{name} = {value!r}: must be an integer, not {type(value).__name__}")
    n = int(value)
    if (low is not None and n < low) or (high is not None and n > high):
        if allowed is None:
            allowed = (f"an integer >= {low}" if high is None else f"an integer <= {high}" if low is None
                       else f"an integer in [{low}, {high}]")
        raise ValueError(f"{name} = {n}: must be {allowed}")
    return n


def seed(value, name: str = "seed") -> int:
    """A seed: an integer in [0, 2**64 − 1]."""
    return integer(name, value, low=0, high=MAX_SEED, allowed=f"an integer in [0, 2**64 - 1 = {MAX_SEED}]")
