"""Worker processes tied to the process that started them: they die with it, and it can stop them at once.

A worker that outlives its parent (``kill -9`` of ``citygen generate``) holds its memory for nothing, forever. Two
ties, both set up in the worker by :func:`tie_to_parent`: on Linux the kernel's parent-death signal
(``prctl(PR_SET_PDEATHSIG, SIGKILL)``), and everywhere a watchdog thread that ends the worker when its parent
process id changes (the parent died and the worker was re-parented). Workers ignore Ctrl-C: the terminal sends
SIGINT to the whole process group, and the parent, which handles it, stops them (:func:`stop_workers`), so no
worker prints a traceback of its own.
"""
from __future__ import annotations

import contextlib
import ctypes
import ctypes.util
import multiprocessing
import os
import signal
import sys
import threading
from collections.abc import Callable, Iterator
from concurrent.futures import ProcessPoolExecutor
from typing import TypeVar

T = TypeVar("T")

#: ``PR_SET_PDEATHSIG`` of ``<linux/prctl.h>``.
PR_SET_PDEATHSIG = 1
#: Seconds between the watchdog's looks at the parent process id.
WATCH_INTERVAL = 0.5


def tie_to_parent(parent: int) -> None:
    """In a worker process started by process ``parent``: die when it does (see the module docstring)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    if sys.platform.startswith("linux"):
        with contextlib.suppress(OSError, AttributeError):
            libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)
            libc.prctl(PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
    if os.getppid() != parent:  # it died before the tie was made
        os._exit(1)
    threading.Thread(target=_watch, args=(parent,), name="citygen-parent-watchdog", daemon=True).start()


def _watch(parent: int) -> None:
    stop = threading.Event()
    while not stop.wait(WATCH_INTERVAL):
        if os.getppid() != parent:
            os._exit(1)


def stop_workers(pool: ProcessPoolExecutor, grace: float = 2.0) -> None:
    """End ``pool``'s worker processes now (SIGTERM, then SIGKILL after ``grace`` seconds) and drop its queued
    work: what an interrupted run does instead of waiting for the chunks in flight."""
    processes = list((getattr(pool, "_processes", None) or {}).values())
    for process in processes:
        with contextlib.suppress(OSError, ValueError):
            process.terminate()
    for process in processes:
        with contextlib.suppress(OSError, ValueError):
            process.join(grace)
            if process.is_alive():
                process.kill()
                process.join(grace)
    pool.shutdown(wait=False, cancel_futures=True)


@contextlib.contextmanager
def apart(fn: Callable[[], T]) -> Iterator[Callable[[], T | None]]:
    """``fn()`` started now in a child process forked from this one (and tied to it); yields the call that waits for
    its result, pickled back. What ``fn`` allocates on the way -- a city's imported footprints -- never stays in
    this process's memory, nor in the memory of workers forked from it later; and this process goes on meanwhile.
    The result is ``None`` where this process cannot fork (not Linux) or when the child failed: the caller then
    calls ``fn`` itself, which raises the error where it is reported. Leaving the block kills the child if it has
    not answered (the caller met an error of its own)."""
    if not sys.platform.startswith("linux"):
        yield lambda: None
        return
    context = multiprocessing.get_context("fork")
    receive, send = context.Pipe(duplex=False)
    child = context.Process(target=_apart, args=(fn, send, os.getpid()), daemon=True)
    child.start()
    send.close()

    def result() -> T | None:
        try:
            return receive.recv()
        except EOFError:  # (it ended without an answer: killed, out of memory)
            return None

    try:
        yield result
    finally:
        if child.is_alive():
            child.kill()  # (harmless once it has answered: it only exits then)
        receive.close()
        child.join()


def run_apart(fn: Callable[[], T]) -> T | None:
    """``fn()`` computed apart (:func:`apart`), waited for at once."""
    with apart(fn) as result:
        return result()


def _apart(fn: Callable[[], object], send, parent: int) -> None:
    tie_to_parent(parent)
    try:
        send.send(fn())
    except BaseException:
        send.send(None)
    finally:
        send.close()
        os._exit(0)  # (no cleanup of the parent's state)
