"""Argument types shared by the Python commands (fleet, montecarlo, synthetic): each refuses a
bad value while argparse parses, so the message is one line naming the option, before any work."""

from __future__ import annotations

import argparse
import math
from typing import Callable


def whole(low: int, high: int | None = None) -> Callable[[str], int]:
    """A whole number in ``[low, high]`` (no upper bound when ``high`` is None)."""

    def parse(text: str) -> int:
        try:
            n = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
        if n < low or (high is not None and n > high):
            bound = f"{low}-{high}" if high is not None else f"at least {low}"
            raise argparse.ArgumentTypeError(f"{n}: expected {bound}")
        return n

    return parse


def positive(text: str) -> float:
    """A finite number above zero."""
    try:
        x = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not (x > 0 and math.isfinite(x)):
        raise argparse.ArgumentTypeError(f"{text}: expected a positive number")
    return x
