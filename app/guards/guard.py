"""What a hostile or broken client cannot do to the viewer: flood the terminal, or leave the server
holding the memory its oversized messages took.

- viser drops a connection whose message does not decode (the handler fails, websockets logs the
  traceback): `OncePerKind` says so in one line (the page's mistake, not the server's: no traceback), once per kind
  of mistake, then counts; any other failure keeps its first traceback per kind.
- Decoding a 20 MB frame allocates 20 MB that the C allocator keeps after it is freed (measured: +90
  MiB after a burst, for good). `big_blocks_go_back` makes large blocks mmap'd (freed straight back),
  and `release_memory` hands back what smaller ones leave (glibc's malloc_trim, about 5 ms); the viewer
  sets the first at start and calls the second every few seconds from a thread of its own.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import functools
import logging
import sys
import threading
import warnings

LOGGERS = ("websockets.server", "websockets", "viser", "asyncio")


class OncePerKind(logging.Filter):
    """Pass the first record of each (logger, message, exception type); count the rest, noting every 100th."""

    def __init__(self):
        super().__init__()
        self.seen: dict[tuple, int] = {}
        self._lock = threading.Lock()

    def filter(self, record: logging.LogRecord) -> bool:
        kind = type(record.exc_info[1]).__name__ if record.exc_info and record.exc_info[1] is not None else ""
        key = (record.name, str(record.msg), kind)
        with self._lock:
            n = self.seen[key] = self.seen.get(key, 0) + 1
        if n == 1 and _undecodable(record):  # a page's mistake: one quiet line, the frames (and its message) dropped
            error = record.exc_info[1]
            record.msg, record.args = "floatsim viewer: closed a page's connection: its message did not decode (%s: %.120s)", (kind, error)
            record.exc_info, record.exc_text = None, None
            return True
        if n == 1:
            if record.exc_info:  # the text only: a kept traceback would keep the frames, and the bad message in them
                record.exc_text = logging.Formatter().formatException(record.exc_info)
                record.exc_info = None
            return True
        if n % 100 == 0:
            print(
                f"floatsim viewer: {record.getMessage()} ({kind or record.levelname}) x{n} so far (tracebacks shown once)", file=sys.stderr
            )
        return False


def _undecodable(record: logging.LogRecord) -> bool:
    """Whether the record is a connection's failure to decode what its page sent (viser's Message.deserialize)."""
    tb = record.exc_info[2] if record.exc_info else None
    while tb is not None:
        if tb.tb_frame.f_code.co_name == "deserialize":
            return True
        tb = tb.tb_next
    return False


_filter = OncePerKind()


def quiet_repeated_tracebacks() -> OncePerKind:
    # a page that left (or was closed) while its controls were being made: viser warns of each message still queued for it
    warnings.filterwarnings("ignore", message=r"Queued a \w+ on a closed connection", category=UserWarning)
    for name in LOGGERS:
        logger = logging.getLogger(name)
        if _filter not in logger.filters:
            logger.addFilter(_filter)
    return _filter


M_MMAP_THRESHOLD = -3


@functools.cache
def _libc() -> ctypes.CDLL | None:
    """The C library, found once: ctypes.util.find_library forks `ldconfig -p` on every call."""
    try:
        return ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
    except OSError:
        return None


def big_blocks_go_back() -> bool:
    """Make glibc serve every block over 1 MiB by mmap, returned to the system when freed. By default the
    threshold rises after the first large free, and later large messages then stay in the heap."""
    try:
        return bool(_libc().mallopt(M_MMAP_THRESHOLD, 1 << 20))
    except AttributeError:  # no C library found, or one without mallopt (not glibc)
        return False


def release_memory() -> bool:
    """Return freed heap memory to the system where the C library can (glibc); False elsewhere."""
    try:
        return bool(_libc().malloc_trim(0))
    except AttributeError:
        return False
