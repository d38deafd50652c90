"""Deterministic random streams: no global state, one stream per (scene seed, stable ids).

Ids are strings or ints (building id, face index, plugin id). They are hashed with BLAKE2b -- never ``hash()``,
which is salted per process -- into entropy words for :class:`numpy.random.SeedSequence`.
"""
from __future__ import annotations

import hashlib

import numpy as np


#: The largest seed (scene ``seed``, ``--seed``): the stage stores it as ``citygen:seed``, a 32-bit int.
MAX_SEED = 2**31 - 1


def seed_words(*ids: str | int) -> list[int]:
    """Stable 32-bit entropy words for a sequence of ids."""
    digest = hashlib.blake2b("\x1f".join(map(str, ids)).encode("utf-8"), digest_size=16).digest()
    return [int.from_bytes(digest[i:i + 4], "little") for i in range(0, 16, 4)]


def derive_seed(*ids: str | int) -> int:
    """A stable 63-bit integer seed for ids (for plugins that want a plain int)."""
    words = seed_words(*ids)
    return (words[0] | words[1] << 32) & (2**63 - 1)


def derive_rng(*ids: str | int) -> np.random.Generator:
    """A PCG64 generator for ids: same ids, same stream, on every machine and process."""
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence(seed_words(*ids))))
