"""Argument types of the command line: numbers that are finite and in bounds, refused by argparse otherwise (one
``error: argument --x: ...`` line naming the option, exit status 2, no traceback)."""
from __future__ import annotations

import argparse
import math

from citygen.request import MIN_STOREY
from citygen.rng import MAX_SEED

#: The largest facade side (metres) of the one-facade preview commands.
MAX_SIDE = 1000.0


def metres(low: float, high: float, what: str):
    """A finite number of metres, at least ``low`` (more than 0 when ``low`` is 0) and at most ``high``."""
    def parse(text: str) -> float:
        value = _float(text, "a number of metres")
        if not (value >= low and value <= high and value > 0):  # (NaN fails every test)
            least = f"at least {low:g}" if low > 0 else "more than 0"
            raise argparse.ArgumentTypeError(f"{what} must be {least} and at most {high:g} m, got {text}")
        return value
    return parse


def seconds(text: str) -> float:
    """A finite positive number of seconds."""
    value = _float(text, "a number of seconds")
    if not 0 < value < math.inf:
        raise argparse.ArgumentTypeError(f"must be a finite positive number of seconds, got {text}")
    return value


def whole(least: int):
    """An integer of at least ``least``."""
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
        if value < least:
            raise argparse.ArgumentTypeError(f"must be at least {least}, got {value}")
        return value
    return parse


def seed(text: str) -> int:
    """A seed: an integer from 0 to :data:`citygen.rng.MAX_SEED`."""
    value = whole(0)(text)
    if value > MAX_SEED:
        raise argparse.ArgumentTypeError(f"must be at most {MAX_SEED} (2**31 - 1), got {value}")
    return value


def _float(text: str, what: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not {what}") from None


def add_size_arguments(parser: argparse.ArgumentParser, floor_height: float | None = None,
                       ground: bool = False) -> None:
    """``--size W H`` of a one-facade preview command, with ``--floor-height`` (when it has a default) and
    ``--ground-height`` (``ground``)."""
    parser.add_argument("--size", nargs=2, type=metres(0.0, MAX_SIDE, "a facade side"), metavar=("W", "H"),
                        required=True, help=f"facade width and height in metres (at most {MAX_SIDE:g} each)")
    storey = metres(MIN_STOREY, 100.0, "a storey")
    if floor_height is not None:
        parser.add_argument("--floor-height", type=storey, default=floor_height,
                            help=f"storey height in metres (default {floor_height:g})")
    if ground:
        parser.add_argument("--ground-height", type=storey, default=None,
                            help="ground floor height in metres (default: the storey height)")
